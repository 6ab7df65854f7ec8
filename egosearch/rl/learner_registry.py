"""The learners by name: ``cfg.algorithm`` -> the agent the training loop builds, and an actor file's
``format`` -> the function that loads its network.

:data:`LEARNERS` holds one :class:`Learner` per algorithm name; :data:`ALGORITHMS` (its live names)
is what ``LearnerConfig.validate`` accepts. Adding a learner is one module with its agent class (an
:class:`egosearch.rl.learner.Agent`, most simply a subclass of :class:`egosearch.rl.learner.AgentBase`)
and one :func:`register` line below, which also names the dataclass of its own settings (most simply
built from :mod:`egosearch.rl.network_settings`'s pieces). Agents, loaders and settings may be named
``"module:attribute"``, imported on first use: this module imports neither torch nor a learner, nor the
config (:mod:`egosearch.rl.config` imports it); it types configs as :class:`egosearch.rl.learner.LearnerSettings`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from egosearch.core.named_registry import Registry, resolve

if TYPE_CHECKING:
    from egosearch.rl.learner import ActorFileNet, Agent, LearnerSettings


@dataclass(frozen=True)
class Learner:
    """One registered learner.

    ``name``: its ``cfg.algorithm``; ``display_name``: how the training loop names it;
    ``agent``: its agent class or factory (or ``"module:Class"``), called as
    ``agent(cfg, action_dim, mask_dim, proprio_dim, device=device[, state_dim=state_dim])``;
    ``actor_formats``: the ``format`` of each actor file it writes -> the function
    ``(state, device) -> net`` (or ``"module:function"``) that loads that file's network, an
    :class:`egosearch.rl.learner.ActorFileNet`;
    ``takes_state_dim``: whether ``agent`` takes ``state_dim`` (the privileged state's size);
    ``settings``: the dataclass of its own settings (or ``"module:Class"``), which
    :mod:`egosearch.rl.config` composes with the run settings into its config; None: the run settings alone;
    ``stacked``: its seeds can train in one process, their updates vmapped (:mod:`egosearch.rl.stacked`);
    ``smoke_overrides``: config fields on top of the ``smoke`` preset that make its networks test-sized (the
    tests build every registered learner with them)."""

    name: str
    display_name: str
    agent: str | Callable[..., Agent]
    actor_formats: Mapping[str, str | Callable[..., ActorFileNet]] = field(default_factory=dict)
    takes_state_dim: bool = True
    settings: str | type | None = None
    stacked: bool = False
    smoke_overrides: Mapping[str, object] = field(default_factory=dict)

    def settings_class(self) -> type | None:
        return None if self.settings is None else resolve(self.settings)

    def agent_factory(self) -> Callable[..., Agent]:
        return resolve(self.agent)

    def make(self, cfg: LearnerSettings, action_dim: int, mask_dim: int, proprio_dim: int, device,
             state_dim: int = 0, **options: object) -> Agent:
        """The agent; ``options``: keyword arguments of this learner's own constructor (SAC+CURL's ``impl``)."""
        factory = self.agent_factory()
        if self.takes_state_dim:
            return factory(cfg, action_dim, mask_dim, proprio_dim, device=device, state_dim=state_dim, **options)
        return factory(cfg, action_dim, mask_dim, proprio_dim, device=device, **options)


_REGISTRY: Registry[Learner] = Registry("algorithm", describe=lambda entry: entry.display_name)
LEARNERS: dict[str, Learner] = _REGISTRY.entries
"""Every registered learner by algorithm name, in registration order."""
ALGORITHMS = LEARNERS.keys()
"""The registered algorithm names (a live view of :data:`LEARNERS`)."""


def register(name: str, display_name: str, agent: str | Callable[..., Agent],
             actor_formats: Mapping[str, str | Callable[..., ActorFileNet]] | None = None, *,
             takes_state_dim: bool = True, settings: str | type | None = None, stacked: bool = False,
             smoke_overrides: Mapping[str, object] | None = None, replace: bool = False) -> Learner:
    """Register a learner under algorithm ``name`` (see :class:`Learner` for the arguments); a name
    already taken needs ``replace``, and an actor format another learner loads differently is refused."""
    learner = Learner(name, display_name, agent, dict(actor_formats or {}), takes_state_dim, settings, stacked,
                      dict(smoke_overrides or {}))
    if name in LEARNERS and not replace:
        _REGISTRY.add(name, learner)  # the registry's one line: the name is taken
    for other in LEARNERS.values():
        for fmt, loader in learner.actor_formats.items():
            if other.name != name and fmt in other.actor_formats and other.actor_formats[fmt] != loader:
                raise ValueError(f"actor format {fmt!r} is loaded differently by algorithm {other.name!r}")
    return _REGISTRY.add(name, learner, replace=replace)


def learner(algorithm: str) -> Learner:
    """The learner registered as ``algorithm``."""
    return _REGISTRY.get(algorithm)


def stacked_algorithms() -> tuple[str, ...]:
    """The learners whose seeds can be stacked (:mod:`egosearch.rl.stacked`), in registration order."""
    return tuple(name for name, entry in LEARNERS.items() if entry.stacked)


def make_agent(cfg: LearnerSettings, action_dim: int, mask_dim: int, proprio_dim: int, device,
               state_dim: int = 0, **options: object) -> Agent:
    """The agent of the learner ``cfg.algorithm`` names; ``state_dim``: size of the env's privileged
    state (``critic_privileged_state``), for the learners that take it; ``options``: keyword arguments
    of that learner's own constructor."""
    return learner(cfg.algorithm).make(cfg, action_dim, mask_dim, proprio_dim, device, state_dim, **options)


def actor_formats() -> dict[str, str | Callable[..., ActorFileNet]]:
    """Every registered actor file ``format`` -> the function that loads its network."""
    return {fmt: loader for entry in LEARNERS.values() for fmt, loader in entry.actor_formats.items()}


def actor_loader(fmt: str) -> Callable[..., ActorFileNet] | None:
    """The function ``(state, device) -> ActorFileNet`` that loads an actor file of format ``fmt``
    (None for a format no registered learner writes)."""
    loader = actor_formats().get(fmt)
    return None if loader is None else resolve(loader)


# ---- the learners -------------------------------------------------------------------------------

register("sac_curl", "SAC+CURL", "egosearch.rl.sac_curl:SacCurlAgent",
         {"egosearch-sac-curl-actor-v1": "egosearch.rl.sac_curl:load_actor_net"}, takes_state_dim=False,
         settings="egosearch.rl.sac_curl_settings:SacCurlSettings", stacked=True)
register("sac_drq", "SAC-DrQ", "egosearch.rl.sac_drq:SacDrqAgent",
         {"egosearch-sac-drq-actor-v1": "egosearch.rl.pooled:load_drq_actor_net"},
         settings="egosearch.rl.sac_drq_settings:SacDrqSettings", stacked=True,
         smoke_overrides={"obs_downsample": 4, "encoder_stride2_layers": 2})
register("sac_drq_recurrent", "recurrent SAC-DrQ", "egosearch.rl.sac_drq_recurrent:SacDrqRecurrentAgent",
         {"egosearch-sac-drq-recurrent-actor-v1": "egosearch.rl.sac_drq_recurrent:load_recurrent_actor_net"},
         settings="egosearch.rl.sac_drq_recurrent_settings:SacDrqRecurrentSettings",
         smoke_overrides={"obs_downsample": 4, "encoder_stride2_layers": 2, "recurrent_hidden_dim": 8,
                          "sequence_length": 2, "burn_in": 1})
register("ppo", "PPO", "egosearch.rl.ppo:PpoAgent",
         {"egosearch-sac-drq-actor-v1": "egosearch.rl.pooled:load_drq_actor_net"},
         settings="egosearch.rl.ppo_settings:PpoSettings",
         smoke_overrides={"obs_downsample": 4, "encoder_stride2_layers": 2, "init_steps": 0, "update_every": 32,
                          "replay_capacity": 64})

"""What a learner is to the training loop and what its actor file is to a policy: the :class:`Agent`
protocol, :class:`AgentBase` (its optional hooks' default behaviour), and the actor file's contract
(:class:`ActorFile`, :class:`ActorArch`, :class:`ActorFileNet`).

:mod:`egosearch.rl.train` (``LiveRun``), :mod:`egosearch.rl.imitation` and
:class:`egosearch.rl.actor.AgentPolicy` call an agent through :class:`Agent` only, and call every
hook directly: a learner that subclasses :class:`AgentBase` inherits the hooks it does not need. A
learner is registered by name in :mod:`egosearch.rl.learner_registry` (one ``register`` line), which
``cfg.algorithm`` then picks; :class:`egosearch.rl.actor.ActorPolicy` loads its actor files through
the loader registered with their ``format``.

This module imports neither torch nor a learner, nor the learner config: it is the contract its
implementers import, so it imports nothing of theirs (the config imports the registry, which imports
this module). What it reads of a config is :class:`LearnerSettings`.
"""

from __future__ import annotations

import functools
from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, Any, ClassVar, NotRequired, Protocol, TypedDict, runtime_checkable

import numpy as np

if TYPE_CHECKING:
    import torch

    from egosearch.rl.replay import MultiReplay


class LearnerSettings(Protocol):
    """What the registry and :class:`AgentBase`'s defaults read of a learner config
    (:class:`egosearch.rl.config.LearnerConfig` is one; a learner reads its own fields from it)."""

    @property
    def algorithm(self) -> str: ...

    @property
    def image_size(self) -> int: ...

    @property
    def batch_size(self) -> int: ...


@runtime_checkable
class Agent(Protocol):
    """What the training loop (``egosearch.rl.train.LiveRun``), imitation (:mod:`egosearch.rl.imitation`)
    and ``AgentPolicy`` may call on a learner: every attribute and method below, and nothing else.

    Acting: ``act(obs, deterministic)`` -> one action (A,) in [-1, 1] for ONE env observation (the
    evaluation episode's, for a recurrent agent); ``act_batch(obs, deterministic)`` -> (B, A) for a
    stacked batch of the first B training envs' observations. The loop acts with ``act`` when it
    steps one env and the agent is not ``recurrent``, else with ``act_batch``.

    Replay: the loop stores ``replay_obs(obs)`` (e.g. pooled depth) in a replay of side
    ``replay_image_size`` and feeds ``update`` with ``sample_batch(replay)``; ``update(batch)``
    returns the :data:`egosearch.rl.common.METRIC_KEYS` floats (NaN for a loss not computed).

    Memory: ``reset_state(env_index)`` when training env ``env_index``'s episode ends or is cut;
    ``reset_policy_state()`` when an evaluation episode starts.

    Demonstrations (configs with ``bc_updates`` or ``bc_weight``): before RL, behaviour cloning
    builds one optimiser over ``clone_parameters()`` and calls ``clone_update(batch, optimiser)`` on
    ``cloning_batch(sources, batch_size)`` (the teacher's transitions, or a recurrent agent's sequences,
    with the teacher's ``action``) for each step; during RL, with ``demo_batch_fraction``, an update's
    batch is ``sample_with_demonstrations(replay, demos, fraction)`` (its demonstration rows marked by a
    (B, 1) ``demo`` column), and with ``bc_weight`` the loop sets ``bc_weight_now`` (the decayed weight of
    the update's behaviour-cloning term) before each env step's updates.

    Persistence: ``state_dict()`` / ``load_state_dict(state)`` (the checkpoint's agent, which
    raises :class:`egosearch.rl.common.AgentStateError` on a mismatch); ``actor_state(metadata)``
    -> the actor file (:class:`ActorFile`), whose ``format`` the registry maps to the function that
    loads its network (:class:`ActorFileNet`).

    Logs: ``num_updates`` (gradient updates so far) and ``alpha``, the weight of the entropy term
    (SAC's temperature, PPO's entropy coefficient): a finite number >= 0, 0 for a learner without
    one. The loop only logs it."""

    recurrent: bool
    """True when ``act_batch`` carries a memory per training env (then ``act`` is the evaluation
    episode's and training envs always act through ``act_batch``)."""
    num_updates: int
    bc_weight_now: float

    @property
    def alpha(self) -> float: ...

    @property
    def replay_image_size(self) -> int: ...

    def act(self, obs: dict, deterministic: bool = False) -> np.ndarray: ...

    def act_batch(self, obs: dict, deterministic: bool = False) -> np.ndarray: ...

    def replay_obs(self, obs: dict) -> dict: ...

    def sample_batch(self, replay: MultiReplay) -> dict[str, torch.Tensor]: ...

    def sample_with_demonstrations(self, replay: MultiReplay, demos: MultiReplay,
                                   fraction: float) -> dict[str, torch.Tensor]: ...

    def cloning_batch(self, sources: list[MultiReplay], batch_size: int) -> dict[str, torch.Tensor]: ...

    def update(self, batch: dict[str, torch.Tensor]) -> dict[str, float]: ...

    def clone_parameters(self) -> list[torch.nn.Parameter]: ...

    def clone_update(self, batch: dict[str, torch.Tensor], optimiser: torch.optim.Optimizer) -> dict[str, float]: ...

    def reset_state(self, env_index: int | None = None) -> None: ...

    def reset_policy_state(self) -> None: ...

    def state_dict(self) -> dict[str, Any]: ...

    def load_state_dict(self, state: dict[str, Any]) -> None: ...

    def actor_state(self, metadata: dict[str, Any] | None = None) -> ActorFile: ...


@functools.cache
def demo_column(rows: int, from_demos: int, device: torch.device) -> torch.Tensor:
    """(rows, 1): 0 on a batch's online rows, 1 on its last ``from_demos`` rows (the demonstrations'); made once
    per size and device, not at every update."""
    import torch

    return torch.cat([torch.zeros(rows - from_demos, 1), torch.ones(from_demos, 1)]).to(device)


class AgentBase(ABC):
    """A learner's optional hooks, with the behaviour of a memoryless agent whose replay holds the
    env's observations as they are and that cannot learn from demonstrations. A subclass sets
    ``cfg`` and ``num_updates`` and defines ``alpha``, ``act``, ``update``, ``state_dict``,
    ``load_state_dict`` and ``actor_state``."""

    recurrent: ClassVar[bool] = False
    cfg: LearnerSettings
    num_updates: int
    bc_weight_now: float = 0.0
    """The behaviour-cloning term's weight at this update, set by the loop; without such a term in
    ``update``, it is never read."""

    @property
    @abstractmethod
    def alpha(self) -> float: ...

    @abstractmethod
    def act(self, obs: dict, deterministic: bool = False) -> np.ndarray: ...

    @abstractmethod
    def update(self, batch: dict[str, torch.Tensor]) -> dict[str, float]: ...

    @abstractmethod
    def state_dict(self) -> dict[str, Any]: ...

    @abstractmethod
    def load_state_dict(self, state: dict[str, Any]) -> None: ...

    @abstractmethod
    def actor_state(self, metadata: dict[str, Any] | None = None) -> ActorFile: ...

    def act_batch(self, obs: dict, deterministic: bool = False) -> np.ndarray:
        """Actions (B, A) for a stacked batch: ``act`` on each observation in turn."""
        return np.stack([self.act({k: v[i] for k, v in obs.items()}, deterministic)
                         for i in range(len(obs["depth"]))])

    @property
    def replay_image_size(self) -> int:
        """Side of the depth frames the replay stores: the env's."""
        return self.cfg.image_size

    def replay_obs(self, obs: dict) -> dict:
        """An observation as the replay stores it: unchanged."""
        return obs

    def sample_batch(self, replay: MultiReplay) -> dict[str, torch.Tensor]:
        """An update's batch: ``batch_size`` transitions drawn uniformly."""
        return replay.sample(self.cfg.batch_size)

    def sample_with_demonstrations(self, replay: MultiReplay, demos: MultiReplay,
                                   fraction: float) -> dict[str, torch.Tensor]:
        """An update's batch with ``fraction`` of its ``batch_size`` transitions drawn from the demonstrations
        (the last rows, marked 1 in the (B, 1) ``demo`` column), the rest from the online replay (RLPD)."""
        import torch  # a learner's module loads it; this protocol's module does not

        size = self.cfg.batch_size
        from_demos = round(size * fraction)
        online, demo = replay.sample(size - from_demos), demos.sample(from_demos)
        batch = {k: torch.cat([online[k], demo[k]]) for k in online}
        batch["demo"] = demo_column(size, from_demos, batch["reward"].device)
        return batch

    def cloning_batch(self, sources: list[MultiReplay], batch_size: int) -> dict[str, torch.Tensor]:
        """A behaviour-cloning batch: ``batch_size`` transitions drawn from ``sources`` in proportion to
        their sizes (the demonstrations, then each DAgger round's labelled states)."""
        import torch

        from egosearch.rl.replay import proportional_counts

        counts = proportional_counts([len(s) for s in sources], batch_size)
        parts = [s.sample(n) for s, n in zip(sources, counts) if n > 0]
        return {k: torch.cat([p[k] for p in parts]) for k in ("obs_depth", "mask", "proprio", "action")}

    def clone_parameters(self) -> list[torch.nn.Parameter]:
        """What behaviour cloning trains: nothing here, so it is refused."""
        raise NotImplementedError(self._no_cloning())

    def clone_update(self, batch: dict[str, torch.Tensor], optimiser: torch.optim.Optimizer) -> dict[str, float]:
        """A behaviour-cloning step: refused without ``clone_parameters``."""
        raise NotImplementedError(self._no_cloning())

    def _no_cloning(self) -> str:
        return (f"{type(self).__name__} does not learn from demonstrations (bc_updates): it defines no "
                "clone_parameters and clone_update")

    def reset_state(self, env_index: int | None = None) -> None:
        """A training env's episode ended: nothing to forget without a memory."""
        return None

    def reset_policy_state(self) -> None:
        """An evaluation episode starts: nothing to forget without a memory."""
        return None


# ---- the actor file ------------------------------------------------------------------------------

class ActorArch(TypedDict):
    """An actor file's ``arch``: the sizes :class:`egosearch.rl.actor.ActorPolicy` reads, beside
    whatever else fixes the network's shapes for its loader (any further keys).

    ``action_dim``: the action's size; ``extra_dim``: the size of the vector the network reads
    beside depth, ``[mask, proprio]``. Read when present: ``mask_dim`` and ``proprio_dim`` (both, to
    tell apart envs whose sums agree); ``crop_size``, the side of the centre crop of the depth
    frames the network reads (without it, the whole frame); ``image_size``, the side of the frames
    it was trained on, which must be the env's (:data:`egosearch.sim.body.IMAGE_SIZE`)."""

    action_dim: int
    extra_dim: int
    mask_dim: NotRequired[int]
    proprio_dim: NotRequired[int]
    crop_size: NotRequired[int]
    image_size: NotRequired[int]


class ActorFile(TypedDict):
    """What ``Agent.actor_state`` returns and ``actor.pt`` holds: tensors and plain python types
    only, so that ``torch.load(weights_only=True)`` reads it. ``format`` names the loader registered
    for it (:func:`egosearch.rl.learner_registry.actor_loader`); ``state_dict`` holds the weights;
    ``metadata`` what the training recorded (variant, env id, config, ...)."""

    format: str
    arch: ActorArch
    state_dict: dict[str, Any]
    metadata: dict[str, Any]


@runtime_checkable
class ActorFileNet(Protocol):
    """The network an actor file's loader returns (``(state, device) -> ActorFileNet``), as
    :class:`egosearch.rl.actor.ActorPolicy` drives it: ``net(depth, extra) -> (mu, anything)`` with
    ``depth`` the K newest frames (1, K, S, S) as floats in [0, 255] (centre-cropped to
    ``crop_size``) and ``extra`` (1, ``extra_dim``) = ``[mask, proprio]``; ``mu`` (1, ``action_dim``)
    is the Gaussian mean BEFORE the tanh, which the policy applies. A net with ``recurrent = True``
    is called ``net(depth, extra, h) -> (mu, anything, new h)`` instead, ``h`` None at an episode's
    start."""

    def __call__(self, depth: torch.Tensor, extra: torch.Tensor, *state: Any) -> tuple[Any, ...]: ...

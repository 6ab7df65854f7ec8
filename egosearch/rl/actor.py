"""A trained actor as a policy: :class:`ActorPolicy` loads ``actor.pt`` (any learner's, by its
``format``) behind the project's policy interface, ``reset(seed)`` and ``act(obs)``;
:class:`AgentPolicy` puts a live agent behind the same interface (the training loop's evaluations).

What an actor file holds and how its network is called is written down in :mod:`egosearch.rl.learner`
(:class:`~egosearch.rl.learner.ActorFile`, :class:`~egosearch.rl.learner.ActorArch`,
:class:`~egosearch.rl.learner.ActorFileNet`); :func:`check_actor_file` holds a file to it on loading.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import torch

from egosearch.envs import ALL_ENV_IDS, env_options, env_space_dims, observation_kwargs
from egosearch.rl.common import AgentStateError, obs_to_tensors, resolve_device
from egosearch.rl.learner import ActorFileNet, Agent
from egosearch.rl.learner_registry import actor_loader
from egosearch.sim.body import IMAGE_SIZE


class AgentPolicy:
    """The live agent behind the shared policy interface (deterministic actions)."""

    def __init__(self, agent: Agent):
        self.agent = agent

    def reset(self, seed: int | None = None) -> None:
        self.agent.reset_policy_state()  # a recurrent agent's memory

    def act(self, obs: dict) -> np.ndarray:
        return self.agent.act(obs, deterministic=True)


def check_actor_file(state: dict) -> None:
    """Raise :class:`AgentStateError` (one line) unless the actor file ``state``'s ``arch`` holds what
    :class:`ActorPolicy` reads (:class:`egosearch.rl.learner.ActorArch`) and the actor was trained on
    frames of the env's size (its ``arch["image_size"]``, else its recorded config's, where either is
    written): an actor on other frames would otherwise crop or pool them to the wrong size in silence."""
    arch = state.get("arch")
    if not isinstance(arch, dict):
        raise AgentStateError("the actor file has no arch (a dict of its sizes: egosearch.rl.learner.ActorArch)")
    for key in ("action_dim", "extra_dim") + tuple(k for k in ("crop_size", "mask_dim", "proprio_dim") if k in arch):
        if not isinstance(arch.get(key), int) or isinstance(arch[key], bool) or arch[key] < 1:
            raise AgentStateError(f"the actor file's arch has {key}={arch.get(key)!r}; it needs an integer >= 1 "
                                  "(egosearch.rl.learner.ActorArch)")
    config = (state.get("metadata") or {}).get("config") or {}
    side = arch.get("image_size", config.get("image_size"))
    if side is not None and side != IMAGE_SIZE:
        where = "arch" if "image_size" in arch else "recorded config"
        raise AgentStateError(f"this actor was trained on {side}x{side} depth frames (its {where}'s image_size); "
                              f"the envs render {IMAGE_SIZE}x{IMAGE_SIZE} (egosearch.sim.body.IMAGE_SIZE)")


def load_any_actor_net(state: dict, device) -> ActorFileNet:
    """An actor file's network, any registered learner's: the loader its ``format`` is registered
    with (:func:`egosearch.rl.learner_registry.actor_loader`), once the file holds what a policy reads
    (:func:`check_actor_file`)."""
    fmt = state.get("format") if isinstance(state, dict) else None
    loader = actor_loader(fmt) if isinstance(fmt, str) else None
    if loader is None:
        raise AgentStateError(f"not an actor file (format={fmt!r})")
    check_actor_file(state)
    return loader(state, device)


class ActorPolicy:
    """A trained actor (``actor.pt``) behind the project's policy interface:
    ``reset(seed=None)`` (no-op: the actor is memoryless given the env's frame history; a recurrent
    actor's hidden state is zeroed) and ``act(obs) -> np.ndarray`` (deterministic: tanh of the
    Gaussian mean, in [-1, 1]; a recurrent actor carries its hidden state to the next call)."""

    def __init__(self, path: str | os.PathLike, device: str = "auto"):
        path = Path(path)
        # torch's own message for a non-torch file advises weights_only=False, which is wrong here.
        not_actor = (f"{path} is not an egosearch actor file; an actor file is the actor.pt that "
                     "`egosearch train` writes (results/<preset>/train/<variant>/seed<N>/actor.pt)")
        if not path.is_file():
            raise FileNotFoundError(f"{path}: no such actor file" if not path.exists() else not_actor)
        try:
            state = torch.load(path, map_location="cpu", weights_only=True)
        except Exception as err:  # noqa: BLE001 - any unreadable file gets one line
            raise AgentStateError(f"{not_actor} (torch cannot read it: {type(err).__name__})") from None
        if not isinstance(state, dict) or "format" not in state:
            raise AgentStateError(not_actor)
        self.device = resolve_device(device)
        try:
            self.net = load_any_actor_net(state, self.device)
        except AgentStateError as err:
            raise AgentStateError(f"{path}: {err}") from None
        self.path = path
        self.arch = state["arch"]
        self.metadata = state.get("metadata", {})
        self.variant = self.metadata.get("variant")
        self.env_id = self.metadata.get("env_id")
        self.config = self.metadata.get("config")
        self.action_dim = int(self.arch["action_dim"])
        # without a crop_size the network reads the whole frame (a centre crop of the frame's own size)
        self.crop_size = int(self.arch.get("crop_size", IMAGE_SIZE))
        self.recurrent = bool(getattr(self.net, "recurrent", False))
        self._h = None

    @property
    def env_kwargs(self) -> dict[str, bool]:
        """The observation options it was trained with (:data:`egosearch.envs.OBSERVATION_OPTIONS`), from the
        config its file records: the env it is evaluated in is built with them."""
        return observation_kwargs(self.config if isinstance(self.config, dict) else None)

    def fits(self, env_id: str, env_kwargs: dict | None = None) -> bool:
        """Whether the actor's action and observation sizes are those of the registered ``env_id`` with the
        observation options ``env_kwargs`` (default: those it was trained with)."""
        dims = env_space_dims(env_id, self.env_kwargs if env_kwargs is None else env_kwargs)
        if "mask_dim" in self.arch and "proprio_dim" in self.arch:
            return (self.action_dim, int(self.arch["mask_dim"]), int(self.arch["proprio_dim"])) == (
                dims["action"], dims["mask"], dims["proprio"])
        return (self.action_dim, int(self.arch["extra_dim"])) == (dims["action"], dims["mask"] + dims["proprio"])

    def trained_env_id(self) -> str | None:
        """The env id the actor was trained in: the one its file records, else the one registered id
        whose sizes it fits (None when no single id does)."""
        if self.env_id:
            return self.env_id
        # a decision env reads no observation option, so an actor trained with one fits none of them
        fitting = [env_id for env_id in ALL_ENV_IDS if not (self.env_kwargs and env_options(env_id).modular)
                   and self.fits(env_id)]
        return fitting[0] if len(fitting) == 1 else None

    def check_env(self, env_id: str, env_kwargs: dict | None = None) -> None:
        """Raise :class:`AgentStateError` (one line naming the env id and options it was trained for) unless
        the actor can act in ``env_id`` with the observation options ``env_kwargs`` (default: its own): a
        mismatch otherwise surfaces only as a broadcasting error in the first episode's step."""
        options = self.env_kwargs if env_kwargs is None else env_kwargs
        if self.fits(env_id, options):
            return
        trained = self.trained_env_id()
        dims = env_space_dims(env_id, options)

        def named(kwargs: dict) -> str:
            on = [k for k, v in kwargs.items() if v]
            return f" with {', '.join(on)}" if on else ""

        told = f"was trained in {trained}{named(self.env_kwargs)}" if trained else "fits no registered env id"
        hint = f": run it in {trained}{named(self.env_kwargs)}" if trained else ""
        raise AgentStateError(f"{self.path}: this actor {told} ({self.action_dim} action values, "
                              f"{self.arch['extra_dim']} observation values besides depth), not in {env_id}"
                              f"{named(options)} ({dims['action']} and {dims['mask'] + dims['proprio']}){hint}")

    def reset(self, seed: int | None = None) -> None:
        self._h = None

    def act(self, obs: dict) -> np.ndarray:
        with torch.inference_mode():
            depth, extra = obs_to_tensors(obs, self.device, self.crop_size)
            if self.recurrent:
                mu, _, self._h = self.net(depth.float(), extra, self._h)
            else:
                mu, _ = self.net(depth.float(), extra)
            return torch.tanh(mu)[0].cpu().numpy().astype(np.float32)

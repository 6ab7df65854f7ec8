"""What a learner is to the training loop: the :class:`Agent` protocol and :class:`AgentBase`, its
optional hooks' default behaviour.

:mod:`egosearch.rl.train` (``_Run``) and :class:`egosearch.rl.actor.AgentPolicy` call an agent
through :class:`Agent` only, and call every hook directly: a learner that subclasses
:class:`AgentBase` inherits the hooks it does not need. A learner is registered by name in
:mod:`egosearch.rl.registry` (one ``register`` line), which ``cfg.algorithm`` then picks.

This module imports neither torch nor a learner.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, runtime_checkable

import numpy as np

if TYPE_CHECKING:
    import torch

    from egosearch.rl.config import LearnerConfig
    from egosearch.rl.replay import MultiReplay


@runtime_checkable
class Agent(Protocol):
    """What the training loop (``egosearch.rl.train._Run``) and ``AgentPolicy`` may call on a learner.

    Acting: ``act(obs, deterministic)`` -> one action (A,) in [-1, 1] for ONE env observation (the
    evaluation episode's, for a recurrent agent); ``act_batch(obs, deterministic)`` -> (B, A) for a
    stacked batch of the first B training envs' observations. The loop acts with ``act`` when it
    steps one env and the agent is not ``recurrent``, else with ``act_batch``.

    Replay: the loop stores ``replay_obs(obs)`` (e.g. pooled depth) in a replay of side
    ``replay_image_size`` and feeds ``update`` with ``sample_batch(replay)``; ``update(batch)``
    returns the :data:`egosearch.rl.common.METRIC_KEYS` floats (NaN for a loss not computed).

    Memory: ``reset_state(env_index)`` when training env ``env_index``'s episode ends or is cut;
    ``reset_policy_state()`` when an evaluation episode starts.

    Persistence: ``state_dict()`` / ``load_state_dict(state)`` (the checkpoint's agent, which
    raises :class:`egosearch.rl.common.AgentStateError` on a mismatch); ``actor_state(metadata)``
    -> the actor file (``format``, ``arch``, ``state_dict``, ``metadata``), whose ``format`` the
    registry maps to the function that loads its network.

    Logs: ``num_updates`` (gradient updates so far) and ``alpha`` (SAC's temperature, PPO's
    entropy weight)."""

    recurrent: bool
    """True when ``act_batch`` carries a memory per training env (then ``act`` is the evaluation
    episode's and training envs always act through ``act_batch``)."""
    num_updates: int

    @property
    def alpha(self) -> float: ...

    @property
    def replay_image_size(self) -> int: ...

    def act(self, obs: dict, deterministic: bool = False) -> np.ndarray: ...

    def act_batch(self, obs: dict, deterministic: bool = False) -> np.ndarray: ...

    def replay_obs(self, obs: dict) -> dict: ...

    def sample_batch(self, replay: MultiReplay) -> dict[str, torch.Tensor]: ...

    def update(self, batch: dict[str, torch.Tensor]) -> dict[str, float]: ...

    def reset_state(self, env_index: int | None = None) -> None: ...

    def reset_policy_state(self) -> None: ...

    def state_dict(self) -> dict[str, Any]: ...

    def load_state_dict(self, state: dict[str, Any]) -> None: ...

    def actor_state(self, metadata: dict[str, Any] | None = None) -> dict[str, Any]: ...


class AgentBase(ABC):
    """A learner's optional hooks, with the behaviour of a memoryless agent whose replay holds the
    env's observations as they are. A subclass sets ``cfg`` and ``num_updates`` and defines
    ``alpha``, ``act``, ``update``, ``state_dict``, ``load_state_dict`` and ``actor_state``."""

    recurrent: ClassVar[bool] = False
    cfg: LearnerConfig
    num_updates: int

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
    def actor_state(self, metadata: dict[str, Any] | None = None) -> dict[str, Any]: ...

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

    def reset_state(self, env_index: int | None = None) -> None:
        """A training env's episode ended: nothing to forget without a memory."""
        return None

    def reset_policy_state(self) -> None:
        """An evaluation episode starts: nothing to forget without a memory."""
        return None

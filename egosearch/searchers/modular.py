"""A modular learned searcher (the issue's lever (d), after SemExp, Chaplot et al. NeurIPS 2020, and the
modular pipeline of Gervet et al. 2023): a learned policy decides where to explore and how to sweep the head;
the frontier searcher's mapping, planning and walking (:mod:`egosearch.searchers.frontier`) carry it there.

The learned part is a high-level policy. Every decision it names
- a point on the floor in the body's frame, up to :attr:`GoalFrontierPolicy.GOAL_REACH` ahead/behind and
  left/right: the walk goes to the reachable frontier cell nearest that point (path length breaks ties);
- with the head, the sweep while it walks: the yaw's amplitude and the pitch's centre.

It decides again after :attr:`GoalFrontierPolicy.DECIDE_EVERY` body steps, or when the body stands at the
frontier it chose. Once the target is seen, the classical searcher walks to it and looks at it to the end of
the episode: the rest of the episode is the decision's outcome.

:class:`ModularSearchEnv` is that high level as a gymnasium env, for training (ids ``EgoSearchModular-v0`` and
``EgoSearchNoHeadModular-v0``): one env step is one decision; its reward is the sum of the paper's per-step
rewards over the body steps the decision ran; ``info`` is the body env's at the last of them, so evaluation
scores the paper's task and metrics (success, SPL, steps, collisions) unchanged. Its observation is the
paper's (depth frames, the target mask's features, the head's pose) and, appended to ``mask``, the
searcher's own floor map around the body (:meth:`egosearch.sim.floormap.FloorMap.egocentric`, built from
its depth frames and pose): a CHANGE OF OBSERVATION, and of what is learned. The body's steps are not learned,
so the paper's claims about backward steps and speed near cabinets cannot be read on this searcher.

:class:`ModularPolicy` is the same searcher as a per-step policy of the body env (``EgoSearch-v0``,
``EgoSearchNoHead-v0``): an actor trained in the decision env decides whenever a decision is due, with the
same observation, so an episode is the same body step for body step. Evaluation, traces, the video and the
full-body replanner run a modular actor that way.
"""

from __future__ import annotations

import copy
import math

import gymnasium
import numpy as np
from gymnasium import spaces

from egosearch.searchers.decision_envs import (
    MODULAR_MAP_CELL_SIZE,
    MODULAR_MAP_CELLS,
    MODULAR_MAP_DIM,
    check_decision_options,
    modular_decision_dim,
)
from egosearch.searchers.frontier import FrontierPolicy
from egosearch.searchers.policies import RandomPolicy
from egosearch.sim.env import MASK_FEATURE_DIM, SearchEnv


class GoalFrontierPolicy(FrontierPolicy):
    """The frontier searcher walking where a high-level decision (:meth:`decide`) points."""

    DECIDE_EVERY = 10
    """Body steps per decision at most (1.5 s of the paper's 0.15 s steps)."""
    GOAL_REACH = 3.0
    """The decision's point lies within this (m) of the body along each axis of its frame."""
    PATH_WEIGHT = 0.25
    """The chosen frontier cell minimises its distance to the decision's point plus this times its path
    length from the body: a tie-break toward cells that are cheap to reach."""
    ARRIVED = 0.3
    """The body stands at its chosen frontier within this (m): time for the next decision."""
    YAW_AMPLITUDE = (0.0, 1.2)
    """The range of the sweep's yaw amplitude (rad); the classical searcher sweeps 1.1."""
    PITCH_CENTRE = (-0.8, 0.0)
    """The range of the sweep's pitch centre (rad); the classical searcher's is -0.4."""
    PITCH_SWEEP = 0.15
    """The pitch swings this (rad) about its centre, as the classical searcher's does."""

    def reset(self, seed: int | None = None) -> None:
        super().reset(seed)
        self.goal: tuple[float, float] | None = None
        self.chosen: tuple[int, int] | None = None
        self.yaw_amplitude, self.pitch_centre = 1.1, -0.4
        self.since_decision = 0
        self._mapped = (-1, False)

    def decide(self, decision: np.ndarray) -> None:
        """Take a decision in [-1, 1] (:func:`egosearch.searchers.decision_envs.modular_decision_dim`), read in
        the body's current frame."""
        a = np.clip(np.asarray(decision, np.float64), -1.0, 1.0)
        s = self.env.state
        forward, left = a[0] * self.GOAL_REACH, a[1] * self.GOAL_REACH
        c, sn = math.cos(s.theta), math.sin(s.theta)
        self.goal = (s.x + c * forward - sn * left, s.y + sn * forward + c * left)
        if len(a) > 2:
            low, high = self.YAW_AMPLITUDE
            self.yaw_amplitude = low + (a[2] + 1) / 2 * (high - low)
            low, high = self.PITCH_CENTRE
            self.pitch_centre = low + (a[3] + 1) / 2 * (high - low)
        self.since_decision = 0
        self.last_plan = -99  # plan toward the new point at the next step

    def decision_due(self) -> bool:
        """Whether the high level decides again: never once the target is seen; else after DECIDE_EVERY
        body steps, or on arrival at the chosen frontier (after at least two steps)."""
        if self.target is not None:
            return False
        if self.since_decision >= self.DECIDE_EVERY:
            return True
        if self.since_decision < 2 or self.chosen is None:
            return False
        s = self.env.state
        x, y = self._xy(*self.chosen)
        return math.hypot(x - s.x, y - s.y) <= self.ARRIVED

    def map_feature(self, obs: dict) -> np.ndarray:
        """The high level's map: the latest frame folded in, then the egocentric squares (MODULAR_MAP_DIM values)."""
        self._map(obs)
        return self.map.egocentric(self.env.state, MODULAR_MAP_CELLS, MODULAR_MAP_CELL_SIZE)

    def _map(self, obs: dict) -> bool:
        # the frame a decision's map already holds is not folded in twice (nor its visit counted twice)
        steps = self.env.steps
        if self._mapped[0] != steps:
            self._mapped = (steps, super()._map(obs))
        return self._mapped[1]

    def choose_frontier(self, frontier: np.ndarray, dist: np.ndarray, offset: tuple[int, int]) -> tuple[int, int]:
        if self.goal is None:
            end = super().choose_frontier(frontier, dist, offset)
        else:
            rows, cols = np.nonzero(frontier)
            gr, gc = self._cell(*self.goal)
            off_goal = np.hypot(rows + offset[0] - gr, cols + offset[1] - gc) * self.RESOLUTION
            i = int(np.argmin(off_goal + self.PATH_WEIGHT * dist[rows, cols]))
            end = (int(rows[i]), int(cols[i]))
        self.chosen = (end[0] + offset[0], end[1] + offset[1])
        return end

    def scan_head(self) -> tuple[float, float]:
        pitch = self.pitch_centre + self.PITCH_SWEEP * math.sin(0.2 * self.steps)
        return pitch, self.yaw_amplitude * math.sin(0.45 * self.steps)

    def act(self, obs: dict) -> np.ndarray:
        self.since_decision += 1
        return super().act(obs)


def decision_observation(obs: dict, searcher: GoalFrontierPolicy) -> dict:
    """What the high level reads: the body env's observation with the searcher's map appended to the
    mask's features."""
    out = dict(obs)
    out["mask"] = np.concatenate([obs["mask"][:MASK_FEATURE_DIM], searcher.map_feature(obs)]).astype(np.float32)
    return out


class ModularSearchEnv(gymnasium.Env):
    """The high level of the modular searcher as an env (see the module docstring). Keywords go to the body's
    :class:`egosearch.sim.env.SearchEnv`; attributes it does not have are the body env's (the state, the
    layout, the target), so that evaluation and traces read it as they read the body env."""

    metadata = {"render_modes": []}

    def __init__(self, head: bool = True, **env_kwargs):
        check_decision_options(None, {"head": head, **env_kwargs})
        self.body_env = SearchEnv(head=head, **env_kwargs)
        self.searcher = GoalFrontierPolicy(self.body_env)
        inner = self.body_env.observation_space
        observation_spaces = dict(inner.spaces)
        observation_spaces["mask"] = spaces.Box(-4.0, 4.0, (MASK_FEATURE_DIM + MODULAR_MAP_DIM,), np.float32)
        self.observation_space = spaces.Dict(observation_spaces)
        self.action_space = spaces.Box(-1.0, 1.0, (modular_decision_dim(self.body_env.spec_agent.head),), np.float32)
        self._obs: dict | None = None

    def __getattr__(self, name: str):
        if name.startswith("_") or name == "body_env":
            raise AttributeError(name)
        return getattr(self.body_env, name)

    def _observation(self, obs: dict) -> dict:
        return decision_observation(obs, self.searcher)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        obs, info = self.body_env.reset(seed=seed, options=options)
        self.searcher.reset()
        self._obs = obs
        return self._observation(obs), info

    def step(self, action):
        self.searcher.decide(action)
        total = 0.0
        while True:
            obs, reward, terminated, truncated, info = self.body_env.step(self.searcher.act(self._obs))
            self._obs = obs
            total += float(reward)
            if terminated or truncated or self.searcher.decision_due():
                break
        info = dict(info, decision_steps=self.searcher.since_decision)
        return self._observation(obs), total, terminated, truncated, info

    def close(self):
        self.body_env.close()


class ModularPolicy:
    """A high-level actor (trained in a ``*Modular-v0`` env) with the frontier searcher walking, as a
    per-step policy of the body env (see the module docstring). ``snapshot()`` / ``restore()`` keep the
    searcher's map, plan and pending decision across the replanner's look-ahead (paper Algorithm 1); the
    high level is memoryless (the map is its memory)."""

    learns = "decisions"
    """What its policy decides (traces record it): where to explore and the head's sweep, not the body's steps."""

    def __init__(self, high_level, env):
        self.high_level = high_level
        self.searcher = GoalFrontierPolicy(env)
        self.decided = False

    def reset(self, seed: int | None = None) -> None:
        self.searcher.reset(seed)
        self.high_level.reset(seed=seed)
        self.decided = False

    def act(self, obs: dict) -> np.ndarray:
        if not self.decided or self.searcher.decision_due():
            self.searcher.decide(self.high_level.act(decision_observation(obs, self.searcher)))
            self.decided = True
        return self.searcher.act(obs)

    def snapshot(self) -> dict:
        searcher = {k: copy.deepcopy(v) for k, v in vars(self.searcher).items() if k not in ("env", "map")}
        return {"searcher": searcher, "map": self.searcher.map.copy_state(), "decided": self.decided}

    def restore(self, snap: dict) -> None:
        for k, v in snap["searcher"].items():
            setattr(self.searcher, k, copy.deepcopy(v))
        self.searcher.map.set_state(snap["map"])
        self.decided = snap["decided"]


def random_decisions(env, seed: int = 0) -> ModularPolicy:
    """The modular searcher's floor (``--policy modular_random``, ``modular_random_head_off``): its walk in the
    body env ``env``, each decision (of the head's size) drawn uniformly at random."""
    head = env.unwrapped.spec_agent.head
    return ModularPolicy(RandomPolicy(modular_decision_dim(head), seed=seed), env)

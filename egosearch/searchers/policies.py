"""Searchers that share one interface, so evaluation and the replanner never ask which they hold.

A policy has ``reset(seed=None)`` (called at the start of every episode) and
``act(obs) -> np.ndarray`` (a normalised action in [-1, 1]). The learned actor lives in
:mod:`egosearch.rl.actor` (``ActorPolicy``) and follows the same interface.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np

from egosearch.sim.body import wrap_angle
from egosearch.sim.navgrid import NavGrid
from egosearch.sim.scenarios import SUCCESS_DISTANCE, navgrid_for, success_region


class Policy(Protocol):
    def reset(self, seed: int | None = None) -> None: ...

    def act(self, obs: dict) -> np.ndarray: ...


class RandomPolicy:
    """The floor: uniform random actions."""

    def __init__(self, action_dim: int, seed: int = 0):
        self.action_dim = action_dim
        self.rng = np.random.default_rng(seed)

    def reset(self, seed: int | None = None) -> None:
        if seed is not None:
            self.rng = np.random.default_rng(seed)

    def act(self, obs: dict) -> np.ndarray:
        return self.rng.uniform(-1.0, 1.0, self.action_dim).astype(np.float32)


def random_searcher(env, seed: int = 0) -> RandomPolicy:
    """``--policy random``: uniform random actions of ``env``'s size."""
    return RandomPolicy(env.action_space.shape[0], seed=seed)


class OraclePolicy:
    """A privileged searcher that proves the task solvable: it knows the target, walks the
    geodesic shortest path to the nearest pose that sees it, and aims the camera at it.

    It reads the env's hidden state (``env.unwrapped``), which a learned policy never sees.
    """

    #: How far ahead along the path the body aims (m): smooths the grid's zig-zags.
    LOOKAHEAD = 0.35
    #: The oracle aims this far inside the success distance (m), so that a body anywhere in
    #: its goal cell is within the distance.
    GOAL_SLACK = 0.08

    def __init__(self, env):
        self.env = env.unwrapped
        self._episode_key = None

    def reset(self, seed: int | None = None) -> None:
        self._episode_key = None

    def _plan(self) -> None:
        env = self.env
        self.grid: NavGrid = navgrid_for(env.layout)
        goal = success_region(env.layout, env.target, env.base_height, SUCCESS_DISTANCE - self.GOAL_SLACK)
        if not goal.any():
            goal = success_region(env.layout, env.target, env.base_height)
        self.dist = self.grid.distances_to(goal)
        gx, gy = np.meshgrid(self.grid.xs, self.grid.ys)
        self._cells_xy = (gx, gy)

    def act(self, obs: dict) -> np.ndarray:
        env = self.env
        key = (id(env.target), env.scenario_id, env.base_height)
        if env.steps == 0 or key != self._episode_key:
            self._plan()
            self._episode_key = key
        s, spec, target = env.state, env.spec_agent, env.target
        wx, wy = self._waypoint(s.x, s.y)
        to_target = math.atan2(target.center[1] - s.y, target.center[0] - s.x)
        arrived = (wx, wy) == (s.x, s.y)
        if arrived or not spec.head and math.hypot(wx - s.x, wy - s.y) < 0.6:
            heading = to_target
        else:
            heading = math.atan2(wy - s.y, wx - s.x)
        dtheta = float(np.clip(wrap_angle(heading - s.theta), -spec.max_turn, spec.max_turn))
        theta = s.theta + dtheta
        # The env moves the body in its frame at the start of the step, then turns it.
        ddx, ddy = wx - s.x, wy - s.y
        c, sn = math.cos(s.theta), math.sin(s.theta)
        dx, dy = c * ddx + sn * ddy, -sn * ddx + c * ddy
        dx = float(np.clip(dx, -spec.max_forward, spec.max_forward))
        dy = float(np.clip(dy, -spec.max_lateral, spec.max_lateral))
        action = [dx / spec.max_forward, dy / spec.max_lateral, dtheta / spec.max_turn]
        if spec.head:
            nx, ny = s.x + c * dx - sn * dy, s.y + sn * dx + c * dy
            look = math.atan2(target.center[1] - ny, target.center[0] - nx)
            want_yaw = float(np.clip(wrap_angle(look - theta), *spec.yaw_limits))
            horizontal = math.hypot(target.center[0] - nx, target.center[1] - ny)
            want_pitch = math.atan2(target.center[2] - s.camera_height, horizontal)
            want_pitch = float(np.clip(want_pitch, *spec.pitch_limits))
            action += [(want_pitch - s.pitch) / spec.max_pitch_rate, (want_yaw - s.head_yaw) / spec.max_yaw_rate]
        return np.clip(np.asarray(action, dtype=np.float32), -1.0, 1.0)

    def _waypoint(self, x: float, y: float) -> tuple[float, float]:
        """The cell within LOOKAHEAD of (x, y), reachable in a straight free line, that is
        geodesically nearest the goal."""
        row, col = self.grid.cell(x, y)
        if self.dist[row, col] == 0:
            return (x, y)
        k = int(math.ceil(self.LOOKAHEAD / self.grid.resolution))
        r0, r1 = max(0, row - k), min(self.grid.shape[0], row + k + 1)
        c0, c1 = max(0, col - k), min(self.grid.shape[1], col + k + 1)
        gx, gy = self._cells_xy
        window = self.dist[r0:r1, c0:c1].copy()
        far = (gx[r0:r1, c0:c1] - x) ** 2 + (gy[r0:r1, c0:c1] - y) ** 2 > self.LOOKAHEAD ** 2
        window[far] = np.inf
        for flat in np.argsort(window, axis=None):
            i, j = np.unravel_index(int(flat), window.shape)
            if not np.isfinite(window[i, j]):
                break
            wx, wy = self.grid.center(r0 + i, c0 + j)
            if self._line_free(x, y, wx, wy):
                return (wx, wy)
        return (x, y)

    def _line_free(self, x0: float, y0: float, x1: float, y1: float) -> bool:
        length = math.hypot(x1 - x0, y1 - y0)
        n = max(2, int(length / (self.grid.resolution / 2)) + 1)
        # The grid's clearance is a lower bound: a body may stand where its cell reads blocked.
        # Then the first few centimetres of any way out are ignored.
        skip = 0.0 if self.grid.is_free(x0, y0) else 2 * self.grid.resolution
        return all(self.grid.is_free(x0 + t * (x1 - x0), y0 + t * (y1 - y0))
                   for t in np.linspace(0, 1, n)[1:] if t * length >= skip)

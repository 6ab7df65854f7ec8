"""A classical searcher from the actor's observation: frontier exploration (Yamauchi 1997).

It sees what the learned actor sees (the depth frames and the target mask) plus its own pose, as
habitat's GPS+compass sensor gives it (``env.unwrapped.state``: position, heading, head angles and
camera height; never the target, the home's plan or its free space). From the latest depth frame
it maps the floor into free, occupied and unknown 0.1 m cells, walks to the nearest reachable
frontier (a free cell next to unknown ones), scans with its head while it walks, and once the mask
shows the target it remembers where it is (from the depth under the mask) and walks there while
looking at it. It is a reference, never a tuning target: the learned searcher's headroom.

``head=False`` holds the camera fixed (the head-off body): the searcher must turn its body to look.

``memory_window=K`` holds the searcher to its last K steps (the memory-window measurement,
docs/baselines.md#how-much-memory-the-task-asks-for): its map is the one its last K depth frames build
(:class:`egosearch.sim.floormap.WindowedFloorMap`), and what it noted about places (cells found blocked; the
tuned searcher's reached frontiers and tried places) is forgotten K steps after it was noted. The target's
last-seen position is kept, as a learned actor's target memory keeps it. ``None``: the whole episode.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from egosearch.sim.body import wrap_angle
from egosearch.sim.floormap import FREE, OCCUPIED, UNKNOWN, FloorMap, WindowedFloorMap
from egosearch.sim.scenarios import SUCCESS_DISTANCE
from egosearch.sim.sensor import camera_axes


class FrontierPolicy:
    """Frontier exploration and a target memory (see the module docstring)."""

    RESOLUTION = FloorMap.RESOLUTION
    INFLATE = 0.25
    """Occupied cells are grown by this (m): the body's radius and a margin."""
    LOOKAHEAD = 0.35
    """How far ahead along the path the body aims (m)."""
    REPLAN_EVERY = 3
    """Steps between path plans (and at once when something changes: the target seen, stuck)."""

    def __init__(self, env, head: bool | None = None, memory_window: int | None = None):
        self.env = env.unwrapped
        spec = self.env.spec_agent
        self.head = spec.head if head is None else bool(head) and spec.head
        if memory_window is not None and int(memory_window) < 1:
            raise ValueError(f"memory_window={memory_window}: a searcher remembers at least its latest step")
        self.memory_window = None if memory_window is None else int(memory_window)
        sensor = self.env.sensor
        self.map = (FloorMap.for_sensor(sensor) if self.memory_window is None
                    else WindowedFloorMap.for_sensor(sensor, window=self.memory_window))
        self.max_depth = sensor.max_depth
        self.focal = sensor.focal_px
        self.n = self.map.n
        self.reset()

    # -- episode ------------------------------------------------------------------------------
    def reset(self, seed: int | None = None) -> None:
        self.map.reset()
        self.target = None
        self.steps = 0
        self.path: list[tuple[int, int]] = []
        self.last_plan = -99
        self.recent: list[tuple[float, float]] = []
        self.blocked: dict[tuple[int, int], int] = {}
        """Cells found blocked (the body stuck walking into them), each with the step it was noted at."""
        self.reach = SUCCESS_DISTANCE - 0.15
        self.idle = 0

    def forgotten(self, noted_at: int) -> bool:
        """Whether what was noted at step ``noted_at`` lies outside the memory window by now."""
        return self.memory_window is not None and self.steps - noted_at >= self.memory_window

    def forget(self) -> None:
        """Drop what lies outside the memory window (nothing without one); a subclass drops its own notes too."""
        if self.memory_window is not None:
            self.blocked = {cell: at for cell, at in self.blocked.items() if not self.forgotten(at)}

    @property
    def grid(self) -> np.ndarray:
        return self.map.grid

    def _cell(self, x: float, y: float) -> tuple[int, int]:
        return self.map.cell(x, y)

    def _xy(self, row: int, col: int) -> tuple[float, float]:
        return self.map.xy(row, col)

    # -- mapping ------------------------------------------------------------------------------
    def _map(self, obs: dict) -> bool:
        """Fold the latest depth frame into the map; True when the target is in view."""
        s = self.env.state
        self.map.update(obs["depth"][-1], s)
        axes = camera_axes(s.camera_yaw, s.pitch)
        cam = np.array(s.camera_position)
        feature = np.asarray(obs["mask"])
        seen = bool(feature[29] > 0.5)
        if seen:  # the mask feature's centroid, at the depth of the frame there (the target is nearest)
            frame = obs["depth"][-1]
            h, w = frame.shape
            col = int(np.clip((feature[0] + 1) / 2 * w, 0, w - 1))
            row = int(np.clip((1 - feature[1]) / 2 * h, 0, h - 1))
            z = float(frame[row, col]) / 255.0 * self.max_depth
            ray = np.array([feature[0] * (w / 2) / self.focal, feature[1] * (h / 2) / self.focal, 1.0])
            self.target = cam + axes.T @ (ray * z)
        return seen

    # -- planning -----------------------------------------------------------------------------
    def _window(self, start: tuple[int, int]) -> tuple[slice, slice]:
        """The known part of the map (and the body's cell), with a margin: planning never looks further."""
        rows, cols = np.nonzero(self.grid != UNKNOWN)
        r0, r1 = min(rows.min(), start[0]) - 3, max(rows.max(), start[0]) + 4
        c0, c1 = min(cols.min(), start[1]) - 3, max(cols.max(), start[1]) + 4
        return slice(max(0, r0), min(self.n, r1)), slice(max(0, c0), min(self.n, c1))

    def _traversable(self, grid: np.ndarray, offset: tuple[int, int], start: tuple[int, int],
                     optimistic: bool) -> np.ndarray:
        """Cells the body may cross: free (or, ``optimistic``, not yet seen) and clear of obstacles by
        INFLATE; around the body's own cell every cell not seen occupied, so that a body that slid
        close to an obstacle can always leave it."""
        occupied = grid == OCCUPIED
        for r, c in self.blocked:
            if 0 <= r - offset[0] < grid.shape[0] and 0 <= c - offset[1] < grid.shape[1]:
                occupied[r - offset[0], c - offset[1]] = True
        clearance = ndimage.distance_transform_edt(~occupied) * self.RESOLUTION
        open_ = (grid != OCCUPIED) if optimistic else (grid == FREE)
        out = open_ & (clearance > self.INFLATE)
        k = 3
        r0, c0 = max(0, start[0] - k), max(0, start[1] - k)
        out[r0:start[0] + k + 1, c0:start[1] + k + 1] |= ~occupied[r0:start[0] + k + 1, c0:start[1] + k + 1] & (
            clearance[r0:start[0] + k + 1, c0:start[1] + k + 1] > self.RESOLUTION)
        return out

    @staticmethod
    def _distances(free: np.ndarray, start: tuple[int, int], resolution: float) -> np.ndarray:
        """Path length (m) from ``start`` to every traversable cell (8-connected), inf elsewhere."""
        free = free.copy()
        free[start] = True  # the body stands where it stands, whatever the inflated map says
        rows, cols = np.nonzero(free)
        index = -np.ones(free.shape, np.int64)
        index[rows, cols] = np.arange(len(rows))
        src, dst, w = [], [], []
        for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1)):
            r2, c2 = rows + dr, cols + dc
            ok = (r2 >= 0) & (r2 < free.shape[0]) & (c2 >= 0) & (c2 < free.shape[1])
            ok[ok] = free[r2[ok], c2[ok]]
            src.append(index[rows[ok], cols[ok]])
            dst.append(index[r2[ok], c2[ok]])
            w.append(np.full(int(ok.sum()), math.hypot(dr, dc) * resolution))
        graph = csr_matrix((np.concatenate(w), (np.concatenate(src), np.concatenate(dst))),
                           shape=(len(rows), len(rows)))
        d = dijkstra(graph, directed=False, indices=int(index[start]))
        out = np.full(free.shape, np.inf)
        out[rows, cols] = d
        return out

    def _plan(self, start: tuple[int, int]) -> None:
        rs, cs = self._window(start)
        grid, offset = self.grid[rs, cs], (rs.start, cs.start)
        local = (start[0] - offset[0], start[1] - offset[1])
        # toward a target seen, cells not seen yet are crossed too (they are most often floor)
        free = self._traversable(grid, offset, local, optimistic=self.target is not None)
        dist = self._distances(free, local, self.RESOLUTION)
        if self.target is not None:
            rr, cc = np.mgrid[rs, cs]
            ox, oy = self.map.origin
            xs = ox + (cc - self.n // 2 + 0.5) * self.RESOLUTION
            ys = oy + (rr - self.n // 2 + 0.5) * self.RESOLUTION
            near = np.hypot(xs - self.target[0], ys - self.target[1]) - self.env.spec_agent.body_radius
            end = self.choose_approach(near, dist, offset)
        else:
            next_to_unknown = ndimage.binary_dilation(grid == UNKNOWN, structure=np.ones((3, 3), bool))
            goal = np.isfinite(dist) & next_to_unknown & (dist >= 0.5)
            end = self.choose_frontier(goal, dist, offset) if goal.any() else None
        if end is None:
            self.path = []
            return
        # walk back down the distance field from the goal to the start
        path = [tuple(int(v) for v in end)]
        while path[-1] != local:
            r, c = path[-1]
            best, best_d = None, dist[r, c]
            for dr in (-1, 0, 1):
                for dc in (-1, 0, 1):
                    r2, c2 = r + dr, c + dc
                    if ((dr or dc) and 0 <= r2 < dist.shape[0] and 0 <= c2 < dist.shape[1]
                            and dist[r2, c2] < best_d):
                        best, best_d = (r2, c2), dist[r2, c2]
            if best is None:
                break
            path.append(best)
        self.path = [(r + offset[0], c + offset[1]) for r, c in path[::-1]]

    def choose_frontier(self, frontier: np.ndarray, dist: np.ndarray, offset: tuple[int, int]) -> tuple[int, int]:
        """Where to explore next: a cell of ``frontier`` (free, reachable, next to unknown cells, at least
        0.5 m away) of the planning window whose top-left map cell is ``offset``; ``dist`` is the path
        length (m) to each cell. This searcher takes the nearest by path; a searcher that learns where to
        go overrides only this choice and keeps the mapping, planning and walking."""
        return np.unravel_index(int(np.argmin(np.where(frontier, dist, np.inf))), dist.shape)

    def choose_approach(self, near: np.ndarray, dist: np.ndarray, offset: tuple[int, int]) -> tuple[int, int] | None:
        """Where to walk once the target is seen: a cell of the planning window whose top-left map cell is
        ``offset``; ``near`` is each cell's distance (m) from the body's surface to the target's estimate,
        ``dist`` the path length (m) to it (inf where unreachable); None: nowhere to go. This searcher takes
        the nearest by path of the cells from which the target is well within reach (``near <= self.reach``),
        and while none is reachable the cell that gets as near as the map allows."""
        goal = np.isfinite(dist) & (near <= self.reach)
        if not goal.any():
            score = np.where(np.isfinite(dist), near + 0.1 * dist, np.inf)
            if not np.isfinite(score).any():
                return None
            goal = score == score.min()
        return np.unravel_index(int(np.argmin(np.where(goal, dist, np.inf))), dist.shape)

    def target_not_in_view(self) -> None:
        """Called when the body has stood at the place it walked to for the target for 3 steps without seeing
        it: this searcher takes the estimate to be off and goes closer (down to 0.1 m)."""
        self.reach = max(0.1, self.reach - 0.1)

    def scan_head(self) -> tuple[float, float]:
        """Where the head looks (pitch, yaw in rad) while no target is known: this searcher sweeps the yaw
        across the view and the pitch between far and near surfaces; a searcher that learns how to move its
        head overrides only this."""
        return -0.25 - 0.3 * (1 + math.sin(0.2 * self.steps)) / 2, 1.1 * math.sin(0.45 * self.steps)

    # -- acting -------------------------------------------------------------------------------
    def act(self, obs: dict) -> np.ndarray:
        env, s, spec = self.env, self.env.state, self.env.spec_agent
        if env.steps == 0 and self.steps:
            self.reset()
        self.forget()
        seen = self._map(obs)
        start = self._cell(s.x, s.y)
        self.recent = (self.recent + [(s.x, s.y)])[-6:]
        stuck = len(self.recent) == 6 and math.hypot(self.recent[0][0] - s.x, self.recent[0][1] - s.y) < 0.05
        if stuck and self.path:  # something the map missed: block the cell ahead
            ahead = self.path[min(3, len(self.path) - 1)]
            self.blocked[ahead] = self.steps
            self.recent = []
        if (self.steps - self.last_plan >= self.REPLAN_EVERY or seen or stuck or not self.path
                or start not in self.path):
            self._plan(start)
            self.last_plan = self.steps
        if start in self.path:
            self.path = self.path[self.path.index(start):]
        self.steps += 1

        wx, wy = s.x, s.y
        for cell in self.path[1:]:
            x, y = self._xy(*cell)
            if math.hypot(x - s.x, y - s.y) > self.LOOKAHEAD:
                break
            wx, wy = x, y
        if self.target is not None:
            to_target = math.atan2(self.target[1] - s.y, self.target[0] - s.x)
        else:
            to_target = None
        if (wx, wy) == (s.x, s.y):
            # nowhere to go: turn toward the target, or turn to look around
            heading = to_target if to_target is not None else s.theta + spec.max_turn
            self.idle += 1
            if self.target is not None and self.idle >= 3 and not seen:
                self.target_not_in_view()
                self.idle = 0
                self.last_plan = -99
        elif to_target is not None and not self.head and math.hypot(wx - s.x, wy - s.y) < 0.2:
            heading = to_target
        else:
            heading = math.atan2(wy - s.y, wx - s.x)
        dtheta = float(np.clip(wrap_angle(heading - s.theta), -spec.max_turn, spec.max_turn))
        c, sn = math.cos(s.theta), math.sin(s.theta)
        ddx, ddy = wx - s.x, wy - s.y
        dx = float(np.clip(c * ddx + sn * ddy, -spec.max_forward, spec.max_forward))
        dy = float(np.clip(-sn * ddx + c * ddy, -spec.max_lateral, spec.max_lateral))
        action = [dx / spec.max_forward, dy / spec.max_lateral, dtheta / spec.max_turn]
        if spec.head:
            if not self.head:
                want_pitch, want_yaw = s.pitch, s.head_yaw
            elif self.target is not None:
                theta = s.theta + dtheta
                look = math.atan2(self.target[1] - s.y, self.target[0] - s.x)
                want_yaw = float(np.clip(wrap_angle(look - theta), *spec.yaw_limits))
                horizontal = math.hypot(self.target[0] - s.x, self.target[1] - s.y)
                want_pitch = math.atan2(self.target[2] - s.camera_height, max(horizontal, 0.1))
            else:
                want_pitch, want_yaw = self.scan_head()
            want_pitch = float(np.clip(want_pitch, *spec.pitch_limits))
            action += [(want_pitch - s.pitch) / spec.max_pitch_rate, (want_yaw - s.head_yaw) / spec.max_yaw_rate]
        return np.clip(np.asarray(action, dtype=np.float32), -1.0, 1.0)

"""A top-down map of the floor built from depth frames and the body's own pose.

Cells are unknown, free or occupied (0.1 m). Each depth frame marks the floor it sees, and the
floor along each ray up to what it hits, as free, and every point at a body's height
(``OBSTACLE_BAND``) as occupied; occupied is never overwritten by free. The map also counts the
steps the body spent in each cell. The classical frontier searcher plans on it
(:mod:`egosearch.searchers.frontier`); the env's ``floor_map`` option summarises it around the body for a
learned actor (:meth:`FloorMap.egocentric`).

It reads the pose as habitat's GPS+compass sensor gives it (position, heading, head angles and
camera height), never the home's plan.

:class:`WindowedFloorMap` is the same map held to the last K frames (a searcher's ``memory_window``): it equals
a map built afresh from those frames alone, at the cost of one frame added and one taken away per step.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from egosearch.sim.sensor import camera_axes, pixel_rays_camera

UNKNOWN, FREE, OCCUPIED = 0, 1, 2


class FloorMap:
    RESOLUTION = 0.1
    """Cell side (m)."""
    EXTENT = 32.0
    """Map side (m), centred on the first pose: larger than any home, so the home's size is not told."""
    OBSTACLE_BAND = (0.08, 1.8)
    """Heights (m) at which a depth point is an obstacle for the body (the floor is below)."""
    FREE_REACH = 3.0
    """A ray that hits nothing marks the floor free this far along its track (m)."""
    def __init__(self, width: int, height: int, fov_deg: float, max_depth: float, pixel_stride: int = 3,
                 free_step: float = 0.1):
        """``pixel_stride``: every this many pixels of a depth frame are mapped; ``free_step`` (m): the
        spacing of the free samples along each ray's track (coarser is cheaper, and leaves gaps)."""
        rays = pixel_rays_camera(width, height, fov_deg)
        s = self.pixel_stride = int(pixel_stride)
        self.free_step = float(free_step)
        self._rays = rays[s // 2::s, s // 2::s].reshape(-1, 3)
        self._pix = (slice(s // 2, None, s), slice(s // 2, None, s))
        self.max_depth = float(max_depth)
        self.n = int(round(self.EXTENT / self.RESOLUTION))
        self.reset()

    @classmethod
    def for_sensor(cls, sensor, **kwargs) -> FloorMap:
        return cls(sensor.width, sensor.height, sensor.fov_deg, sensor.max_depth, **kwargs)

    def reset(self) -> None:
        self.grid = np.zeros((self.n, self.n), np.uint8)
        self.visits = np.zeros((self.n, self.n), np.uint16)
        self.origin: tuple[float, float] | None = None

    def copy_state(self) -> tuple:
        return (self.grid.copy(), self.visits.copy(), self.origin)

    def set_state(self, state: tuple) -> None:
        grid, visits, self.origin = state
        self.grid, self.visits = grid.copy(), visits.copy()

    # -- cells ----------------------------------------------------------------------------------
    def cell(self, x: float, y: float) -> tuple[int, int]:
        ox, oy = self.origin
        return (int(math.floor((y - oy) / self.RESOLUTION)) + self.n // 2,
                int(math.floor((x - ox) / self.RESOLUTION)) + self.n // 2)

    def xy(self, row: int, col: int) -> tuple[float, float]:
        ox, oy = self.origin
        return (ox + (col - self.n // 2 + 0.5) * self.RESOLUTION, oy + (row - self.n // 2 + 0.5) * self.RESOLUTION)

    def _indices(self, xs: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        ox, oy = self.origin
        rows = np.floor((np.asarray(ys) - oy) / self.RESOLUTION).astype(int) + self.n // 2
        cols = np.floor((np.asarray(xs) - ox) / self.RESOLUTION).astype(int) + self.n // 2
        ok = (rows >= 0) & (rows < self.n) & (cols >= 0) & (cols < self.n)
        return rows[ok], cols[ok]

    def mark(self, xs: np.ndarray, ys: np.ndarray, value: int) -> None:
        rows, cols = self._indices(xs, ys)
        if value == OCCUPIED:
            self.grid[rows, cols] = OCCUPIED
        else:  # free never overwrites an obstacle seen before
            self.grid[rows, cols] = np.where(self.grid[rows, cols] == OCCUPIED, OCCUPIED, FREE)

    # -- updates --------------------------------------------------------------------------------
    def update(self, depth_frame: np.ndarray, state) -> None:
        """Fold one uint8 depth frame (as the env renders it) seen from ``state`` into the map, and count
        the body's cell as visited."""
        if self.origin is None:
            self.origin = (state.x, state.y)
        depth = depth_frame[self._pix].reshape(-1).astype(np.float64) / 255.0 * self.max_depth
        axes = camera_axes(state.camera_yaw, state.pitch)
        cam = np.array(state.camera_position)
        points = cam + (self._rays * depth[:, None]) @ axes
        hit = depth < self.max_depth * 0.99
        reach = np.where(hit, np.hypot(points[:, 0] - cam[0], points[:, 1] - cam[1]), self.FREE_REACH)
        direction = np.arctan2(points[:, 1] - cam[1], points[:, 0] - cam[0])
        ts = np.arange(0.0, self.FREE_REACH, self.free_step)
        rays_i, steps_i = np.nonzero(ts[None, :] < reach[:, None] - self.RESOLUTION)
        self.mark(cam[0] + ts[steps_i] * np.cos(direction[rays_i]), cam[1] + ts[steps_i] * np.sin(direction[rays_i]),
                  FREE)
        low, high = self.OBSTACLE_BAND
        obstacle = hit & (points[:, 2] > low) & (points[:, 2] < high)
        self.mark(points[obstacle, 0], points[obstacle, 1], OCCUPIED)
        floor = hit & (points[:, 2] <= low)
        self.mark(points[floor, 0], points[floor, 1], FREE)
        rows, cols = self._indices(np.array([state.x]), np.array([state.y]))
        self.visits[rows, cols] = np.minimum(self.visits[rows, cols] + 1, 60_000)

    # -- a learned actor's view -------------------------------------------------------------------
    def egocentric(self, state, cells: int = 7, cell_size: float = 0.6) -> np.ndarray:
        """A ``cells`` x ``cells`` grid of ``cell_size`` m squares around the body, rotated with it
        (row 0 ahead, column 0 to the left), three channels in [0, 1]: the share of floor seen, the
        share seen occupied, and whether the body has stood there. Flattened: (3 * cells**2,)."""
        k = max(1, int(round(cell_size / self.RESOLUTION)))
        half = cells * k / 2
        # sample points: the centres of the map cells inside each egocentric square, in the body frame
        offs = (np.arange(cells * k) + 0.5) - half
        fwd = -offs * self.RESOLUTION  # row 0 = farthest ahead
        left = -offs * self.RESOLUTION  # column 0 = farthest left
        f, lft = np.meshgrid(fwd, left, indexing="ij")
        c, s = math.cos(state.theta), math.sin(state.theta)
        xs = state.x + c * f - s * lft
        ys = state.y + s * f + c * lft
        ox, oy = self.origin
        rows = np.floor((ys - oy) / self.RESOLUTION).astype(int) + self.n // 2
        cols = np.floor((xs - ox) / self.RESOLUTION).astype(int) + self.n // 2
        inside = (rows >= 0) & (rows < self.n) & (cols >= 0) & (cols < self.n)
        rows, cols = np.clip(rows, 0, self.n - 1), np.clip(cols, 0, self.n - 1)
        grid = np.where(inside, self.grid[rows, cols], UNKNOWN)
        visited = np.where(inside, self.visits[rows, cols] > 0, False)
        blocks = np.stack([grid != UNKNOWN, grid == OCCUPIED, visited]).astype(np.float32)
        blocks = blocks.reshape(3, cells, k, cells, k)
        out = blocks.mean(axis=(2, 4))
        out[2] = blocks[2].max(axis=(1, 3))  # stood anywhere in the square
        return out.reshape(-1)


class WindowedFloorMap(FloorMap):
    """A :class:`FloorMap` that remembers only its last ``window`` frames: after each :meth:`update` its grid and
    visit counts are those a fresh map (with the same origin) would hold after those frames alone. Each cell
    counts how many kept frames saw it free and how many occupied; the oldest frame's marks are taken away as
    the newest's are added, so a step costs one frame's marks twice, whatever the window."""

    def __init__(self, *args, window: int, **kwargs):
        if int(window) < 1:
            raise ValueError(f"window={window}: a map remembers at least its latest frame")
        self.window = int(window)
        super().__init__(*args, **kwargs)

    def reset(self) -> None:
        super().reset()
        self.free_count = np.zeros((self.n, self.n), np.uint16)
        self.occupied_count = np.zeros((self.n, self.n), np.uint16)
        self.frames: deque[tuple[np.ndarray, np.ndarray, np.ndarray]] = deque()
        self._marks: dict[int, list[np.ndarray]] | None = None

    def copy_state(self) -> tuple:
        frames = tuple(tuple(a.copy() for a in f) for f in self.frames)
        return super().copy_state() + (self.free_count.copy(), self.occupied_count.copy(), frames)

    def set_state(self, state: tuple) -> None:
        super().set_state(state[:3])
        free, occupied, frames = state[3:]
        self.free_count, self.occupied_count = free.copy(), occupied.copy()
        self.frames = deque(tuple(a.copy() for a in f) for f in frames)

    def mark(self, xs: np.ndarray, ys: np.ndarray, value: int) -> None:
        rows, cols = self._indices(xs, ys)
        self._marks[value].append(np.unique(rows * self.n + cols))

    def update(self, depth_frame: np.ndarray, state) -> None:
        self._marks = {FREE: [], OCCUPIED: []}
        before = self.visits.copy() if self.origin is not None else None
        super().update(depth_frame, state)
        free = np.unique(np.concatenate(self._marks[FREE])) if self._marks[FREE] else np.zeros(0, np.int64)
        occupied = (np.unique(np.concatenate(self._marks[OCCUPIED])) if self._marks[OCCUPIED]
                    else np.zeros(0, np.int64))
        visited = np.flatnonzero(self.visits != before) if before is not None else np.flatnonzero(self.visits)
        self._marks = None
        self.free_count.flat[free] += 1
        self.occupied_count.flat[occupied] += 1
        self.frames.append((free, occupied, visited))
        touched = [free, occupied]
        if len(self.frames) > self.window:
            old_free, old_occupied, old_visited = self.frames.popleft()
            self.free_count.flat[old_free] -= 1
            self.occupied_count.flat[old_occupied] -= 1
            self.visits.flat[old_visited] -= 1
            touched += [old_free, old_occupied]
        cells = np.concatenate(touched)
        occ, fr = self.occupied_count.flat[cells] > 0, self.free_count.flat[cells] > 0
        self.grid.flat[cells] = np.where(occ, OCCUPIED, np.where(fr, FREE, UNKNOWN))

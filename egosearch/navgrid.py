"""Navigation grid of a home at the body radius, and geodesic shortest paths.

The ℓ of SPL (paper 6.4) is the geodesic length from the start to the nearest body position
that satisfies the success distance. Paths run on a 16-connected grid (the 8 king moves plus
the 8 knight moves), whose lengths overestimate the true Euclidean geodesic by at most 2.7%
(the 8-connected grid's error is 8.2%); scipy's Dijkstra computes them exactly on the graph.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from egosearch.agent import AgentSpec
from egosearch.scene.parts import Part, Scene

_MOVES = [(1, 0), (0, 1), (1, 1), (1, -1), (2, 1), (1, 2), (2, -1), (1, -2)]
#: Grid cell size (m): a tenth of the body diameter.
DEFAULT_RESOLUTION = 0.05


def _rasterize(part: Part, xs: np.ndarray, ys: np.ndarray, grow: float = 0.0) -> np.ndarray:
    """Boolean mask of grid cell centres (xs: columns, ys: rows) covered by the footprint."""
    gx, gy = np.meshgrid(xs, ys)
    dx, dy = gx - part.center[0], gy - part.center[1]
    if part.shape == "cylinder":
        return dx * dx + dy * dy <= (part.size[0] / 2 + grow) ** 2
    c, s = math.cos(part.yaw), math.sin(part.yaw)
    lx, ly = c * dx + s * dy, -s * dx + c * dy
    return (np.abs(lx) <= part.size[0] / 2 + grow) & (np.abs(ly) <= part.size[1] / 2 + grow)


@dataclass
class NavGrid:
    """Where the body's centre may be, on a regular grid over the home."""

    scene: Scene
    spec: AgentSpec
    resolution: float = DEFAULT_RESOLUTION
    margin: float = 0.0
    """Extra clearance beyond the body radius (m); 0 for shortest paths, > 0 for planners."""

    def __post_init__(self) -> None:
        x0, y0, x1, y1 = self.scene.bounds
        self.xs = np.arange(x0 + self.resolution / 2, x1, self.resolution)
        self.ys = np.arange(y0 + self.resolution / 2, y1, self.resolution)
        occupied = np.zeros((len(self.ys), len(self.xs)), dtype=bool)
        half_diagonal = self.resolution * math.sqrt(0.5)
        body_lo = self.spec.body_clearance
        body_hi = self.spec.body_clearance + self.spec.body_height
        for part in self.scene.obstacles:
            if part.z_max <= body_lo or part.z_min >= body_hi:
                continue
            # Grown by half a cell diagonal so that a part thinner than a cell is never missed.
            occupied |= _rasterize(part, self.xs, self.ys, grow=half_diagonal)
        # Every point of an obstacle lies within half a diagonal of an occupied centre, so this
        # is a lower bound on the true clearance of each cell centre.
        clearance = (ndimage.distance_transform_edt(~occupied) * self.resolution) - half_diagonal
        inside = np.ones_like(occupied)
        border = int(math.ceil((self.spec.body_radius + self.margin) / self.resolution))
        inside[:border] = inside[-border:] = False
        inside[:, :border] = inside[:, -border:] = False
        self.occupied = occupied
        self.free = (clearance >= self.spec.body_radius + self.margin) & inside
        labels, count = ndimage.label(self.free, structure=np.ones((3, 3)))
        sizes = np.bincount(labels.ravel())
        sizes[0] = 0
        #: The largest connected free region: where starts may be drawn.
        self.main_region = labels == int(np.argmax(sizes)) if count else self.free

    @property
    def shape(self) -> tuple[int, int]:
        return self.free.shape

    def cell(self, x: float, y: float) -> tuple[int, int]:
        """(row, col) of the cell holding (x, y), clipped to the grid."""
        col = int(np.clip((x - self.scene.bounds[0]) / self.resolution, 0, len(self.xs) - 1))
        row = int(np.clip((y - self.scene.bounds[1]) / self.resolution, 0, len(self.ys) - 1))
        return row, col

    def center(self, row: int, col: int) -> tuple[float, float]:
        return float(self.xs[col]), float(self.ys[row])

    def is_free(self, x: float, y: float) -> bool:
        return bool(self.free[self.cell(x, y)])

    @cached_property
    def _graph(self):
        rows, cols = self.shape
        index = np.arange(rows * cols).reshape(rows, cols)
        src, dst, weight = [], [], []
        for dr, dc in _MOVES:
            length = self.resolution * math.hypot(dr, dc)
            r0, r1 = max(0, -dr), rows - max(0, dr)
            c0, c1 = max(0, -dc), cols - max(0, dc)
            a = (slice(r0, r1), slice(c0, c1))
            b = (slice(r0 + dr, r1 + dr), slice(c0 + dc, c1 + dc))
            ok = self.free[a] & self.free[b]
            if abs(dr) + abs(dc) == 3:  # a knight move must not cut a corner
                mid_r, mid_c = (dr // 2 if abs(dr) == 2 else 0), (dc // 2 if abs(dc) == 2 else 0)
                mid = (slice(r0 + mid_r, r1 + mid_r), slice(c0 + mid_c, c1 + mid_c))
                ok &= self.free[mid]
                side = (slice(r0 + dr - mid_r, r1 + dr - mid_r), slice(c0 + dc - mid_c, c1 + dc - mid_c))
                ok &= self.free[side]
            elif dr and dc:  # a diagonal must not squeeze between two blocked cells
                ok &= self.free[r0 + dr:r1 + dr, c0:c1] & self.free[r0:r1, c0 + dc:c1 + dc]
            src.append(index[a][ok])
            dst.append(index[b][ok])
            weight.append(np.full(int(ok.sum()), length))
        src, dst, weight = np.concatenate(src), np.concatenate(dst), np.concatenate(weight)
        n = rows * cols
        return coo_matrix((np.r_[weight, weight], (np.r_[src, dst], np.r_[dst, src])), shape=(n, n)).tocsr()

    def distances_to(self, goal: np.ndarray) -> np.ndarray:
        """Geodesic distance (m) of every cell to the nearest cell of the boolean ``goal``
        mask (inf where unreachable)."""
        goal = goal & self.free
        if not goal.any():
            return np.full(self.shape, np.inf)
        dist = dijkstra(self._graph, directed=False, indices=np.flatnonzero(goal), min_only=True)
        return dist.reshape(self.shape)

    def success_region(self, target_xy: tuple[float, float], success_distance: float) -> np.ndarray:
        """Free cells whose body surface is within ``success_distance`` of the target (2D)."""
        gx, gy = np.meshgrid(self.xs, self.ys)
        reach = success_distance + self.spec.body_radius
        near = (gx - target_xy[0]) ** 2 + (gy - target_xy[1]) ** 2 <= reach * reach
        return near & self.free

    def path_length(self, distances: np.ndarray, x: float, y: float) -> float:
        """Geodesic length from (x, y) given a :meth:`distances_to` field."""
        row, col = self.cell(x, y)
        cx, cy = self.center(row, col)
        return float(distances[row, col] + math.hypot(x - cx, y - cy))

"""Navigation grid of a home at the body radius, and geodesic shortest paths.

Paths run on a 16-connected grid (the 8 king moves plus the 8 knight moves), whose lengths
overestimate the true Euclidean geodesic by at most 2.7% (the 8-connected grid's error is
8.2%); scipy's Dijkstra computes them exactly on the graph.

Two sets of cells, for two jobs:
- ``free``: cells whose centre surely clears the home by the body radius (plus ``margin``). A
  planner that keeps to them never touches anything; starts are drawn from them.
- ``reachable``: every cell that holds *some* position where the env can leave the body, which
  may be in contact with furniture and up to :data:`MAX_PENETRATION` inside it. The ℓ of SPL
  (paper 6.4) runs on these, so that it is a lower bound on the path of every success, up to the
  grid tolerance :data:`LOWER_BOUND_SLACK` (a bound measured on ``free`` alone can exceed the
  path of a body that succeeds while touching the table its target rests on).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from egosearch.scene.parts import Part, Scene
from egosearch.sim.body import AgentSpec

_MOVES = [(1, 0), (0, 1), (1, 1), (1, -1), (2, 1), (1, 2), (2, -1), (1, -2)]
#: Grid cell size (m): a tenth of the body diameter.
DEFAULT_RESOLUTION = 0.05
#: The deepest the env may leave the body inside an obstacle after a step (m): the rule that
#: egosearch.sim.world enforces (this module must not import the physics engine).
MAX_PENETRATION = 0.01
#: ℓ's guarantee: the path p of any success satisfies p >= (ℓ - additive) / (1 + relative).
#: relative: the 16-connected grid's 2.7% excess over a straight line; additive: the start
#: and the end snapped to their cell centres (half a cell diagonal each, 7 cm in all) and a
#: centimetre of grid zig-zag round furniture corners.
LOWER_BOUND_SLACK = {"relative": 0.03, "additive": 0.08}


def lower_bound_holds(shortest_path: float, path_length: float) -> bool:
    """Whether a success with this travelled path respects ℓ's guarantee."""
    return path_length * (1 + LOWER_BOUND_SLACK["relative"]) + LOWER_BOUND_SLACK["additive"] >= shortest_path


def _rasterize(part: Part, xs: np.ndarray, ys: np.ndarray, grow: float = 0.0) -> np.ndarray:
    """Boolean mask of grid cell centres (xs: columns, ys: rows) covered by the footprint."""
    gx, gy = np.meshgrid(xs, ys)
    dx, dy = gx - part.center[0], gy - part.center[1]
    if part.shape == "cylinder":
        return dx * dx + dy * dy <= (part.size[0] / 2 + grow) ** 2
    c, s = math.cos(part.yaw), math.sin(part.yaw)
    lx, ly = c * dx + s * dy, -s * dx + c * dy
    return (np.abs(lx) <= part.size[0] / 2 + grow) & (np.abs(ly) <= part.size[1] / 2 + grow)


def footprint_distance(part: Part, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Exact signed horizontal distance (m) from each point (x, y) to the part's footprint,
    negative inside it."""
    dx, dy = x - part.center[0], y - part.center[1]
    if part.shape == "cylinder":
        return np.hypot(dx, dy) - part.size[0] / 2
    c, s = math.cos(part.yaw), math.sin(part.yaw)
    qx = np.abs(c * dx + s * dy) - part.size[0] / 2
    qy = np.abs(-s * dx + c * dy) - part.size[1] / 2
    return np.hypot(np.maximum(qx, 0.0), np.maximum(qy, 0.0)) + np.minimum(np.maximum(qx, qy), 0.0)


#: Samples per cell side when deciding whether a cell holds a reachable point: the decision is
#: then loose by half a sample's diagonal (7 mm), not half a cell's (35 mm), which would open
#: gaps 7 cm narrower than the body to ℓ.
_REACH_SAMPLES = 5


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
        self.clearance = self._clearance(*np.meshgrid(self.xs, self.ys))
        """Exact horizontal clearance (m) of each cell centre from the home's obstacles."""
        self.reachable = self._reachable_cells()

    def _clearance(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Exact horizontal distance (m) from each point to the obstacles the body can hit. A part
        that overlaps the body's height by no more than MAX_PENETRATION can be pushed into sideways
        without limit, so it is no obstacle here."""
        body_lo = self.spec.body_clearance
        body_hi = body_lo + self.spec.body_height
        out = np.full(np.shape(x), np.inf)
        for part in self.scene.obstacles:
            if min(body_hi, part.z_max) - max(body_lo, part.z_min) > MAX_PENETRATION:
                out = np.minimum(out, footprint_distance(part, x, y))
        return out

    def _reachable_cells(self) -> np.ndarray:
        """Cells holding at least one point where the env may leave the body's centre (clearance
        >= radius - MAX_PENETRATION). Distances are 1-Lipschitz, so a cell whose centre is farther
        than half a diagonal from deciding is decided by its centre; the others by sub-samples."""
        need = self.spec.body_radius - MAX_PENETRATION
        half_diagonal = self.resolution * math.sqrt(0.5)
        reachable = self.clearance >= need
        rows, cols = np.nonzero(~reachable & (self.clearance >= need - half_diagonal))
        if len(rows):
            k = _REACH_SAMPLES
            offsets = ((np.arange(k) + 0.5) / k - 0.5) * self.resolution
            ox, oy = (o.ravel() for o in np.meshgrid(offsets, offsets))
            x = self.xs[cols][:, None] + ox[None, :]
            y = self.ys[rows][:, None] + oy[None, :]
            best = self._clearance(x, y).max(axis=1)
            reachable[rows, cols] = best >= need - half_diagonal / k
        return reachable

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
        return self._graph_on(self.free)

    @cached_property
    def _reachable_graph(self):
        return self._graph_on(self.reachable)

    def _graph_on(self, cells: np.ndarray):
        rows, cols = self.shape
        index = np.arange(rows * cols).reshape(rows, cols)
        src, dst, weight = [], [], []
        for dr, dc in _MOVES:
            length = self.resolution * math.hypot(dr, dc)
            r0, r1 = max(0, -dr), rows - max(0, dr)
            c0, c1 = max(0, -dc), cols - max(0, dc)
            a = (slice(r0, r1), slice(c0, c1))
            b = (slice(r0 + dr, r1 + dr), slice(c0 + dc, c1 + dc))
            ok = cells[a] & cells[b]
            if abs(dr) + abs(dc) == 3:  # a knight move must not cut a corner
                mid_r, mid_c = (dr // 2 if abs(dr) == 2 else 0), (dc // 2 if abs(dc) == 2 else 0)
                mid = (slice(r0 + mid_r, r1 + mid_r), slice(c0 + mid_c, c1 + mid_c))
                ok &= cells[mid]
                side = (slice(r0 + dr - mid_r, r1 + dr - mid_r), slice(c0 + dc - mid_c, c1 + dc - mid_c))
                ok &= cells[side]
            elif dr and dc:  # a diagonal must not squeeze between two blocked cells
                ok &= cells[r0 + dr:r1 + dr, c0:c1] & cells[r0:r1, c0 + dc:c1 + dc]
            src.append(index[a][ok])
            dst.append(index[b][ok])
            weight.append(np.full(int(ok.sum()), length))
        src, dst, weight = np.concatenate(src), np.concatenate(dst), np.concatenate(weight)
        n = rows * cols
        return coo_matrix((np.r_[weight, weight], (np.r_[src, dst], np.r_[dst, src])), shape=(n, n)).tocsr()

    def distances_to(self, goal: np.ndarray, reachable: bool = False) -> np.ndarray:
        """Geodesic distance (m) of every cell to the nearest cell of the boolean ``goal``
        mask (inf where unreachable), through ``free`` cells, or with ``reachable`` through
        every cell the body can reach (the lower bound behind ℓ)."""
        cells, graph = (self.reachable, self._reachable_graph) if reachable else (self.free, self._graph)
        goal = goal & cells
        if not goal.any():
            return np.full(self.shape, np.inf)
        dist = dijkstra(graph, directed=False, indices=np.flatnonzero(goal), min_only=True)
        return dist.reshape(self.shape)

    def success_region(self, target_xy: tuple[float, float], success_distance: float) -> np.ndarray:
        """Free cells whose body surface is within ``success_distance`` of the target (2D)."""
        gx, gy = np.meshgrid(self.xs, self.ys)
        reach = success_distance + self.spec.body_radius
        near = (gx - target_xy[0]) ** 2 + (gy - target_xy[1]) ** 2 <= reach * reach
        return near & self.free

    def touch_region(self, target_xy: tuple[float, float], success_distance: float) -> np.ndarray:
        """Reachable cells holding at least one point whose body surface is within
        ``success_distance`` of the target (2D): the superset of :meth:`success_region` that ℓ
        needs."""
        gx, gy = np.meshgrid(self.xs, self.ys)
        reach = success_distance + self.spec.body_radius + self.resolution * math.sqrt(0.5)
        near = (gx - target_xy[0]) ** 2 + (gy - target_xy[1]) ** 2 <= reach * reach
        return near & self.reachable

    def lower_bound_length(self, distances: np.ndarray, x: float, y: float) -> float:
        """ℓ from (x, y) given a ``distances_to(..., reachable=True)`` field: the distance of
        the cell holding (x, y). Adding the way to its centre, as :meth:`path_length` does,
        would count up to half a cell diagonal that the body may never walk."""
        return float(distances[self.cell(x, y)])

    def path_length(self, distances: np.ndarray, x: float, y: float) -> float:
        """Geodesic length from (x, y) given a :meth:`distances_to` field."""
        row, col = self.cell(x, y)
        cx, cy = self.center(row, col)
        return float(distances[row, col] + math.hypot(x - cx, y - cy))

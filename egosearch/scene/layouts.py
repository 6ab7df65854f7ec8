"""The homes: the two layouts of the paper (Figure 4) and a seeded home generator.

- :func:`kitchen_living`: an open kitchen and a living area separated by a countertop
  (a peninsula with a bar), a dining corner and a study nook behind a partial wall; 11 x 8 m.
- :func:`bedroom_bath`: a master bedroom connected to a bathroom by a doorway; 9 x 7 m.
- :func:`random_home`: 2-3 rooms of random sizes with partition walls and doorways, furnished
  from the same vocabulary by rejection sampling against the walls.

All are plain :class:`Scene` data; :func:`get_scene` maps a name to one (the fixed layouts and
generated homes are cached: a Scene is immutable). Free space is one connected region for a
0.2 m body: doorways are >= 0.85 m wide and passages >= 0.7 m.
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Callable, Sequence

import numpy as np
from scipy import ndimage

from egosearch.scene import furniture as F
from egosearch.scene.parts import Part, Scene, SupportSurface, to_local

LAYOUT_NAMES = ("kitchen_living", "bedroom_bath")
"""The paper's two homes (Figure 4)."""
EASY_LAYOUTS = ("studio",)
"""Small homes where the target is often in view: for learning tests, not for the paper's tables."""
WALL_HEIGHT = F.WALL_HEIGHT
_ALLOWED = "kitchen_living, bedroom_bath, studio, home<seed>"
HELDOUT_HOME_SEEDS = range(900_000, 900_020)
"""The held-out split: generated homes ``home900000`` ... ``home900019``, evaluated by
``snakemake generalise``, never trained in (:mod:`egosearch.sim.home_pool` refuses a training split that
overlaps it)."""

Rect = tuple[float, float, float, float]


class _Home:
    """Accumulates parts, surfaces and room labels, then makes the Scene."""

    def __init__(self, name: str, bounds: Rect):
        self.name, self.bounds = name, bounds
        self.parts: list[Part] = []
        self.surfaces: list[SupportSurface] = []
        self.rooms: list[tuple[str, tuple[float, float]]] = []

    def add(self, built: F.Built) -> None:
        self.parts.extend(built[0])
        self.surfaces.extend(built[1])

    def room(self, label: str, floor_rect: Rect, label_xy: tuple[float, float] | None = None) -> None:
        """A room label and its floor surface (``floor/<label>``)."""
        x0, y0, x1, y1 = floor_rect
        self.surfaces.append(F.floor_surface(f"floor/{re.sub(r'[^a-z0-9]+', '_', label.lower())}", floor_rect))
        self.rooms.append((label, label_xy or (round((x0 + x1) / 2, 3), round((y0 + y1) / 2, 3))))

    def floor(self, name: str, rect: Rect) -> None:
        """A floor surface without a room label (a passage, a strip between rooms)."""
        self.surfaces.append(F.floor_surface(name, rect))

    def scene(self, extra_meta: dict | None = None) -> Scene:
        parts = F.floor_and_ceiling(self.bounds, WALL_HEIGHT) + self.parts
        meta = {"rooms": list(self.rooms)}
        meta.update(extra_meta or {})
        return Scene(self.name, tuple(parts), tuple(self.surfaces), self.bounds, WALL_HEIGHT, meta)


N, S, E, W = 0.0, math.pi, -math.pi / 2, math.pi / 2  # yaw of a piece whose back is on that wall


# ----------------------------------------------------------------------------------- kitchen + living
def _build_kitchen_living() -> Scene:
    b = (0.0, 0.0, 11.0, 8.0)
    h = _Home("kitchen_living", b)
    h.add(F.outer_walls(b))
    # A partial wall (3 m) between the dining corner and the study nook.
    h.add(F.wall("wall/study_partial", (8.4, 8.0), (8.4, 5.0), kind="partition"))

    # --- kitchen (north-west): fridge + counter along the north wall, counter along the west wall,
    # wall cabinets above both, and a peninsula with a bar facing the living area.
    h.add(F.fridge("kitchen/fridge", 0.4, 7.65, N))
    h.add(F.counter("kitchen/counter_north", 2.6, 7.7, N, width=3.6, sections=["open", "open", "closed", "open"],
                    sink_at=-0.9, cooktop_at=1.2, top_clearance=0.55))
    h.add(F.wall_cabinet("kitchen/wall_cabinet_nw", 1.5, 7.825, N, width=1.2))
    h.add(F.wall_cabinet("kitchen/wall_cabinet_ne", 3.7, 7.825, N, width=1.2))
    h.add(F.counter("kitchen/counter_west", 0.3, 5.775, W, width=3.05,
                    sections=["closed", "open", "open", "open"], top_clearance=0.55))
    h.add(F.wall_cabinet("kitchen/wall_cabinet_w", 0.175, 6.1, W, width=1.6))
    h.add(F.counter("kitchen/peninsula", 1.9, 4.475, S, width=2.6, depth=0.95, back_overhang=0.3,
                    sections=["open", "open", "open"], cabinet_color=F.LIGHT_WOOD))
    for i, sx in enumerate((1.2, 1.95, 2.7)):
        h.add(F.stool(f"kitchen/stool{i}", sx, 3.72))
    h.room("kitchen", (0.0, 4.0, 4.6, 8.0), (2.4, 6.2))

    # --- dining corner
    h.add(F.table("dining/table", 6.5, 6.1, 0.0, width=1.6, depth=0.9))
    for i, cx in enumerate((6.1, 6.9)):
        h.add(F.chair(f"dining/chair_s{i}", cx, 5.33, S))
        h.add(F.chair(f"dining/chair_n{i}", cx, 6.87, N))
    h.add(F.low_cabinet("dining/sideboard", 6.5, 7.775, N, width=1.8, depth=0.45, height=0.8, color=F.WOOD))
    h.add(F.plant("dining/plant", 5.0, 7.7))
    h.room("dining", (4.6, 4.0, 8.35, 8.0), (6.5, 4.5))

    # --- study nook (north-east, behind the partial wall)
    h.add(F.bookshelf("study/bookshelf", 9.3, 7.84, N, width=1.2))
    h.add(F.desk("study/desk", 10.65, 6.4, E, width=1.4, depth=0.7))
    h.add(F.chair("study/chair", 10.05, 6.4, W, color=F.DARK_GREY))
    h.add(F.low_cabinet("study/cabinet", 8.675, 6.0, W, width=1.2, depth=0.45, height=0.7, color=F.WHITE))
    h.add(F.floor_lamp("study/lamp", 10.7, 7.65))
    h.room("study", (8.45, 4.0, 11.0, 8.0), (9.7, 5.4))

    # --- living area (south)
    h.add(F.tv_stand("living/tv_stand", 5.5, 0.225, S, width=1.8))
    h.add(F.coffee_table("living/coffee_table", 5.5, 1.35, 0.0))
    h.add(F.sofa("living/sofa", 5.5, 2.55, N, width=2.4))
    h.add(F.round_table("living/side_table", 7.0, 2.7))
    h.add(F.armchair("living/armchair_w", 3.7, 1.4, W))
    h.add(F.armchair("living/armchair_e", 7.3, 1.4, E, color=F.FABRIC_BEIGE))
    h.add(F.bookshelf("living/bookshelf", 0.16, 1.2, W, width=1.2))
    h.add(F.low_cabinet("living/sideboard", 1.8, 0.225, S, width=1.6, depth=0.45, height=0.75))
    h.add(F.low_cabinet("living/cabinet_e", 10.775, 1.6, E, width=1.6, depth=0.45, height=0.6, n_boards=1,
                        color=F.LIGHT_WOOD))
    h.add(F.bookshelf("living/bookshelf_s", 9.1, 0.16, S, width=1.0, height=1.2, n_boards=2))
    h.add(F.armchair("living/reading_chair", 9.2, 2.1, -math.pi / 4, color=F.FABRIC_RED))
    h.add(F.floor_lamp("living/lamp", 10.7, 0.3))
    h.add(F.plant("living/plant", 10.6, 3.5))
    h.room("living", (0.0, 0.0, 11.0, 4.0), (5.5, 3.55))
    return h.scene()


# ----------------------------------------------------------------------------------- bedroom + bath
def _build_bedroom_bath() -> Scene:
    b = (0.0, 0.0, 9.0, 7.0)
    h = _Home("bedroom_bath", b)
    h.add(F.outer_walls(b))
    # The bathroom (north-east) behind two partitions; its doorway faces the bedroom.
    h.add(F.wall("wall/bath_west", (6.2, 3.15), (6.2, 7.0), gaps=[(0.35, 0.9)]))
    h.add(F.wall("wall/bath_south", (6.25, 3.2), (9.0, 3.2)))

    # A partial wall (3.8 m) closes a dressing area in the south-west corner.
    h.add(F.wall("wall/dressing_partial", (0.0, 2.6), (3.8, 2.6)))

    # --- bedroom
    h.add(F.bed("bedroom/bed", 3.0, 5.95, N, width=1.6, length=2.1))
    h.add(F.nightstand("bedroom/nightstand_l", 1.85, 6.8, N))
    h.add(F.nightstand("bedroom/nightstand_r", 4.15, 6.8, N))
    h.add(F.table("bedroom/bench", 3.0, 4.45, 0.0, width=1.2, depth=0.4, height=0.45, color=F.DARK_WOOD,
                  kind="bench"))
    h.add(F.tv_stand("bedroom/tv_stand", 2.9, 2.875, S, width=1.5))
    h.add(F.low_cabinet("bedroom/dresser", 1.0, 2.875, S, width=1.4, depth=0.45, height=0.8, color=F.LIGHT_WOOD))
    h.add(F.bookshelf("bedroom/bookshelf", 0.16, 4.4, W, width=1.0))
    h.add(F.armchair("bedroom/armchair_w", 0.6, 5.7, W, color=F.FABRIC_RED))
    h.add(F.desk("bedroom/desk", 4.9, 0.3, S, width=1.2))
    h.add(F.chair("bedroom/desk_chair", 4.9, 0.88, N, color=F.DARK_GREY))
    h.add(F.plant("bedroom/plant", 5.8, 2.3))
    h.room("bedroom", (0.0, 2.65, 6.15, 7.0), (3.0, 3.75))
    h.floor("floor/bedroom_south", (3.8, 0.0, 6.15, 2.65))

    # --- dressing area
    h.add(F.wardrobe("dressing/wardrobe", 1.4, 0.3, S, width=2.0))
    h.add(F.low_cabinet("dressing/shoe_cabinet", 1.3, 2.375, N, width=1.4, depth=0.35, height=0.5, n_boards=0,
                        color=F.WHITE, kind="shoe_cabinet"))
    h.add(F.shelf_unit("dressing/shelf", 0.16, 1.35, W, width=0.8, depth=0.32, height=1.5))
    h.add(F.low_cabinet("dressing/cabinet", 3.15, 0.225, S, width=0.9, depth=0.45, height=0.9, n_boards=2,
                        color=F.LIGHT_WOOD))
    h.room("dressing", (0.0, 0.0, 3.8, 2.55), (2.1, 1.35))

    # --- sitting corner (south-east of the bedroom)
    h.add(F.armchair("bedroom/armchair", 7.3, 1.5, E, color=F.FABRIC_BEIGE))
    h.add(F.round_table("bedroom/side_table", 7.4, 2.35, diameter=0.45))
    h.add(F.low_cabinet("bedroom/cabinet_e", 8.775, 1.1, E, width=1.2, depth=0.45, height=0.6, n_boards=1))
    h.add(F.bookshelf("bedroom/bookshelf_s", 7.3, 0.16, S, width=0.9, height=1.2, n_boards=2))
    h.add(F.floor_lamp("bedroom/lamp", 8.7, 2.7))
    h.room("corner", (6.15, 0.0, 9.0, 3.15), (7.9, 0.9))

    # --- bathroom
    h.add(F.bathtub("bath/bathtub", 8.15, 6.625, N))
    h.add(F.toilet("bath/toilet", 8.66, 4.7, E))
    h.add(F.wall_cabinet("bath/wall_cabinet_toilet", 8.85, 4.7, E, width=0.8, depth=0.3, z_bottom=1.4))
    h.add(F.sink_cabinet("bath/sink", 7.55, 3.5, S))
    h.add(F.wall_cabinet("bath/wall_cabinet_sink", 7.55, 3.4, S, width=0.8, depth=0.3, z_bottom=1.4))
    h.add(F.shelf_unit("bath/shelf", 6.4, 5.6, W))
    h.room("bathroom", (6.25, 3.25, 9.0, 7.0), (7.5, 5.2))
    return h.scene()


@functools.cache
def studio() -> Scene:
    """A 4.5 x 4 m room with a table, an armchair and a low open cabinet: most targets are in
    view from most of the floor. The easy setting of the learning tests."""
    b = (0.0, 0.0, 4.5, 4.0)
    h = _Home("studio", b)
    h.add(F.outer_walls(b))
    h.add(F.table("studio/table", 2.6, 2.6, 0.0, width=1.0, depth=0.7))
    h.add(F.armchair("studio/armchair", 0.6, 3.3, W, color=F.FABRIC_BEIGE))
    h.add(F.low_cabinet("studio/cabinet", 3.2, 0.225, S, width=1.2, depth=0.45, height=0.6, n_boards=1))
    h.room("studio", (0.0, 0.0, 4.5, 4.0))
    return h.scene()


@functools.cache
def kitchen_living() -> Scene:
    """Paper Figure 4a: an open kitchen and a living area separated by a countertop."""
    return _build_kitchen_living()


@functools.cache
def bedroom_bath() -> Scene:
    """Paper Figure 4b: a bedroom connected to a bathroom."""
    return _build_bedroom_bath()


# ----------------------------------------------------------------------------------- generator
def free_space_grid(parts: Sequence[Part], bounds: Rect, radius: float = 0.2, res: float = 0.1,
                    z_max: float = 1.8) -> np.ndarray:
    """Boolean grid (rows = y, cols = x) of cell centres a body of ``radius`` can stand on.

    A cell is blocked when it lies within ``radius`` of the footprint of an obstacle whose
    bottom is below ``z_max`` (boxes exactly, cylinders by their bounding box).
    """
    x0, y0, x1, y1 = bounds
    nx, ny = int(round((x1 - x0) / res)), int(round((y1 - y0) / res))
    xs = x0 + (np.arange(nx) + 0.5) * res
    ys = y0 + (np.arange(ny) + 0.5) * res
    free = np.ones((ny, nx), dtype=bool)
    for p in parts:
        if not p.is_obstacle or p.z_min >= z_max or p.z_max <= 0:
            continue
        corners = np.asarray(p.footprint_corners())
        (cx0, cy0), (cx1, cy1) = corners.min(axis=0) - radius, corners.max(axis=0) + radius
        i0, i1 = np.searchsorted(xs, cx0), np.searchsorted(xs, cx1, side="right")
        j0, j1 = np.searchsorted(ys, cy0), np.searchsorted(ys, cy1, side="right")
        if i0 >= i1 or j0 >= j1:
            continue
        gx, gy = np.meshgrid(xs[i0:i1], ys[j0:j1])
        lx, ly = to_local((gx, gy), p.center[:2], p.yaw)
        dx = np.maximum(np.abs(lx) - p.size[0] / 2, 0.0)
        dy = np.maximum(np.abs(ly) - p.size[1] / 2, 0.0)
        free[j0:j1, i0:i1] &= np.hypot(dx, dy) >= radius
    return free


def largest_component_share(free: np.ndarray) -> float:
    """Share of free cells in the largest 4-connected component (1.0 when all connected)."""
    labels, n = ndimage.label(free)
    if n == 0:
        return 0.0
    counts = np.bincount(labels.ravel())[1:]
    return float(counts.max() / counts.sum())


def _overlap(a: Rect, b: Rect) -> bool:
    return a[0] < b[2] - 1e-9 and b[0] < a[2] - 1e-9 and a[1] < b[3] - 1e-9 and b[1] < a[3] - 1e-9


def _grow(r: Rect, m: float) -> Rect:
    return (r[0] - m, r[1] - m, r[2] + m, r[3] + m)


Factory = Callable[[str, float, float, float], F.Built]


class _RequiredPieceMissing(RuntimeError):
    """A draw of the generator left a room without its required piece: draw again."""


class _Room:
    """A room to furnish: ``sides`` are the ones that are real walls (others open onto floor)."""

    def __init__(self, label: str, kind: str, rect: Rect, sides: str = "nsew"):
        self.label, self.kind, self.rect, self.sides = label, kind, rect, sides


class _Furnisher:
    """Places pieces against walls by rejection sampling, keeping doorways and passages free."""

    ACCESS = 0.6  # free depth kept in front of every piece (m)

    def __init__(self, rng: np.random.Generator, home: _Home, structure: list[Part]):
        self.rng, self.home = rng, home
        self.hard: list[Rect] = []  # footprints
        self.soft: list[Rect] = []  # access zones in front of pieces
        self.keep_out: list[Rect] = []  # around doorways
        self.structure = structure  # walls (for the connectivity check)

    def _connected(self, extra: list[Part]) -> bool:
        free = free_space_grid(self.structure + self.home.parts + extra, self.home.bounds, res=0.1)
        return largest_component_share(free) >= 0.985

    def _try(self, name: str, factory: Factory, x: float, y: float, yaw: float, hard: Rect, soft: Rect | None,
             room: _Room) -> bool:
        r = room.rect
        if hard[0] < r[0] - 1e-9 or hard[1] < r[1] - 1e-9 or hard[2] > r[2] + 1e-9 or hard[3] > r[3] + 1e-9:
            return False
        if any(_overlap(hard, o) for o in self.hard + self.soft + self.keep_out):
            return False
        if soft is not None and any(_overlap(soft, o) for o in self.hard):
            return False
        built = factory(name, x, y, yaw)
        if not self._connected(built[0]):
            return False
        self.home.add(built)
        self.hard.append(hard)
        if soft is not None:
            self.soft.append(soft)
        return True

    def against_wall(self, room: _Room, name: str, width: float, depth: float, factory: Factory,
                     required: bool = False, tries: int = 80, access: float | None = None) -> bool:
        access = self.ACCESS if access is None else access
        x0, y0, x1, y1 = room.rect
        sides = list(room.sides)
        lengths = np.array([x1 - x0 if side in "ns" else y1 - y0 for side in sides])
        for _ in range(tries):
            side = sides[int(self.rng.choice(len(sides), p=lengths / lengths.sum()))]
            lo, hi = (x0, x1) if side in "ns" else (y0, y1)
            if hi - lo < width:
                continue
            along = round(float(self.rng.uniform(lo + width / 2, hi - width / 2)), 2)
            x, y, yaw = F.against_wall(side, along, depth, room.rect)
            if side in "ns":
                hard = (along - width / 2, y - depth / 2, along + width / 2, y + depth / 2)
                soft = ((hard[0], hard[1] - access, hard[2], hard[1]) if side == "n"
                        else (hard[0], hard[3], hard[2], hard[3] + access))
            else:
                hard = (x - depth / 2, along - width / 2, x + depth / 2, along + width / 2)
                soft = ((hard[2], hard[1], hard[2] + access, hard[3]) if side == "w"
                        else (hard[0] - access, hard[1], hard[0], hard[3]))
            if self._try(name, factory, x, y, yaw, hard, soft if access > 0 else None, room):
                return True
        if required:
            raise _RequiredPieceMissing(f"random home: could not place required {name!r} in {room.label}")
        return False

    def free_standing(self, room: _Room, name: str, width: float, depth: float, factory: Factory,
                      margin: float = 0.7, tries: int = 80) -> bool:
        x0, y0, x1, y1 = room.rect
        for _ in range(tries):
            turn = bool(self.rng.random() < 0.5)
            w, d = (depth, width) if turn else (width, depth)
            if x1 - x0 < w + 2 * margin or y1 - y0 < d + 2 * margin:
                continue
            x = round(float(self.rng.uniform(x0 + margin + w / 2, x1 - margin - w / 2)), 2)
            y = round(float(self.rng.uniform(y0 + margin + d / 2, y1 - margin - d / 2)), 2)
            hard = (x - w / 2, y - d / 2, x + w / 2, y + d / 2)
            if any(_overlap(_grow(hard, margin), o) for o in self.hard):
                continue
            if self._try(name, factory, x, y, math.pi / 2 if turn else 0.0, hard, None, room):
                return True
        return False


# Composite pieces: (width, depth, factory). Footprints include everything (chairs, nightstands...).
def _kitchen_run(rng: np.random.Generator, scale: float = 1.0) -> tuple[float, float, Factory]:
    width = max(1.8, round(float(rng.uniform(2.4, 3.6)) * scale, 1))
    n_sec = max(2, round(width / 0.9))
    sections = ["open"] * n_sec
    sections[int(rng.integers(n_sec))] = "closed"
    sink = round(float(rng.uniform(-width / 2 + 0.5, -0.4)), 2)
    cook = round(float(rng.uniform(0.4, width / 2 - 0.5)), 2)
    n_wc = 2 if width >= 3.0 else 1

    def make(name, x, y, yaw):
        built = [F.counter(f"{name}/counter", x, y, yaw, width, 0.6, sections=sections, sink_at=sink,
                           cooktop_at=cook, top_clearance=0.55)]
        wc_w = round(min(1.2, (width - 0.2) / n_wc - 0.1), 2)
        for i in range(n_wc):
            lx = -width / 2 + (i + 0.5) * width / n_wc
            wx, wy = F.child_pose(x, y, yaw, lx, 0.3 - 0.175)
            built.append(F.wall_cabinet(f"{name}/wall_cabinet{i}", wx, wy, yaw, width=wc_w))
        return F.merge(*built)

    return width, 0.6, make


def _sofa_group(rng, scale: float = 1.0):
    width = round(float(rng.uniform(1.9, 2.4)), 1)
    color = (F.FABRIC_BLUE, F.FABRIC_GREEN, F.FABRIC_RED, F.FABRIC_BEIGE)[int(rng.integers(4))]
    depth = 0.9 + 0.45 + 0.6

    def make(name, x, y, yaw):
        sx, sy = F.child_pose(x, y, yaw, 0.0, depth / 2 - 0.45)
        tx, ty = F.child_pose(x, y, yaw, 0.0, -depth / 2 + 0.3)
        return F.merge(F.sofa(f"{name}/sofa", sx, sy, yaw, width, color=color),
                       F.coffee_table(f"{name}/coffee_table", tx, ty, yaw, width=min(1.1, width - 0.6)))

    return width, depth, make


def _bed_group(rng, scale: float = 1.0):
    bw = float(rng.choice([1.4, 1.6, 1.8])) if scale >= 1.0 else 1.4
    width = bw + 2 * 0.55

    def make(name, x, y, yaw):
        built = [F.bed(f"{name}/bed", x, y, yaw, bw, 2.0)]
        for i, side in enumerate((-1, 1)):
            nx, ny = F.child_pose(x, y, yaw, side * (bw / 2 + 0.3), 1.0 - 0.2)
            built.append(F.nightstand(f"{name}/nightstand{i}", nx, ny, yaw))
        return F.merge(*built)

    return width, 2.0, make


def _desk_group(rng, scale: float = 1.0):
    width = max(0.9, round(float(rng.uniform(1.0, 1.4)) * scale, 1))
    depth = 0.6 + 0.1 + 0.46

    def make(name, x, y, yaw):
        dx, dy = F.child_pose(x, y, yaw, 0.0, depth / 2 - 0.3)
        cx, cy = F.child_pose(x, y, yaw, 0.0, -depth / 2 + 0.23)
        return F.merge(F.desk(f"{name}/desk", dx, dy, yaw, width, 0.6),
                       F.chair(f"{name}/chair", cx, cy, yaw, color=F.DARK_GREY))

    return width, depth, make


def _dining_group(rng):
    tw = round(float(rng.uniform(1.2, 1.6)), 1)
    td = 0.85
    depth = td + 2 * (0.05 + 0.46)

    def make(name, x, y, yaw):
        built = [F.table(f"{name}/table", x, y, yaw, tw, td)]
        for i, lx in enumerate((-tw / 4, tw / 4)):
            for side, ly in (("s", -(td / 2 + 0.05 + 0.23)), ("n", td / 2 + 0.05 + 0.23)):
                cx, cy = F.child_pose(x, y, yaw, lx, ly)
                built.append(F.chair(f"{name}/chair_{side}{i}", cx, cy, yaw + (math.pi if side == "s" else 0.0)))
        return F.merge(*built)

    return tw, depth, make


def _wall_unit(rng, kind):
    """A single against-the-wall piece of the vocabulary."""
    if kind == "low_cabinet":
        w = round(float(rng.uniform(0.9, 1.6)), 1)
        h = round(float(rng.uniform(0.5, 0.9)), 2)
        color = (F.WHITE, F.LIGHT_WOOD, F.WOOD)[int(rng.integers(3))]
        return w, 0.45, lambda n, x, y, yaw: F.low_cabinet(n, x, y, yaw, w, 0.45, h, n_boards=1 if h > 0.6 else 0,
                                                           color=color)
    if kind == "bookshelf":
        w = round(float(rng.uniform(0.8, 1.2)), 1)
        tall = bool(rng.random() < 0.6)
        return w, 0.32, lambda n, x, y, yaw: F.bookshelf(n, x, y, yaw, w, height=1.8 if tall else 1.2,
                                                         n_boards=4 if tall else 2)
    if kind == "tv_stand":
        w = round(float(rng.uniform(1.4, 1.8)), 1)
        return w, 0.45, lambda n, x, y, yaw: F.tv_stand(n, x, y, yaw, w)
    if kind == "fridge":
        return 0.75, 0.7, F.fridge
    if kind == "armchair":
        return 0.85, 0.85, F.armchair
    if kind == "plant":
        return 0.5, 0.5, lambda n, x, y, yaw: F.plant(n, x, y)
    if kind == "lamp":
        return 0.4, 0.4, lambda n, x, y, yaw: F.floor_lamp(n, x, y)
    if kind == "wardrobe":
        w = round(float(rng.uniform(1.2, 2.0)), 1)
        return w, 0.6, lambda n, x, y, yaw: F.wardrobe(n, x, y, yaw, w)
    if kind == "sink":
        def make(n, x, y, yaw):
            wx, wy = F.child_pose(x, y, yaw, 0.0, 0.25 - 0.15)
            return F.merge(F.sink_cabinet(f"{n}/cabinet", x, y, yaw),
                           F.wall_cabinet(f"{n}/wall_cabinet", wx, wy, yaw, width=0.8, depth=0.3, z_bottom=1.4))
        return 0.9, 0.5, make
    if kind == "toilet":
        return 0.4, 0.68, F.toilet
    if kind == "bathtub":
        return 1.7, 0.75, F.bathtub
    if kind == "shelf":
        return 0.6, 0.3, F.shelf_unit
    if kind == "dresser":
        w = round(float(rng.uniform(1.0, 1.4)), 1)
        return w, 0.45, lambda n, x, y, yaw: F.low_cabinet(n, x, y, yaw, w, 0.45, 0.8, color=F.LIGHT_WOOD,
                                                           kind="dresser")
    raise KeyError(kind)


#: What goes in each kind of room, in placement order: (piece, required).
_KITCHEN = [("kitchen_run", True), ("fridge", False), ("low_cabinet", False), ("plant", False)]
_LIVING = [("sofa_group", False), ("tv_stand", False), ("bookshelf", False), ("low_cabinet", False),
           ("armchair", False), ("armchair", False), ("low_cabinet", False), ("plant", False), ("lamp", False)]
_RECIPES: dict[str, list[tuple[str, bool]]] = {
    "kitchen": _KITCHEN,
    "living": _LIVING,
    "kitchen_living": _KITCHEN + _LIVING,
    "bedroom": [("bed_group", True), ("wardrobe", False), ("desk_group", False), ("dresser", False),
                ("bookshelf", False), ("low_cabinet", False), ("armchair", False), ("plant", False),
                ("lamp", False)],
    "study": [("desk_group", True), ("bookshelf", False), ("bookshelf", False), ("low_cabinet", False),
              ("armchair", False), ("low_cabinet", False), ("plant", False), ("lamp", False)],
    "bathroom": [("sink", True), ("toilet", False), ("bathtub", False), ("shelf", False), ("plant", False)],
}
_GROUPS = {"kitchen_run": _kitchen_run, "sofa_group": _sofa_group, "bed_group": _bed_group,
           "desk_group": _desk_group}


def _mirror(scene_parts, surfaces, rooms, bounds, flip_x: bool, flip_y: bool):
    """Mirror a home in x and/or y inside ``bounds`` (boxes are symmetric, so yaw -> -yaw)."""
    x0, y0, x1, y1 = bounds

    def xy(x, y):
        return (round(x0 + x1 - x, 9) if flip_x else x), (round(y0 + y1 - y, 9) if flip_y else y)

    def yaw(a):
        return (-a if flip_x != flip_y else a) + 0.0

    parts = [Part(p.name, p.shape, (*xy(*p.center[:2]), p.center[2]), p.size, yaw(p.yaw), p.tags, p.color,
                  p.mesh_file) for p in scene_parts]
    surfs = [SupportSurface(s.name, (*xy(*s.center[:2]), s.center[2]), s.size, yaw(s.yaw), s.clearance, s.tags)
             for s in surfaces]
    return parts, surfs, [(label, xy(*c)) for label, c in rooms]


#: Draws of :func:`random_home` before it gives up; about one seed in 1,000 needs a second.
MAX_HOME_ATTEMPTS = 20


def home_rng(seed: int, attempt: int) -> np.random.Generator:
    """The generator of draw ``attempt`` of home ``seed``: the plain seed first (so the homes
    of the first draw never change), then seeds derived from (seed, attempt)."""
    return np.random.default_rng(seed if attempt == 0 else [seed, attempt])


@functools.lru_cache(maxsize=64)
def random_home(seed: int) -> Scene:
    """A seeded home of 2-3 rooms (8-12 x 6-9 m) furnished from the layouts' vocabulary.

    The west room is always a kitchen + living room (counters with low open cabinets, wall
    cabinets...), split by a peninsula counter when the home is deep enough (like Figure 4a);
    the rest are a bedroom, and a bathroom or a study. Partition walls have
    0.85-1.1 m doorways at random offsets. Pieces go against walls by rejection sampling: no
    overlaps, a free access zone in front of each, doorways kept clear, and free space kept
    one connected region. The whole home is finally mirrored at random. Same seed, same Scene.

    Every seed builds: a draw whose required piece (kitchen run, bed, desk, sink) finds no
    room is drawn again from :func:`home_rng` ``(seed, attempt)``, and ``meta["attempt"]``
    records which draw the home is.
    """
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise ValueError(f"random_home seed={seed!r}; allowed: an integer >= 0")
    seed = int(seed)
    for attempt in range(MAX_HOME_ATTEMPTS):
        try:
            return _draw_home(seed, attempt)
        except _RequiredPieceMissing:
            continue
    raise RuntimeError(f"random home {seed}: no draw of {MAX_HOME_ATTEMPTS} placed every required piece")


def _draw_home(seed: int, attempt: int) -> Scene:
    rng = home_rng(seed, attempt)
    W = round(float(rng.uniform(8.0, 12.0)), 1)
    H = round(float(rng.uniform(6.0, 9.0)), 1)
    bounds = (0.0, 0.0, W, H)
    home = _Home(f"home{seed}", bounds)
    home.add(F.outer_walls(bounds))
    n_rooms = 3 if rng.random() < 0.7 else 2
    xs = round(float(rng.uniform(0.5, 0.62)) * W, 2)
    t = F.WALL_THICKNESS / 2

    def door(lo, hi):
        width = round(float(rng.uniform(0.85, 1.1)), 2)
        start = round(float(rng.uniform(lo + 0.3, hi - 0.3 - width)), 2)
        return start, width

    keep_out = []
    mw = xs - t
    if H >= 7.0 and rng.random() < 0.8:
        # A peninsula from the west wall separates the kitchen (north) from the living area.
        kd = round(float(rng.uniform(2.6, 3.0)), 2)
        yk = round(H - kd - 0.475, 2)
        pl = round(float(rng.uniform(2.0, min(3.0, mw - 1.6))), 1)
        pen = F.counter("kitchen/peninsula", pl / 2, yk, math.pi, pl, 0.95, back_overhang=0.3,
                        cabinet_color=F.LIGHT_WOOD)
        stools = [F.stool(f"kitchen/stool{i}", round(sx, 2), yk - 0.475 - 0.2)
                  for i, sx in enumerate(np.arange(0.45, pl - 0.25, 0.75))]
        home.add(F.merge(pen, *stools))
        rooms = [_Room("kitchen", "kitchen", (0.0, yk + 0.475, mw, H), sides="new"),
                 _Room("living", "living", (0.0, 0.0, mw, yk - 0.875), sides="sew")]
        keep_out.append((pl, yk - 0.9, mw, yk + 0.5))  # the passage past the peninsula's end
        home.floor("floor/peninsula", (0.0, yk - 0.875, mw, yk + 0.475))
        main_hard = [(0.0, yk - 0.875, pl, yk + 0.475)]
    else:
        rooms = [_Room("kitchen + living", "kitchen_living", (0.0, 0.0, mw, H))]
        main_hard = []
    if n_rooms == 2:
        kind = "bedroom" if rng.random() < 0.7 else "study"
        rooms.append(_Room(kind, kind, (xs + t, 0.0, W, H)))
        d0, dw = door(0.0, H)
        home.add(F.wall("wall/partition", (xs, 0.0), (xs, H), gaps=[(d0, dw)]))
        keep_out.append((xs - 1.0, d0 - 0.1, xs + 1.0, d0 + dw + 0.1))
    else:
        ys = round(float(rng.uniform(0.4, 0.6)) * H, 2)
        low, up = (xs + t, 0.0, W, ys - t), (xs + t, ys + t, W, H)
        big_low = (ys - t) >= (H - ys - t)
        small_kind = "bathroom" if rng.random() < 0.6 else "study"
        kinds = ("bedroom", small_kind) if big_low else (small_kind, "bedroom")
        rooms.append(_Room(kinds[0], kinds[0], low))
        rooms.append(_Room(kinds[1], kinds[1], up))
        g0 = door(0.0, ys - t)
        g1 = door(ys + t, H)
        home.add(F.wall("wall/partition", (xs, 0.0), (xs, H), gaps=[g0, g1]))
        home.add(F.wall("wall/partition_h", (xs + t, ys), (W, ys)))
        for d0, dw in (g0, g1):
            keep_out.append((xs - 1.0, d0 - 0.1, xs + 1.0, d0 + dw + 0.1))
    structure = [p for p in home.parts if p.name.startswith("wall/")]
    home.parts = [p for p in home.parts if not p.name.startswith("wall/")]
    fur = _Furnisher(rng, home, structure)
    fur.keep_out = keep_out
    fur.hard.extend(main_hard)
    for room in rooms:
        tag = room.kind.split("_")[0]
        for k, (piece, required) in enumerate(_RECIPES[room.kind]):
            maker = _GROUPS.get(piece)
            access = 0.4 if piece in ("plant", "lamp") else None
            for scale in ((1.0, 0.8, 0.65) if required else (1.0,)):  # required pieces shrink to fit
                w, d, make = maker(rng, scale) if maker else _wall_unit(rng, piece)
                last = required and scale == 0.65
                if fur.against_wall(room, f"{tag}/{piece}{k}", w, d, make, required=last, access=access):
                    break
        if room.kind in ("kitchen_living", "kitchen"):
            w, d, make = _dining_group(rng)
            fur.free_standing(room, f"{tag}/dining", w, d, make)
        home.room(room.label, room.rect)
    flip_x, flip_y = bool(rng.random() < 0.5), bool(rng.random() < 0.5)
    parts, surfs, labels = _mirror(structure + home.parts, home.surfaces, home.rooms, bounds, flip_x, flip_y)
    home.parts, home.surfaces, home.rooms = parts, surfs, labels
    return home.scene({"seed": seed, "attempt": attempt, "flip": (flip_x, flip_y)})


# ----------------------------------------------------------------------------------- lookup
def get_scene(name: str) -> Scene:
    """A scene by name: ``"kitchen_living"``, ``"bedroom_bath"``, ``"studio"`` or ``"home<seed>"``
    (e.g. ``"home7"``)."""
    if name == "kitchen_living":
        return kitchen_living()
    if name == "bedroom_bath":
        return bedroom_bath()
    if name == "studio":
        return studio()
    m = re.fullmatch(r"home(\d+)", name) if isinstance(name, str) else None
    if m:
        return random_home(int(m.group(1)))
    raise ValueError(f"scene name={name!r}; allowed: {_ALLOWED}")

"""Furniture made of boxes and cylinders, as plain data.

Every builder returns ``(parts, surfaces)``: the solid pieces (:class:`Part`) and the places a
target may rest (:class:`SupportSurface`). Builders share one convention:

- ``x, y`` is the centre of the piece's footprint in the world frame and ``yaw`` turns it about
  the vertical axis;
- in the piece's own frame the width runs along local x, the depth along local y, the
  **front faces local -y** and the back (the side that goes against a wall) is at +y. So a
  piece against the north wall has ``yaw=0``, against the south wall ``yaw=pi``, against the
  west wall ``yaw=pi/2`` and against the east wall ``yaw=-pi/2`` (see :func:`against_wall`);
- quarter-turn yaws are folded into the sizes, so axis-aligned furniture gives parts with
  ``yaw == 0`` (simpler for every consumer);
- every solid furniture part is tagged ``{TAG_OBSTACLE, TAG_FURNITURE, <kind>}``, walls
  ``{TAG_OBSTACLE, TAG_WALL, <kind>}``;
- a support surface lies exactly at the top face of the part it belongs to, shrunk by
  :data:`SURFACE_MARGIN` from the edges, and its ``clearance`` is the free height above it (the
  distance to the board above inside a cabinet, :data:`OPEN_TOP_CLEARANCE` for open tops).

Open cabinets are built from separate side panels, back, bottom, boards (and top), so the inside
is really hollow and can only be seen through the open front.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

from egosearch.scene.parts import (
    TAG_FURNITURE,
    TAG_LOW_CABINET_INTERIOR,
    TAG_OBSTACLE,
    TAG_WALL,
    Part,
    SupportSurface,
    to_world,
)

Built = tuple[list[Part], list[SupportSurface]]

#: Support surfaces stay this far from the edges of the part they lie on (m).
SURFACE_MARGIN = 0.03
#: Clearance given to surfaces with nothing above them (m).
OPEN_TOP_CLEARANCE = 1.0
#: Panel thickness of cabinets and shelves (m).
PANEL = 0.02
#: Surfaces inside cabinets hung on a wall (free text; the code relies only on the low one).
TAG_WALL_CABINET_INTERIOR = "wall_cabinet_interior"
#: Default height of walls and of doorway lintels (m).
WALL_HEIGHT = 2.6
DOOR_HEIGHT = 2.05
WALL_THICKNESS = 0.1

# A small palette (RGB in [0, 1]).
WALL = (0.86, 0.84, 0.80)
WOOD = (0.62, 0.45, 0.30)
LIGHT_WOOD = (0.80, 0.67, 0.50)
DARK_WOOD = (0.38, 0.27, 0.18)
WHITE = (0.93, 0.93, 0.91)
OFF_WHITE = (0.88, 0.86, 0.80)
GREY = (0.55, 0.56, 0.58)
DARK_GREY = (0.25, 0.25, 0.27)
BLACK = (0.08, 0.08, 0.09)
STEEL = (0.72, 0.74, 0.76)
STONE = (0.50, 0.50, 0.48)
FABRIC_BLUE = (0.30, 0.40, 0.58)
FABRIC_GREEN = (0.38, 0.52, 0.40)
FABRIC_RED = (0.62, 0.30, 0.28)
FABRIC_BEIGE = (0.78, 0.72, 0.60)
PORCELAIN = (0.96, 0.96, 0.97)
LEAF = (0.24, 0.50, 0.24)
TERRACOTTA = (0.70, 0.40, 0.28)
BOOK_COLORS = ((0.55, 0.15, 0.15), (0.15, 0.30, 0.55), (0.20, 0.45, 0.25), (0.85, 0.75, 0.35),
               (0.35, 0.25, 0.45), (0.90, 0.90, 0.85), (0.20, 0.20, 0.22))


def _quarter_turns(yaw: float) -> int | None:
    k = yaw / (math.pi / 2)
    if abs(k - round(k)) < 1e-9:
        return int(round(k)) % 4
    return None


def _clean(v: float) -> float:
    """Drop floating-point dust (cos(pi/2) != 0) from world x, y."""
    return round(v, 9) + 0.0


def child_pose(x: float, y: float, yaw: float, lx: float, ly: float) -> tuple[float, float]:
    """World (x, y) of the point ``(lx, ly)`` in the frame of a piece at ``(x, y, yaw)``."""
    wx, wy = to_world((lx, ly), (x, y), yaw)
    return _clean(wx), _clean(wy)


def against_wall(side: str, along: float, depth: float, rect: Sequence[float]) -> tuple[float, float, float]:
    """Pose ``(x, y, yaw)`` of a piece ``depth`` deep with its back on one side of ``rect``.

    ``rect`` is a room's interior ``(x0, y0, x1, y1)``; ``side`` is ``"n"``, ``"s"``, ``"e"`` or
    ``"w"``; ``along`` is the x (north/south walls) or y (east/west walls) of the piece's centre.
    """
    x0, y0, x1, y1 = rect
    if side == "n":
        return along, y1 - depth / 2, 0.0
    if side == "s":
        return along, y0 + depth / 2, math.pi
    if side == "w":
        return x0 + depth / 2, along, math.pi / 2
    if side == "e":
        return x1 - depth / 2, along, -math.pi / 2
    raise ValueError(f"side={side!r}; allowed: n, s, e, w")


def merge(*builts: Built) -> Built:
    parts: list[Part] = []
    surfaces: list[SupportSurface] = []
    for p, s in builts:
        parts.extend(p)
        surfaces.extend(s)
    return parts, surfaces


class _Piece:
    """Collects the parts and surfaces of one piece, given in its local frame."""

    def __init__(self, name: str, x: float, y: float, yaw: float, kind: str, color,
                 base_tags: Iterable[str] = (TAG_OBSTACLE, TAG_FURNITURE)):
        self.name, self.x, self.y, self.yaw = name, x, y, yaw
        self.kind, self.color = kind, tuple(color)
        self.base_tags = frozenset(base_tags) | {kind}
        self.quarter = _quarter_turns(yaw)
        self.parts: list[Part] = []
        self.surfaces: list[SupportSurface] = []

    def _pose(self, lx, ly, sx, sy):
        wx, wy = child_pose(self.x, self.y, self.yaw, lx, ly)
        if self.quarter is None:
            return (wx, wy), (sx, sy), self.yaw
        if self.quarter % 2:
            sx, sy = sy, sx
        return (wx, wy), (sx, sy), 0.0

    def box(self, suffix: str, x0, x1, y0, y1, z0, z1, color=None, tags: Iterable[str] = ()) -> None:
        """An axis-aligned (in the local frame) box given by its bounds."""
        (wx, wy), (sx, sy), yaw = self._pose((x0 + x1) / 2, (y0 + y1) / 2, x1 - x0, y1 - y0)
        self.parts.append(Part(f"{self.name}/{suffix}", "box", (wx, wy, (z0 + z1) / 2),
                               (sx, sy, z1 - z0), yaw, self.base_tags | set(tags),
                               tuple(color or self.color)))

    def cyl(self, suffix: str, lx, ly, z0, z1, diameter, color=None, tags: Iterable[str] = ()) -> None:
        wx, wy = child_pose(self.x, self.y, self.yaw, lx, ly)
        self.parts.append(Part(f"{self.name}/{suffix}", "cylinder", (wx, wy, (z0 + z1) / 2),
                               (diameter, diameter, z1 - z0), 0.0, self.base_tags | set(tags),
                               tuple(color or self.color)))

    def surface(self, suffix: str, x0, x1, y0, y1, z, clearance, tags: Iterable[str] = (),
                margin: float = SURFACE_MARGIN) -> None:
        """A support surface on the rectangle (local bounds), shrunk by ``margin``."""
        x0, x1, y0, y1 = x0 + margin, x1 - margin, y0 + margin, y1 - margin
        if x1 - x0 <= 0.02 or y1 - y0 <= 0.02 or clearance <= 0.02:
            return
        (wx, wy), (sx, sy), yaw = self._pose((x0 + x1) / 2, (y0 + y1) / 2, x1 - x0, y1 - y0)
        self.surfaces.append(SupportSurface(f"{self.name}/{suffix}", (wx, wy, z), (sx, sy), yaw,
                                            clearance, frozenset({self.kind, *tags})))

    def built(self) -> Built:
        return self.parts, self.surfaces


# ----------------------------------------------------------------------------------- walls
def wall(name: str, p0: Sequence[float], p1: Sequence[float], gaps: Iterable[tuple[float, float]] = (),
         thickness: float = WALL_THICKNESS, height: float = WALL_HEIGHT, door_height: float = DOOR_HEIGHT,
         kind: str = "partition", color=WALL) -> Built:
    """A straight wall centred on the segment ``p0``-``p1`` with doorway gaps.

    ``gaps`` holds ``(offset, width)`` pairs: a doorway ``width`` wide starting ``offset`` metres
    from ``p0`` along the wall. Above every doorway a lintel closes the wall from ``door_height``
    up (the body never reaches that high).
    """
    (ax, ay), (bx, by) = p0[:2], p1[:2]
    length = math.hypot(bx - ax, by - ay)
    if length <= 0:
        raise ValueError(f"wall {name!r}: p0 and p1 coincide")
    yaw = math.atan2(by - ay, bx - ax)
    gaps = sorted((float(o), float(w)) for o, w in gaps)
    for o, w in gaps:
        if o < 0 or w <= 0 or o + w > length + 1e-9:
            raise ValueError(f"wall {name!r}: gap (offset={o}, width={w}) outside 0..{length:.2f}")
    cx, cy = (ax + bx) / 2, (ay + by) / 2
    piece = _Piece(name, cx, cy, yaw, kind, color, base_tags=(TAG_OBSTACLE, TAG_WALL))
    h = thickness / 2
    start = 0.0
    pieces = []
    for o, w in gaps:
        pieces.append((start, o))
        start = o + w
    pieces.append((start, length))
    for i, (s, e) in enumerate(pieces):
        if e - s > 1e-6:
            piece.box(f"seg{i}", s - length / 2, e - length / 2, -h, h, 0.0, height)
    for i, (o, w) in enumerate(gaps):
        if door_height < height:
            piece.box(f"lintel{i}", o - length / 2, o + w - length / 2, -h, h, door_height, height,
                      tags=("lintel",))
    return piece.built()


def outer_walls(bounds: Sequence[float], gaps: dict[str, list[tuple[float, float]]] | None = None,
                thickness: float = WALL_THICKNESS, height: float = WALL_HEIGHT) -> Built:
    """Four walls whose inner faces are exactly ``bounds``; the south/north walls cover the corners.

    ``gaps`` maps a side (``"n"``, ``"s"``, ``"e"``, ``"w"``) to doorway gaps measured from the
    west end (north/south walls) or the south end (east/west walls) of the interior.
    """
    x0, y0, x1, y1 = bounds
    gaps = gaps or {}
    t, h = thickness, thickness / 2

    def shift(side, extra):
        return [(o + extra, w) for o, w in gaps.get(side, [])]

    return merge(
        wall("wall/south", (x0 - t, y0 - h), (x1 + t, y0 - h), shift("s", t), t, height, kind="outer"),
        wall("wall/north", (x0 - t, y1 + h), (x1 + t, y1 + h), shift("n", t), t, height, kind="outer"),
        wall("wall/west", (x0 - h, y0), (x0 - h, y1), shift("w", 0.0), t, height, kind="outer"),
        wall("wall/east", (x1 + h, y0), (x1 + h, y1), shift("e", 0.0), t, height, kind="outer"),
    )


def floor_and_ceiling(bounds: Sequence[float], height: float = WALL_HEIGHT,
                      margin: float = WALL_THICKNESS) -> list[Part]:
    """The floor (top face at z = 0) and the ceiling (bottom face at ``height``): not obstacles."""
    x0, y0, x1, y1 = bounds
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    sx, sy = x1 - x0 + 2 * margin, y1 - y0 + 2 * margin
    return [
        Part("floor", "box", (cx, cy, -0.05), (sx, sy, 0.1), 0.0, frozenset({"floor"}), (0.72, 0.64, 0.52)),
        Part("ceiling", "box", (cx, cy, height + 0.05), (sx, sy, 0.1), 0.0, frozenset({"ceiling"}),
             (0.97, 0.97, 0.97)),
    ]


def floor_surface(name: str, rect: Sequence[float], margin: float = SURFACE_MARGIN,
                  clearance: float = 2.0) -> SupportSurface:
    """A floor rectangle ``rect = (x0, y0, x1, y1)`` (shrunk by ``margin``) tagged ``"floor"``."""
    x0, y0, x1, y1 = rect
    return SupportSurface(name, ((x0 + x1) / 2, (y0 + y1) / 2, 0.0),
                          (x1 - x0 - 2 * margin, y1 - y0 - 2 * margin), 0.0, clearance, frozenset({"floor"}))


# ----------------------------------------------------------------------------------- cabinets
def open_cabinet(name: str, x: float, y: float, yaw: float = 0.0, width: float = 1.0, depth: float = 0.45,
                 height: float = 0.8, n_boards: int = 1, z0: float = 0.0, n_columns: int | None = None,
                 kind: str = "low_cabinet", interior_tags: Iterable[str] | None = None,
                 with_top: bool = True, top_surface: bool = True, top_clearance: float = OPEN_TOP_CLEARANCE,
                 base: float | None = None, color=WHITE, books: bool = False) -> Built:
    """An open-front cabinet: sides, back, bottom, ``n_boards`` boards and (optionally) a top.

    ``z0`` is the height of its underside: 0 for floor cabinets (which get a 0.1 m plinth as
    bottom), about 1.4-1.5 m for wall cabinets (a panel as bottom). Wide cabinets are split into
    ``n_columns`` compartments by vertical dividers (default: one per 0.9 m). Each compartment
    floor and board is a support surface tagged ``interior_tags`` (default: the low-cabinet tag
    for floor cabinets, the wall-cabinet tag otherwise); the top is a surface tagged
    ``"cabinet_top"`` only when ``top_surface`` (never a low-cabinet interior).
    ``books`` puts a few books at one end of alternate boards (clutter for bookshelves).
    """
    P = PANEL
    base = (0.1 if z0 <= 0 else P) if base is None else base
    if interior_tags is None:
        interior_tags = (TAG_LOW_CABINET_INTERIOR,) if z0 <= 0 else (TAG_WALL_CABINET_INTERIOR,)
    interior_tags = tuple(interior_tags)
    n_columns = n_columns or max(1, math.ceil(width / 0.9 - 1e-9))
    w2, d2 = width / 2, depth / 2
    piece = _Piece(name, x, y, yaw, kind, color)
    z_top = z0 + height
    z_in_top = z_top - P if with_top else z_top  # underside of whatever closes the cabinet
    piece.box("side_l", -w2, -w2 + P, -d2, d2, z0, z_in_top)
    piece.box("side_r", w2 - P, w2, -d2, d2, z0, z_in_top)
    piece.box("back", -w2 + P, w2 - P, d2 - P, d2, z0, z_in_top)
    piece.box("bottom", -w2 + P, w2 - P, -d2, d2 - P, z0, z0 + base)
    if with_top:
        piece.box("top", -w2, w2, -d2, d2, z_in_top, z_top)
    zb = z0 + base
    free = (z_in_top - zb - n_boards * P) / (n_boards + 1)
    if free <= 0.05:
        raise ValueError(f"open_cabinet {name!r}: {n_boards} boards do not fit in height {height}")
    inner = 2 * w2 - 2 * P
    col_w = (inner - (n_columns - 1) * P) / n_columns
    cols = []
    for c in range(n_columns):
        cx0 = -w2 + P + c * (col_w + P)
        cols.append((cx0, cx0 + col_w))
        if c > 0:
            piece.box(f"divider{c}", cx0 - P, cx0, -d2, d2 - P, zb, z_in_top)
    levels = [zb] + [zb + (i + 1) * free + (i + 1) * P for i in range(n_boards)]
    for i in range(n_boards):
        piece.box(f"board{i}", -w2 + P, w2 - P, -d2, d2 - P, levels[i + 1] - P, levels[i + 1])
    for li, z in enumerate(levels):
        for c, (cx0, cx1) in enumerate(cols):
            suffix = f"level{li}" + (f"_col{c}" if n_columns > 1 else "")
            piece.surface(suffix, cx0, cx1, -d2, d2 - P, z, free, tags=interior_tags)
    if with_top and top_surface:
        piece.surface("top_surface", -w2, w2, -d2, d2, z_top, top_clearance, tags=("cabinet_top",))
    if books:
        for li, z in enumerate(levels):
            if li % 2 == 1 or li == 0 and n_boards == 0:
                continue
            _books(piece, f"books{li}", cols[(li // 2) % len(cols)], li, -d2, d2 - P, z, free)
    return piece.built()


def _books(piece: _Piece, suffix: str, col: tuple[float, float], seed: int, y0: float, y1: float,
           z: float, free: float) -> None:
    """A row of upright books against one side of a compartment (deterministic pattern)."""
    cx0, cx1 = col
    left = seed % 4 < 2
    widths = (0.035, 0.03, 0.045, 0.025, 0.04, 0.03)
    heights = (0.24, 0.21, 0.27, 0.2, 0.23, 0.26)
    n = 4 + seed % 3
    pos = cx0 + 0.005 if left else cx1 - 0.005
    for i in range(n):
        k = (i + seed) % len(widths)
        w = widths[k]
        h = min(heights[k], free - 0.03)
        d = min(0.2 + 0.01 * (k % 3), (y1 - y0) - 0.02)
        a, b = (pos, pos + w) if left else (pos - w, pos)
        piece.box(f"{suffix}_{i}", a, b, y1 - 0.01 - d, y1 - 0.01, z, z + h,
                  color=BOOK_COLORS[(i * 3 + seed) % len(BOOK_COLORS)], tags=("books",))
        pos = b if left else a


def low_cabinet(name: str, x: float, y: float, yaw: float = 0.0, width: float = 1.2, depth: float = 0.45,
                height: float = 0.8, n_boards: int = 1, color=WHITE, kind: str = "low_cabinet") -> Built:
    """An open floor cabinet (sideboard, dresser): interiors tagged low-cabinet, top is not."""
    return open_cabinet(name, x, y, yaw, width, depth, height, n_boards, 0.0, kind=kind, color=color)


def wall_cabinet(name: str, x: float, y: float, yaw: float = 0.0, width: float = 0.9, depth: float = 0.35,
                 z_bottom: float = 1.45, height: float = 0.6, n_boards: int = 1, color=WHITE) -> Built:
    """An open cabinet hung on a wall (bottom at ``z_bottom``, typically 1.4-1.5 m)."""
    return open_cabinet(name, x, y, yaw, width, depth, height, n_boards, z_bottom, kind="wall_cabinet",
                        top_surface=False, color=color)


def bookshelf(name: str, x: float, y: float, yaw: float = 0.0, width: float = 1.0, depth: float = 0.32,
              height: float = 1.8, n_boards: int = 4, color=LIGHT_WOOD, books: bool = True) -> Built:
    """An open bookshelf: every board is a surface whose clearance is the board spacing."""
    return open_cabinet(name, x, y, yaw, width, depth, height, n_boards, 0.0, n_columns=1,
                        kind="bookshelf", interior_tags=("shelf",), top_surface=height <= 1.5,
                        color=color, books=books)


def wardrobe(name: str, x: float, y: float, yaw: float = 0.0, width: float = 1.6, depth: float = 0.6,
             height: float = 2.0, color=OFF_WHITE) -> Built:
    """A closed wardrobe: a body, a plinth and door handles (no surfaces)."""
    w2, d2 = width / 2, depth / 2
    piece = _Piece(name, x, y, yaw, "wardrobe", color)
    piece.box("plinth", -w2 + 0.03, w2 - 0.03, -d2 + 0.05, d2, 0.0, 0.08, color=DARK_GREY)
    piece.box("body", -w2, w2, -d2, d2, 0.08, height)
    n_doors = max(2, round(width / 0.5))
    for i in range(n_doors):
        if i % 2 == 0 and i + 1 < n_doors:
            hx = -w2 + (i + 1) * width / n_doors
            piece.box(f"handle{i}_a", hx - 0.06, hx - 0.04, -d2 - 0.02, -d2, 0.9, 1.2, color=STEEL)
            piece.box(f"handle{i}_b", hx + 0.04, hx + 0.06, -d2 - 0.02, -d2, 0.9, 1.2, color=STEEL)
    return piece.built()


# ----------------------------------------------------------------------------------- kitchen
def counter(name: str, x: float, y: float, yaw: float = 0.0, width: float = 2.4, depth: float = 0.6,
            height: float = 0.9, sections: Sequence[str] | None = None, top_clearance: float = OPEN_TOP_CLEARANCE,
            sink_at: float | None = None, cooktop_at: float | None = None, cabinet_color=WHITE,
            top_color=STONE, n_boards: int = 1, kind: str = "counter", back_overhang: float = 0.0) -> Built:
    """A kitchen counter: a countertop slab on low cabinets.

    ``sections`` lists what sits under the top from local -x to +x, each an equal share of the
    width: ``"open"`` (an open low cabinet, interior surfaces tagged low-cabinet) or ``"closed"``
    (a solid block: dishwasher, blind corner). Default: one open section per ~0.9 m.
    ``sink_at`` / ``cooktop_at`` put a basin + tap / a cooktop at that local x. The countertop is a
    surface (tag ``"counter"``) with clearance ``top_clearance`` (the gap to wall cabinets above).
    ``back_overhang`` lets the top reach past the back of the cabinets (a bar on a peninsula).
    """
    top_t = 0.04
    w2, d2 = width / 2, depth / 2
    if sections is None:
        sections = ["open"] * max(1, round(width / 0.9))
    n = len(sections)
    sec_w = width / n
    carcass_d = depth - 0.02 - back_overhang  # the top overhangs the front by 2 cm
    carcass_y = -d2 + 0.02 + carcass_d / 2
    built = []
    for i, kind_i in enumerate(sections):
        lx = -w2 + (i + 0.5) * sec_w
        sx, sy = child_pose(x, y, yaw, lx, carcass_y)
        if kind_i == "open":
            built.append(open_cabinet(f"{name}/sec{i}", sx, sy, yaw, sec_w, carcass_d, height - top_t, n_boards,
                                      0.0, with_top=False, kind=kind, color=cabinet_color))
        elif kind_i == "closed":
            p = _Piece(f"{name}/sec{i}", sx, sy, yaw, kind, cabinet_color)
            p.box("block", -sec_w / 2, sec_w / 2, -carcass_d / 2, carcass_d / 2, 0.0, height - top_t)
            p.box("handle", -0.2, 0.2, -carcass_d / 2 - 0.02, -carcass_d / 2, height - 0.15, height - 0.13,
                  color=STEEL)
            built.append(p.built())
        else:
            raise ValueError(f"counter {name!r}: section {kind_i!r}; allowed: open, closed")
    top = _Piece(name, x, y, yaw, kind, top_color)
    top.box("top", -w2, w2, -d2, d2, height - top_t, height)
    top.surface("top_surface", -w2, w2, -d2, d2, height, top_clearance, tags=("counter",))
    if sink_at is not None:
        hw = min(0.3, width / 2 - 0.1)
        top.box("sink", sink_at - hw, sink_at + hw, -d2 + 0.06, d2 - 0.15, height, height + 0.03, color=STEEL,
                tags=("sink",))
        top.cyl("tap", sink_at, d2 - 0.08, height, height + 0.3, 0.035, color=STEEL, tags=("sink",))
    if cooktop_at is not None:
        top.box("cooktop", cooktop_at - 0.3, cooktop_at + 0.3, -0.25, 0.25, height, height + 0.01, color=BLACK,
                tags=("cooktop",))
    built.append(top.built())
    return merge(*built)


def kitchen_island(name: str, x: float, y: float, yaw: float = 0.0, width: float = 1.8, depth: float = 0.95,
                   height: float = 0.9, cabinet_color=LIGHT_WOOD, top_color=STONE) -> Built:
    """A free-standing counter: open low cabinets facing local -y, a bar overhang at +y."""
    return counter(name, x, y, yaw, width, depth, height, cabinet_color=cabinet_color, top_color=top_color,
                   kind="kitchen_island", back_overhang=0.3)


def fridge(name: str, x: float, y: float, yaw: float = 0.0, width: float = 0.75, depth: float = 0.7,
           height: float = 1.85, color=(0.85, 0.86, 0.88)) -> Built:
    w2, d2 = width / 2, depth / 2
    p = _Piece(name, x, y, yaw, "fridge", color)
    p.box("body", -w2, w2, -d2, d2, 0.0, height)
    p.box("handle", w2 - 0.1, w2 - 0.07, -d2 - 0.04, -d2, 0.9, 1.5, color=STEEL)
    return p.built()


def stool(name: str, x: float, y: float, height: float = 0.65, color=DARK_GREY) -> Built:
    p = _Piece(name, x, y, 0.0, "stool", color)
    p.cyl("base", 0, 0, 0.0, 0.03, 0.38)
    p.cyl("post", 0, 0, 0.03, height - 0.05, 0.05, color=STEEL)
    p.cyl("seat", 0, 0, height - 0.05, height, 0.36, color=color)
    return p.built()


# ----------------------------------------------------------------------------------- tables, seats
def table(name: str, x: float, y: float, yaw: float = 0.0, width: float = 1.2, depth: float = 0.8,
          height: float = 0.75, color=WOOD, kind: str = "table", lower_shelf: bool = False) -> Built:
    """A table with four legs; the top is a surface. ``lower_shelf`` adds a board near the floor."""
    w2, d2, t, leg = width / 2, depth / 2, 0.04, 0.05
    p = _Piece(name, x, y, yaw, kind, color)
    p.box("top", -w2, w2, -d2, d2, height - t, height)
    for i, (sx, sy) in enumerate(((-1, -1), (1, -1), (1, 1), (-1, 1))):
        lx, ly = sx * (w2 - 0.04 - leg / 2), sy * (d2 - 0.04 - leg / 2)
        p.box(f"leg{i}", lx - leg / 2, lx + leg / 2, ly - leg / 2, ly + leg / 2, 0.0, height - t)
    p.surface("top_surface", -w2, w2, -d2, d2, height, OPEN_TOP_CLEARANCE, tags=("table",))
    if lower_shelf:
        ix, iy = w2 - 0.04 - leg, d2 - 0.04 - leg
        zs = 0.1
        p.box("shelf", -ix, ix, -iy, iy, zs - PANEL, zs)
        p.surface("shelf_surface", -ix, ix, -iy, iy, zs, height - t - zs, tags=("lower_shelf",))
    return p.built()


def coffee_table(name: str, x: float, y: float, yaw: float = 0.0, width: float = 1.1, depth: float = 0.6,
                 height: float = 0.42, color=DARK_WOOD) -> Built:
    """A low table with a shelf board under the top (both surfaces)."""
    return table(name, x, y, yaw, width, depth, height, color, kind="coffee_table", lower_shelf=True)


def round_table(name: str, x: float, y: float, diameter: float = 0.5, height: float = 0.55, color=WOOD,
                kind: str = "side_table") -> Built:
    """A pedestal table with a round top; its surface is the square inscribed in the top."""
    p = _Piece(name, x, y, 0.0, kind, color)
    p.cyl("base", 0, 0, 0.0, 0.03, min(0.4, diameter * 0.7))
    p.cyl("post", 0, 0, 0.03, height - 0.03, 0.06)
    p.cyl("top", 0, 0, height - 0.03, height, diameter)
    h = diameter / (2 * math.sqrt(2))
    p.surface("top_surface", -h, h, -h, h, height, OPEN_TOP_CLEARANCE, tags=("table",), margin=0.01)
    return p.built()


def chair(name: str, x: float, y: float, yaw: float = 0.0, width: float = 0.44, depth: float = 0.46,
          seat_height: float = 0.46, back_height: float = 0.9, color=WOOD) -> Built:
    """A chair facing local -y (the back is at +y): seat (a surface), back and four legs."""
    w2, d2, leg = width / 2, depth / 2, 0.04
    p = _Piece(name, x, y, yaw, "chair", color)
    p.box("seat", -w2, w2, -d2, d2, seat_height - 0.04, seat_height)
    p.box("back", -w2, w2, d2 - 0.04, d2, seat_height, back_height)
    for i, (sx, sy) in enumerate(((-1, -1), (1, -1), (1, 1), (-1, 1))):
        lx, ly = sx * (w2 - leg / 2), sy * (d2 - leg / 2)
        p.box(f"leg{i}", lx - leg / 2, lx + leg / 2, ly - leg / 2, ly + leg / 2, 0.0, seat_height - 0.04)
    p.surface("seat_surface", -w2, w2, -d2, d2 - 0.04, seat_height, OPEN_TOP_CLEARANCE, tags=("seat",))
    return p.built()


def sofa(name: str, x: float, y: float, yaw: float = 0.0, width: float = 2.2, depth: float = 0.9,
         color=FABRIC_BLUE, kind: str = "sofa") -> Built:
    """A sofa facing local -y: base, back, two arms, a seat (a surface) and back cushions."""
    w2, d2, arm, back = width / 2, depth / 2, 0.18, 0.2
    seat_z = 0.45
    p = _Piece(name, x, y, yaw, kind, color)
    dark = tuple(0.8 * c for c in color)
    p.box("base", -w2 + arm, w2 - arm, -d2, d2 - back, 0.0, 0.3, color=dark)
    p.box("back", -w2, w2, d2 - back, d2, 0.0, 0.85, color=dark)
    p.box("arm_l", -w2, -w2 + arm, -d2, d2 - back, 0.0, 0.62, color=dark)
    p.box("arm_r", w2 - arm, w2, -d2, d2 - back, 0.0, 0.62, color=dark)
    p.box("seat", -w2 + arm, w2 - arm, -d2, d2 - back, 0.3, seat_z)
    n = max(1, round((width - 2 * arm) / 0.65))
    cw = (width - 2 * arm) / n
    for i in range(n):  # back cushions resting on the seat
        a = -w2 + arm + i * cw
        p.box(f"cushion{i}", a + 0.02, a + cw - 0.02, d2 - back - 0.14, d2 - back, seat_z, 0.78)
    p.surface("seat_surface", -w2 + arm, w2 - arm, -d2, d2 - back, seat_z, OPEN_TOP_CLEARANCE, tags=("seat",))
    return p.built()


def armchair(name: str, x: float, y: float, yaw: float = 0.0, color=FABRIC_GREEN) -> Built:
    return sofa(name, x, y, yaw, width=0.85, depth=0.85, color=color, kind="armchair")


def desk(name: str, x: float, y: float, yaw: float = 0.0, width: float = 1.2, depth: float = 0.6,
         color=LIGHT_WOOD, monitor: bool = True) -> Built:
    """A desk (a table against a wall) with a monitor near its back edge."""
    parts, surfaces = table(name, x, y, yaw, width, depth, 0.74, color, kind="desk")
    if monitor:
        p = _Piece(name, x, y, yaw, "desk", BLACK)
        yb = depth / 2 - 0.12
        p.box("monitor_foot", -0.12, 0.12, yb - 0.08, yb + 0.08, 0.74, 0.755, color=DARK_GREY)
        p.box("monitor_post", -0.025, 0.025, yb + 0.02, yb + 0.05, 0.755, 0.95, color=DARK_GREY)
        p.box("monitor", -0.3, 0.3, yb - 0.01, yb + 0.02, 0.9, 1.25)
        parts += p.parts
    return parts, surfaces


# ----------------------------------------------------------------------------------- living room
def tv_stand(name: str, x: float, y: float, yaw: float = 0.0, width: float = 1.8, depth: float = 0.45,
             height: float = 0.5, color=DARK_WOOD) -> Built:
    """A low open cabinet (interior tagged low-cabinet) with a TV standing on it."""
    parts, surfaces = open_cabinet(name, x, y, yaw, width, depth, height, 0, 0.0, kind="tv_stand", color=color)
    p = _Piece(name, x, y, yaw, "tv", BLACK)
    yb = depth / 2 - 0.13
    p.box("tv_foot", -0.2, 0.2, yb - 0.09, yb + 0.09, height, height + 0.02, color=DARK_GREY)
    p.box("tv_post", -0.03, 0.03, yb - 0.02, yb + 0.02, height + 0.02, height + 0.12, color=DARK_GREY)
    tv_w = min(1.3, width - 0.2)
    p.box("tv_screen", -tv_w / 2, tv_w / 2, yb - 0.03, yb + 0.03, height + 0.1, height + 0.1 + 0.56 * tv_w)
    return parts + p.parts, surfaces


def plant(name: str, x: float, y: float, height: float = 1.3, color=LEAF) -> Built:
    p = _Piece(name, x, y, 0.0, "plant", color)
    p.cyl("pot", 0, 0, 0.0, 0.35, 0.32, color=TERRACOTTA)
    p.cyl("leaves", 0, 0, 0.35, height, 0.5)
    return p.built()


def floor_lamp(name: str, x: float, y: float, height: float = 1.6) -> Built:
    p = _Piece(name, x, y, 0.0, "lamp", DARK_GREY)
    p.cyl("base", 0, 0, 0.0, 0.03, 0.3)
    p.cyl("pole", 0, 0, 0.03, height - 0.3, 0.03)
    p.cyl("shade", 0, 0, height - 0.3, height, 0.4, color=OFF_WHITE)
    return p.built()


# ----------------------------------------------------------------------------------- bedroom
def bed(name: str, x: float, y: float, yaw: float = 0.0, width: float = 1.6, length: float = 2.0,
        color=LIGHT_WOOD, linen=(0.85, 0.88, 0.92)) -> Built:
    """A bed with its head at local +y: frame, mattress (a surface), headboard and pillows."""
    w2, l2 = width / 2, length / 2
    p = _Piece(name, x, y, yaw, "bed", color)
    p.box("frame", -w2, w2, -l2, l2 - 0.06, 0.0, 0.3)
    p.box("headboard", -w2, w2, l2 - 0.06, l2, 0.0, 1.05)
    p.box("mattress", -w2 + 0.02, w2 - 0.02, -l2 + 0.02, l2 - 0.06, 0.3, 0.55, color=linen)
    n = 2 if width >= 1.2 else 1
    pw = (width - 0.2) / n
    for i in range(n):
        a = -w2 + 0.1 + i * pw
        p.box(f"pillow{i}", a + 0.03, a + pw - 0.03, l2 - 0.45, l2 - 0.1, 0.55, 0.67, color=(0.97, 0.97, 0.97))
    p.surface("mattress_surface", -w2 + 0.02, w2 - 0.02, -l2 + 0.02, l2 - 0.06, 0.55, OPEN_TOP_CLEARANCE,
              tags=("bed",))
    return p.built()


def nightstand(name: str, x: float, y: float, yaw: float = 0.0, width: float = 0.5, depth: float = 0.4,
               height: float = 0.55, color=LIGHT_WOOD, lamp: bool = True) -> Built:
    """A small open cabinet (one compartment, tagged low-cabinet) with a top and a table lamp."""
    parts, surfaces = open_cabinet(name, x, y, yaw, width, depth, height, 0, 0.0, kind="nightstand", color=color)
    if lamp:
        p = _Piece(name, x, y, yaw, "lamp", OFF_WHITE)
        lx, ly = width / 2 - 0.12, depth / 2 - 0.12
        p.cyl("lamp_base", lx, ly, height, height + 0.25, 0.04, color=DARK_GREY)
        p.cyl("lamp_shade", lx, ly, height + 0.2, height + 0.4, 0.2)
        parts += p.parts
    return parts, surfaces


# ----------------------------------------------------------------------------------- bathroom
def sink_cabinet(name: str, x: float, y: float, yaw: float = 0.0, width: float = 0.9, depth: float = 0.5,
                 height: float = 0.85, color=WHITE) -> Built:
    """A vanity: an open low cabinet under a top with a basin and a tap."""
    return counter(name, x, y, yaw, width, depth, height, sections=["open"], sink_at=0.0, cabinet_color=color,
                   top_color=PORCELAIN, n_boards=0, kind="sink_cabinet", top_clearance=0.55)


def toilet(name: str, x: float, y: float, yaw: float = 0.0, color=PORCELAIN) -> Built:
    """A toilet facing local -y (0.4 m wide, 0.68 m deep); the cistern lid is a surface."""
    d2 = 0.34
    p = _Piece(name, x, y, yaw, "toilet", color)
    p.box("cistern", -0.2, 0.2, d2 - 0.2, d2, 0.38, 0.8)
    p.box("pedestal", -0.12, 0.12, -d2 + 0.15, d2, 0.0, 0.38)
    p.cyl("bowl", 0, -d2 + 0.19, 0.2, 0.42, 0.38)
    p.surface("cistern_surface", -0.2, 0.2, d2 - 0.2, d2, 0.8, OPEN_TOP_CLEARANCE, tags=("toilet",), margin=0.02)
    return p.built()


def bathtub(name: str, x: float, y: float, yaw: float = 0.0, length: float = 1.7, depth: float = 0.75,
            height: float = 0.55, color=PORCELAIN) -> Built:
    """A hollow bathtub (length along local x): its inside floor is a surface."""
    l2, d2, t = length / 2, depth / 2, 0.08
    p = _Piece(name, x, y, yaw, "bathtub", color)
    p.box("bottom", -l2 + t, l2 - t, -d2 + t, d2 - t, 0.0, 0.1)
    p.box("rim_front", -l2, l2, -d2, -d2 + t, 0.0, height)
    p.box("rim_back", -l2, l2, d2 - t, d2, 0.0, height)
    p.box("rim_l", -l2, -l2 + t, -d2 + t, d2 - t, 0.0, height)
    p.box("rim_r", l2 - t, l2, -d2 + t, d2 - t, 0.0, height)
    p.cyl("tap", l2 - 0.12, d2 - 0.04, height, height + 0.15, 0.04, color=STEEL)
    p.surface("inside", -l2 + t, l2 - t, -d2 + t, d2 - t, 0.1, OPEN_TOP_CLEARANCE, tags=("bathtub",))
    return p.built()


def shelf_unit(name: str, x: float, y: float, yaw: float = 0.0, width: float = 0.6, depth: float = 0.3,
               height: float = 1.5, n_boards: int = 3, color=LIGHT_WOOD) -> Built:
    """A narrow open shelf (towels, toiletries); boards are surfaces, the top one too."""
    return open_cabinet(name, x, y, yaw, width, depth, height, n_boards, 0.0, n_columns=1, kind="shelf_unit",
                        interior_tags=("shelf",), top_surface=height <= 1.5, color=color)

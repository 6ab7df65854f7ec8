"""The scene description: plain data, no engine.

A home is a tuple of :class:`Part` (what is solid) and a tuple of :class:`SupportSurface`
(where a target may rest). Physics (``egosearch.sim.world``), the depth sensor
(``egosearch.sim.sensor``), the pictures (``egosearch.sim.render``) and the navigation grid
(``egosearch.sim.navgrid``) each build their own view from this one description.

Conventions, shared by every consumer:
- world frame: metres, z up, the floor is the plane z = 0;
- a part's ``center`` is the centre of its bounding box in the world frame, and ``yaw`` turns
  it about the vertical axis through that centre (furniture never tilts);
- ``size`` is the full extent along the part's local x, y, z axes. A cylinder's axis is local
  z and its diameter is ``size[0]`` (``size[1]`` must equal it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

SHAPES = ("box", "cylinder", "mesh")

#: Tags with a meaning the code relies on. Others (``"sofa"``, ``"sink"``...) are free text.
TAG_WALL = "wall"
TAG_FLOOR = "floor"
TAG_FURNITURE = "furniture"
TAG_TARGET = "target"
#: Parts without this tag are seen by the sensor but the body may pass through them
#: (e.g. a rug); every wall and furniture part is an obstacle.
TAG_OBSTACLE = "obstacle"
#: Surfaces inside low floor cabinets: the placement scheme ``no_low_cabinets`` skips them.
TAG_LOW_CABINET_INTERIOR = "low_cabinet_interior"


@dataclass(frozen=True)
class Part:
    """One solid piece of a home or one target object."""

    name: str
    """Unique within its scene, e.g. ``"kitchen/counter_top"``."""
    shape: str
    """One of :data:`SHAPES`."""
    center: tuple[float, float, float]
    """Centre of the bounding box in the world frame (m)."""
    size: tuple[float, float, float]
    """Full extent along local x, y, z (m). Cylinders: (diameter, diameter, height)."""
    yaw: float = 0.0
    """Rotation about the vertical axis through ``center`` (rad)."""
    tags: frozenset[str] = frozenset()
    """What the part is: see the ``TAG_*`` constants."""
    color: tuple[float, float, float] = (0.7, 0.7, 0.7)
    """RGB in [0, 1], for pictures only."""
    mesh_file: str | None = None
    """For ``shape == "mesh"``: a path relative to ``pybullet_data``'s data folder. The mesh is
    scaled uniformly to fit ``size`` and centred on ``center``."""

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise ValueError(f"Part {self.name!r}: shape={self.shape!r}; allowed: {', '.join(SHAPES)}")
        if len(self.center) != 3 or len(self.size) != 3:
            raise ValueError(f"Part {self.name!r}: center and size need 3 values each")
        if min(self.size) <= 0:
            raise ValueError(f"Part {self.name!r}: size={self.size} must be positive")
        if self.shape == "cylinder" and not math.isclose(self.size[0], self.size[1]):
            raise ValueError(f"Part {self.name!r}: a cylinder needs size[0] == size[1] (diameter)")
        if self.shape == "mesh" and not self.mesh_file:
            raise ValueError(f"Part {self.name!r}: a mesh part needs mesh_file")
        object.__setattr__(self, "tags", frozenset(self.tags))

    @property
    def is_obstacle(self) -> bool:
        return TAG_OBSTACLE in self.tags

    def footprint_corners(self) -> list[tuple[float, float]]:
        """The four corners of the part's footprint (x, y) in the world frame."""
        return rectangle_corners(self.center[:2], self.size[:2], self.yaw)

    @property
    def z_min(self) -> float:
        return self.center[2] - self.size[2] / 2

    @property
    def z_max(self) -> float:
        return self.center[2] + self.size[2] / 2


@dataclass(frozen=True)
class SupportSurface:
    """A horizontal rectangle a target may rest on: a table top, a shelf board, the floor."""

    name: str
    """Unique within its scene."""
    center: tuple[float, float, float]
    """Centre of the rectangle; ``center[2]`` is the height of the surface itself (m)."""
    size: tuple[float, float]
    """Extent along the surface's local x and y (m)."""
    yaw: float = 0.0
    """Rotation about the vertical axis (rad)."""
    clearance: float = 2.0
    """Free height above the surface (m): a shelf board below another has less."""
    tags: frozenset[str] = frozenset()
    """e.g. ``{"table"}``, ``{"floor"}``, ``{TAG_LOW_CABINET_INTERIOR}``."""

    def __post_init__(self) -> None:
        if min(self.size) <= 0 or self.clearance <= 0:
            raise ValueError(f"SupportSurface {self.name!r}: size and clearance must be positive")
        object.__setattr__(self, "tags", frozenset(self.tags))

    @property
    def area(self) -> float:
        return self.size[0] * self.size[1]


@dataclass(frozen=True)
class Scene:
    """A whole home: what is solid and where targets may rest."""

    name: str
    """``"kitchen_living"``, ``"bedroom_bath"`` or ``"home<seed>"``."""
    parts: tuple[Part, ...]
    """Walls, floor, furniture (never the target: that is added per scenario)."""
    surfaces: tuple[SupportSurface, ...]
    """Every place a target may be put."""
    bounds: tuple[float, float, float, float]
    """Interior (x_min, y_min, x_max, y_max) of the home (m)."""
    wall_height: float = 2.6
    """Height of the outer walls (m)."""
    meta: dict = field(default_factory=dict, compare=False, hash=False)
    """Free-form facts for pictures and docs (room labels and their centres...)."""

    def __post_init__(self) -> None:
        names = [p.name for p in self.parts] + [s.name for s in self.surfaces]
        dupes = sorted({n for n in names if names.count(n) > 1})
        if dupes:
            raise ValueError(f"Scene {self.name!r}: duplicate part/surface names {dupes}")

    def part(self, name: str) -> Part:
        for p in self.parts:
            if p.name == name:
                return p
        raise KeyError(name)

    @property
    def obstacles(self) -> tuple[Part, ...]:
        return tuple(p for p in self.parts if p.is_obstacle)

    @property
    def size_xy(self) -> tuple[float, float]:
        x0, y0, x1, y1 = self.bounds
        return (x1 - x0, y1 - y0)

    def with_parts(self, extra: tuple[Part, ...]) -> Scene:
        """A copy with ``extra`` parts appended (e.g. a placed target)."""
        return Scene(self.name, self.parts + tuple(extra), self.surfaces, self.bounds,
                     self.wall_height, self.meta)


def rectangle_corners(center_xy, size_xy, yaw: float) -> list[tuple[float, float]]:
    """Corners of a yawed rectangle, counter-clockwise."""
    c, s = math.cos(yaw), math.sin(yaw)
    hx, hy = size_xy[0] / 2, size_xy[1] / 2
    out = []
    for lx, ly in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)):
        out.append((center_xy[0] + c * lx - s * ly, center_xy[1] + s * lx + c * ly))
    return out


def to_local(point_xy, center_xy, yaw: float) -> tuple[float, float]:
    """World (x, y) into the frame of a rectangle centred at ``center_xy`` turned by ``yaw``."""
    dx, dy = point_xy[0] - center_xy[0], point_xy[1] - center_xy[1]
    c, s = math.cos(yaw), math.sin(yaw)
    return (c * dx + s * dy, -s * dx + c * dy)


def to_world(local_xy, center_xy, yaw: float) -> tuple[float, float]:
    """Inverse of :func:`to_local`."""
    c, s = math.cos(yaw), math.sin(yaw)
    return (center_xy[0] + c * local_xy[0] - s * local_xy[1],
            center_xy[1] + s * local_xy[0] + c * local_xy[1])

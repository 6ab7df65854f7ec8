"""Where a target may be put: placement schemes (paper section 6.1) and the sampler.

The paper evaluates two schemes: ``"no_low_cabinets"`` samples everywhere except inside the
low cabinets on the floor, ``"everywhere"`` samples every surface.

Sampling (:func:`sample_target`): first a *piece* uniformly (a piece of furniture, or the
floor of one room: the surfaces sharing the first two parts of their name, such as all boards
of ``kitchen/counter_north``), then one of its surfaces with probability proportional to area,
then a position uniform over the places where the object's whole (yawed) footprint lies inside
that surface, with a uniform yaw. A spot that would not fit under the surface's clearance or
would overlap an obstacle is rejected and the whole draw repeated.

Why pieces and not plain area: by area the floor, the largest surface by far, takes about 80%
of all targets and the cabinets almost none, whereas the paper's targets are household items
left "on any surface ... including the interior of cabinets" (6.1). Each piece being equally
likely reads as "someone left it somewhere", and puts about one target in six inside a low
cabinet under ``everywhere``.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from egosearch.scene.objects import TargetObject, target_part
from egosearch.scene.parts import TAG_LOW_CABINET_INTERIOR, Part, Scene, SupportSurface, to_local, to_world

PLACEMENT_SCHEMES = ("no_low_cabinets", "everywhere")
_EPS = 1e-6


class PlacementError(RuntimeError):
    """No valid spot was found for a target."""


def eligible_surfaces(scene: Scene, scheme: str) -> tuple[SupportSurface, ...]:
    """The surfaces a scheme allows: ``no_low_cabinets`` drops low-cabinet interiors."""
    if scheme not in PLACEMENT_SCHEMES:
        raise ValueError(f"placement scheme={scheme!r}; allowed: {', '.join(PLACEMENT_SCHEMES)}")
    if scheme == "everywhere":
        return scene.surfaces
    return tuple(s for s in scene.surfaces if TAG_LOW_CABINET_INTERIOR not in s.tags)


# ----------------------------------------------------------------------------------- geometry
def _corners(part: Part) -> np.ndarray:
    return np.asarray(part.footprint_corners())


def _separated(a: np.ndarray, b: np.ndarray) -> bool:
    """Separating axis test for two convex quadrilaterals (4 x 2 corners, in order)."""
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=0) - poly
        for ex, ey in edges[:2]:  # rectangles: two edge directions suffice
            axis = np.array([-ey, ex])
            pa, pb = a @ axis, b @ axis
            if pa.max() <= pb.min() + _EPS * math.hypot(ex, ey) or pb.max() <= pa.min() + _EPS * math.hypot(ex, ey):
                return True
    return False


@functools.lru_cache(maxsize=16)
def _obstacle_table(scene: Scene) -> tuple[tuple[Part, ...], np.ndarray, np.ndarray]:
    """Obstacles of ``scene`` with their world AABBs (x0, y0, x1, y1, z0, z1) and corners."""
    obstacles = scene.obstacles
    corners = np.array([_corners(p) for p in obstacles]).reshape(-1, 4, 2)
    boxes = np.column_stack([corners[:, :, 0].min(1), corners[:, :, 1].min(1), corners[:, :, 0].max(1),
                             corners[:, :, 1].max(1), [p.z_min for p in obstacles], [p.z_max for p in obstacles]])
    return obstacles, boxes, corners


def overlaps_obstacle(scene: Scene, part: Part) -> bool:
    """Whether ``part`` overlaps an obstacle of ``scene`` (other than a part of the same name).

    Two parts overlap when their z-ranges overlap and their footprints do (separating axis
    test on the yawed rectangles; a cylinder counts as its bounding box). Touching is not overlap.
    """
    obstacles, boxes, corners = _obstacle_table(scene)
    if not obstacles:
        return False
    mine = _corners(part)
    (x0, y0), (x1, y1) = mine.min(0), mine.max(0)
    cand = np.nonzero((boxes[:, 0] < x1 - _EPS) & (boxes[:, 2] > x0 + _EPS) & (boxes[:, 1] < y1 - _EPS)
                      & (boxes[:, 3] > y0 + _EPS) & (boxes[:, 4] < part.z_max - _EPS)
                      & (boxes[:, 5] > part.z_min + _EPS))[0]
    for i in cand:
        if obstacles[i].name == part.name:
            continue
        if not _separated(mine, corners[i]):
            return True
    return False


def _inside(surface: SupportSurface, corners: np.ndarray, tol: float) -> bool:
    for c in corners:
        lx, ly = to_local(c, surface.center[:2], surface.yaw)
        if abs(lx) > surface.size[0] / 2 + tol or abs(ly) > surface.size[1] / 2 + tol:
            return False
    return True


def rests_on_support(scene: Scene, part: Part, tol: float = 1e-3) -> SupportSurface | None:
    """The surface ``part`` stands on: its bottom at the surface height (within ``tol``) and its
    whole footprint inside the surface rectangle. None when there is none."""
    corners = _corners(part)
    for s in scene.surfaces:
        if abs(part.z_min - s.center[2]) <= tol and _inside(s, corners, tol):
            return s
    return None


# ----------------------------------------------------------------------------------- sampling
def piece_of(surface: SupportSurface) -> str:
    """The piece a surface belongs to: the first two parts of its name (``dining/sideboard``)."""
    return "/".join(surface.name.split("/")[:2])


def sample_target(scene: Scene, obj: TargetObject, scheme: str, rng: np.random.Generator,
                  max_tries: int = 200) -> Part:
    """A random collision-free resting spot for ``obj`` under ``scheme``, as the target Part.

    Piece uniform, surface ~ area within the piece (among the surfaces whose clearance fits the
    object), position uniform with the
    yawed footprint inside the surface, yaw uniform in [-pi, pi), bottom exactly on the surface.
    Raises :class:`PlacementError` after ``max_tries`` rejected draws.
    """
    surfaces = [s for s in eligible_surfaces(scene, scheme) if s.clearance > obj.size[2] + 1e-3]
    if not surfaces:
        raise PlacementError(f"no {scheme} surface of {scene.name!r} has room for {obj.name!r} "
                             f"({obj.size[2]:.3f} m tall)")
    pieces: dict[str, list[SupportSurface]] = {}
    for surface in surfaces:
        pieces.setdefault(piece_of(surface), []).append(surface)
    groups = [(members, np.array([m.area for m in members]) / sum(m.area for m in members))
              for members in pieces.values()]
    hx, hy = obj.size[0] / 2, obj.size[1] / 2
    for _ in range(max_tries):
        members, weights = groups[int(rng.integers(len(groups)))]
        s = members[int(rng.choice(len(members), p=weights))]
        yaw = float(rng.uniform(-math.pi, math.pi))
        rel = yaw - s.yaw
        c, si = abs(math.cos(rel)), abs(math.sin(rel))
        ex, ey = c * hx + si * hy, si * hx + c * hy  # half extents in the surface frame
        fx, fy = s.size[0] / 2 - ex, s.size[1] / 2 - ey
        if fx < 0 or fy < 0:
            continue
        lx, ly = float(rng.uniform(-fx, fx)), float(rng.uniform(-fy, fy))
        x, y = to_world((lx, ly), s.center[:2], s.yaw)
        part = target_part(obj, x, y, s.center[2], yaw)
        if not overlaps_obstacle(scene, part):
            return part
    raise PlacementError(f"no free spot for {obj.name!r} in {scene.name!r} ({scheme}) after {max_tries} tries")

"""How deep the body cylinder is inside the scene's parts, from the parts' own numbers.

This reads the scene description only (no physics engine), so it can check what pybullet does:
the body is an upright cylinder of ``radius`` from ``z0`` to ``z1`` centred at (x, y). Boxes are
yawed rectangles extruded along z, cylinders upright circles, meshes their bounding box (as
:func:`egosearch.sim.world.add_static_part` builds them).
"""

from __future__ import annotations

import math
from collections.abc import Iterable

from egosearch.scene.parts import Part, to_local


def part_penetration(part: Part, x: float, y: float, radius: float, z0: float, z1: float) -> float:
    """Depth (m, >= 0) of the shortest move that takes the body out of ``part``: the smaller of
    the horizontal push-out and the vertical overlap; 0 when they are apart or only touch."""
    vertical = min(z1, part.z_max) - max(z0, part.z_min)
    if vertical <= 0:
        return 0.0
    if part.shape == "cylinder":
        horizontal = radius + part.size[0] / 2 - math.hypot(x - part.center[0], y - part.center[1])
    else:
        lx, ly = to_local((x, y), part.center[:2], part.yaw)
        qx, qy = abs(lx) - part.size[0] / 2, abs(ly) - part.size[1] / 2
        if qx > 0 or qy > 0:  # the axis is outside the footprint
            horizontal = radius - math.hypot(max(qx, 0.0), max(qy, 0.0))
        else:  # the axis is inside: leave by the nearest side
            horizontal = radius + min(-qx, -qy)
    return max(0.0, min(horizontal, vertical))


def deepest_penetration(parts: Iterable[Part], x: float, y: float, radius: float, z0: float,
                        z1: float) -> tuple[float, str | None]:
    """(depth in m, part name) of the part the body is deepest inside; (0.0, None) when free.
    Only obstacles count: a rug or the floor is never inside the body."""
    worst, name = 0.0, None
    for part in parts:
        if not part.is_obstacle:
            continue
        depth = part_penetration(part, x, y, radius, z0, z1)
        if depth > worst:
            worst, name = depth, part.name
    return worst, name

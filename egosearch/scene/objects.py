"""The target objects: real sizes, and the Part a placed target becomes.

Mesh targets use meshes shipped with ``pybullet_data``. A mesh part is scaled uniformly to fit
its ``size`` (see :func:`egosearch.scene.meshes.part_mesh`), so a mesh target's ``size`` is the
mesh's own extents times one scale: the bounding box of the drawn mesh is exactly ``size``.
Meshes are used as stored (only yaw turns them): the duck and the teddy files are y-up, so in
this z-up world they lie on their side / back; their ``size`` says so honestly.
"""

from __future__ import annotations

from dataclasses import dataclass

from egosearch.scene.meshes import mesh_extents_ratio
from egosearch.scene.parts import SHAPES, TAG_TARGET, Part


@dataclass(frozen=True)
class TargetObject:
    """One searchable object of real size."""

    name: str
    shape: str
    """``"box"``, ``"cylinder"`` (axis vertical, ``size[0] == size[1]``) or ``"mesh"``."""
    size: tuple[float, float, float]
    """Full extent along local x, y, z (m); for meshes, the scaled mesh's own extents."""
    mesh_file: str | None = None
    """Path relative to ``pybullet_data`` for mesh objects."""
    color: tuple[float, float, float] = (0.8, 0.2, 0.2)

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise ValueError(f"TargetObject {self.name!r}: shape={self.shape!r}; allowed: {', '.join(SHAPES)}")
        if (self.shape == "mesh") != (self.mesh_file is not None):
            raise ValueError(f"TargetObject {self.name!r}: mesh_file is required for meshes and only for them")

    @property
    def height(self) -> float:
        return self.size[2]


def _mesh_object(name: str, mesh_file: str, longest: float, color) -> TargetObject:
    """A mesh object scaled uniformly so its longest extent is ``longest`` metres."""
    ratio = mesh_extents_ratio(mesh_file)
    size = tuple(float(r) * longest for r in ratio)
    return TargetObject(name, "mesh", size, mesh_file, color)


def _catalogue() -> dict[str, TargetObject]:
    objs = [
        TargetObject("mustard_bottle", "box", (0.095, 0.06, 0.19), color=(0.95, 0.80, 0.10)),
        TargetObject("glasses_case", "box", (0.16, 0.065, 0.04), color=(0.15, 0.25, 0.60)),
        # objects/mug.obj: 0.674 x 1 x 0.822 (handle along y) -> 0.081 x 0.12 x 0.099 m.
        _mesh_object("mug", "objects/mug.obj", 0.12, (0.85, 0.30, 0.20)),
        TargetObject("remote", "box", (0.18, 0.05, 0.025), color=(0.10, 0.10, 0.12)),
        # duck_vhacd.obj: 1 x 0.935 x 0.701 -> 0.12 x 0.112 x 0.084 m.
        _mesh_object("duck", "duck_vhacd.obj", 0.12, (1.00, 0.85, 0.10)),
        # teddy2_VHACD_CHs.obj: 0.816 x 1 x 0.673 (stored y-up) -> 0.204 x 0.25 x 0.168 m.
        _mesh_object("teddy", "teddy2_VHACD_CHs.obj", 0.25, (0.60, 0.40, 0.22)),
        TargetObject("book", "box", (0.24, 0.17, 0.03), color=(0.70, 0.15, 0.15)),
        TargetObject("phone", "box", (0.15, 0.075, 0.009), color=(0.12, 0.12, 0.14)),
        TargetObject("keys", "box", (0.08, 0.04, 0.02), color=(0.75, 0.72, 0.55)),
        TargetObject("soda_can", "cylinder", (0.066, 0.066, 0.122), color=(0.85, 0.10, 0.10)),
        TargetObject("cereal_box", "box", (0.19, 0.07, 0.28), color=(0.90, 0.55, 0.15)),
    ]
    return {o.name: o for o in objs}


#: Every searchable object by name (mesh sizes are read from the shipped files once).
TARGET_OBJECTS: dict[str, TargetObject] = _catalogue()


def get_object(name: str) -> TargetObject:
    """The catalogue entry ``name``; a ValueError names the allowed ones."""
    if name not in TARGET_OBJECTS:
        raise ValueError(f"target object={name!r}; allowed: {', '.join(TARGET_OBJECTS)}")
    return TARGET_OBJECTS[name]


def target_part(obj: TargetObject, x: float, y: float, z_bottom: float, yaw: float = 0.0) -> Part:
    """The Part named ``"target"`` for ``obj`` standing with its bottom at ``z_bottom``."""
    return Part("target", obj.shape, (float(x), float(y), float(z_bottom) + obj.size[2] / 2), tuple(obj.size),
                float(yaw), frozenset({TAG_TARGET}), tuple(obj.color), obj.mesh_file)

"""Triangle meshes of scene parts, in the world frame, for the renderers and the sensor."""

from __future__ import annotations

import functools
import os

import numpy as np
import trimesh

from egosearch.scene.parts import Part, Scene

#: Facets of a cylinder's side. 16 keeps a round table round in a 100x100 depth image
#: and keeps the house near 10k triangles.
CYLINDER_SECTIONS = 16


def pybullet_data_path(relative: str) -> str:
    """Absolute path of a file shipped in ``pybullet_data`` (no downloads, ever)."""
    import pybullet_data

    path = os.path.join(pybullet_data.getDataPath(), relative)
    if not os.path.exists(path):
        raise FileNotFoundError(f"{relative!r} is not in pybullet_data ({pybullet_data.getDataPath()})")
    return path


@functools.lru_cache(maxsize=32)
def _unit_mesh(mesh_file: str) -> trimesh.Trimesh:
    """A shipped mesh centred on its bounding box and scaled so its largest extent is 1."""
    mesh = trimesh.load(pybullet_data_path(mesh_file), force="mesh", process=True)
    mesh.apply_translation(-mesh.bounds.mean(axis=0))
    mesh.apply_scale(1.0 / float(mesh.extents.max()))
    return mesh


def mesh_extents_ratio(mesh_file: str) -> np.ndarray:
    """Extents of the shipped mesh with its largest extent scaled to 1."""
    return _unit_mesh(mesh_file).extents.copy()


def part_mesh(part: Part) -> trimesh.Trimesh:
    """The part as a triangle mesh in the world frame."""
    if part.shape == "box":
        mesh = trimesh.creation.box(extents=part.size)
    elif part.shape == "cylinder":
        mesh = trimesh.creation.cylinder(radius=part.size[0] / 2, height=part.size[2],
                                         sections=CYLINDER_SECTIONS)
    else:
        unit = _unit_mesh(part.mesh_file)
        # Uniform scale so the mesh fits inside the requested box without distortion.
        scale = float(np.min(np.asarray(part.size) / np.maximum(unit.extents, 1e-9)))
        mesh = unit.copy()
        mesh.apply_scale(scale)
    transform = trimesh.transformations.rotation_matrix(part.yaw, (0, 0, 1))
    transform[:3, 3] = part.center
    mesh.apply_transform(transform)
    return mesh


def scene_meshes(scene: Scene) -> list[tuple[Part, trimesh.Trimesh]]:
    """Every part with its world-frame mesh, in scene order."""
    return [(part, part_mesh(part)) for part in scene.parts]


def triangle_count(scene: Scene) -> int:
    return sum(len(m.faces) for _, m in scene_meshes(scene))

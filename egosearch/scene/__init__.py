"""Homes as plain data: parts, layouts, target objects and their placement (no engine, no renderer).
Imports: nothing.
Imported by: cli, motion, report, rl, runs, sim, variants, Snakefile.
Packages: matplotlib, numpy, pybullet_data, scipy, trimesh.
No engine and no renderer: matplotlib only for the top-down drawings, pybullet_data only for the meshes it ships."""

from egosearch.scene.layouts import LAYOUT_NAMES, get_scene, random_home
from egosearch.scene.objects import TARGET_OBJECTS, get_object
from egosearch.scene.parts import (
    SHAPES,
    TAG_FLOOR,
    TAG_FURNITURE,
    TAG_LOW_CABINET_INTERIOR,
    TAG_OBSTACLE,
    TAG_TARGET,
    TAG_WALL,
    Part,
    Scene,
    SupportSurface,
)
from egosearch.scene.placement import PLACEMENT_SCHEMES, sample_target

__all__ = [
    "SHAPES", "TAG_FLOOR", "TAG_FURNITURE", "TAG_LOW_CABINET_INTERIOR", "TAG_OBSTACLE",
    "TAG_TARGET", "TAG_WALL", "Part", "Scene", "SupportSurface",
    "LAYOUT_NAMES", "get_scene", "random_home", "TARGET_OBJECTS", "get_object",
    "PLACEMENT_SCHEMES", "sample_target",
]

"""Homes as plain data: parts, layouts, target objects and their placement."""

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

__all__ = [
    "SHAPES", "TAG_FLOOR", "TAG_FURNITURE", "TAG_LOW_CABINET_INTERIOR", "TAG_OBSTACLE",
    "TAG_TARGET", "TAG_WALL", "Part", "Scene", "SupportSurface",
]

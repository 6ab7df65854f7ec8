"""A clean top-down map of a home (like the paper's Figure 4), drawn with matplotlib (Agg)."""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Circle, Polygon, Rectangle  # noqa: E402

from egosearch.scene.parts import (  # noqa: E402
    TAG_FURNITURE,
    TAG_LOW_CABINET_INTERIOR,
    TAG_WALL,
    Part,
    Scene,
    rectangle_corners,
)

_MOUNTED = 1.2  # parts whose bottom is above this (wall cabinets) are drawn see-through
_LOW_CAB = (0.85, 0.2, 0.15)


def _shade(color, k: float):
    return tuple(max(0.0, min(1.0, c * k)) for c in color)


def plot_topdown(scene: Scene, ax=None, targets=(), starts=(), title: str | None = None):
    """Draw ``scene`` from above and return the figure.

    Walls are dark, furniture footprints take their part colour (higher parts drawn over
    lower ones, wall cabinets see-through and dashed), low-cabinet interiors are hatched red.
    ``targets``: Parts or (x, y) points, drawn as stars; ``starts``: (x, y) or (x, y, yaw)
    agent starts, drawn as circles of the body radius with a heading tick.
    """
    if ax is None:
        x0, y0, x1, y1 = scene.bounds
        fig, ax = plt.subplots(figsize=(1.0 + 0.75 * (x1 - x0), 0.6 + 0.75 * (y1 - y0)))
    else:
        fig = ax.figure
    x0, y0, x1, y1 = scene.bounds
    ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor=(0.96, 0.94, 0.90), edgecolor="none", zorder=0))
    for s in scene.surfaces:  # floor rectangles, faint
        if "floor" in s.tags:
            ax.add_patch(Polygon(rectangle_corners(s.center[:2], s.size, s.yaw), closed=True, facecolor="none",
                                 edgecolor=(0.85, 0.82, 0.76), lw=0.5, zorder=0.5))
    # Lintels over doorways are left out so the doorways show.
    solid = [p for p in scene.parts if p.is_obstacle and not (TAG_WALL in p.tags and p.z_min >= 1.8)]
    for z, p in enumerate(sorted(solid, key=lambda p: (TAG_WALL in p.tags, p.z_max))):
        wall = TAG_WALL in p.tags
        mounted = p.z_min > _MOUNTED and not wall
        face = (0.18, 0.18, 0.2) if wall else p.color
        kw = dict(facecolor=face, edgecolor=(0.1, 0.1, 0.1) if wall else _shade(p.color, 0.55),
                  lw=0.3 if wall else 0.5, alpha=0.35 if mounted else 1.0, ls="--" if mounted else "-",
                  zorder=1 + z * 1e-3 + (2 if mounted else 0) + (3 if wall else 0))
        if p.shape == "cylinder":
            ax.add_patch(Circle(p.center[:2], p.size[0] / 2, **kw))
        else:
            ax.add_patch(Polygon(p.footprint_corners(), closed=True, **kw))
    for s in scene.surfaces:
        if TAG_LOW_CABINET_INTERIOR in s.tags:
            ax.add_patch(Polygon(rectangle_corners(s.center[:2], s.size, s.yaw), closed=True, facecolor="none",
                                 edgecolor=_LOW_CAB, hatch="////", lw=0.6, zorder=2.5))
    for label, (lx, ly) in scene.meta.get("rooms", []):
        ax.text(lx, ly, label, ha="center", va="center", fontsize=10, color=(0.3, 0.3, 0.35), style="italic",
                zorder=9, bbox=dict(boxstyle="round,pad=0.2", fc=(1, 1, 1, 0.6), ec="none"))
    for t in targets:
        tx, ty = (t.center[0], t.center[1]) if isinstance(t, Part) else (t[0], t[1])
        ax.plot(tx, ty, marker="*", ms=14, color=(1.0, 0.8, 0.0), mec="k", mew=0.8, zorder=10)
    for st in starts:
        ax.add_patch(Circle((st[0], st[1]), 0.2, facecolor=(0.2, 0.5, 0.9, 0.5), edgecolor=(0.1, 0.3, 0.7),
                            zorder=10))
        if len(st) > 2:
            ax.plot([st[0], st[0] + 0.35 * math.cos(st[2])], [st[1], st[1] + 0.35 * math.sin(st[2])],
                    color=(0.1, 0.3, 0.7), lw=1.5, zorder=10)
    # 1 m scale bar under the south-west corner.
    sb_y = y0 - 0.35
    ax.plot([x0, x0 + 1.0], [sb_y, sb_y], color="k", lw=2.5, solid_capstyle="butt")
    ax.text(x0 + 0.5, sb_y - 0.08, "1 m", ha="center", va="top", fontsize=8)
    ax.set_xlim(x0 - 0.3, x1 + 0.3)
    ax.set_ylim(y0 - 0.7, y1 + 0.3)
    ax.set_aspect("equal")
    ax.set_axis_off()
    n_furn = sum(TAG_FURNITURE in p.tags for p in scene.parts)
    ax.set_title(title if title is not None else f"{scene.name}  ({x1 - x0:g} x {y1 - y0:g} m, "
                 f"{n_furn} furniture parts)", fontsize=10)
    fig.tight_layout()
    return fig

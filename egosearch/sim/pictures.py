"""``egosearch pictures``: the world's figures for one home, as PNG.

- ``<layout>_topdown.png``: the top-down map (the paper's Figure 4);
- ``<layout>_placements.png``: targets placed by both schemes, close up (Figure 5);
- ``<layout>_views.png``: one first-person depth + mask frame beside a third-person RGB view of
  the abstract searcher (Figure 1).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from egosearch.scene.layouts import get_scene
from egosearch.scene.objects import TARGET_OBJECTS, get_object
from egosearch.scene.parts import TAG_LOW_CABINET_INTERIOR, Part
from egosearch.scene.placement import PLACEMENT_SCHEMES, rests_on_support, sample_target
from egosearch.scene.topdown import plot_topdown
from egosearch.sim.body import AgentSpec
from egosearch.sim.render import SceneRenderer, depth_to_colormap
from egosearch.sim.scenarios import navgrid_for, visible_from
from egosearch.sim.sensor import DepthMaskSensor

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")


def agent_parts(x: float, y: float, yaw: float, camera_height: float):
    """The abstract searcher drawn as parts: a body cylinder and a camera box on a neck."""
    spec = AgentSpec()
    body_top = max(0.2, camera_height - 0.15)
    parts = [Part("agent/body", "cylinder", (x, y, body_top / 2), (2 * spec.body_radius,) * 2 + (body_top,),
                  color=(0.2, 0.45, 0.85)),
             Part("agent/camera", "box",
                  (x + 0.08 * math.cos(yaw), y + 0.08 * math.sin(yaw), camera_height),
                  (0.16, 0.1, 0.08), yaw=yaw, color=(0.1, 0.1, 0.1))]
    return parts


def _viewpoint(layout: str, target, height: float, rng, near: float = 0.8, far: float = 1.8):
    """A free body position from which the camera at ``height`` sees the target."""
    grid = navgrid_for(layout)
    gx, gy = np.meshgrid(grid.xs, grid.ys)
    d = np.hypot(gx - target.center[0], gy - target.center[1])
    rows, cols = np.nonzero(grid.main_region & (d >= near) & (d <= far))
    if len(rows) == 0:
        return None
    order = rng.permutation(len(rows))[:400]
    cams = np.column_stack([grid.xs[cols[order]], grid.ys[rows[order]], np.full(len(order), height)])
    seen = visible_from(layout, cams, target)
    if not seen.any():
        return None
    return cams[int(np.argmax(seen))]


def _over_the_shoulder(layout: str, scene, x: float, y: float, yaw: float, height: float):
    """A third-person eye behind the searcher that sees it past walls and furniture."""
    head = Part("probe", "box", (x, y, height - 0.3), (0.3, 0.3, 0.6))
    x0, y0, x1, y1 = scene.bounds
    candidates = []
    for distance in (2.4, 1.9, 1.4, 1.0):
        for turn in (0.0, 0.4, -0.4, 0.8, -0.8, 1.2, -1.2):
            a = yaw + math.pi + turn
            ex, ey = x + distance * math.cos(a), y + distance * math.sin(a)
            if x0 + 0.1 < ex < x1 - 0.1 and y0 + 0.1 < ey < y1 - 0.1:
                candidates.append((ex, ey, min(2.3, scene.wall_height - 0.2)))
    seen = visible_from(layout, np.asarray(candidates), head)
    return candidates[int(np.argmax(seen))] if seen.any() else (x, y, scene.wall_height - 0.2)


def make_pictures(layout: str, out_dir: str | os.PathLike, seed: int = 0) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt


    scene = get_scene(layout)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    written = []

    # Figure 4: the map, with a few example targets of each scheme.
    names = sorted(TARGET_OBJECTS)
    targets = [sample_target(scene, get_object(names[i % len(names)]), PLACEMENT_SCHEMES[i % 2], rng)
               for i in range(12)]
    fig = plot_topdown(scene, targets=targets)
    path = out / f"{layout}_topdown.png"
    fig.savefig(path, dpi=150, bbox_inches="tight")
    plt.close(fig)
    written.append(path)

    # Figure 5: close-ups of placements, half of them inside low cabinets when possible.

    shots = []
    tries = 0
    while len(shots) < 6 and tries < 200:
        tries += 1
        scheme = "everywhere" if len(shots) % 2 else "no_low_cabinets"
        obj = get_object(names[int(rng.integers(len(names)))])
        target = sample_target(scene, obj, scheme, rng)
        if scheme == "everywhere":
            surface = rests_on_support(scene, target)
            if surface is None or TAG_LOW_CABINET_INTERIOR not in surface.tags:
                continue
        eye = _viewpoint(layout, target, height=min(1.2, target.center[2] + 0.7), rng=rng)
        if eye is None:
            continue
        renderer = SceneRenderer(scene, target=target)
        image = renderer.third_person_rgb(eye, target.center, width=480, height=360, fov_deg=50)
        where = "inside a low cabinet" if scheme == "everywhere" else "no_low_cabinets"
        shots.append((image, f"{obj.name} ({where})"))
    fig, axes = plt.subplots(2, 3, figsize=(12, 6.4))
    for ax, (image, title) in zip(axes.ravel(), shots):
        ax.imshow(image)
        ax.set_title(title, fontsize=9)
    for ax in axes.ravel():
        ax.axis("off")
    fig.suptitle(f"Object placements in {layout}")
    fig.tight_layout()
    path = out / f"{layout}_placements.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    written.append(path)

    # Figure 1: what the searcher sees, and the searcher seen from behind.
    height = 1.65
    for _ in range(50):
        target = sample_target(scene, get_object("mustard_bottle"), "no_low_cabinets", rng)
        eye = _viewpoint(layout, target, height, rng, near=1.0, far=2.5)
        if eye is not None:
            break
    x, y = float(eye[0]), float(eye[1])
    yaw = math.atan2(target.center[1] - y, target.center[0] - x)
    pitch = math.atan2(target.center[2] - height, math.hypot(target.center[0] - x, target.center[1] - y))
    sensor = DepthMaskSensor(scene)
    sensor.set_target(target)
    depth, mask = sensor.render((x, y, height), yaw, pitch)
    first_person = depth_to_colormap(depth, mask, max_depth=sensor.max_depth)
    renderer = SceneRenderer(scene.with_parts(tuple(agent_parts(x, y, yaw, height))), target=target)
    eye3 = _over_the_shoulder(layout, scene, x, y, yaw, height)
    third_person = renderer.third_person_rgb(eye3, (x + math.cos(yaw), y + math.sin(yaw), 0.6),
                                             width=640, height=480, fov_deg=70)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.6), gridspec_kw={"width_ratios": [4, 3]})
    axes[0].imshow(third_person)
    axes[0].set_title("third-person view")
    axes[1].imshow(first_person)
    axes[1].set_title("first-person depth (target mask in red)")
    for ax in axes:
        ax.axis("off")
    fig.tight_layout()
    path = out / f"{layout}_views.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    written.append(path)
    return written

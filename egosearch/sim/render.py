"""Pictures of a scene with pyrender (figures, videos, and a cross-check of the sensor).

Never on the training hot path: the training sensor is :class:`egosearch.sim.sensor.DepthMaskSensor`.
The camera convention (yaw, pitch, pixel centres, z-depth, horizontal field of view) is the one
documented in :mod:`egosearch.sim.sensor`.

Headless use needs ``PYOPENGL_PLATFORM=egl`` (set here by default before pyrender is imported).
The depth pass runs WITHOUT multisampling: pyrender 0.1.45 always renders into a 4x multisample
framebuffer (``Renderer._configure_main_framebuffer`` hard-codes 4 samples; no flag turns it off)
and resolves depth with a nearest-sample blit, i.e. at a sample position that is not the pixel
centre. :class:`SceneRenderer` replaces that method on its own renderer instance with one that
allocates single-sample buffers for depth, so each pixel is sampled at its centre like the
sensor's rays. Colour pictures keep 4x MSAA (smoother edges).
"""

from __future__ import annotations

import math
import os
import types
from collections.abc import Iterable, Sequence

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

import numpy as np  # noqa: E402
import trimesh  # noqa: E402

from egosearch.scene.meshes import part_mesh  # noqa: E402
from egosearch.scene.parts import Part, Scene  # noqa: E402
from egosearch.sim.sensor import (  # noqa: E402
    DEFAULT_FOV_DEG,
    DEFAULT_HEIGHT,
    DEFAULT_MAX_DEPTH,
    DEFAULT_WIDTH,
    camera_axes,
    vertical_fov_deg,
)

TARGET_NODE = "target"
Z_NEAR = 0.02
Z_FAR = 100.0


def _pyrender():
    import pyrender

    return pyrender


def camera_pose(position, yaw: float, pitch: float) -> np.ndarray:
    """4x4 pyrender (OpenGL) camera pose for the sensor convention: x right, y up, looks along -z."""
    right, up, forward = camera_axes(yaw, pitch)
    pose = np.eye(4)
    pose[:3, 0] = right
    pose[:3, 1] = up
    pose[:3, 2] = -forward
    pose[:3, 3] = position
    return pose


def look_at_pose(eye, look_at) -> np.ndarray:
    """4x4 OpenGL camera pose at ``eye`` looking at ``look_at``, no roll (world z up)."""
    eye = np.asarray(eye, float)
    forward = np.asarray(look_at, float) - eye
    dist = np.linalg.norm(forward)
    if dist < 1e-9:
        raise ValueError("eye and look_at coincide")
    forward /= dist
    yaw = math.atan2(forward[1], forward[0]) if math.hypot(forward[0], forward[1]) > 1e-9 else 0.0
    pitch = math.asin(max(-1.0, min(1.0, forward[2])))
    return camera_pose(eye, yaw, pitch)


def _configure_main_framebuffer_samples(self):
    """pyrender's ``Renderer._configure_main_framebuffer`` with a selectable sample count.

    ``self._egosearch_samples`` (0 = no multisampling, pyrender's default is 4) is read on every
    render; the framebuffers are rebuilt when it changes.
    """
    import pyrender.renderer as prr

    want = int(getattr(self, "_egosearch_samples", 4))
    if self._main_fb is not None and getattr(self, "_egosearch_fb_samples", None) != want:
        self._delete_main_framebuffer()
    original = prr.glRenderbufferStorageMultisample

    def storage(target, _samples, internal_format, width, height):
        return original(target, want, internal_format, width, height)

    prr.glRenderbufferStorageMultisample = storage
    try:
        prr.Renderer._configure_main_framebuffer(self)
    finally:
        prr.glRenderbufferStorageMultisample = original
    self._egosearch_fb_samples = want


class SceneRenderer:
    """pyrender view of a :class:`Scene`: parts merged by (colour, tags), lights, a camera.

    ``hide_tags`` in the picture methods hides every part carrying one of those tags.
    """

    def __init__(self, scene: Scene, target: Part | None = None, max_depth: float = DEFAULT_MAX_DEPTH,
                 bg_color: Sequence[float] = (1.0, 1.0, 1.0), ambient: float = 0.35):
        pyrender = _pyrender()
        self.scene = scene
        self.max_depth = float(max_depth)
        self._pr_scene = pyrender.Scene(bg_color=(*bg_color[:3], 1.0), ambient_light=(ambient,) * 3)
        self._tag_nodes: list[tuple[frozenset[str], object]] = []
        groups: dict[tuple, list[trimesh.Trimesh]] = {}
        for part in scene.parts:
            key = (tuple(round(c, 4) for c in part.color), part.tags)
            groups.setdefault(key, []).append(part_mesh(part))
        for (color, tags), meshes in groups.items():
            node = self._pr_scene.add(self._pr_mesh(meshes, color), name="/".join(sorted(tags)) or "part")
            self._tag_nodes.append((frozenset(tags), node))
        # Two soft directional lights from above plus the ambient term.
        for direction, intensity in (((0.4, 0.3, -1.0), 1.6), ((-0.5, -0.6, -0.8), 0.9)):
            light = pyrender.DirectionalLight(color=np.ones(3), intensity=intensity)
            self._pr_scene.add(light, pose=look_at_pose((0, 0, 0), direction))
        self._camera_node = None
        self._target_node = None
        self.target: Part | None = None
        self._offscreen = None
        self.set_target(target)

    @staticmethod
    def _pr_mesh(meshes: list[trimesh.Trimesh], color) -> object:
        pyrender = _pyrender()
        merged = trimesh.util.concatenate(meshes) if len(meshes) > 1 else meshes[0]
        material = pyrender.MetallicRoughnessMaterial(baseColorFactor=(*color[:3], 1.0), metallicFactor=0.0,
                                                      roughnessFactor=0.9)
        return pyrender.Mesh.from_trimesh(merged, material=material, smooth=False)

    def set_target(self, target: Part | None) -> None:
        if self._target_node is not None:
            self._pr_scene.remove_node(self._target_node)
            self._target_node = None
        self.target = target
        if target is not None:
            self._target_node = self._pr_scene.add(self._pr_mesh([part_mesh(target)], target.color),
                                                   name=TARGET_NODE)

    # -- low level ------------------------------------------------------------------------------

    def _renderer(self, width: int, height: int, msaa: bool):
        """The one offscreen renderer (one GL context: pyrender binds meshes to a context)."""
        if self._offscreen is None:
            self._offscreen = _pyrender().OffscreenRenderer(width, height)
            inner = self._offscreen._renderer
            inner._configure_main_framebuffer = types.MethodType(_configure_main_framebuffer_samples, inner)
        self._offscreen.viewport_width, self._offscreen.viewport_height = int(width), int(height)
        self._offscreen._renderer._egosearch_samples = 4 if msaa else 0
        return self._offscreen

    def _set_camera(self, camera, pose: np.ndarray) -> None:
        if self._camera_node is not None:
            self._pr_scene.remove_node(self._camera_node)
        self._camera_node = self._pr_scene.add(camera, pose=pose)
        self._pr_scene.main_camera_node = self._camera_node

    def _perspective(self, width: int, height: int, fov_deg: float):
        return _pyrender().PerspectiveCamera(yfov=math.radians(vertical_fov_deg(width, height, fov_deg)),
                                             aspectRatio=width / height, znear=Z_NEAR, zfar=Z_FAR)

    def _render(self, camera, pose, width, height, flags, msaa, hide_tags: Iterable[str] = ()):
        hide = frozenset(hide_tags)
        hidden = []
        for tags, node in self._tag_nodes:
            if tags & hide and node.mesh.is_visible:
                node.mesh.is_visible = False
                hidden.append(node)
        try:
            self._set_camera(camera, pose)
            return self._renderer(width, height, msaa).render(self._pr_scene, flags=flags)
        finally:
            for node in hidden:
                node.mesh.is_visible = True

    # -- pictures -------------------------------------------------------------------------------

    def depth(self, position, yaw: float, pitch: float, width: int = DEFAULT_WIDTH,
              height: int = DEFAULT_HEIGHT, fov_deg: float = DEFAULT_FOV_DEG) -> np.ndarray:
        """float32 z-depth (m), sensor convention; no MSAA, no face culling; misses and anything
        beyond ``max_depth`` read ``max_depth``."""
        flags = _pyrender().RenderFlags.DEPTH_ONLY | _pyrender().RenderFlags.SKIP_CULL_FACES
        d = self._render(self._perspective(width, height, fov_deg), camera_pose(position, yaw, pitch),
                         width, height, flags, msaa=False)
        d = np.asarray(d, np.float32).copy()
        d[(d <= 0) | (d > self.max_depth)] = self.max_depth
        return d

    def first_person_rgb(self, position, yaw: float, pitch: float, width: int = 320, height: int = 320,
                         fov_deg: float = DEFAULT_FOV_DEG, hide_tags: Iterable[str] = ()) -> np.ndarray:
        """uint8 RGB through the agent's camera (same convention and horizontal FOV as the sensor)."""
        color, _ = self._render(self._perspective(width, height, fov_deg), camera_pose(position, yaw, pitch),
                                width, height, _pyrender().RenderFlags.NONE, msaa=True, hide_tags=hide_tags)
        return np.ascontiguousarray(color[..., :3])

    def third_person_rgb(self, eye, look_at, width: int = 640, height: int = 480, fov_deg: float = 60.0,
                         hide_tags: Iterable[str] = ("ceiling",)) -> np.ndarray:
        """uint8 RGB from ``eye`` looking at ``look_at`` (horizontal FOV ``fov_deg``), ceiling hidden."""
        color, _ = self._render(self._perspective(width, height, fov_deg), look_at_pose(eye, look_at),
                                width, height, _pyrender().RenderFlags.NONE, msaa=True, hide_tags=hide_tags)
        return np.ascontiguousarray(color[..., :3])

    def top_down_rgb(self, width: int = 640, height: int | None = None, margin: float = 0.3,
                     hide_tags: Iterable[str] = ("ceiling",)) -> tuple[np.ndarray, dict]:
        """Orthographic view from above: image up = +y, right = +x.

        Returns the picture and ``{"x0", "y1", "px_per_m"}`` to map world (x, y) to pixels:
        ``col = (x - x0) * px_per_m``, ``row = (y1 - y) * px_per_m``.
        """
        x0, y0, x1, y1 = self.scene.bounds
        x0, y0, x1, y1 = x0 - margin, y0 - margin, x1 + margin, y1 + margin
        px_per_m = width / (x1 - x0)
        if height is None:
            height = int(round((y1 - y0) * px_per_m))
        else:
            px_per_m = min(px_per_m, height / (y1 - y0))
        half_w, half_h = width / px_per_m / 2, height / px_per_m / 2
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        camera = _pyrender().OrthographicCamera(xmag=half_w, ymag=half_h, znear=0.05, zfar=Z_FAR)
        pose = np.eye(4)
        pose[:3, 3] = (cx, cy, self.scene.wall_height + 10.0)
        color, _ = self._render(camera, pose, width, height, _pyrender().RenderFlags.NONE, msaa=True,
                                hide_tags=hide_tags)
        return np.ascontiguousarray(color[..., :3]), {"x0": cx - half_w, "y1": cy + half_h,
                                                      "px_per_m": px_per_m}

    def close(self) -> None:
        if self._offscreen is not None:
            try:
                self._offscreen.delete()
            except Exception:  # noqa: BLE001 - best effort on shutdown
                pass
            self._offscreen = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def depth_to_colormap(depth_m: np.ndarray, mask: np.ndarray | None = None,
                      max_depth: float = DEFAULT_MAX_DEPTH, cmap: str = "gray",
                      mask_color: Sequence[int] = (230, 30, 30)) -> np.ndarray:
    """uint8 RGB picture of a depth image (near = dark, ``max_depth`` = bright for ``"gray"``;
    any matplotlib colormap name otherwise) with the target mask painted in ``mask_color``."""
    d = np.clip(np.asarray(depth_m, np.float64) / max_depth, 0.0, 1.0)
    if cmap == "gray":
        rgb = np.repeat((d * 255.0 + 0.5).astype(np.uint8)[..., None], 3, axis=2)
    else:
        import matplotlib

        rgb = (matplotlib.colormaps[cmap](d)[..., :3] * 255.0 + 0.5).astype(np.uint8)
    if mask is not None:
        rgb[np.asarray(mask, bool)] = np.asarray(mask_color, np.uint8)
    return rgb


def upscale(image: np.ndarray, factor: int) -> np.ndarray:
    """Nearest-neighbour enlargement (for looking at 100x100 sensor images)."""
    return np.repeat(np.repeat(image, factor, axis=0), factor, axis=1)

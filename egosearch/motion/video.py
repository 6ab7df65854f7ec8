"""Search videos of full-body characters, like the paper's Figures 1 and 3.

Each frame puts what the character's camera sees (the depth image with the target mask in red,
as the policy gets it) beside a third-person view of the home with the character drawn from its
collision shapes (the humanoid's spheres, capsules and feet boxes; Fetch's cylinders and boxes),
its camera as a small dark box, the current abstract plan as grey dots on the floor, and a red
ring around the target. The ring is drawn on the picture, not in the scene, so it shows where the
target is even while furniture hides it (targets inside cabinets are the common case). Under the
first-person view each frame names its step, whether the target is seen and its distance (the
one of the success test: from the body's surface to the target's centre, horizontally).

The third-person picture has its own pyrender scene built from the scene parts with
:func:`egosearch.scene.meshes.part_mesh`, so the character can move without rebuilding the home.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

import numpy as np  # noqa: E402
import trimesh  # noqa: E402

from egosearch.motion import quat  # noqa: E402
from egosearch.motion.base import FullBodyPose  # noqa: E402
from egosearch.motion.fetch import FETCH_PARTS
from egosearch.motion.humanoid import HUMANOID_SCALE, limb_shapes
from egosearch.motion.replan import make_motion_generator, run_fullbody_episode
from egosearch.runs.evaluate import make_env
from egosearch.scene.meshes import part_mesh
from egosearch.sim.body import STEP_SECONDS  # noqa: E402
from egosearch.sim.env import target_distance
from egosearch.sim.render import depth_to_colormap, look_at_pose, upscale
from egosearch.sim.scenarios import MAX_STEPS

CHARACTERS = ("humanoid_phase", "humanoid_matching", "fetch")
FRAME_HEIGHT = 384
THIRD_WIDTH = 512
HUMANOID_COLOR = (0.25, 0.5, 0.85)
FETCH_COLOR = (0.85, 0.85, 0.88)
CAMERA_COLOR = (0.1, 0.1, 0.1)
PLAN_COLOR = (0.55, 0.55, 0.55)
TARGET_RING_COLOR = (230, 30, 30)
"""The first-person mask's red (:func:`egosearch.sim.render.depth_to_colormap`): one colour for the target."""
TARGET_RING_RADIUS = 0.3
"""m around the target's centre: wide enough to read at the follow camera's distance."""
THIRD_YFOV_DEG = 55.0
LABEL_SIZE = 17
END_HOLD_SECONDS = 1.5
GIF_MAX_BYTES = 3_000_000
"""A film small enough to sit in a README page."""


class NotACleanSuccess(RuntimeError):
    """The episode to film did not succeed, or some pose of it put a limb inside the home."""


def clean_successes(runs, min_steps: int = 0) -> list[int]:
    """Scenario ids of a full-body CSV's episodes that succeeded with no penetrating pose (none of
    the character's collision shapes more than :data:`~egosearch.motion.collision.PENETRATION_DEPTH`
    inside furniture or walls) in at least ``min_steps`` steps, in scenario_id order: the films'
    candidates, so that a film never shows a body passing through the home."""
    ok = runs["success"].astype(bool) & (runs["penetrations"] == 0) & (runs["steps"] >= min_steps)
    return sorted(int(i) for i in runs.loc[ok, "scenario_id"])


def _transform(position, rotation=None) -> np.ndarray:
    t = np.eye(4)
    if rotation is not None:
        x, y, z, w = rotation
        t[:3, :3] = trimesh.transformations.quaternion_matrix([w, x, y, z])[:3, :3]
    t[:3, 3] = position
    return t


def _centred(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    mesh.apply_translation(-mesh.bounds.mean(axis=0))
    return mesh


def camera_mesh(pose: FullBodyPose) -> trimesh.Trimesh:
    """A small box at the camera, turned by the head's yaw and pitch."""
    yaw = pose.theta + pose.head_yaw
    rot = quat.mul(quat.yaw(yaw), quat.from_axis_angle((0, 1, 0), -pose.pitch))
    box = trimesh.creation.box(extents=(0.12, 0.08, 0.06))
    box.apply_translation((0.1, 0.0, 0.0))
    box.apply_transform(_transform((pose.x, pose.y, pose.camera_height), rot))
    return box


def humanoid_mesh(pose: FullBodyPose) -> trimesh.Trimesh:
    s = HUMANOID_SCALE
    meshes = []
    for shape, centre, rot in limb_shapes(pose, s):
        if shape.kind == "sphere":
            m = trimesh.creation.icosphere(subdivisions=2, radius=shape.radius * s)
        elif shape.kind == "capsule":
            m = _centred(trimesh.creation.capsule(height=shape.length * s, radius=shape.radius * s, count=[12, 12]))
        else:
            m = trimesh.creation.box(extents=np.asarray(shape.size) * s)
        m.apply_transform(_transform(centre, rot))
        meshes.append(m)
    return trimesh.util.concatenate(meshes)


def fetch_mesh(pose: FullBodyPose) -> trimesh.Trimesh:
    meshes = []
    for kind, centre, dims in FETCH_PARTS:
        if kind == "cylinder":
            m = trimesh.creation.cylinder(radius=dims[0], height=dims[1], sections=24)
        else:
            m = trimesh.creation.box(extents=dims)
        m.apply_translation(centre)
        meshes.append(m)
    body = trimesh.util.concatenate(meshes)
    body.apply_transform(_transform((pose.x, pose.y, 0.0), quat.yaw(pose.theta)))
    return body


def plan_mesh(plan) -> trimesh.Trimesh | None:
    if not plan:
        return None
    dots = []
    for s in plan:
        d = trimesh.creation.cylinder(radius=0.04, height=0.01, sections=12)
        d.apply_translation((s.x, s.y, 0.01))
        dots.append(d)
    return trimesh.util.concatenate(dots)


class CharacterView:
    """pyrender third-person views of a home with one moving character."""

    def __init__(self, scene, target=None, width: int = THIRD_WIDTH, height: int = FRAME_HEIGHT):
        import pyrender


        self._pyrender = pyrender
        self._look_at_pose = look_at_pose
        self.width, self.height = width, height
        self.scene = pyrender.Scene(bg_color=(1.0, 1.0, 1.0, 1.0), ambient_light=(0.35,) * 3)
        groups: dict[tuple, list] = {}
        parts = [p for p in scene.parts if "ceiling" not in p.tags] + ([target] if target is not None else [])
        for part in parts:
            groups.setdefault(tuple(round(c, 4) for c in part.color), []).append(part_mesh(part))
        for color, meshes in groups.items():
            self.scene.add(self._mesh(trimesh.util.concatenate(meshes), color))
        for direction, intensity in (((0.4, 0.3, -1.0), 1.6), ((-0.5, -0.6, -0.8), 0.9)):
            light = pyrender.DirectionalLight(color=np.ones(3), intensity=intensity)
            self.scene.add(light, pose=look_at_pose((0, 0, 0), direction))
        self.camera = pyrender.PerspectiveCamera(yfov=math.radians(THIRD_YFOV_DEG), aspectRatio=width / height)
        self._camera_node = self.scene.add(self.camera, pose=np.eye(4))
        self.camera_pose = np.eye(4)
        self._dynamic: list = []
        self._renderer = pyrender.OffscreenRenderer(width, height)

    def _mesh(self, mesh: trimesh.Trimesh, color):
        pr = self._pyrender
        material = pr.MetallicRoughnessMaterial(baseColorFactor=(*color[:3], 1.0), metallicFactor=0.0,
                                                roughnessFactor=0.9)
        return pr.Mesh.from_trimesh(mesh, material=material, smooth=False)

    def render(self, items: list[tuple[trimesh.Trimesh, tuple]], eye, look_at) -> np.ndarray:
        for node in self._dynamic:
            self.scene.remove_node(node)
        self._dynamic = [self.scene.add(self._mesh(m, c)) for m, c in items if m is not None]
        self.camera_pose = self._look_at_pose(eye, look_at)
        self.scene.set_pose(self._camera_node, self.camera_pose)
        color, _ = self._renderer.render(self.scene)
        return np.ascontiguousarray(color[..., :3])

    def project(self, point) -> tuple[float, float, float] | None:
        """(column, row, pixels per metre) of a world point in the last rendered picture; None behind
        the camera."""
        x, y, z, _ = np.linalg.inv(self.camera_pose) @ np.append(np.asarray(point, float), 1.0)
        if z >= -1e-6:  # OpenGL: the camera looks along -z
            return None
        f = 0.5 * self.height / math.tan(math.radians(THIRD_YFOV_DEG) / 2)
        return 0.5 * self.width + f * x / -z, 0.5 * self.height - f * y / -z, f / -z

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.delete()
            self._renderer = None


def _character_items(character: str, pose: FullBodyPose, plan) -> list:
    body = fetch_mesh(pose) if character == "fetch" else humanoid_mesh(pose)
    color = FETCH_COLOR if character == "fetch" else HUMANOID_COLOR
    return [(body, color), (camera_mesh(pose), CAMERA_COLOR), (plan_mesh(plan), PLAN_COLOR)]


def _font(size: int):
    from PIL import ImageFont

    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1: the fixed bitmap font
        return ImageFont.load_default()


def _draw_target_ring(third: np.ndarray, view: CharacterView, target) -> np.ndarray:
    from PIL import Image, ImageDraw

    at = view.project(target.center)
    if at is None:
        return third
    u, v, px_per_m = at
    r = float(np.clip(TARGET_RING_RADIUS * px_per_m, 8.0, 80.0))
    image = Image.fromarray(third)
    ImageDraw.Draw(image).ellipse((u - r, v - r, u + r, v + r), outline=TARGET_RING_COLOR, width=3)
    return np.asarray(image)


def frame_label(step: int, max_steps: int, visible: bool, distance: float, found: bool) -> tuple[str, str]:
    """The two lines written under the first-person view."""
    seen = "target found" if found else ("target seen" if visible else "target not seen")
    return f"step {step} / {max_steps}", f"{seen}, {distance:.2f} m away"


def _write_label(first: np.ndarray, top: str, bottom: str, margin: int) -> np.ndarray:
    """``top`` and ``bottom`` centred in the white margins (``margin`` rows each) above and below the
    depth picture."""
    from PIL import Image, ImageDraw

    image = Image.fromarray(first)
    draw = ImageDraw.Draw(image)
    font = _font(LABEL_SIZE)
    y = max(margin, LABEL_SIZE + 4) / 2
    for text, at in ((top, y), (bottom, first.shape[0] - y)):
        draw.text((first.shape[1] / 2, at), text, fill=(0, 0, 0), font=font, anchor="mm")
    return np.asarray(image)


def write_gif(path: Path, frames: list[np.ndarray], max_bytes: int = GIF_MAX_BYTES) -> int:
    """Write ``frames`` (one per step) as a looping GIF of at most ``max_bytes``: a long episode keeps
    every k-th step (and the last), each shown k steps long, so the film stays the whole search in real
    time at a lower frame rate. The last frame is held, so the loop does not restart the moment the
    target is found. Returns k."""
    import imageio.v2 as imageio

    for k in range(1, len(frames) + 1):
        keep = list(range(0, len(frames) - 1, k)) + [len(frames) - 1]
        durations = [k * STEP_SECONDS * 1000] * (len(keep) - 1) + [END_HOLD_SECONDS * 1000]
        imageio.mimsave(path, [frames[i] for i in keep], duration=durations, loop=0)
        if path.stat().st_size <= max_bytes:
            break
    return k


VIDEO_SUFFIXES = (".mp4", ".gif")
"""The formats :func:`write_search_video` writes a film in."""


def write_search_video(layout: str, character: str, policy, scenario, out_path: str | os.PathLike,
                       still_path: str | os.PathLike | None = None, method: str = "ours", M: int = 5,
                       T: int = 20, seed: int = 0, env_id: str = "EgoSearch-v0",
                       require_clean: bool = False, env_kwargs: dict | None = None) -> dict:
    """Run one full-body episode and write it as a video (``.mp4`` or ``.gif``) plus one still PNG.

    Args:
        character: ``humanoid_phase``, ``humanoid_matching`` or ``fetch`` (the motion generator).
        policy: a policy (``reset``/``act``) or a factory ``policy(env)`` (e.g. ``OraclePolicy``).
        still_path: the frame where the target is found (else the last one), as PNG.
        seed: the episode's seed; ``egosearch fullbody`` seeds scenario k with its ``--seed`` + k.
        require_clean: raise :class:`NotACleanSuccess` before drawing anything unless the episode
            succeeds with no penetrating pose.
        env_kwargs: the env's observation options (a trained actor's recorded ones).
    Returns the episode's row (see :data:`egosearch.motion.replan.FULLBODY_COLUMNS`) with the paths.
    """
    import imageio.v2 as imageio


    if character not in CHARACTERS:
        raise ValueError(f"character={character!r}; allowed: {', '.join(CHARACTERS)}")
    # imageio picks its writer by the suffix, and fails on an unknown one only after the search ran
    if not os.fspath(out_path).lower().endswith(VIDEO_SUFFIXES):
        raise ValueError(f"{os.fspath(out_path)}: a video is written as {' or '.join(VIDEO_SUFFIXES)}")
    if still_path is not None and not os.fspath(still_path).lower().endswith(".png"):
        raise ValueError(f"{os.fspath(still_path)}: the still is written as .png")
    if scenario.layout != layout:
        raise ValueError(f"scenario {scenario.scenario_id} is in {scenario.layout!r}, not {layout!r}")
    env = make_env(env_id, scenario, **(env_kwargs or {}))
    view = None
    try:
        u = env.unwrapped
        pol = policy(env) if isinstance(policy, type) or not hasattr(policy, "act") else policy
        mg = make_motion_generator(character, u.world)
        trace: list = []
        row = run_fullbody_episode(env, pol, mg, scenario, T=T, M=M, seed=seed, method=method, trace=trace)
        if require_clean and not (row["success"] and row["penetrations"] == 0):
            raise NotACleanSuccess(f"scenario {scenario.scenario_id} with seed {seed}: success {row['success']}, "
                                   f"{row['penetrations']} penetrating pose(s) in {row['steps']} steps")
        view = CharacterView(u.scene, u.target)
        kind = "fetch" if character == "fetch" else "humanoid"
        frames = []
        cam_yaw = trace[0]["pose"].theta
        radius = u.spec_agent.body_radius
        for step, item in enumerate(trace):
            q, s = item["pose"], item["state"]
            depth, mask = u.sensor.render(s.camera_position, s.camera_yaw, s.pitch)
            first = depth_to_colormap(depth, mask, max_depth=u.sensor.max_depth)
            factor = max(1, FRAME_HEIGHT // first.shape[0])
            first = upscale(first, factor)
            pad = FRAME_HEIGHT - first.shape[0]
            if pad > 0:
                first = np.pad(first, ((pad // 2, pad - pad // 2), (pad // 2, pad - pad // 2), (0, 0)),
                               constant_values=255)
            found = bool(row["success"]) and step == len(trace) - 1
            first = _write_label(first, *frame_label(step, MAX_STEPS, item["visible"],
                                                     target_distance(s, u.target, radius), found), pad // 2)
            # A follow camera behind and above the character, turning smoothly.
            cam_yaw += 0.3 * math.atan2(math.sin(q.theta - cam_yaw), math.cos(q.theta - cam_yaw))
            c, sn = math.cos(cam_yaw), math.sin(cam_yaw)
            eye = (q.x - 2.2 * c, q.y - 2.2 * sn, 3.3)
            look = (q.x + 0.6 * c, q.y + 0.6 * sn, 0.7)
            third = _draw_target_ring(view.render(_character_items(kind, q, item["plan"]), eye, look), view, u.target)
            frames.append(np.concatenate([first[:, :FRAME_HEIGHT], third], axis=1))
        out_path = Path(out_path)
        out_path.parent.mkdir(parents=True, exist_ok=True)
        fps = 1.0 / STEP_SECONDS
        if out_path.suffix.lower() == ".gif":
            write_gif(out_path, frames)
        else:
            with imageio.get_writer(out_path, fps=fps, codec="libx264", quality=7, macro_block_size=16) as w:
                for f in frames:
                    w.append_data(f)
        row["video"] = str(out_path)
        if still_path is not None:
            still_path = Path(still_path)
            still_path.parent.mkdir(parents=True, exist_ok=True)
            seen = [i for i, item in enumerate(trace) if item["visible"]]
            imageio.imwrite(still_path, frames[seen[-1] if seen else -1])
            row["still"] = str(still_path)
        return row
    finally:
        if view is not None:
            view.close()
        env.close()

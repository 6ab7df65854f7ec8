"""DeepMimic motion clips from ``pybullet_data/data/motions`` as numpy arrays (no downloads).

A clip file is JSON ``{"Loop": ..., "Frames": [[duration, root xyz, root quat (w x y z), chest
quat, neck quat, right hip quat, right knee angle, right ankle quat, right shoulder quat, right
elbow angle, left hip quat, left knee, left ankle quat, left shoulder quat, left elbow], ...]}``
in DeepMimic's y-up frame, root positions in metres for the humanoid at ``globalScaling=0.25``.
The last frame repeats the first one cycle later (duration 0), so a looping clip has
``N - 1`` distinct frames.

:func:`load_clip` converts to our z-up world (see :mod:`egosearch.motion.skeleton`) and to the
humanoid's scale. :func:`make_track` re-expresses a clip in the character frame the motion
generators use: per frame, the root's ground velocity in the facing frame, the facing's turn
rate, and the pose relative to the facing frame, resampled at any rate, optionally played
backwards or bent into a curve (database augmentation for motion matching).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from egosearch.motion import quat
from egosearch.motion.skeleton import (
    MOCAP_JOINTS,
    MOCAP_SCALE,
    REVOLUTE,
    SPHERICAL,
    eye_position,
    forward_kinematics,
    point_on,
    pybullet_data_path,
)

MOTIONS_DIR = "data/motions"
#: Clips the motion generators use (all ship with pybullet_data).
LOCOMOTION_CLIPS = ("walk", "run", "spin")
#: Standard deviation (s) of the Gaussian that smooths the pelvis yaw into the facing direction.
FACING_SMOOTHING_S = 0.25
#: A clip whose pelvis heading changes less than this over one cycle (rad) is taken to go
#: straight: DeepMimic's walk ends its cycle 0.12 rad off its start while its root travels in a
#: straight line, a loop-closure error of the capture, not a turn.
LOOP_DRIFT_RAD = 0.3


def clip_path(name: str):
    path = pybullet_data_path() / MOTIONS_DIR / f"humanoid3d_{name}.txt"
    if not path.exists():
        known = sorted(p.stem.replace("humanoid3d_", "") for p in (pybullet_data_path() / MOTIONS_DIR).glob(
            "humanoid3d_*.txt"))
        raise ValueError(f"clip {name!r} is not in pybullet_data; known: {', '.join(known)}")
    return path


@dataclass
class Clip:
    """One looping clip in our z-up world at the humanoid's scale."""

    name: str
    dt: float
    """Native frame duration (s)."""
    root_pos: np.ndarray
    """(N, 3) pelvis positions (m), z up."""
    root_rot: np.ndarray
    """(N, 4) pelvis orientations (x, y, z, w) in the world; the model's frame is y-up, so the
    identity pose corresponds to ``quat.Y_UP_TO_Z_UP``."""
    joints: dict[str, np.ndarray]
    """Spherical joints: (N, 4) quaternions (x, y, z, w); revolute joints: (N,) angles (rad)."""
    scale: float
    """pybullet ``globalScaling`` of the humanoid these positions fit."""
    loop: bool = True

    @property
    def n_frames(self) -> int:
        return len(self.root_pos)

    @property
    def duration(self) -> float:
        """One cycle (s)."""
        return self.dt * (self.n_frames - 1)

    @property
    def times(self) -> np.ndarray:
        return np.arange(self.n_frames) * self.dt


@lru_cache(maxsize=32)
def load_clip(name: str, scale: float) -> Clip:
    """Load ``humanoid3d_<name>.txt`` for a humanoid loaded at ``globalScaling=scale``."""
    data = json.loads(clip_path(name).read_text())
    frames = np.asarray(data["Frames"], dtype=np.float64)
    if frames.shape[1] != 44:
        raise ValueError(f"clip {name!r}: expected 44 values per frame, got {frames.shape[1]}")
    durations = frames[:-1, 0]
    dt = float(np.median(durations))
    if not np.allclose(durations, dt, rtol=1e-3):
        raise ValueError(f"clip {name!r}: frames of unequal duration are not supported")
    ratio = scale / MOCAP_SCALE
    root_pos = quat.rotate(quat.Y_UP_TO_Z_UP, frames[:, 1:4]) * ratio
    root_rot = quat.mul(quat.Y_UP_TO_Z_UP, _wxyz_to_xyzw(frames[:, 4:8]))
    joints = {}
    col = 8
    for jname, n in MOCAP_JOINTS:
        if n == 4:
            joints[jname] = quat.normalize(_wxyz_to_xyzw(frames[:, col:col + 4]))
        else:
            joints[jname] = frames[:, col].copy()
        col += n
    return Clip(name, dt, root_pos, quat.normalize(root_rot), joints, scale,
                loop=str(data.get("Loop", "wrap")).lower() != "none")


def _wxyz_to_xyzw(q: np.ndarray) -> np.ndarray:
    return np.concatenate([q[..., 1:4], q[..., :1]], axis=-1)


# -- the character frame ---------------------------------------------------------------------------

@dataclass
class CharacterFrames:
    """A clip in the character frame, at its native frames 0..N-2 (one cycle)."""

    facing: np.ndarray
    """(N-1,) smoothed pelvis heading (rad, unwrapped, world)."""
    vel_local: np.ndarray
    """(N-1, 2) ground velocity of the root in the facing frame (m/s): (forward, left)."""
    omega: np.ndarray
    """(N-1,) facing turn rate (rad/s)."""
    root_z: np.ndarray
    root_local: np.ndarray
    """(N-1, 4) pelvis rotation with the facing removed."""


def character_frames(clip: Clip) -> CharacterFrames:
    n = clip.n_frames - 1
    heading = np.unwrap(quat.heading(clip.root_rot))
    dh = heading[-1] - heading[0]  # heading change over one cycle
    if abs(dh) < LOOP_DRIFT_RAD:
        dh = 0.0  # a straight clip whose loop does not quite close: the drift is not a turn
    trend = np.arange(clip.n_frames) * dh / n
    detr = (heading - trend)[:n]
    sigma = FACING_SMOOTHING_S / clip.dt
    k = np.arange(-int(3 * sigma) - 1, int(3 * sigma) + 2)
    w = np.exp(-0.5 * (k / max(sigma, 1e-6)) ** 2)
    w /= w.sum()
    smooth = np.array([np.sum(w * detr[(i + k) % n]) for i in range(n)])
    facing = smooth + trend[:n]
    # Root positions one cycle before and after, for wrap-around differences.
    p = clip.root_pos[:, :2]
    rot = np.array([[math.cos(dh), -math.sin(dh)], [math.sin(dh), math.cos(dh)]])
    nxt = p[-1] + (p[:n] - p[0]) @ rot.T
    prev = p[0] + (p[:n] - p[-1]) @ rot  # the inverse cycle transform
    ext = np.concatenate([prev[-1:], p[:n], nxt[:1]], axis=0)
    v_world = (ext[2:] - ext[:-2]) / (2 * clip.dt)
    c, s = np.cos(facing), np.sin(facing)
    vel_local = np.column_stack([c * v_world[:, 0] + s * v_world[:, 1], -s * v_world[:, 0] + c * v_world[:, 1]])
    fext = np.concatenate([[facing[-1] - dh], facing, [facing[0] + dh]])
    omega = (fext[2:] - fext[:-2]) / (2 * clip.dt)
    root_local = quat.mul(quat.yaw(-facing), clip.root_rot[:n])
    return CharacterFrames(facing, vel_local, omega, clip.root_pos[:n, 2].copy(), quat.normalize(root_local))


# -- tracks: resampled, augmented clips in the character frame ------------------------------------

@dataclass
class Track:
    """A clip resampled at ``dt`` in the character frame: everything a motion generator plays."""

    name: str
    dt: float
    vel_local: np.ndarray
    """(n, 2) root velocity in the facing frame (m/s)."""
    omega: np.ndarray
    """(n,) turn rate (rad/s)."""
    root_z: np.ndarray
    root_local: np.ndarray
    joints: dict[str, np.ndarray]
    eye_z: np.ndarray
    """(n,) eye height above the floor (m)."""
    eye_forward: np.ndarray
    """(n,) eye position ahead of the root along the facing (m)."""
    feet: np.ndarray
    """(n, 2, 3) right/left ankle positions relative to the root's ground point, facing frame."""
    meta: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.omega)

    @property
    def speed(self) -> float:
        return float(np.mean(np.hypot(self.vel_local[:, 0], self.vel_local[:, 1])))


def _interp_cyclic(values: np.ndarray, pos: np.ndarray) -> np.ndarray:
    n = len(values)
    i0 = np.floor(pos).astype(int) % n
    i1 = (i0 + 1) % n
    f = (pos - np.floor(pos)).reshape((-1,) + (1,) * (values.ndim - 1))
    return values[i0] * (1 - f) + values[i1] * f


def _slerp_cyclic(values: np.ndarray, pos: np.ndarray) -> np.ndarray:
    n = len(values)
    i0 = np.floor(pos).astype(int) % n
    i1 = (i0 + 1) % n
    return quat.slerp(values[i0], values[i1], pos - np.floor(pos))


def pose_at(clip: Clip, frames: CharacterFrames, pos: np.ndarray) -> dict:
    """Pose at fractional native frame positions ``pos`` (cyclic): root_z, root_local, joints."""
    n = clip.n_frames - 1
    joints = {}
    for name in SPHERICAL:
        joints[name] = _slerp_cyclic(clip.joints[name][:n], pos)
    for name in REVOLUTE:
        joints[name] = _interp_cyclic(clip.joints[name][:n], pos)
    return {"root_z": _interp_cyclic(frames.root_z, pos), "root_local": _slerp_cyclic(frames.root_local, pos),
            "joints": joints}


def pose_features(root_z, root_local, joints, scale: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eye height, eye forward offset and ankle positions of poses in the character frame."""
    root_z = np.asarray(root_z, dtype=np.float64)
    base = np.stack([np.zeros_like(root_z), np.zeros_like(root_z), root_z], axis=-1)
    fr = forward_kinematics(base, root_local, joints, scale)
    eye = eye_position(fr, scale)
    feet = np.stack([point_on(fr, "right_ankle", np.zeros(3), scale),
                     point_on(fr, "left_ankle", np.zeros(3), scale)], axis=-2)
    return eye[..., 2], eye[..., 0], feet


def make_track(name: str, scale: float, dt: float, rate: float = 1.0, reverse: bool = False,
               curvature: float = 0.0) -> Track:
    """Clip ``name`` played at ``rate`` x its speed, sampled every ``dt`` seconds for one cycle.

    ``reverse`` plays it backwards (walking backwards); ``curvature`` (rad/s) adds a constant
    turn rate to the facing, bending a straight walk into a curve.
    """
    clip = load_clip(name, scale)
    cf = character_frames(clip)
    n_native = clip.n_frames - 1
    n = max(2, int(round(clip.duration / (rate * dt))))
    step = n_native / n  # native frames per output frame
    pos = np.arange(n) * step
    if reverse:
        pos = (n_native - pos) % n_native
    sign = -1.0 if reverse else 1.0
    vel = _interp_cyclic(cf.vel_local, pos) * rate * sign
    omega = _interp_cyclic(cf.omega, pos) * rate * sign + curvature
    pose = pose_at(clip, cf, pos)
    eye_z, eye_fwd, feet = pose_features(pose["root_z"], pose["root_local"], pose["joints"], scale)
    label = f"{name}x{rate:g}" + ("_back" if reverse else "") + (f"_curve{curvature:+g}" if curvature else "")
    return Track(label, dt, vel, omega, pose["root_z"], pose["root_local"], pose["joints"], eye_z, eye_fwd, feet,
                 meta={"clip": name, "rate": rate, "reverse": reverse, "curvature": curvature})


# -- measurements ------------------------------------------------------------------------------

def forward_speed(clip: Clip) -> float:
    """Mean horizontal root speed over one cycle (m/s)."""
    return stride_length(clip) / clip.duration


def stride_length(clip: Clip) -> float:
    """Horizontal root displacement over one cycle (m): a walk clip is one gait cycle, two steps."""
    d = clip.root_pos[-1, :2] - clip.root_pos[0, :2]
    return float(math.hypot(d[0], d[1]))


def eye_heights(clip: Clip) -> np.ndarray:
    """Eye height (m) at each distinct frame."""
    n = clip.n_frames - 1
    fr = forward_kinematics(clip.root_pos[:n], clip.root_rot[:n], {k: v[:n] for k, v in clip.joints.items()},
                            clip.scale)
    return eye_position(fr, clip.scale)[:, 2]


def head_oscillation(clip: Clip) -> float:
    """Peak-to-peak vertical oscillation of the eyes over one cycle (m)."""
    z = eye_heights(clip)
    return float(z.max() - z.min())


def measure(name: str, scale: float) -> dict[str, float]:
    clip = load_clip(name, scale)
    cf = character_frames(clip)
    z = eye_heights(clip)
    return {"clip": name, "duration_s": clip.duration, "forward_speed_mps": forward_speed(clip),
            "stride_length_m": stride_length(clip), "eye_height_mean_m": float(z.mean()),
            "head_oscillation_m": float(z.max() - z.min()),
            "max_turn_rate_radps": float(np.max(np.abs(cf.omega))),
            "heading_change_rad": float(cf.facing[-1] - cf.facing[0])}

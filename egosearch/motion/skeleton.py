"""The DeepMimic humanoid's skeleton (pybullet_data ``humanoid/humanoid.urdf``) in numpy.

The URDF is the one source of truth: joint offsets and collision shapes are read from it, so
forward kinematics here agrees with pybullet's for the same joint values (checked in the tests).

Frames: the URDF is y-up (the model stands along +y, faces +x, its right side is +z). Our world
is z-up; a model placed with base orientation ``quat.Y_UP_TO_Z_UP`` stands along +z, faces +x
and has its left side at +y, the convention of :class:`egosearch.sim.body.AgentState` (theta = 0
faces +x).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from egosearch.motion import quat

URDF = "humanoid/humanoid.urdf"

#: The DeepMimic frame layout after the duration entry: root pos (3), root quat (4, w x y z),
#: then these joints in order; spherical joints are quaternions (w x y z), revolute ones angles.
MOCAP_JOINTS: tuple[tuple[str, int], ...] = (
    ("chest", 4), ("neck", 4),
    ("right_hip", 4), ("right_knee", 1), ("right_ankle", 4), ("right_shoulder", 4), ("right_elbow", 1),
    ("left_hip", 4), ("left_knee", 1), ("left_ankle", 4), ("left_shoulder", 4), ("left_elbow", 1),
)
SPHERICAL = tuple(name for name, n in MOCAP_JOINTS if n == 4)
REVOLUTE = tuple(name for name, n in MOCAP_JOINTS if n == 1)
#: Left/right joint pairs (for mirroring and foot features).
FEET = ("right_ankle", "left_ankle")

#: Scale at which DeepMimic's clips were recorded (``globalScaling=0.25`` in its examples); the
#: clips' root positions are in metres at this scale.
MOCAP_SCALE = 0.25
#: Eye point in the neck link's frame (unscaled URDF units, y-up, +x forward): in front of and
#: a little above the head sphere's centre (0, 0.7, 0), radius 0.41.
EYE_IN_NECK = np.array([0.30, 0.78, 0.0])


def pybullet_data_path() -> Path:
    import pybullet_data

    return Path(pybullet_data.getDataPath())


@dataclass(frozen=True)
class Joint:
    name: str
    kind: str  # "fixed", "spherical", "revolute"
    parent: str  # parent link
    child: str  # child link
    origin: np.ndarray  # joint frame origin in the parent link frame (unscaled)
    axis: np.ndarray


@dataclass(frozen=True)
class Shape:
    link: str
    kind: str  # "sphere", "capsule", "box"
    origin: np.ndarray
    rot: np.ndarray  # quaternion of the shape frame in the link frame
    radius: float = 0.0
    length: float = 0.0  # capsule: distance between the end-sphere centres (along shape z)
    size: tuple[float, float, float] = (0.0, 0.0, 0.0)  # box: full extents


@dataclass(frozen=True)
class Skeleton:
    joints: tuple[Joint, ...]  # parents before children
    shapes: tuple[Shape, ...]
    base: str

    def joint(self, name: str) -> Joint:
        for j in self.joints:
            if j.name == name:
                return j
        raise KeyError(name)


def _floats(text: str | None, n: int = 3) -> np.ndarray:
    if not text:
        return np.zeros(n)
    return np.array([float(v) for v in text.split()])


def _rpy_quat(rpy: np.ndarray) -> np.ndarray:
    r, p, y = rpy
    qx = quat.from_axis_angle((1, 0, 0), r)
    qy = quat.from_axis_angle((0, 1, 0), p)
    qz = quat.from_axis_angle((0, 0, 1), y)
    return quat.mul(qz, quat.mul(qy, qx))


@lru_cache(maxsize=1)
def load_skeleton() -> Skeleton:
    text = (pybullet_data_path() / URDF).read_bytes().decode("utf-8", errors="ignore")
    root = ET.fromstring(text.replace("\x00", ""))
    joints = []
    for j in root.findall("joint"):
        origin = j.find("origin")
        axis = j.find("axis")
        joints.append(Joint(j.get("name"), j.get("type"), j.find("parent").get("link"), j.find("child").get("link"),
                            _floats(origin.get("xyz") if origin is not None else None),
                            _floats(axis.get("xyz") if axis is not None else "0 0 1")))
    shapes = []
    for link in root.findall("link"):
        for col in link.findall("collision"):
            origin = col.find("origin")
            xyz = _floats(origin.get("xyz") if origin is not None else None)
            rot = _rpy_quat(_floats(origin.get("rpy") if origin is not None else None))
            geom = col.find("geometry")[0]
            if geom.tag == "sphere":
                shapes.append(Shape(link.get("name"), "sphere", xyz, rot, radius=float(geom.get("radius"))))
            elif geom.tag == "capsule":
                shapes.append(Shape(link.get("name"), "capsule", xyz, rot, radius=float(geom.get("radius")),
                                    length=float(geom.get("length"))))
            elif geom.tag == "box":
                shapes.append(Shape(link.get("name"), "box", xyz, rot, size=tuple(_floats(geom.get("size")))))
    children = {j.child for j in joints}
    base = next(link.get("name") for link in root.findall("link") if link.get("name") not in children)
    # Order joints parents-first.
    ordered, known = [], {base}
    pending = list(joints)
    while pending:
        for j in list(pending):
            if j.parent in known:
                ordered.append(j)
                known.add(j.child)
                pending.remove(j)
    return Skeleton(tuple(ordered), tuple(shapes), base)


def forward_kinematics(base_pos: np.ndarray, base_rot: np.ndarray, joints: dict[str, np.ndarray],
                       scale: float) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """World (position, rotation) of every link frame, vectorised over leading axes.

    ``joints`` maps spherical joint names to quaternions (x, y, z, w) and revolute ones to angles
    (shape (..., 1) or (...)); missing joints are at rest. ``scale`` is pybullet's
    ``globalScaling``.
    """
    skel = load_skeleton()
    base_pos = np.asarray(base_pos, dtype=np.float64)
    base_rot = np.asarray(base_rot, dtype=np.float64)
    frames = {skel.base: (base_pos, base_rot)}
    for j in skel.joints:
        ppos, prot = frames[j.parent]
        pos = ppos + quat.rotate(prot, j.origin * scale)
        value = joints.get(j.name)
        if j.kind == "spherical" and value is not None:
            rot = quat.mul(prot, value)
        elif j.kind == "revolute" and value is not None:
            angle = np.asarray(value, dtype=np.float64)
            if angle.ndim and angle.shape[-1] == 1:
                angle = angle[..., 0]
            rot = quat.mul(prot, quat.from_axis_angle(j.axis, angle))
        else:
            rot = np.broadcast_to(prot, np.broadcast_shapes(prot.shape, ppos.shape[:-1] + (4,))).copy()
        frames[j.child] = (pos, rot)
    return frames


def eye_position(frames: dict[str, tuple[np.ndarray, np.ndarray]], scale: float) -> np.ndarray:
    pos, rot = frames["neck"]
    return pos + quat.rotate(rot, EYE_IN_NECK * scale)


def point_on(frames, link: str, local: np.ndarray, scale: float) -> np.ndarray:
    pos, rot = frames[link]
    return pos + quat.rotate(rot, np.asarray(local) * scale)


def shape_segments(frames, scale: float) -> list[tuple[Shape, np.ndarray, np.ndarray]]:
    """For drawing: every collision shape with its world centre and rotation."""
    out = []
    for s in load_skeleton().shapes:
        pos, rot = frames[s.link]
        out.append((s, pos + quat.rotate(rot, s.origin * scale), quat.mul(rot, s.rot)))
    return out


def standing_root_height(scale: float) -> float:
    """Root height that puts the soles of the rest pose on the floor."""
    frames = forward_kinematics(np.zeros(3), quat.Y_UP_TO_Z_UP, {}, scale)
    lowest = math.inf
    for s in load_skeleton().shapes:
        if s.kind != "box":
            continue
        pos, rot = frames[s.link]
        centre = pos + quat.rotate(rot, s.origin * scale)
        lowest = min(lowest, centre[2] - s.size[1] * scale / 2)  # box local y is up at rest
    return -lowest

"""A kinematic 1.65 m humanoid: DeepMimic's ``humanoid/humanoid.urdf`` posed from mocap.

Scale: DeepMimic records its clips for the URDF at ``globalScaling=0.25``, where the eyes of
the walk clip sit at 1.508 m on average. We load it at :data:`HUMANOID_SCALE` = 0.2735
(x 1.094), which puts the eyes at 1.650 m on average over the walk cycle (1.681 m standing;
the top of the head at about 1.77 m), the paper's humanoid camera height (6.3).

Collision geometry is the URDF's own: spheres for pelvis, chest and head, capsules for the
limbs and boxes for the feet, posed with ``resetBasePositionAndOrientation`` and
``resetJointStateMultiDof`` on a fixed-base multibody.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from egosearch.motion import quat
from egosearch.motion.base import FullBodyPose, Limits, union_aabb
from egosearch.motion.skeleton import (
    REVOLUTE,
    SPHERICAL,
    URDF,
    eye_position,
    forward_kinematics,
    pybullet_data_path,
    shape_segments,
    standing_root_height,
)
from egosearch.sim.body import AgentSpec
from egosearch.sim.bullet import pybullet, quiet_native_output

HUMANOID_SCALE = 0.2735
"""pybullet ``globalScaling`` of the humanoid: mean walking eye height 1.65 m."""

_SPEC = AgentSpec()
HUMANOID_LIMITS = Limits(
    max_forward=1.5,  # a brisk walk; the walk clip itself goes 1.07 m/s at this scale
    max_backward=0.8,
    max_lateral=0.7,  # side steps
    max_accel=2.5,  # m/s^2: about a quarter g, a walking start/stop
    max_turn_rate=2.5,  # rad/s, ~140 deg/s
    max_turn_accel=12.0,
    pitch_limits=_SPEC.pitch_limits,  # the neck is the abstract model's
    yaw_limits=_SPEC.yaw_limits,
    max_pitch_rate=_SPEC.max_pitch_rate / 0.15,
    max_yaw_rate=_SPEC.max_yaw_rate / 0.15,
)


@lru_cache(maxsize=4)
def stand_pose(scale: float = HUMANOID_SCALE) -> dict:
    """The rest pose (all joints at zero: upright, arms down), feet on the floor."""
    joints = {name: quat.IDENTITY.copy() for name in SPHERICAL}
    joints.update({name: np.zeros(()) for name in REVOLUTE})
    return {"root_z": standing_root_height(scale), "root_local": quat.Y_UP_TO_Z_UP.copy(), "joints": joints}


def pose_frames(pose: FullBodyPose, scale: float = HUMANOID_SCALE):
    """World frames of every link of a humanoid pose."""
    base = np.array([pose.x, pose.y, pose.root_z])
    rot = quat.mul(quat.yaw(pose.theta), pose.root_local)
    return forward_kinematics(base, rot, pose.joints, scale)


def eye_height(root_z: float, root_local: np.ndarray, joints: dict, scale: float = HUMANOID_SCALE) -> float:
    fr = forward_kinematics(np.array([0.0, 0.0, root_z]), root_local, joints, scale)
    return float(eye_position(fr, scale)[2])


def limb_shapes(pose: FullBodyPose, scale: float = HUMANOID_SCALE):
    """(shape, world centre, world rotation) of every collision shape, for drawing."""
    return shape_segments(pose_frames(pose, scale), scale)


#: The URDF importer's warnings about the spherical joints, which have no <axis>: harmless.
_URDF_NOISE = ("b3Warning[examples/Importers/ImportURDFDemo/BulletUrdfImporter.cpp", "urdfdom: no axis element")


class HumanoidBody:
    """The humanoid's collision shapes in a pybullet client, posed kinematically."""

    def __init__(self, client, scale: float = HUMANOID_SCALE):
        self._p = client
        self.scale = scale
        with quiet_native_output(_URDF_NOISE):
            self.body_id = client.loadURDF(str(pybullet_data_path() / URDF), [0, 0, -50], globalScaling=scale,
                                           useFixedBase=True, flags=pybullet.URDF_MAINTAIN_LINK_ORDER)
        self.joint_index = {}
        for j in range(client.getNumJoints(self.body_id)):
            info = client.getJointInfo(self.body_id, j)
            self.joint_index[info[1].decode()] = j

    def set_pose(self, pose: FullBodyPose) -> None:
        p = self._p
        if pose.joints is None:
            raise ValueError("a humanoid pose needs joints")
        orn = quat.mul(quat.yaw(pose.theta), pose.root_local)
        p.resetBasePositionAndOrientation(self.body_id, (pose.x, pose.y, pose.root_z), tuple(orn))
        for name in SPHERICAL:
            p.resetJointStateMultiDof(self.body_id, self.joint_index[name], tuple(np.asarray(pose.joints[name])))
        for name in REVOLUTE:
            p.resetJointState(self.body_id, self.joint_index[name], float(np.asarray(pose.joints[name]).reshape(-1)[0]))

    def aabb(self):
        return union_aabb(self._p, self.body_id)

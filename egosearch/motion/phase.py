"""``PhaseMG``: a phase-driven walk in the spirit of PFNN [HKS17].

A gait phase in [0, 1) advances with the distance the root travels (one cycle per stride of the
walk clip, backwards when walking backwards, and a little when turning on the spot) and picks
the pose of DeepMimic's walk clip; as the root slows down the pose blends to standing, so the
head's vertical oscillation (3.6 cm peak to peak at full gait) fades with the speed.

The root follows the plan like a PFNN character follows its gamepad trajectory: the desired
velocity is the plan's velocity plus a pull towards the plan's position, a critically damped
spring on velocity smooths it, and acceleration, speed (body-frame box) and turn-rate limits
clip it. The spring's lag and the limits make the root cut corners and trail the plan.
"""

from __future__ import annotations

import math

import numpy as np

from egosearch.motion import mocap, quat
from egosearch.motion.base import (
    SUBSTEP_SECONDS,
    SUBSTEPS,
    FullBodyPose,
    Limits,
    MotionGenerator,
    plan_at,
    plan_velocity,
    spring_step,
)
from egosearch.motion.humanoid import HUMANOID_LIMITS, HUMANOID_SCALE, eye_height, stand_pose
from egosearch.motion.skeleton import REVOLUTE, SPHERICAL
from egosearch.sim.body import STEP_SECONDS, AgentState, wrap_angle

#: Effective foot radius (m) for the stepping that turning on the spot needs.
TURN_STEP_RADIUS = 0.2


class PhaseMG(MotionGenerator):
    name = "humanoid_phase"
    character = "humanoid"

    def __init__(self, world=None, scale: float = HUMANOID_SCALE, limits: Limits = HUMANOID_LIMITS,
                 halflife: float = 0.15, turn_halflife: float = 0.1, track_time: float = 0.4,
                 gait_time: float = 0.2):
        """
        Args:
            halflife: of the velocity spring (s).
            turn_halflife: of the turn-rate spring (s).
            track_time: the pull towards the plan's position closes its error in this time (s).
            gait_time: time constant (s) of the blend between standing and walking.
        """
        super().__init__(world)
        self.scale = scale
        self.limits = limits
        self.halflife = halflife
        self.turn_halflife = turn_halflife
        self.track_time = track_time
        self.gait_time = gait_time
        self.clip = mocap.load_clip("walk", scale)
        self.frames = mocap.character_frames(self.clip)
        self.stride = mocap.stride_length(self.clip)
        self.walk_speed = mocap.forward_speed(self.clip)
        self.stand = stand_pose(scale)

    # -- poses --------------------------------------------------------------------------------
    def body_pose(self, phase: float, gait: float) -> tuple[float, np.ndarray, dict]:
        """(root_z, root_local, joints) at ``phase`` blended with standing by ``gait`` in [0, 1]."""
        n = self.clip.n_frames - 1
        walk = mocap.pose_at(self.clip, self.frames, np.array([phase % 1.0 * n]))
        g = float(np.clip(gait, 0.0, 1.0))
        joints = {}
        for name in SPHERICAL:
            joints[name] = quat.slerp(self.stand["joints"][name], walk["joints"][name][0], g)
        for name in REVOLUTE:
            joints[name] = np.asarray((1 - g) * self.stand["joints"][name] + g * walk["joints"][name][0])
        root_z = float((1 - g) * self.stand["root_z"] + g * walk["root_z"][0])
        root_local = quat.slerp(self.stand["root_local"], walk["root_local"][0], g)
        return root_z, root_local, joints

    def _pose(self, x, y, theta, pitch, head_yaw, phase, gait, vx=0.0, vy=0.0, omega=0.0, blocked=False,
              state=None) -> FullBodyPose:
        root_z, root_local, joints = self.body_pose(phase, gait)
        return FullBodyPose(x, y, theta, eye_height(root_z, root_local, joints, self.scale), pitch, head_yaw,
                            joints=joints, root_z=root_z, root_local=root_local, phase=phase % 1.0, clip="walk",
                            vx=vx, vy=vy, omega=omega, blocked=blocked,
                            state=dict(state or {"ax": 0.0, "ay": 0.0, "alpha": 0.0, "gait": gait}))

    def initial_pose(self, state: AgentState) -> FullBodyPose:
        pitch, head_yaw = (float(np.clip(state.pitch, *self.limits.pitch_limits)),
                           float(np.clip(state.head_yaw, *self.limits.yaw_limits)))
        return self._pose(state.x, state.y, state.theta, pitch, head_yaw, 0.0, 0.0)

    # -- one env step -------------------------------------------------------------------------
    def _advance(self, pose: FullBodyPose, plan: list[AgentState], k: int) -> FullBodyPose:
        lim, dt = self.limits, SUBSTEP_SECONDS
        x, y, th = pose.x, pose.y, pose.theta
        vx, vy, om = pose.vx, pose.vy, pose.omega
        ax, ay, alpha = pose.state.get("ax", 0.0), pose.state.get("ay", 0.0), pose.state.get("alpha", 0.0)
        gait = pose.state.get("gait", 0.0)
        phase, pitch, head_yaw = pose.phase, pose.pitch, pose.head_yaw
        blocked = False
        for j in range(SUBSTEPS):
            tau = k + (j + 1) / SUBSTEPS
            px, py, pth, _, _ = plan_at(plan, tau)
            fx, fy, fom = plan_velocity(plan, k + j / SUBSTEPS)
            # Desired velocity: feed-forward plus a pull towards where the plan is now.
            dvx = fx + (px - x) / self.track_time
            dvy = fy + (py - y) / self.track_time
            dom = fom + wrap_angle(pth - th) / self.track_time
            dvx, dvy = lim.clamp_velocity(dvx, dvy, th)
            dom = float(np.clip(dom, -lim.max_turn_rate, lim.max_turn_rate))
            # Critically damped springs on velocity and turn rate, then the limits.
            nvx, ax = spring_step(vx, ax, dvx, self.halflife, dt)
            nvy, ay = spring_step(vy, ay, dvy, self.halflife, dt)
            nom, alpha = spring_step(om, alpha, dom, self.turn_halflife, dt)
            nom = om + float(np.clip(nom - om, -lim.max_turn_accel * dt, lim.max_turn_accel * dt))
            cap = lim.turn_cap(math.hypot(vx, vy))
            nom = float(np.clip(nom, -cap, cap))
            nth = th + nom * dt
            nvx, nvy = lim.limit_velocity(nvx, nvy, vx, vy, nth, dt)
            ax, ay, alpha = (nvx - vx) / dt, (nvy - vy) / dt, (nom - om) / dt
            nx, ny, hit = self._move_root(x, y, x + nvx * dt, y + nvy * dt)
            if hit:
                blocked = True
                nvx, nvy, ax, ay = (nx - x) / dt, (ny - y) / dt, 0.0, 0.0
            # Gait phase: travelled distance over the stride, signed by walking direction.
            dist = math.hypot(nx - x, ny - y)
            forward = math.cos(nth) * (nx - x) + math.sin(nth) * (ny - y)
            sign = -1.0 if forward < -0.5 * dist else 1.0
            phase = (phase + (sign * dist + TURN_STEP_RADIUS * abs(nth - th)) / self.stride) % 1.0
            activity = (math.hypot(nvx, nvy) + TURN_STEP_RADIUS * abs(nom)) / (0.5 * self.walk_speed)
            gait += (min(1.0, activity) - gait) * (1.0 - math.exp(-dt / self.gait_time))
            pitch, head_yaw = self._track_head(pitch, head_yaw, nth, plan, tau, dt)
            x, y, th, vx, vy, om = nx, ny, nth, nvx, nvy, nom
            self._record(x, y, th)
        return self._pose(x, y, wrap_angle(th), pitch, head_yaw, phase, gait, vx, vy, om, blocked,
                          {"ax": ax, "ay": ay, "alpha": alpha, "gait": gait})


def step_velocity(a: FullBodyPose, b: FullBodyPose) -> tuple[float, float]:
    """Mean velocity between two consecutive poses (m/s)."""
    return (b.x - a.x) / STEP_SECONDS, (b.y - a.y) / STEP_SECONDS

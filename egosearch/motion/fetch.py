"""A Fetch-like robot [WFK*16]: differential-drive base, pan/tilt head, camera at 1.05 m.

The base cannot move sideways: it drives along its heading (unicycle), forward up to 1.0 m/s
and backwards up to 0.3 m/s, turns at up to 1.5 rad/s, with acceleration limits. ``FetchMG``
follows the plan's positions as waypoints (pure pursuit of the next one not yet reached),
turning on the spot first when it is off to the side and reversing where that is quicker than
turning round; it ignores the plan's timing, so it falls behind a plan faster than itself, and it
cannot side-step. It keeps the plan's gaze with a pan/tilt head that has Fetch's
ranges and speeds (pan +-1.57 rad, tilt 0.76 rad up to 1.45 rad down, both 1.57 rad/s).

Collision geometry: the round base (radius 0.28 m), the torso column and the head box.
"""

from __future__ import annotations

import math

import numpy as np

from egosearch.motion import quat
from egosearch.motion.base import (
    SUBSTEP_SECONDS,
    SUBSTEPS,
    FullBodyPose,
    Limits,
    MotionGenerator,
)
from egosearch.sim.body import AgentState, wrap_angle
from egosearch.sim.bullet import pybullet

FETCH_CAMERA_HEIGHT = 1.05
FETCH_BASE_RADIUS = 0.28
FETCH_LIMITS = Limits(
    max_forward=1.0,
    max_backward=0.3,
    max_lateral=0.0,
    max_accel=1.0,
    max_turn_rate=1.5,
    max_turn_accel=3.0,
    pitch_limits=(-1.45, 0.76),  # tilt: 1.45 rad down to 0.76 rad up (our pitch is positive up)
    yaw_limits=(-1.57, 1.57),
    max_pitch_rate=1.57,
    max_yaw_rate=1.57,
)
#: Collision/drawing parts in the robot frame: (kind, centre xyz, dims). Cylinders: (radius,
#: height); boxes: full extents.
FETCH_PARTS = (
    ("cylinder", (0.0, 0.0, 0.20), (FETCH_BASE_RADIUS, 0.36)),  # base, 2 cm above the floor
    ("cylinder", (-0.07, 0.0, 0.68), (0.17, 0.60)),  # torso column
    ("box", (0.02, 0.0, 0.99), (0.26, 0.34, 0.10)),  # shoulder / arm tucked on the torso
    ("box", (0.04, 0.0, FETCH_CAMERA_HEIGHT + 0.02), (0.22, 0.30, 0.16)),  # head with the camera
)


class FetchMG(MotionGenerator):
    name = "fetch"
    character = "fetch"

    def __init__(self, world=None, limits: Limits = FETCH_LIMITS, reach: float = 0.08, final_reach: float = 0.02,
                 arrive_time: float = 0.5, turn_gain: float = 3.0, turn_first: float = 0.6):
        """
        Args:
            reach: a plan waypoint closer than this (m) counts as reached.
            final_reach: the same for the plan's last state (it is where the plan wants to be).
            arrive_time: the base slows down to arrive at the end of the plan in this time (s).
            turn_gain: turn rate per rad of heading error (1/s).
            turn_first: heading error (rad) above which the base turns on the spot before driving.
        """
        super().__init__(world)
        self.limits = limits
        self.reach = reach
        self.final_reach = final_reach
        self.arrive_time = arrive_time
        self.turn_gain = turn_gain
        self.turn_first = turn_first

    def initial_pose(self, state: AgentState) -> FullBodyPose:
        pitch = float(np.clip(state.pitch, *self.limits.pitch_limits))
        head_yaw = float(np.clip(state.head_yaw, *self.limits.yaw_limits))
        return FullBodyPose(state.x, state.y, state.theta, FETCH_CAMERA_HEIGHT, pitch, head_yaw, clip="drive",
                            state={"v": 0.0, "waypoint": 1})

    def generate(self, plan: list[AgentState], m: int, start: FullBodyPose | None = None) -> list[FullBodyPose]:
        if start is not None:
            start = start.copy()
            start.state["waypoint"] = 1  # a new plan: follow it from its first step
        return super().generate(plan, m, start)

    def _controls(self, x: float, y: float, th: float, plan: list[AgentState], w: int) -> tuple[float, float, int]:
        """Pure pursuit of the next plan waypoint not yet reached: (v_des, omega_des, waypoint)."""
        lim, last = self.limits, len(plan) - 1
        while w < last and math.hypot(plan[w].x - x, plan[w].y - y) < self.reach:
            w += 1
        w = min(w, last)
        target = plan[w]
        dx, dy = target.x - x, target.y - y
        dist = math.hypot(dx, dy)
        if dist < (self.final_reach if w == last else self.reach):
            return 0.0, self.turn_gain * wrap_angle(target.theta - th), w
        remaining = dist + sum(math.hypot(plan[i + 1].x - plan[i].x, plan[i + 1].y - plan[i].y)
                               for i in range(w, last))
        err = wrap_angle(math.atan2(dy, dx) - th)
        # Drive forwards or in reverse, whichever reaches the end of the plan first.
        err_r = wrap_angle(err - math.pi)
        t_fwd = abs(err) / lim.max_turn_rate + remaining / lim.max_forward
        t_rev = abs(err_r) / lim.max_turn_rate + remaining / max(lim.max_backward, 1e-9)
        if t_rev < t_fwd:
            err, speed = err_r, -min(lim.max_backward, remaining / self.arrive_time)
        else:
            speed = min(lim.max_forward, remaining / self.arrive_time)
        v_des = 0.0 if abs(err) > self.turn_first else speed * math.cos(err)
        return v_des, self.turn_gain * err, w

    def _advance(self, pose: FullBodyPose, plan: list[AgentState], k: int) -> FullBodyPose:
        lim, dt = self.limits, SUBSTEP_SECONDS
        x, y, th = pose.x, pose.y, pose.theta
        v, om = pose.state.get("v", 0.0), pose.omega
        w = pose.state.get("waypoint", 1)
        pitch, head_yaw = pose.pitch, pose.head_yaw
        blocked = False
        for j in range(SUBSTEPS):
            tau = k + (j + 1) / SUBSTEPS
            v_des, om_des, w = self._controls(x, y, th, plan, w)
            v_des = float(np.clip(v_des, -lim.max_backward, lim.max_forward))
            om_des = float(np.clip(om_des, -lim.max_turn_rate, lim.max_turn_rate))
            nv = v + float(np.clip(v_des - v, -lim.max_accel * dt, lim.max_accel * dt))
            nom = om + float(np.clip(om_des - om, -lim.max_turn_accel * dt, lim.max_turn_accel * dt))
            # Exact unicycle motion over the sub-step (an arc): never a sideways component.
            if abs(nom) > 1e-9:
                tx = x + nv / nom * (math.sin(th + nom * dt) - math.sin(th))
                ty = y - nv / nom * (math.cos(th + nom * dt) - math.cos(th))
            else:
                tx, ty = x + nv * dt * math.cos(th), y + nv * dt * math.sin(th)
            nth = th + nom * dt
            chord = th + 0.5 * nom * dt
            nx, ny, hit = self._move_root(x, y, tx, ty, heading=chord)
            if hit:
                blocked = True
                nv = ((nx - x) * math.cos(chord) + (ny - y) * math.sin(chord)) / dt
            pitch, head_yaw = self._track_head(pitch, head_yaw, nth, plan, tau, dt)
            x, y, th, v, om = nx, ny, nth, nv, nom
            self._record(x, y, th)
        c, s = math.cos(th), math.sin(th)
        return FullBodyPose(x, y, wrap_angle(th), FETCH_CAMERA_HEIGHT, pitch, head_yaw, clip="drive",
                            vx=v * c, vy=v * s, omega=om, blocked=blocked, state={"v": v, "waypoint": w})


class FetchBody:
    """Fetch's collision shapes as one compound body."""

    def __init__(self, client):
        self._p = client
        types, radii, lengths, extents, positions = [], [], [], [], []
        for kind, centre, dims in FETCH_PARTS:
            if kind == "cylinder":
                types.append(pybullet.GEOM_CYLINDER)
                radii.append(dims[0])
                lengths.append(dims[1])
                extents.append((0, 0, 0))
            else:
                types.append(pybullet.GEOM_BOX)
                radii.append(0)
                lengths.append(0)
                extents.append(tuple(d / 2 for d in dims))
            positions.append(centre)
        shape = client.createCollisionShapeArray(shapeTypes=types, radii=radii, lengths=lengths,
                                                 halfExtents=extents, collisionFramePositions=positions)
        self.body_id = client.createMultiBody(baseMass=0, baseCollisionShapeIndex=shape, basePosition=(0, 0, -50))

    def set_pose(self, pose: FullBodyPose) -> None:
        self._p.resetBasePositionAndOrientation(self.body_id, (pose.x, pose.y, 0.0), tuple(quat.yaw(pose.theta)))

    def aabb(self):
        return self._p.getAABB(self.body_id, -1)

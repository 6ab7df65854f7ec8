"""One interface for motion generators (MG of paper section 5, Algorithm 1 line 8).

``MotionGenerator.generate(plan, m, start)`` takes the abstract plan s_0..s_T (one
:class:`~egosearch.sim.body.AgentState` per env step of :data:`~egosearch.sim.body.STEP_SECONDS`) and
returns the ``m`` full-body poses that follow ``start`` (the character's current pose, taken at
the time of s_0), i.e. the poses at the times of s_1..s_m. ``start=None`` starts the character
standing at s_0. Each generator moves with its own limits, so its poses deviate from the plan.

Inside, every generator integrates at :data:`SUBSTEPS` sub-steps per env step and, when bound
to a :class:`~egosearch.sim.world.World`, stops the root where the abstract body cylinder would end
inside an obstacle (``FullBodyPose.blocked``): the realised path is collision-checked.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from egosearch.sim.body import STEP_SECONDS, AgentSpec, AgentState, wrap_angle
from egosearch.sim.world import PENETRATION_TOLERANCE

#: Integration sub-steps per env step (0.03 s each, the rate of the mocap clips).
SUBSTEPS = 5
SUBSTEP_SECONDS = STEP_SECONDS / SUBSTEPS


@dataclass
class FullBodyPose:
    """One full-body pose q_t of Algorithm 1."""

    x: float
    y: float
    theta: float
    """Root heading (rad): the character's facing."""
    camera_height: float
    """Eye / camera height above the floor (m); oscillates with the humanoid's gait."""
    pitch: float = 0.0
    """Head pitch (rad, positive up), the abstract model's q_p."""
    head_yaw: float = 0.0
    """Head yaw relative to the body (rad, positive left), the abstract model's q_y."""
    joints: dict[str, np.ndarray] | None = None
    """Joint rotations where the character has them (humanoid: spherical joints as quaternions
    (x, y, z, w), knees and elbows as angles); None for Fetch and the abstract body."""
    root_z: float | None = None
    """Pelvis height (m), humanoid only."""
    root_local: np.ndarray | None = None
    """Pelvis orientation with the facing removed (quaternion, z-up world), humanoid only."""
    phase: float = 0.0
    """Gait phase in [0, 1) of the clip being played."""
    clip: str = ""
    """Name of the clip (or database track) this pose comes from."""
    vx: float = 0.0
    vy: float = 0.0
    """Root velocity at this instant (m/s, world frame)."""
    omega: float = 0.0
    """Turn rate at this instant (rad/s)."""
    blocked: bool = False
    """The root was stopped by an obstacle on the way to this pose."""
    state: dict = field(default_factory=dict)
    """The generator's own continuation state (spring accelerations, clip cursor...)."""

    def copy(self) -> FullBodyPose:
        joints = None if self.joints is None else {k: np.array(v, copy=True) for k, v in self.joints.items()}
        return replace(self, joints=joints, state=dict(self.state),
                       root_local=None if self.root_local is None else np.array(self.root_local, copy=True))

    def abstract(self) -> AgentState:
        """The abstract state with this pose's root, camera height and head."""
        return AgentState(self.x, self.y, self.theta, self.pitch, self.head_yaw, self.camera_height)

    @property
    def speed(self) -> float:
        return math.hypot(self.vx, self.vy)


@dataclass(frozen=True)
class Limits:
    """A character's motor limits. Velocities are in the body frame."""

    max_forward: float
    """Forward speed (m/s)."""
    max_backward: float
    """Backward speed (m/s)."""
    max_lateral: float
    """Sideways speed (m/s); 0 for a differential drive."""
    max_accel: float
    """|dv/dt| (m/s^2)."""
    max_turn_rate: float
    """|omega| (rad/s)."""
    max_turn_accel: float
    """|domega/dt| (rad/s^2)."""
    pitch_limits: tuple[float, float]
    yaw_limits: tuple[float, float]
    max_pitch_rate: float
    """rad/s."""
    max_yaw_rate: float
    """rad/s."""

    def clamp_velocity(self, vx: float, vy: float, theta: float) -> tuple[float, float]:
        """Project a world velocity onto the body-frame box of allowed velocities."""
        c, s = math.cos(theta), math.sin(theta)
        f, l = c * vx + s * vy, -s * vx + c * vy
        f = min(max(f, -self.max_backward), self.max_forward)
        l = min(max(l, -self.max_lateral), self.max_lateral)
        return c * f - s * l, s * f + c * l

    def in_box(self, vx: float, vy: float, theta: float, eps: float = 1e-12) -> bool:
        c, s = math.cos(theta), math.sin(theta)
        f, l = c * vx + s * vy, -s * vx + c * vy
        return -self.max_backward - eps <= f <= self.max_forward + eps and abs(l) <= self.max_lateral + eps

    def limit_velocity(self, vx: float, vy: float, prev_vx: float, prev_vy: float, theta: float,
                       dt: float) -> tuple[float, float]:
        """The velocity nearest the wanted (vx, vy) that is within ``max_accel * dt`` of the previous
        one and inside the body-frame box at heading ``theta``. When both cannot hold (the box turned
        away from the previous velocity by more than the acceleration allows), acceleration wins."""
        step = self.max_accel * dt
        bx, by = self.clamp_velocity(vx, vy, theta)
        dx, dy = bx - prev_vx, by - prev_vy
        n = math.hypot(dx, dy)
        if n > step:
            dx, dy = dx * step / n, dy * step / n
        cx, cy = prev_vx + dx, prev_vy + dy
        if self.in_box(cx, cy, theta):
            return cx, cy
        px, py = self.clamp_velocity(prev_vx, prev_vy, theta)  # inside the box
        gap = math.hypot(px - prev_vx, py - prev_vy)
        if gap > step:
            return prev_vx + (px - prev_vx) * step / gap, prev_vy + (py - prev_vy) * step / gap
        lo, hi = 0.0, 1.0  # p -> c: p is in both sets, c in the ball; keep the last point in the box
        for _ in range(30):
            mid = (lo + hi) / 2
            if self.in_box(px + mid * (cx - px), py + mid * (cy - py), theta):
                lo = mid
            else:
                hi = mid
        return px + lo * (cx - px), py + lo * (cy - py)

    def turn_cap(self, speed: float) -> float:
        """Largest turn rate at ``speed``: the velocity must be able to turn with the body within
        the acceleration limit (centripetal acceleration speed * omega <= max_accel)."""
        if speed <= 1e-9 or math.isinf(self.max_accel):
            return self.max_turn_rate
        return min(self.max_turn_rate, self.max_accel / speed)

    @property
    def max_speed(self) -> float:
        return math.hypot(max(self.max_forward, self.max_backward), self.max_lateral)


def abstract_limits(spec: AgentSpec | None = None) -> Limits:
    spec = spec or AgentSpec()
    return Limits(spec.max_forward / STEP_SECONDS, spec.max_forward / STEP_SECONDS, spec.max_lateral / STEP_SECONDS,
                  math.inf, spec.max_turn / STEP_SECONDS, math.inf, spec.pitch_limits, spec.yaw_limits,
                  spec.max_pitch_rate / STEP_SECONDS, spec.max_yaw_rate / STEP_SECONDS)


# -- plan helpers ------------------------------------------------------------------------------

def plan_at(plan: list[AgentState], tau: float) -> tuple[float, float, float, float, float]:
    """(x, y, theta, pitch, head_yaw) of the plan at fractional step ``tau`` (held past the end)."""
    if tau <= 0:
        s = plan[0]
        return s.x, s.y, s.theta, s.pitch, s.head_yaw
    last = len(plan) - 1
    if tau >= last:
        s = plan[last]
        return s.x, s.y, s.theta, s.pitch, s.head_yaw
    i = int(math.floor(tau))
    f = tau - i
    a, b = plan[i], plan[i + 1]
    return (a.x + f * (b.x - a.x), a.y + f * (b.y - a.y), a.theta + f * wrap_angle(b.theta - a.theta),
            a.pitch + f * (b.pitch - a.pitch), a.head_yaw + f * (b.head_yaw - a.head_yaw))


def plan_velocity(plan: list[AgentState], tau: float) -> tuple[float, float, float]:
    """Feed-forward (vx, vy, omega) of the plan segment holding ``tau`` (zero past the end)."""
    last = len(plan) - 1
    i = int(math.floor(tau))
    if i < 0 or i >= last:
        return 0.0, 0.0, 0.0
    a, b = plan[i], plan[i + 1]
    return ((b.x - a.x) / STEP_SECONDS, (b.y - a.y) / STEP_SECONDS, wrap_angle(b.theta - a.theta) / STEP_SECONDS)


def spring_step(x: float, v: float, target: float, halflife: float, dt: float) -> tuple[float, float]:
    """Exact critically damped spring of ``x`` towards ``target``: returns (x, dx/dt)."""
    y = 2.0 * math.log(2.0) / max(halflife, 1e-6)  # half the damping 4 ln2 / halflife
    j0 = x - target
    j1 = v + j0 * y
    e = math.exp(-y * dt)
    return e * (j0 + j1 * dt) + target, e * (v - j1 * y * dt)


def rate_limit(value: float, previous: float, max_delta: float) -> float:
    return previous + min(max(value - previous, -max_delta), max_delta)


# -- the interface -----------------------------------------------------------------------------

class MotionGenerator:
    """Base class: subclasses implement :meth:`_advance` (one env step) and :meth:`initial_pose`."""

    name = "base"
    character = "abstract"
    limits: Limits

    def __init__(self, world=None):
        self.world = world
        self.substeps: list | None = None
        """Set to a list to record (x, y, theta) after every sub-step (for tests and plots)."""

    def _record(self, x: float, y: float, theta: float) -> None:
        if self.substeps is not None:
            self.substeps.append((x, y, theta))

    def bind(self, world) -> MotionGenerator:
        """Collision-check the root against this world from now on."""
        self.world = world
        return self

    # -- to implement --------------------------------------------------------------------------
    def initial_pose(self, state: AgentState) -> FullBodyPose:
        raise NotImplementedError

    def _advance(self, pose: FullBodyPose, plan: list[AgentState], k: int) -> FullBodyPose:
        """The pose one env step after ``pose``, which is at plan step ``k``."""
        raise NotImplementedError

    # -- shared --------------------------------------------------------------------------------
    def generate(self, plan: list[AgentState], m: int, start: FullBodyPose | None = None) -> list[FullBodyPose]:
        """The ``m`` poses after ``start`` that follow ``plan`` (poses at the times of s_1..s_m)."""
        if not plan:
            raise ValueError("an empty plan")
        if m < 0:
            raise ValueError(f"m={m} must be >= 0")
        pose = self.initial_pose(plan[0]) if start is None else start.copy()
        out = []
        for k in range(m):
            pose = self._advance(pose, plan, k)
            out.append(pose)
        return out

    def limit_head(self, previous: FullBodyPose, pitch: float, head_yaw: float) -> tuple[float, float]:
        """A head command after ``previous`` within this character's head range and rates."""
        lim = self.limits
        pitch = rate_limit(float(np.clip(pitch, *lim.pitch_limits)), previous.pitch, lim.max_pitch_rate * STEP_SECONDS)
        head_yaw = rate_limit(float(np.clip(head_yaw, *lim.yaw_limits)), previous.head_yaw,
                              lim.max_yaw_rate * STEP_SECONDS)
        return (float(np.clip(pitch, *lim.pitch_limits)), float(np.clip(head_yaw, *lim.yaw_limits)))

    def _track_head(self, pose_pitch: float, pose_yaw: float, theta: float, plan: list[AgentState], tau: float,
                    dt: float) -> tuple[float, float]:
        """Head command that keeps the plan's gaze (world yaw and pitch) from the realised body."""
        _, _, ptheta, ppitch, pyaw = plan_at(plan, tau)
        lim = self.limits
        want_yaw = float(np.clip(wrap_angle(ptheta + pyaw - theta), *lim.yaw_limits))
        want_pitch = float(np.clip(ppitch, *lim.pitch_limits))
        return (rate_limit(want_pitch, pose_pitch, lim.max_pitch_rate * dt),
                rate_limit(want_yaw, pose_yaw, lim.max_yaw_rate * dt))

    #: How far (m) the root may end inside an obstacle before it is stopped (IdentityMG accepts
    #: the abstract physics' own solver slop).
    root_tolerance = 0.0

    def _free(self, x: float, y: float) -> bool:
        return self.world.clearance_at(x, y, 0.01) > -self.root_tolerance

    def _move_root(self, x0: float, y0: float, x1: float, y1: float,
                   heading: float | None = None) -> tuple[float, float, bool]:
        """The root's move x0,y0 -> x1,y1 against the home (collide and slide).

        A move whose end would put the abstract body cylinder inside an obstacle is stopped at
        the obstacle; what is left of it slides along the obstacle's surface (for a
        differential drive, ``heading`` given, only the part along its heading). Returns the
        end point and whether the root was blocked.
        """
        world = self.world
        if world is None or (x0 == x1 and y0 == y1):
            return x1, y1, False
        if self._free(x1, y1):
            return x1, y1, False
        if not self._free(x0, y0):
            # Started inside (a spawn or solver slop): allow moves that do not go deeper.
            if world.clearance_at(x1, y1, 0.05) >= world.clearance_at(x0, y0, 0.05):
                return x1, y1, False
            return x0, y0, True
        bx, by = self._last_free(x0, y0, x1, y1)
        # Slide: remove the component of the rest of the move that points into the obstacle.
        h = 0.01
        gx = world.clearance_at(bx + h, by, 0.1) - world.clearance_at(bx - h, by, 0.1)
        gy = world.clearance_at(bx, by + h, 0.1) - world.clearance_at(bx, by - h, 0.1)
        norm = math.hypot(gx, gy)
        rx, ry = x1 - bx, y1 - by
        if norm > 1e-9:
            nx, ny = gx / norm, gy / norm
            into = rx * nx + ry * ny
            if into < 0:
                rx, ry = rx - into * nx, ry - into * ny
        if heading is not None:
            c, s = math.cos(heading), math.sin(heading)
            along = rx * c + ry * s
            rx, ry = along * c, along * s
        if rx == 0 and ry == 0:
            return bx, by, True
        if self._free(bx + rx, by + ry):
            return bx + rx, by + ry, True
        ex, ey = self._last_free(bx, by, bx + rx, by + ry)
        return ex, ey, True

    def _last_free(self, x0: float, y0: float, x1: float, y1: float) -> tuple[float, float]:
        """The last free point on the segment (x0, y0) (free) -> (x1, y1) (blocked), by bisection."""
        free, blocked = 0.0, 1.0
        for _ in range(8):
            mid = (free + blocked) / 2
            if self._free(x0 + mid * (x1 - x0), y0 + mid * (y1 - y0)):
                free = mid
            else:
                blocked = mid
        return x0 + free * (x1 - x0), y0 + free * (y1 - y0)


class IdentityMG(MotionGenerator):
    """The abstract body itself: returns the plan exactly (Algorithm 1 then equals open-loop
    execution of the plan). For tests and as the 'abstract' reference."""

    name = "abstract"
    character = "abstract"
    root_tolerance = PENETRATION_TOLERANCE + 1e-3

    def __init__(self, world=None, spec: AgentSpec | None = None):
        super().__init__(world)
        self.limits = abstract_limits(spec)

    def initial_pose(self, state: AgentState) -> FullBodyPose:
        return FullBodyPose(state.x, state.y, state.theta, state.camera_height, state.pitch, state.head_yaw)

    def _advance(self, pose: FullBodyPose, plan: list[AgentState], k: int) -> FullBodyPose:
        s = plan[min(k + 1, len(plan) - 1)]
        x, y, blocked = self._move_root(pose.x, pose.y, s.x, s.y)  # plans from rollouts are free already
        return FullBodyPose(x, y, s.theta, s.camera_height, s.pitch, s.head_yaw,
                            vx=(x - pose.x) / STEP_SECONDS, vy=(y - pose.y) / STEP_SECONDS,
                            omega=wrap_angle(s.theta - pose.theta) / STEP_SECONDS, blocked=blocked)

    def limit_head(self, previous: FullBodyPose, pitch: float, head_yaw: float) -> tuple[float, float]:
        return pitch, head_yaw  # the env already applied the abstract limits


def union_aabb(client, body_id: int) -> tuple[list[float], list[float]]:
    """The axis-aligned box around every link of a pybullet body (its base included)."""
    lo = np.full(3, math.inf)
    hi = np.full(3, -math.inf)
    for link in range(-1, client.getNumJoints(body_id)):
        a, b = client.getAABB(body_id, link)
        lo = np.minimum(lo, a)
        hi = np.maximum(hi, b)
    return lo.tolist(), hi.tolist()

"""The abstract searcher of paper section 4: a cylinder body with a 2-DOF camera.

Plain numbers only; the physics lives in :mod:`egosearch.sim.world`.

An env step lasts :data:`STEP_SECONDS` so that the paper's 100 steps are about 15 s of
human motion (paper 6.1). The per-step bounds below are human limits at that rate.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

STEP_SECONDS = 0.15
"""Duration of one env step (s): 100 steps ~ 15 s, paper 6.1."""
IMAGE_SIZE = 100
"""Side (px) of the square depth frames the camera renders (paper Table 2 "Image Size" 100x100): the
one source of the env's frames (:mod:`egosearch.sim.env`) and the sensor's default size
(:mod:`egosearch.sim.sensor`). A learner config's ``image_size`` and an actor file's
``arch["image_size"]`` must equal it (:class:`egosearch.rl.actor.ActorPolicy` checks the actor's on
loading it)."""

#: Camera heights the paper evaluates (m): the humanoid, the Fetch robot and a short agent.
EVAL_HEIGHTS = (0.45, 1.05, 1.65)
#: Sensible camera heights an evaluation may ask for (m).
HEIGHT_RANGE = (0.3, 2.0)


@dataclass(frozen=True)
class AgentSpec:
    """Body, camera and action limits of the abstract searcher."""

    body_radius: float = 0.2
    """Radius of the body cylinder (m): shoulder half-width of an adult."""
    body_height: float = 1.7
    """Height of the collision cylinder (m). Fixed whatever the camera height, so that every
    evaluated height moves through the same free space (and the same shortest paths)."""
    body_clearance: float = 0.05
    """Gap under the collision cylinder (m), so that it never touches the floor."""
    max_forward: float = 0.25
    """|dx| per step (m): 1.67 m/s, a brisk walk."""
    max_lateral: float = 0.15
    """|dy| per step (m): side steps are slower than walking forward."""
    max_turn: float = 0.4
    """|dtheta| per step (rad): about 150 deg/s, a quick body turn."""
    max_pitch_rate: float = 0.25
    """|dq_p| per step (rad): about 95 deg/s of head pitch."""
    max_yaw_rate: float = 0.35
    """|dq_y| per step (rad): about 135 deg/s of head yaw."""
    pitch_limits: tuple[float, float] = (-1.0, 0.5)
    """Camera pitch range (rad): 57 deg down to 29 deg up, a human neck's range."""
    yaw_limits: tuple[float, float] = (-1.4, 1.4)
    """Camera yaw range relative to the body (rad): about +-80 deg, a human neck's range."""
    train_height_range: tuple[float, float] = (1.0, 1.8)
    """Per-episode camera height in training (m), paper 4.1 domain randomisation."""
    height_noise: float = 0.1
    """Per-step white noise U[-h, h] on the camera height in training (m), paper 4.1."""
    head: bool = True
    """False for the head-off variant: the camera is fixed to the body."""
    fixed_pitch: float = -0.35
    """Camera pitch of the head-off body (rad): 20 deg down, the gaze of a walking person, so
    that the fixed camera sees the floor ahead as well as table tops."""

    @property
    def action_dim(self) -> int:
        return 5 if self.head else 3

    def action_scale(self) -> np.ndarray:
        """Multiply a normalised action in [-1, 1] by this to get the physical deltas."""
        scale = [self.max_forward, self.max_lateral, self.max_turn]
        if self.head:
            scale += [self.max_pitch_rate, self.max_yaw_rate]
        return np.asarray(scale, dtype=np.float64)


@dataclass
class AgentState:
    """Where the searcher is: the abstract state s of Algorithm 1."""

    x: float
    y: float
    theta: float
    """Body heading (rad), 0 along +x."""
    pitch: float = 0.0
    """Camera pitch q_p (rad), positive up."""
    head_yaw: float = 0.0
    """Camera yaw q_y relative to the body (rad), positive to the left."""
    camera_height: float = 1.65
    """Camera height above the floor (m), noise included."""

    @property
    def camera_yaw(self) -> float:
        """World heading of the camera (rad)."""
        return self.theta + self.head_yaw

    @property
    def camera_position(self) -> tuple[float, float, float]:
        return (self.x, self.y, self.camera_height)

    def copy(self) -> AgentState:
        return AgentState(self.x, self.y, self.theta, self.pitch, self.head_yaw, self.camera_height)


def wrap_angle(angle: float) -> float:
    """Angle in [-pi, pi)."""
    return (angle + math.pi) % (2 * math.pi) - math.pi


def check_height(height: float) -> float:
    """A camera height in :data:`HEIGHT_RANGE`, or a one-line error naming the field."""
    lo, hi = HEIGHT_RANGE
    if isinstance(height, bool) or not isinstance(height, numbers.Real):
        raise ValueError(f"height={height!r} is a {type(height).__name__}, not a number; allowed: a number of "
                         f"metres in [{lo}, {hi}]")
    if not lo <= float(height) <= hi:
        raise ValueError(f"height={height!r} is outside the sensible range [{lo}, {hi}] m")
    return float(height)

"""Physics of the abstract searcher: a pybullet world built from a scene description.

The body is a cylinder on a planar (x, y, yaw) joint chain; each env step sets a target
configuration and pybullet's position control tracks it, so walls and furniture stop the body
instead of being teleported through. The camera joints need no physics: they are clamped
angles in :class:`egosearch.sim.body.AgentState`.
"""

from __future__ import annotations

import math

import numpy as np

from egosearch.scene.parts import Part, Scene
from egosearch.sim.body import AgentSpec
from egosearch.sim.bullet import connect, pybullet

#: Physics sub-steps per env step. Enough that the body (moving <= 0.25 m per env step)
#: advances less than half its radius per sub-step, so it cannot tunnel through a 0.1 m wall.
SUBSTEPS = 4
#: Contacts closer than this (m) count as a collision: touching a wall is hitting it.
CONTACT_DISTANCE = 0.001
#: A body may end a step at most this deep (m) in the home; the solver's slop is backed off.
PENETRATION_TOLERANCE = 0.005
#: Deepest (m) the body may be in the home after any sub-step. Deeper means the motors are
#: squeezing it through a gap narrower than itself (two chair and sofa arms 33 cm apart let a
#: 40 cm body through, 4.5 cm deep at the pinch, and the step ended outside both); the step then
#: stops before the pinch. Below ``egosearch.sim.navgrid.MAX_PENETRATION`` (1 cm), the bound that
#: ℓ's grid assumes, by 2 mm for pybullet's cylinder against the exact geometry (a test keeps it
#: below; this module must not import that one's scipy).
SWEEP_TOLERANCE = 0.008
_JOINT_X, _JOINT_Y, _JOINT_YAW = 0, 1, 2
_BODY_LINK = 2


def add_static_part(client, part: Part) -> int:
    """One immovable pybullet body for an obstacle part, in ``client``."""
    if part.shape == "cylinder":
        shape = client.createCollisionShape(pybullet.GEOM_CYLINDER, radius=part.size[0] / 2, height=part.size[2])
    else:  # boxes, and meshes by their bounding box: furniture is never a loose mesh
        shape = client.createCollisionShape(pybullet.GEOM_BOX, halfExtents=[s / 2 for s in part.size])
    return client.createMultiBody(baseMass=0, baseCollisionShapeIndex=shape, basePosition=part.center,
                                  baseOrientation=client.getQuaternionFromEuler((0, 0, part.yaw)))


class World:
    """One pybullet client holding the static home and the searcher's body."""

    def __init__(self, scene: Scene, spec: AgentSpec):
        self.scene = scene
        self.spec = spec
        self._p = connect()
        p = self._p
        p.setPhysicsEngineParameter(fixedTimeStep=0.15 / SUBSTEPS, numSubSteps=0,
                                    numSolverIterations=10, deterministicOverlappingPairs=1)
        p.setGravity(0, 0, 0)
        self.static_ids = [add_static_part(self._p, part) for part in scene.obstacles]
        self._static_set = frozenset(self.static_ids)
        self.agent_id = self._add_agent()
        self._probe_id = self._add_probe()

    def close(self) -> None:
        if self._p is not None:
            self._p.disconnect()
            self._p = None

    def __del__(self):  # pybullet clients are a process-wide resource: release them
        try:
            self.close()
        except Exception:
            pass

    # -- building -------------------------------------------------------------------------
    def _body_shape(self) -> int:
        return self._p.createCollisionShape(pybullet.GEOM_CYLINDER, radius=self.spec.body_radius,
                                            height=self.spec.body_height)

    def _add_agent(self) -> int:
        p, spec = self._p, self.spec
        body_z = spec.body_clearance + spec.body_height / 2
        agent = p.createMultiBody(
            baseMass=0,
            basePosition=(0, 0, 0),
            linkMasses=[1.0, 1.0, 60.0],
            linkCollisionShapeIndices=[-1, -1, self._body_shape()],
            linkVisualShapeIndices=[-1, -1, -1],
            linkPositions=[(0, 0, 0), (0, 0, 0), (0, 0, body_z)],
            linkOrientations=[(0, 0, 0, 1)] * 3,
            linkInertialFramePositions=[(0, 0, 0)] * 3,
            linkInertialFrameOrientations=[(0, 0, 0, 1)] * 3,
            linkParentIndices=[0, 1, 2],
            linkJointTypes=[pybullet.JOINT_PRISMATIC, pybullet.JOINT_PRISMATIC, pybullet.JOINT_REVOLUTE],
            linkJointAxis=[(1, 0, 0), (0, 1, 0), (0, 0, 1)],
        )
        for j in range(3):
            p.changeDynamics(agent, j, linearDamping=0, angularDamping=0, lateralFriction=0.0,
                             jointDamping=0)
        return agent

    def _add_probe(self) -> int:
        """A collision-only copy of the body, parked far away, for free-space queries."""
        p, spec = self._p, self.spec
        probe = p.createMultiBody(baseMass=0, baseCollisionShapeIndex=self._body_shape(),
                                  basePosition=(0, 0, -100))
        p.setCollisionFilterPair(probe, self.agent_id, -1, _BODY_LINK, 0)
        del spec
        return probe

    # -- queries --------------------------------------------------------------------------
    def pose(self) -> tuple[float, float, float]:
        states = self._p.getJointStates(self.agent_id, (_JOINT_X, _JOINT_Y, _JOINT_YAW))
        return (states[0][0], states[1][0], states[2][0])

    def penetration(self) -> float:
        """Deepest penetration of the body, where it is now, into the home (m, >= 0)."""
        return self._penetration_at(self.pose())

    def _penetration_at(self, pose) -> float:
        return max(0.0, -self.clearance_at(pose[0], pose[1], 0.01))

    def clearance_at(self, x: float, y: float, max_distance: float = 0.5) -> float:
        """Signed distance (m) from a body placed at (x, y) to the nearest obstacle, capped."""
        p, spec = self._p, self.spec
        z = spec.body_clearance + spec.body_height / 2
        p.resetBasePositionAndOrientation(self._probe_id, (x, y, z), (0, 0, 0, 1))
        r = spec.body_radius + max_distance
        lo = (x - r, y - r, spec.body_clearance - max_distance)
        hi = (x + r, y + r, spec.body_clearance + spec.body_height + max_distance)
        nearest = max_distance
        for body, _ in p.getOverlappingObjects(lo, hi) or ():
            if body in self._static_set:
                for c in p.getClosestPoints(self._probe_id, body, max_distance):
                    nearest = min(nearest, c[8])
        p.resetBasePositionAndOrientation(self._probe_id, (0, 0, -100), (0, 0, 0, 1))
        return nearest

    def is_free(self, x: float, y: float, margin: float = 0.0) -> bool:
        return self.clearance_at(x, y, max_distance=margin + 0.05) > margin

    # -- motion ---------------------------------------------------------------------------
    def reset_agent(self, x: float, y: float, theta: float) -> None:
        p = self._p
        self.swept_poses = [(x, y, theta)]
        for joint, value in ((_JOINT_X, x), (_JOINT_Y, y), (_JOINT_YAW, theta)):
            p.resetJointState(self.agent_id, joint, value, 0.0)
        # Motors hold the reset pose until the first command.
        self._command(x, y, theta)

    def _command(self, x: float, y: float, theta: float) -> None:
        self._p.setJointMotorControlArray(
            self.agent_id, (_JOINT_X, _JOINT_Y, _JOINT_YAW), pybullet.POSITION_CONTROL,
            targetPositions=(x, y, theta), targetVelocities=(0, 0, 0),
            forces=(5000, 5000, 5000), positionGains=(1.0, 1.0, 1.0),
            velocityGains=(1.0, 1.0, 1.0))

    def move(self, dx: float, dy: float, dtheta: float) -> tuple[tuple[float, float, float], bool]:
        """Track a body-frame move for one env step. Returns the new (x, y, theta) and whether
        the body touched the home on the way."""
        p = self._p
        x, y, theta = self.pose()
        c, s = math.cos(theta), math.sin(theta)
        target = (x + c * dx - s * dy, y + s * dx + c * dy, theta + dtheta)
        self._command(*target)
        collided = False
        passed = [(x, y, theta)]
        for _ in range(SUBSTEPS):
            p.stepSimulation()
            if not collided:
                collided = any(c[8] < CONTACT_DISTANCE
                               for c in p.getContactPoints(bodyA=self.agent_id))
            now = self.pose()
            # Contact points come from the collision pass *before* each sub-step's motion, so
            # only the pose itself shows a body pushed deep into (or through) furniture.
            depth = self._penetration_at(now)
            if depth > SWEEP_TOLERANCE:
                collided = True
                pose = self._back_off(passed[-1], now)
                depth = self._penetration_at(pose)
                break
            passed.append(now)
        else:
            pose = passed.pop()
        # Checked on every step, not only after a reported contact: a body that travels into
        # furniture during the last sub-step has no contact to show for it, and would start
        # the next step inside.
        if depth > PENETRATION_TOLERANCE:
            collided = True
            pose = self._back_off((x, y, theta), pose)
        #: The poses this step passed through (after each sub-step) and ended at.
        self.swept_poses = passed[1:] + [pose]
        # Freeze the body where it ended: a blocked target must not keep pushing next step.
        for joint in (_JOINT_X, _JOINT_Y, _JOINT_YAW):
            p.resetJointState(self.agent_id, joint, pose[joint], 0.0)
        self._command(*pose)
        return pose, collided

    def _back_off(self, start, end, iterations: int = 8):
        """The last pose on the segment start -> end whose body clears the home: the solver
        leaves the body a few cm inside what it hit, and a body must end outside. Every step
        starts legal, so the answer is at worst ``start`` itself."""
        free, blocked = 0.0, 1.0
        for _ in range(iterations):
            mid = (free + blocked) / 2
            if self.clearance_at(start[0] + mid * (end[0] - start[0]),
                                 start[1] + mid * (end[1] - start[1]), 0.01) > 0:
                free = mid
            else:
                blocked = mid
        return tuple(a + free * (b - a) for a, b in zip(start, end))


def random_free_pose(world: World, rng: np.random.Generator, margin: float = 0.05,
                     max_tries: int = 10_000) -> tuple[float, float, float]:
    """A uniformly random collision-free body pose inside the home."""
    x0, y0, x1, y1 = world.scene.bounds
    r = world.spec.body_radius
    for _ in range(max_tries):
        x, y = rng.uniform(x0 + r, x1 - r), rng.uniform(y0 + r, y1 - r)
        if world.is_free(x, y, margin):
            return (float(x), float(y), float(rng.uniform(-math.pi, math.pi)))
    raise RuntimeError(f"no free pose found in {world.scene.name} after {max_tries} tries")

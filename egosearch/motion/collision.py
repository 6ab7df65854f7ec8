"""Full-body penetration of the home: the paper's Figure 8 failure as a measured rate.

A :class:`PenetrationCounter` holds its own pybullet client with the home's static obstacles
built exactly as :class:`egosearch.sim.world.World` builds them (boxes, cylinders, meshes by their
bounding box) plus one character body (humanoid capsules, Fetch cylinders or the abstract
cylinder). Keeping it apart from the env's world means posing the character never disturbs the
abstract model's physics. A pose *penetrates* when any of the character's collision shapes is
more than :data:`PENETRATION_DEPTH` inside an obstacle (pybullet ``getClosestPoints``).
"""

from __future__ import annotations

from egosearch.motion import quat
from egosearch.motion.base import FullBodyPose
from egosearch.motion.fetch import FetchBody
from egosearch.motion.humanoid import HumanoidBody
from egosearch.scene.parts import Scene
from egosearch.sim.body import AgentSpec
from egosearch.sim.bullet import connect, pybullet
from egosearch.sim.world import add_static_part

#: A shape this deep (m) inside an obstacle counts as a penetration; shallower contact is touch.
PENETRATION_DEPTH = 0.01


class PenetrationCounter:
    def __init__(self, scene: Scene, character: str):
        self.scene = scene
        self.character = character
        self._p = connect()
        self.static_ids = [add_static_part(self._p, part) for part in scene.obstacles]
        self._static_set = frozenset(self.static_ids)
        self._part_of = dict(zip(self.static_ids, scene.obstacles))
        if character == "humanoid":
            self.body = HumanoidBody(self._p)
        elif character == "fetch":
            self.body = FetchBody(self._p)
        elif character == "abstract":
            self.body = CylinderBody(self._p, AgentSpec())
        else:
            raise ValueError(f"character={character!r}; allowed: humanoid, fetch, abstract")

    def close(self) -> None:
        if self._p is not None:
            self._p.disconnect()
            self._p = None

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    def contacts(self, pose: FullBodyPose) -> list[tuple[str, float]]:
        """(obstacle part name, penetration depth in m > 0) for every obstacle the pose is inside."""
        p = self._p
        self.body.set_pose(pose)
        lo, hi = self.body.aabb()
        out = {}
        for body, _ in p.getOverlappingObjects(lo, hi) or ():
            if body in self._static_set:
                for c in p.getClosestPoints(self.body.body_id, body, 0.0):
                    if c[8] < 0:
                        name = self._part_of[body].name
                        out[name] = max(out.get(name, 0.0), -c[8])
        return sorted(out.items(), key=lambda kv: -kv[1])

    def depth(self, pose: FullBodyPose) -> float:
        """Deepest penetration of the pose into the home (m, >= 0)."""
        found = self.contacts(pose)
        return found[0][1] if found else 0.0

    def penetrates(self, pose: FullBodyPose) -> bool:
        return self.depth(pose) > PENETRATION_DEPTH


class CylinderBody:
    """The abstract searcher's collision cylinder."""

    def __init__(self, client, spec: AgentSpec):
        self._p = client
        self.spec = spec
        shape = client.createCollisionShape(pybullet.GEOM_CYLINDER, radius=spec.body_radius, height=spec.body_height)
        self.body_id = client.createMultiBody(baseMass=0, baseCollisionShapeIndex=shape, basePosition=(0, 0, -50))

    def set_pose(self, pose: FullBodyPose) -> None:
        z = self.spec.body_clearance + self.spec.body_height / 2
        self._p.resetBasePositionAndOrientation(self.body_id, (pose.x, pose.y, z),
                                                tuple(quat.yaw(pose.theta)))

    def aabb(self):
        return self._p.getAABB(self.body_id, -1)


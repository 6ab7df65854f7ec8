"""``MatchingMG``: motion matching in the spirit of NSM [SZKS19] / Clavet's motion matching.

The database holds every frame of DeepMimic's walk, run and spin clips (pybullet_data), resampled
at the sub-step rate and augmented the usual way: the walk at five playback rates, each bent into
curves of five turn rates, played backwards for backward steps, the run slowed to a jog, the spin
slowed down, and standing still or turning on the spot. Each frame's feature vector holds the
clip's own future root trajectory (positions and facings 0.3, 0.6 and 0.9 s ahead, in the
frame's character frame), its current root velocity and turn rate, and its ankle positions and
velocities (for continuity).

Every :data:`SEARCH_FRAMES` sub-steps the generator builds the same features from the plan (where
the plan will be 0.3/0.6/0.9 s ahead, seen from where the character actually is) and from its
current pose, finds the nearest database frame, and cross-fades to it over :data:`BLEND_FRAMES`.
The root moves with the clip's own root motion (clipped to the humanoid's limits), not with the
plan: speeds are quantised to the database's, turns come from curved clips played for a while,
so the character overshoots turns and cannot side-step (there is no side-step clip), a different
deviation from the plan than :class:`~egosearch.motion.phase.PhaseMG`'s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from egosearch.motion import mocap, quat
from egosearch.motion.base import (
    SUBSTEP_SECONDS,
    SUBSTEPS,
    FullBodyPose,
    Limits,
    MotionGenerator,
    plan_at,
)
from egosearch.motion.humanoid import HUMANOID_LIMITS, HUMANOID_SCALE, eye_height, stand_pose
from egosearch.motion.skeleton import REVOLUTE, SPHERICAL
from egosearch.sim.body import AgentState, wrap_angle

#: Future trajectory samples (sub-steps ahead): 0.3, 0.6, 0.9 s.
FUTURE_FRAMES = (10, 20, 30)
#: Play the matched clip this many sub-steps before searching again (0.3 s).
SEARCH_FRAMES = 10
#: Cross-fade length (sub-steps).
BLEND_FRAMES = 5
#: Feature group weights (after per-dimension standardisation).
WEIGHTS = {"traj_pos": 1.0, "traj_dir": 1.0, "vel": 1.0, "omega": 1.0, "feet": 0.5, "feet_vel": 0.5}

WALK_RATES = (0.6, 0.8, 1.0, 1.2, 1.4)
WALK_CURVES = (-1.6, -0.8, 0.0, 0.8, 1.6)
SMALL_CURVES = (-0.8, 0.0, 0.8)
IDLE_TURNS = (-2.0, -1.0, 0.0, 1.0, 2.0)
#: The run at 0.43 x speed is a 1.67 m/s jog (the abstract model's top speed, clipped to the
#: humanoid's 1.5 m/s); the spin at 0.3 x keeps its turn under 2.5 rad/s.
RUN_RATE = 0.43
SPIN_RATE = 0.3
#: A window is searchable only while the eyes stay above this fraction of the mean walking eye
#: height (1.35 m for the 1.65 m humanoid).
UPRIGHT_EYE_FRACTION = 0.82


def _idle_track(scale: float, dt: float, turn: float, n: int = 20) -> mocap.Track:
    stand = stand_pose(scale)
    root_z = np.full(n, stand["root_z"])
    root_local = np.tile(stand["root_local"], (n, 1))
    joints = {k: np.repeat(np.asarray(v, dtype=np.float64)[None], n, axis=0) for k, v in stand["joints"].items()}
    eye_z, eye_fwd, feet = mocap.pose_features(root_z, root_local, joints, scale)
    return mocap.Track(f"idle{turn:+g}" if turn else "idle", dt, np.zeros((n, 2)), np.full(n, turn), root_z,
                       root_local, joints, eye_z, eye_fwd, feet, meta={"clip": "idle", "curvature": turn})


@dataclass
class Database:
    tracks: list[mocap.Track]
    starts: np.ndarray
    """(n_tracks + 1,) first row of every track in ``raw``."""
    raw: np.ndarray
    """(F, D) features of every frame of every track (unstandardised)."""
    track_of: np.ndarray
    """(S,) track index of every searchable row."""
    frame_of: np.ndarray
    """(S,) frame index within its track."""
    features: np.ndarray
    """(S, D) standardised, weighted features of the searchable rows."""
    mean: np.ndarray
    scale: np.ndarray
    """Per-dimension divisor (std / sqrt(weight))."""

    def raw_row(self, track: int, frame: int) -> np.ndarray:
        return self.raw[self.starts[track] + frame % len(self.tracks[track])]


def _track_features(t: mocap.Track) -> np.ndarray:
    n, dt = len(t), t.dt
    horizon = max(FUTURE_FRAMES)
    rows = []
    feet = t.feet  # (n, 2, 3)
    feet_vel = (feet[(np.arange(n) + 1) % n] - feet[(np.arange(n) - 1) % n]) / (2 * dt)
    for i in range(n):
        pos = np.zeros(2)
        facing = 0.0
        traj_pos, traj_dir = [], []
        for f in range(horizon):
            k = (i + f) % n
            c, s = math.cos(facing), math.sin(facing)
            v = t.vel_local[k]
            pos = pos + dt * np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])
            facing += t.omega[k] * dt
            if f + 1 in FUTURE_FRAMES:
                traj_pos.extend(pos)
                traj_dir.extend((math.cos(facing), math.sin(facing)))
        rows.append(np.concatenate([traj_pos, traj_dir, t.vel_local[i], [t.omega[i]], feet[i, :, :].ravel(),
                                    feet_vel[i].ravel()]))
    return np.asarray(rows)


def _groups() -> list[tuple[str, int]]:
    k = len(FUTURE_FRAMES)
    return [("traj_pos", 2 * k), ("traj_dir", 2 * k), ("vel", 2), ("omega", 1), ("feet", 6), ("feet_vel", 6)]


@lru_cache(maxsize=4)
def build_database(scale: float = HUMANOID_SCALE, dt: float = SUBSTEP_SECONDS) -> Database:
    tracks = []
    for rate in WALK_RATES:
        for curve in WALK_CURVES:
            tracks.append(mocap.make_track("walk", scale, dt, rate=rate, curvature=curve))
    for curve in SMALL_CURVES:
        tracks.append(mocap.make_track("walk", scale, dt, rate=0.6, reverse=True, curvature=curve))
        tracks.append(mocap.make_track("run", scale, dt, rate=RUN_RATE, curvature=curve))
    tracks.append(mocap.make_track("spin", scale, dt, rate=SPIN_RATE))
    for turn in IDLE_TURNS:
        tracks.append(_idle_track(scale, dt, turn))
    feats = [_track_features(t) for t in tracks]
    raw = np.concatenate(feats)
    starts = np.concatenate([[0], np.cumsum([len(f) for f in feats])])
    # Searchable windows: the character stays upright for the whole window (the spin clip is a
    # dance spin that crouches to the floor; its upright turning parts stay in).
    upright = UPRIGHT_EYE_FRACTION * float(np.mean(mocap.make_track("walk", scale, dt).eye_z))
    keep_t, keep_f = [], []
    for i, t in enumerate(tracks):
        n = len(t)
        for f in range(n):
            window = t.eye_z[(f + np.arange(SEARCH_FRAMES + BLEND_FRAMES)) % n]
            if window.min() >= upright:
                keep_t.append(i)
                keep_f.append(f)
    track_of, frame_of = np.array(keep_t), np.array(keep_f)
    rows = raw[starts[track_of] + frame_of]
    mean = rows.mean(axis=0)
    std = rows.std(axis=0) + 1e-6
    weight = np.concatenate([np.full(n, WEIGHTS[g] / n) for g, n in _groups()])
    div = std / np.sqrt(weight)
    return Database(tracks, starts, raw, track_of, frame_of, (rows - mean) / div, mean, div)


class MatchingMG(MotionGenerator):
    name = "humanoid_matching"
    character = "humanoid"

    def __init__(self, world=None, scale: float = HUMANOID_SCALE, limits: Limits = HUMANOID_LIMITS,
                 search_frames: int = SEARCH_FRAMES, blend_frames: int = BLEND_FRAMES):
        super().__init__(world)
        self.scale = scale
        self.limits = limits
        self.search_frames = search_frames
        self.blend_frames = blend_frames
        self.db = build_database(scale)
        self._idle = next(i for i, t in enumerate(self.db.tracks) if t.name == "idle")

    # -- database access ----------------------------------------------------------------------

    def _frame_pose(self, track: int, frame: float):
        t = self.db.tracks[track]
        i = int(frame) % len(t)
        return t.root_z[i], t.root_local[i], {k: v[i] for k, v in t.joints.items()}

    def _blended_pose(self, st: dict) -> tuple[float, np.ndarray, dict]:
        z, r, j = self._frame_pose(st["track"], st["frame"])
        if st["blend"] <= 0:
            return float(z), r, j
        w = 1.0 - st["blend"] / self.blend_frames
        z0, r0, j0 = self._frame_pose(st["prev_track"], st["prev_frame"])
        joints = {}
        for name in SPHERICAL:
            joints[name] = quat.slerp(j0[name], j[name], w)
        for name in REVOLUTE:
            joints[name] = np.asarray((1 - w) * j0[name] + w * j[name])
        return float((1 - w) * z0 + w * z), quat.slerp(r0, r, w), joints

    def _root_motion(self, st: dict) -> tuple[float, float, float]:
        t = self.db.tracks[st["track"]]
        i = st["frame"] % len(t)
        v, om = t.vel_local[i], t.omega[i]
        if st["blend"] > 0:
            w = 1.0 - st["blend"] / self.blend_frames
            t0 = self.db.tracks[st["prev_track"]]
            i0 = st["prev_frame"] % len(t0)
            v = (1 - w) * t0.vel_local[i0] + w * v
            om = (1 - w) * t0.omega[i0] + w * om
        return float(v[0]), float(v[1]), float(om)

    def _pose(self, x, y, theta, pitch, head_yaw, st: dict, vx=0.0, vy=0.0, omega=0.0, blocked=False):
        root_z, root_local, joints = self._blended_pose(st)
        t = self.db.tracks[st["track"]]
        return FullBodyPose(x, y, theta, eye_height(root_z, root_local, joints, self.scale), pitch, head_yaw,
                            joints=joints, root_z=root_z, root_local=root_local,
                            phase=(st["frame"] % len(t)) / len(t), clip=t.name, vx=vx, vy=vy, omega=omega,
                            blocked=blocked, state=dict(st))

    def initial_pose(self, state: AgentState) -> FullBodyPose:
        st = {"track": self._idle, "frame": 0, "prev_track": self._idle, "prev_frame": 0, "blend": 0,
              "since_search": self.search_frames, "searches": 0}
        pitch = float(np.clip(state.pitch, *self.limits.pitch_limits))
        head_yaw = float(np.clip(state.head_yaw, *self.limits.yaw_limits))
        return self._pose(state.x, state.y, state.theta, pitch, head_yaw, st)

    # -- matching -----------------------------------------------------------------------------
    def query(self, x: float, y: float, theta: float, vx: float, vy: float, omega: float, st: dict,
              plan: list[AgentState], tau: float) -> np.ndarray:
        """The (standardised) feature vector the plan asks for from the current state."""
        c, s = math.cos(theta), math.sin(theta)
        traj_pos, traj_dir = [], []
        for f in FUTURE_FRAMES:
            px, py, pth, _, _ = plan_at(plan, tau + f / SUBSTEPS)
            dx, dy = px - x, py - y
            traj_pos.extend((c * dx + s * dy, -s * dx + c * dy))
            traj_dir.extend((math.cos(pth - theta), math.sin(pth - theta)))
        vel = (c * vx + s * vy, -s * vx + c * vy)
        pose_part = self.db.raw_row(st["track"], st["frame"])[-12:]
        raw = np.concatenate([traj_pos, traj_dir, vel, [omega], pose_part])
        return (raw - self.db.mean) / self.db.scale

    def search(self, q: np.ndarray) -> tuple[int, int, float]:
        d = np.sum((self.db.features - q) ** 2, axis=1)
        i = int(np.argmin(d))
        return int(self.db.track_of[i]), int(self.db.frame_of[i]), float(d[i])

    # -- one env step -------------------------------------------------------------------------
    def _advance(self, pose: FullBodyPose, plan: list[AgentState], k: int) -> FullBodyPose:
        lim, dt = self.limits, SUBSTEP_SECONDS
        st = dict(pose.state)
        x, y, th = pose.x, pose.y, pose.theta
        vx, vy, om = pose.vx, pose.vy, pose.omega
        pitch, head_yaw = pose.pitch, pose.head_yaw
        blocked = False
        for j in range(SUBSTEPS):
            tau = k + j / SUBSTEPS
            if st["since_search"] >= self.search_frames:
                ti, fi, _ = self.search(self.query(x, y, th, vx, vy, om, st, plan, tau))
                st["since_search"] = 0
                st["searches"] = st.get("searches", 0) + 1
                n = len(self.db.tracks[ti])
                same = ti == st["track"] and min((fi - st["frame"]) % n, (st["frame"] - fi) % n) <= 3
                if not same:
                    st.update(prev_track=st["track"], prev_frame=st["frame"], track=ti, frame=fi,
                              blend=self.blend_frames)
            # Root motion of the clip, clipped to the humanoid's limits.
            fwd, left, wom = self._root_motion(st)
            c, s = math.cos(th), math.sin(th)
            wvx, wvy = c * fwd - s * left, s * fwd + c * left
            nom = om + float(np.clip(wom - om, -lim.max_turn_accel * dt, lim.max_turn_accel * dt))
            cap = lim.turn_cap(math.hypot(vx, vy))
            nom = float(np.clip(nom, -cap, cap))
            nth = th + nom * dt
            wvx, wvy = lim.limit_velocity(wvx, wvy, vx, vy, nth, dt)
            nx, ny, hit = self._move_root(x, y, x + wvx * dt, y + wvy * dt)
            if hit:
                blocked = True
                wvx, wvy = (nx - x) / dt, (ny - y) / dt
            pitch, head_yaw = self._track_head(pitch, head_yaw, nth, plan, k + (j + 1) / SUBSTEPS, dt)
            x, y, th, vx, vy, om = nx, ny, nth, wvx, wvy, nom
            self._record(x, y, th)
            # Advance the cursors.
            st["frame"] = (st["frame"] + 1) % len(self.db.tracks[st["track"]])
            if st["blend"] > 0:
                st["prev_frame"] = (st["prev_frame"] + 1) % len(self.db.tracks[st["prev_track"]])
                st["blend"] -= 1
            st["since_search"] += 1
        return self._pose(x, y, wrap_angle(th), pitch, head_yaw, st, vx, vy, om, blocked)

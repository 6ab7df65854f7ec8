"""The search task of paper 4.1 as a ``gymnasium.Env``.

Observation (a ``Dict``):
- ``depth``: the last K = 5 depth frames, oldest first, uint8 100x100, depth / 5 m * 255; at
  reset the first frame is repeated K times;
- ``mask``: the 29-d mask feature [xc, yc, r, alpha, 5x5 mask] plus a visibility flag;
- ``proprio``: (q_p, q_y, last change of q_p, last change of q_y); zeros for the head-off body;
- ``state`` (only with ``privileged_state=True``, for a privileged critic in training): the
  hidden state of :func:`privileged_state`. No policy ever reads it.

With ``target_memory=True`` (the ``*Memory-v0`` ids: a CHANGE OF OBSERVATION, never the paper's)
the ``mask`` vector gains :data:`TARGET_MEMORY_DIM` values after the paper's 30: where the target
was last seen, as a point estimated from that frame's depth under the mask and carried by the
body's own odometry into its current frame (forward, left, up from the camera; m / 5, m / 5,
m / 2), the steps since then (/ 100, capped at 1) and whether it was ever seen this episode. It is
the one-entry "semantic map" of a classical object-goal searcher (habitat's GPS+compass gives the
same odometry), the cheapest memory the policy lacks: it forgets a target as soon as it leaves view.
With ``floor_map=True`` (the ``*Map-v0`` ids, also a CHANGE OF OBSERVATION) it gains
:data:`FLOOR_MAP_DIM` more: a 7 x 7 grid of 0.6 m squares around the body, turning with it, saying
how much of each square's floor it has seen, how much of it is occupied, and whether it has stood
there (:class:`egosearch.sim.floormap.FloorMap`, built from its own depth frames and pose): the map a
classical searcher plans on, as a memory of where it has been and what it has not seen.
The observation options (:mod:`egosearch.sim.observation_options`: keyword options with no id of their
own, each a CHANGE OF OBSERVATION, never the paper's) append their values to these vectors, in registration
order: ``contact_signal=True`` (:mod:`egosearch.sim.contact_signal`, after habitat-lab's ``collisions``
measure) appends a bump bit and the recent collision count to ``proprio``; ``strided_history=True``
(:mod:`egosearch.sim.strided_history`) makes ``depth`` the newest frame and those 1, 4, 16 and 64 steps before it.

Action: [dx, dy, dtheta, dq_p, dq_y] in [-1, 1], scaled by :class:`egosearch.sim.body.AgentSpec`
(head-off: [dx, dy, dtheta]).

Reward: r = 1.0 r_s + 1.0 r_d + 1.0 r_l + 0.1 r_c with r_s = 10 on success, r_d = minus the
distance to the target while it is seen (else 0), r_l = -0.1 and r_c = clip(-0.1 n_col, -3, 0)
over the episode's collision count. TRAINING ONLY, with ``coverage_bonus=b > 0`` (an exploration
aid, never in evaluation): + b for each step that enters a 0.5 m floor cell the body has not been
in this episode (a count-based novelty bonus; ``info["r_cov"]``).

Two ways to start an episode:
- training (no scenario given): a random target on the placement scheme's surfaces, a random
  collision-free start, camera height U[1.0, 1.8] m per episode plus U[-0.1, 0.1] m per step;
  ``reset(options={"start_radius": r})`` draws the start within r m of the target (a training
  curriculum: ``LearnerConfig.curriculum_steps``);
- evaluation: ``reset(options={"scenario": s})`` with an :class:`egosearch.sim.scenarios.Scenario`,
  at its fixed height without noise.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import replace

import gymnasium
import numpy as np
from gymnasium import spaces

from egosearch.scene import layouts as layouts_mod
from egosearch.scene.objects import TARGET_OBJECTS, get_object
from egosearch.scene.parts import Part
from egosearch.scene.placement import sample_target
from egosearch.sim import observation_options as observation_options_mod
from egosearch.sim.body import IMAGE_SIZE, AgentSpec, AgentState, check_height
from egosearch.sim.body_envs import BODY_METADATA, check_flag
from egosearch.sim.floormap import FloorMap
from egosearch.sim.scenarios import (
    MAX_STEPS,
    SUCCESS_DISTANCE,
    Scenario,
    check_placement,
    navgrid_for,
    shortest_path_region,
)
from egosearch.sim.sensor import DepthMaskSensor, camera_axes, mask_feature, pixel_rays_camera
from egosearch.sim.world import World

FRAME_HISTORY = 5
"""K of paper 4.1."""
MASK_FEATURE_DIM = 30
REWARD_WEIGHTS = (1.0, 1.0, 1.0, 0.1)
"""[w_s, w_d, w_l, w_c] of paper eq. 2."""
SUCCESS_REWARD = 10.0
LIVE_PENALTY = -0.1
COLLISION_PENALTY_PER_HIT = -0.1
COLLISION_PENALTY_FLOOR = -3.0
PRIVILEGED_STATE_DIM = 12
"""Size of :func:`privileged_state`."""
TARGET_MEMORY_DIM = 5
"""Values the ``target_memory`` option appends to ``mask`` (see the module docstring)."""
COVERAGE_CELL = 0.5
"""Side (m) of the floor cells the training-only ``coverage_bonus`` counts."""
FLOOR_MAP_CELLS = 7
"""Side of the ``floor_map`` option's egocentric grid (squares)."""
FLOOR_MAP_DIM = 3 * FLOOR_MAP_CELLS * FLOOR_MAP_CELLS
"""Values the ``floor_map`` option appends to ``mask``."""
MEMORY_HORIZON = 100
"""Steps since the target was last seen are divided by this (and capped at 1)."""
PROPRIO_DIM = 4


def space_dims(head: bool = True, target_memory: bool = False, floor_map: bool = False,
               **observation_options: bool) -> dict[str, int]:
    """Sizes of the action and of the observation's vectors for these options (the observation options by
    name, :mod:`egosearch.sim.observation_options`), without building an env: what a trained actor must
    match (``SearchEnv`` builds its spaces from them)."""
    check_observation_options(observation_options)
    extra = observation_options_mod.extra_dims(observation_options)
    mask = MASK_FEATURE_DIM + (TARGET_MEMORY_DIM if target_memory else 0) + (FLOOR_MAP_DIM if floor_map else 0)
    return {"action": replace(AgentSpec(), head=bool(head)).action_dim, "mask": mask + extra.get("mask", 0),
            "proprio": PROPRIO_DIM + extra.get("proprio", 0)}


def check_observation_options(options: dict) -> None:
    """One line for a keyword that is no registered observation option, or a value that is no flag."""
    for name, value in options.items():
        if name not in observation_options_mod.OPTIONS:
            known = ", ".join(observation_options_mod.option_names())
            raise ValueError(f"unknown env option {name!r}; the observation options: {known}")
        check_flag(name, value)


DISTANCE_REWARDS = ("distance", "progress", "geodesic")
"""How r_d is read: ``distance`` is the paper's text (minus the distance while the target is
seen); ``progress`` is Savva et al.'s form, which the paper cites (the decrease of that distance
since the last step, while seen); ``geodesic`` is habitat-lab's ``DistanceToGoalReward``: the
decrease since the last step of the geodesic distance to the poses from which the target counts as
found (``scenarios.shortest_path_region``), at every step, seen or not, and with it the collision
term without its floor (the paper's r_c stops growing at 30 collisions, so pushing on costs
nothing). ``progress`` and ``geodesic`` are training-only ablations, never the default."""


def reward_terms(success: bool, visible: bool, distance: float, n_collisions: int,
                 previous_distance: float | None = None, distance_reward: str = "distance",
                 geodesic_decrease: float = 0.0) -> dict[str, float]:
    """The four terms of paper eq. 2 and their weighted sum. ``previous_distance`` (None when
    the target was not seen at the last step) only matters for ``distance_reward="progress"``,
    ``geodesic_decrease`` (m the body came closer along the floor this step) for ``"geodesic"``."""
    if distance_reward == "geodesic":
        r_d = geodesic_decrease
    elif distance_reward == "progress":
        r_d = previous_distance - distance if visible and previous_distance is not None else 0.0
    else:
        r_d = -distance if visible else 0.0
    floor = -math.inf if distance_reward == "geodesic" else COLLISION_PENALTY_FLOOR
    terms = {
        "r_s": SUCCESS_REWARD if success else 0.0,
        "r_d": r_d,
        "r_l": LIVE_PENALTY,
        "r_c": float(max(COLLISION_PENALTY_PER_HIT * n_collisions, floor)),
    }
    terms["reward"] = float(sum(w * terms[k] for w, k in zip(REWARD_WEIGHTS, ("r_s", "r_d", "r_l", "r_c"))))
    return terms


def target_distance(state: AgentState, target: Part, body_radius: float) -> float:
    """Horizontal distance from the body's surface to the target's centre (m, >= 0)."""
    d = math.hypot(target.center[0] - state.x, target.center[1] - state.y) - body_radius
    return max(0.0, d)


def privileged_state(state: AgentState, target: Part, distance: float, visible: bool) -> np.ndarray:
    """What the env knows and the policy does not (asymmetric actor-critic, Pinto et al. 2018):
    the body's position (m / 10) and heading (cos, sin) in the home, the target's position
    (m / 10), the target in the body's frame (forward, left, m / 5), the distance of eq. 2 (m / 5),
    the camera height (m) and whether the target is seen."""
    dx, dy = target.center[0] - state.x, target.center[1] - state.y
    c, s = math.cos(state.theta), math.sin(state.theta)
    return np.array([state.x / 10, state.y / 10, c, s, target.center[0] / 10, target.center[1] / 10,
                     target.center[2] / 10, (c * dx + s * dy) / 5, (-s * dx + c * dy) / 5, distance / 5,
                     state.camera_height, float(visible)], np.float32)


class SearchEnv(gymnasium.Env):
    metadata = BODY_METADATA

    def __init__(self, layout: str = "kitchen_living", placement: str = "everywhere",
                 head: bool = True, height: float | None = None, height_noise: bool | None = None,
                 max_steps: int = MAX_STEPS, objects: tuple[str, ...] | None = None,
                 distance_reward: str = "distance", train_heights: tuple[float, float] | None = None,
                 privileged_state: bool = False, target_memory: bool = False, floor_map: bool = False,
                 coverage_bonus: float = 0.0, render_mode: str | None = None, **observation_options: bool):
        """
        Args:
            layout: a home name (``kitchen_living``, ``bedroom_bath`` or ``home<seed>``).
            placement: ``no_low_cabinets`` or ``everywhere``.
            head: False for the head-off body (camera fixed to the body).
            height: fixed camera height (m); None draws it per episode as in training.
            height_noise: per-step height noise; default on exactly when ``height`` is None.
            max_steps: T_max.
            objects: target object names to draw from in training (default: all).
            distance_reward: ``distance`` (paper), ``progress`` or ``geodesic`` (ablations): see
                :data:`DISTANCE_REWARDS`.
            train_heights: (low, high) range (m) of the per-episode camera height in training;
                default the paper's ``AgentSpec.train_height_range`` [1.0, 1.8].
            privileged_state: add the ``state`` entry (:func:`privileged_state`) to every
                observation, for a learner's privileged critic; policies never read it.
            target_memory: append the last-seen target memory to ``mask`` (a change of
                observation: see the module docstring).
            floor_map: append the egocentric floor map to ``mask`` (a change of observation).
            coverage_bonus: training-only reward per step into a floor cell not visited this
                episode (0: the paper's reward).
            render_mode: ``"rgb_array"`` gives the depth image with the mask in red.
            observation_options: the observation options turned on, by name (``contact_signal=True``:
                :mod:`egosearch.sim.observation_options`), each a change of observation.
        """
        for name, value in (("head", head), ("target_memory", target_memory), ("floor_map", floor_map)):
            check_flag(name, value)
        check_observation_options(observation_options)
        self.scene = layouts_mod.get_scene(layout)
        self.layout = layout
        self.placement = check_placement(placement)
        self.fixed_height = None if height is None else check_height(height)
        self.height_noise = (height is None) if height_noise is None else bool(height_noise)
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode={render_mode!r}; allowed: None, rgb_array")
        self.render_mode = render_mode
        if isinstance(max_steps, bool) or not isinstance(max_steps, numbers.Integral):
            raise ValueError(f"max_steps={max_steps!r} is a {type(max_steps).__name__}; allowed: an integer >= 1 "
                             "(T_max: the steps before an episode is truncated)")
        if max_steps <= 0:
            raise ValueError(f"max_steps={max_steps}: every episode would end before its first step; allowed: an "
                             "integer >= 1 (T_max: the steps before an episode is truncated)")
        self.max_steps = int(max_steps)
        if distance_reward not in DISTANCE_REWARDS:
            raise ValueError(f"distance_reward={distance_reward!r}; allowed: {', '.join(DISTANCE_REWARDS)}")
        self.distance_reward = distance_reward
        self.objects = tuple(objects) if objects else tuple(sorted(TARGET_OBJECTS))
        for name in self.objects:
            get_object(name)
        self.spec_agent = replace(AgentSpec(), head=bool(head))
        if train_heights is not None:
            low, high = (check_height(h) for h in train_heights)
            if low > high:
                raise ValueError(f"train_heights={train_heights!r}: low must not exceed high")
            self.spec_agent = replace(self.spec_agent, train_height_range=(low, high))
        self._scale = self.spec_agent.action_scale()
        self.world = World(self.scene, self.spec_agent)
        self.sensor = DepthMaskSensor(self.scene, width=IMAGE_SIZE, height=IMAGE_SIZE)
        self.with_state = bool(privileged_state)
        self.target_memory = bool(target_memory)
        self.coverage_bonus = float(coverage_bonus)
        if not (math.isfinite(self.coverage_bonus) and self.coverage_bonus >= 0):
            raise ValueError(f"coverage_bonus={coverage_bonus!r}; allowed: a finite number >= 0")
        self._rays = pixel_rays_camera(IMAGE_SIZE, IMAGE_SIZE, self.sensor.fov_deg) if self.target_memory else None
        # a coarse map is enough for a 0.6 m summary, and keeps the env step cheap (~1 ms)
        self._floor = FloorMap.for_sensor(self.sensor, pixel_stride=6, free_step=0.15) if floor_map else None
        self.observation_options = {name: True for name, on in observation_options.items() if on}
        """The observation options turned on (name -> True)."""
        self._options = observation_options_mod.build(self.observation_options)
        self._offsets = observation_options_mod.frame_offsets(self.observation_options, FRAME_HISTORY)
        """The depth stack's frames as steps back from the newest, oldest first (an option may space them out)."""
        self._strided = self._offsets != tuple(range(FRAME_HISTORY - 1, -1, -1))
        self._history: list[np.ndarray] = []
        """With strided frames: every depth frame of the episode so far (at most T_max + 1)."""
        dims = space_dims(head, self.target_memory, floor_map, **self.observation_options)
        observation_spaces = {
            "depth": spaces.Box(0, 255, (FRAME_HISTORY, IMAGE_SIZE, IMAGE_SIZE), np.uint8),
            "mask": spaces.Box(-4.0, 4.0, (dims["mask"],), np.float32),
            "proprio": spaces.Box(-4.0, 4.0, (dims["proprio"],), np.float32),
        }
        if self.with_state:
            observation_spaces["state"] = spaces.Box(-np.inf, np.inf, (PRIVILEGED_STATE_DIM,), np.float32)
        self.observation_space = spaces.Dict(observation_spaces)
        self.action_space = spaces.Box(-1.0, 1.0, (self.spec_agent.action_dim,), np.float32)
        self._frames = np.zeros((FRAME_HISTORY, IMAGE_SIZE, IMAGE_SIZE), np.uint8)
        self._last_depth = self._last_mask = None

    # -- episode ---------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        rng = self.np_random
        scenario: Scenario | None = (options or {}).get("scenario")
        spec = self.spec_agent
        if scenario is not None:
            if scenario.layout != self.layout:
                raise ValueError(f"scenario layout={scenario.layout!r} but this env is {self.layout!r}")
            self.target = scenario.target()
            x, y, theta = scenario.start_x, scenario.start_y, scenario.start_theta
            self.base_height = scenario.height
            self.scenario_id = scenario.scenario_id
        else:
            self.target = sample_target(self.scene, get_object(self.objects[int(rng.integers(len(self.objects)))]),
                                        self.placement, rng)
            x, y, theta = self._random_start(rng, (options or {}).get("start_radius"))
            lo, hi = spec.train_height_range
            self.base_height = self.fixed_height if self.fixed_height is not None else float(rng.uniform(lo, hi))
            self.scenario_id = -1
        self.sensor.set_target(self.target)
        self.world.reset_agent(x, y, theta)
        pitch = 0.0 if spec.head else spec.fixed_pitch
        self.state = AgentState(x, y, theta, pitch, 0.0, self._camera_height(rng, scenario is None))
        self.steps = 0
        self.collisions = 0
        self.path_length = 0.0
        self._dq = np.zeros(2)
        for option in self._options:
            option.reset(self)
        self._memory_point, self._since_seen = None, 0
        self._visited = {self._cell()}
        if self._floor is not None:
            self._floor.reset()
        depth, mask = self._sense()
        self._remember(depth, mask)
        self._frames[:] = depth
        self._history = [depth] if self._strided else []
        self._seen_distance = target_distance(self.state, self.target, spec.body_radius) if mask.any() else None
        if self.distance_reward == "geodesic":
            grid = navgrid_for(self.layout)
            goal = shortest_path_region(self.layout, self.target, self.base_height)
            if not (goal & grid.reachable).any():
                # a training target this camera height cannot see from near it (a high shelf):
                # shape toward its surroundings instead, so the episode still has a gradient
                goal = grid.touch_region(self.target.center[:2], SUCCESS_DISTANCE)
            self._geodesic_field = grid.distances_to(goal, reachable=True)
            self._geodesic = self._geodesic_to_goal()
        return self._observation(mask), self._info(mask.any(), False)

    def _geodesic_to_goal(self) -> float:
        """ℓ from the body to where the target counts as found (inf off the reachable floor)."""
        return navgrid_for(self.layout).lower_bound_length(self._geodesic_field, self.state.x, self.state.y)

    def _random_start(self, rng, start_radius: float | None = None) -> tuple[float, float, float]:
        """A collision-free start in the home's main free region; with ``start_radius`` (a training
        curriculum) only cells within that horizontal distance of the target are drawn, when any is."""
        grid = navgrid_for(self.layout)
        rows, cols = np.nonzero(grid.main_region)
        if start_radius is not None:
            xs, ys = grid.xs[cols], grid.ys[rows]
            near = np.hypot(xs - self.target.center[0], ys - self.target.center[1]) <= float(start_radius)
            if near.any():
                rows, cols = rows[near], cols[near]
        for _ in range(1000):
            i = int(rng.integers(len(rows)))
            x, y = grid.center(rows[i], cols[i])
            if self.world.is_free(x, y, margin=0.01):
                return x, y, float(rng.uniform(-math.pi, math.pi))
        raise RuntimeError(f"no collision-free start found in {self.layout}")

    def _camera_height(self, rng, noisy: bool) -> float:
        if self.height_noise and noisy:
            return self.base_height + float(rng.uniform(-self.spec_agent.height_noise, self.spec_agent.height_noise))
        return self.base_height

    def step(self, action):
        spec, s = self.spec_agent, self.state
        a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0) * self._scale
        (x, y, theta), collided = self.world.move(a[0], a[1], a[2])
        self.path_length += math.hypot(x - s.x, y - s.y)
        s.x, s.y, s.theta = x, y, theta
        if spec.head:
            pitch = float(np.clip(s.pitch + a[3], *spec.pitch_limits))
            head_yaw = float(np.clip(s.head_yaw + a[4], *spec.yaw_limits))
            self._dq = np.array([pitch - s.pitch, head_yaw - s.head_yaw])
            s.pitch, s.head_yaw = pitch, head_yaw
        s.camera_height = self._camera_height(self.np_random, self.scenario_id < 0)
        self.collisions += int(collided)
        for option in self._options:
            option.moved(self, collided)
        self.steps += 1
        depth, mask = self._sense()
        self._remember(depth, mask)
        self._push(depth)
        visible = bool(mask.any())
        distance = target_distance(s, self.target, spec.body_radius)
        success = visible and distance <= SUCCESS_DISTANCE
        decrease = 0.0
        if self.distance_reward == "geodesic":
            geodesic = self._geodesic_to_goal()
            # a cell the grid cannot reach (a body pressed into furniture) gives no shaping either way
            decrease = self._geodesic - geodesic if math.isfinite(geodesic) and math.isfinite(self._geodesic) else 0.0
            self._geodesic = geodesic
        terms = reward_terms(success, visible, distance, self.collisions, self._seen_distance, self.distance_reward,
                             decrease)
        self._seen_distance = distance if visible else None
        truncated = not success and self.steps >= self.max_steps
        info = self._info(visible, success, distance)
        info.update(terms, collided=collided)
        reward = terms["reward"]
        if self.coverage_bonus:
            cell = self._cell()
            info["r_cov"] = self.coverage_bonus if cell not in self._visited else 0.0
            self._visited.add(cell)
            reward += info["r_cov"]
        return self._observation(mask), reward, success, truncated, info

    # -- the target memory and coverage (options) ------------------------------------------------
    def _cell(self) -> tuple[int, int]:
        return (math.floor(self.state.x / COVERAGE_CELL), math.floor(self.state.y / COVERAGE_CELL))

    def _remember(self, depth: np.ndarray, mask: np.ndarray) -> None:
        """Where the target is, from this frame's depth under the mask, in the home's frame (the
        body's own pose serves as ideal odometry): kept until the next sight. And the floor map."""
        if self._floor is not None:
            self._floor.update(depth, self.state)
        if not self.target_memory:
            return
        if not mask.any():
            self._since_seen += 1
            return
        s = self.state
        z = float(np.median(depth[mask])) / 255.0 * self.sensor.max_depth
        ray = self._rays[mask].mean(axis=0)
        self._memory_point = np.asarray(s.camera_position) + camera_axes(s.camera_yaw, s.pitch).T @ (ray * z)
        self._since_seen = 0

    def _memory_feature(self) -> np.ndarray:
        out = np.zeros(TARGET_MEMORY_DIM, np.float32)
        if self._memory_point is None:
            out[3] = 1.0
            return out
        s = self.state
        dx, dy = self._memory_point[0] - s.x, self._memory_point[1] - s.y
        c, sn = math.cos(s.theta), math.sin(s.theta)
        out[:] = (np.clip((c * dx + sn * dy) / 5, -4, 4), np.clip((-sn * dx + c * dy) / 5, -4, 4),
                  np.clip((self._memory_point[2] - s.camera_height) / 2, -4, 4),
                  min(self._since_seen, MEMORY_HORIZON) / MEMORY_HORIZON, 1.0)
        return out

    # -- state access for the replanner (paper Algorithm 1) ----------------------------------
    def snapshot(self) -> dict:
        """Everything a later :meth:`restore` needs to continue this episode exactly."""
        return {"state": self.state.copy(), "frames": self._frames.copy(), "history": list(self._history),
                "steps": self.steps,
                "collisions": self.collisions, "path_length": self.path_length, "dq": self._dq.copy(),
                "options": [option.snapshot() for option in self._options], "seen_distance": self._seen_distance,
                "memory": (None if self._memory_point is None else self._memory_point.copy(), self._since_seen),
                "visited": set(self._visited),
                "floor": None if self._floor is None else self._floor.copy_state(),
                "rng": self.np_random.bit_generator.state,
                "last": (self._last_depth, self._last_mask)}

    def restore(self, snap: dict) -> None:
        self.set_agent_state(snap["state"])
        self._frames[:] = snap["frames"]
        self._history = list(snap.get("history", []))
        self.steps, self.collisions, self.path_length = snap["steps"], snap["collisions"], snap["path_length"]
        self._dq = snap["dq"].copy()
        for option, state in zip(self._options, snap["options"]):
            option.restore(state)
        self._seen_distance = snap["seen_distance"]
        point, self._since_seen = snap["memory"]
        self._memory_point = None if point is None else point.copy()
        self._visited = set(snap["visited"])
        if self._floor is not None:
            self._floor.set_state(snap["floor"])
        self.np_random.bit_generator.state = snap["rng"]
        self._last_depth, self._last_mask = snap["last"]

    def set_agent_state(self, state: AgentState) -> None:
        """Put the body and camera at ``state`` (no physics on the way, nothing counted)."""
        self.state = state.copy()
        self.world.reset_agent(state.x, state.y, state.theta)

    def observe(self, push: bool = True) -> tuple[dict, bool]:
        """Render at the current state; with ``push`` the frame enters the depth history.
        Returns the observation and whether the target is seen."""
        depth, mask = self._sense()
        if push:
            self._remember(depth, mask)
            self._push(depth)
        return self._observation(mask), bool(mask.any())

    def _push(self, depth: np.ndarray) -> None:
        """The newest frame enters the depth stack (and, with strided frames, the episode's history)."""
        if not self._strided:
            self._frames[:-1] = self._frames[1:]
            self._frames[-1] = depth
            return
        self._history.append(depth)
        newest = len(self._history) - 1
        for j, back in enumerate(self._offsets):
            self._frames[j] = self._history[max(0, newest - back)]

    # -- sensing ---------------------------------------------------------------------------
    def _sense(self):
        s = self.state
        depth, mask = self.sensor.render_uint8(s.camera_position, s.camera_yaw, s.pitch)
        self._last_depth, self._last_mask = depth, mask
        return depth, mask

    def _observation(self, mask: np.ndarray) -> dict:
        s = self.state
        proprio = np.zeros(PROPRIO_DIM, np.float32)
        if self.spec_agent.head:
            proprio[:PROPRIO_DIM] = (s.pitch, s.head_yaw, self._dq[0], self._dq[1])
        feature = mask_feature(mask).astype(np.float32)
        if self.target_memory:
            feature = np.concatenate([feature, self._memory_feature()])
        if self._floor is not None:
            feature = np.concatenate([feature, self._floor.egocentric(self.state, FLOOR_MAP_CELLS)])
        obs = {"depth": self._frames.copy(), "mask": feature, "proprio": proprio}
        for option in self._options:
            for vector, values in option.values(self).items():
                obs[vector] = np.concatenate([obs[vector], values]).astype(np.float32, copy=False)
        if self.with_state:
            distance = target_distance(s, self.target, self.spec_agent.body_radius)
            obs["state"] = privileged_state(s, self.target, distance, bool(mask.any()))
        return obs

    def _info(self, visible: bool, success: bool, distance: float | None = None) -> dict:
        s = self.state
        if distance is None:
            distance = target_distance(s, self.target, self.spec_agent.body_radius)
        return {"success": bool(success), "visible": bool(visible), "distance": float(distance),
                "collisions": self.collisions, "path_length": self.path_length, "steps": self.steps,
                "scenario_id": self.scenario_id, "camera_height": s.camera_height,
                "pose": (s.x, s.y, s.theta, s.pitch, s.head_yaw)}

    def render(self):
        if self.render_mode != "rgb_array":
            return None
        # local: pyrender and its EGL context load only when a picture is asked for
        from egosearch.sim.render import depth_to_colormap

        return depth_to_colormap(self._last_depth.astype(np.float32) / 255.0 * self.sensor.max_depth,
                                 self._last_mask, max_depth=self.sensor.max_depth)

    def close(self):
        self.world.close()

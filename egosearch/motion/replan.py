"""Online motion replanning and synthesis: paper Algorithm 1, its baselines (6.4), and evaluation.

One replanning cycle, from the realised pose q_0 (the env's abstract state already holds q_0's
root, camera height and head, and its depth history ends with the frame seen from there):

1. plan: roll the policy out for T steps in the abstract model (``env.snapshot()`` before and
   ``env.restore()`` after, so the rollout leaves the episode untouched): s_0..s_T (lines 1-7);
2. ``mg.generate(plan, M, q_0)`` gives the M full-body poses q_1..q_M (line 8);
3. for i = 0..M-1: a = pi(o_i); the abstract transition's head s_{i+1}.head (within the
   character's own head limits) overwrites q_{i+1}.head; the abstract state is set to
   q_{i+1}'s root, camera height and that head and rendered, and the frame enters the depth
   history (lines 9-16; the frame for i = 0 is the one already at the end of the history);
4. the next cycle plans from s_M = q_M (line 17).

The episode's success is judged on the realised trajectory: the target within
:data:`~egosearch.sim.scenarios.SUCCESS_DISTANCE` of the abstract body's surface placed at the
character's root and seen from the character's camera; at most ``MAX_STEPS`` = 100 realised
steps. Every realised pose is checked for full-body penetration of the home.

Baselines (paper 6.4):
- ``one_step_short`` / ``one_step_long``: one policy query, a straight line of 5 / 20 steps in
  that action's direction (heading and head as that one action leaves them), the MG follows it
  for M steps (default: the whole line) with no further queries;
- ``noisy_search``: the replanning scheme with a policy that acts uniformly at random until the
  target is seen, then asks the real policy.

Why T = 20 by default: the plan must cover the longest executed prefix (M <= 20) plus the
motion generators' look-ahead (matching looks 0.9 s = 6 steps ahead; beyond the plan's end
every generator holds its last state); a longer plan only costs renders that are thrown away,
since the plan is redone after M steps. 20 steps are 3 s of search, a fifth of an episode.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from egosearch.core.csvio import write_csv_atomic
from egosearch.motion.base import FullBodyPose, IdentityMG, MotionGenerator
from egosearch.motion.collision import PenetrationCounter
from egosearch.motion.fetch import FetchMG
from egosearch.motion.matching import MatchingMG
from egosearch.motion.phase import PhaseMG
from egosearch.runs.evaluate import make_env
from egosearch.runs.metrics import episode_spl
from egosearch.sim.body import AgentState
from egosearch.sim.env import FRAME_HISTORY, target_distance
from egosearch.sim.scenarios import MAX_STEPS, SUCCESS_DISTANCE, Scenario

DEFAULT_T = 20
DEFAULT_M = 5
M_VALUES = (1, 5, 10, 20)

FULLBODY_COLUMNS = ("scenario_id", "method", "mg", "M", "T", "success", "steps", "path_length", "shortest_path",
                    "spl", "attempts", "penetrations", "penetration_rate", "collisions")


@dataclass(frozen=True)
class Method:
    name: str
    kind: str
    """``replan`` (Algorithm 1) or ``one_step``."""
    horizon: int | None = None
    """one_step: length of the extrapolated line (steps)."""
    noisy: bool = False
    """Random actions until the target is seen."""
    default_M: int | None = None


METHODS: dict[str, Method] = {
    "ours": Method("ours", "replan"),
    "one_step_short": Method("one_step_short", "one_step", horizon=5, default_M=5),
    "one_step_long": Method("one_step_long", "one_step", horizon=20, default_M=20),
    "noisy_search": Method("noisy_search", "replan", noisy=True),
}

MOTION_GENERATORS: dict[str, type[MotionGenerator]] = {
    "humanoid_phase": PhaseMG,
    "humanoid_matching": MatchingMG,
    "fetch": FetchMG,
    "abstract": IdentityMG,
}


def get_method(name: str) -> Method:
    if name not in METHODS:
        raise ValueError(f"method={name!r} is unknown; allowed: {', '.join(METHODS)}")
    return METHODS[name]


def parse_setting(setting: str) -> tuple[str, int | None, str]:
    """``ours-M5-humanoid_phase`` -> ("ours", 5, "humanoid_phase"); a baseline such as
    ``noisy_search-fetch`` takes the method's default M (None for the one-step lines, which
    execute their whole line; :data:`DEFAULT_M` for noisy search)."""
    method, _, mg = setting.rpartition("-")
    m: int | None = None
    if method.startswith("ours-M") and method[len("ours-M"):].isdigit():
        method, m = "ours", int(method[len("ours-M"):])
    elif method == "noisy_search":
        m = DEFAULT_M
    if method not in METHODS or method == "ours" and m is None or mg not in MOTION_GENERATORS:
        raise ValueError(f"setting={setting!r}; expected ours-M<M>-<mg>, one_step_short-<mg>, one_step_long-<mg> "
                         f"or noisy_search-<mg> with <mg> in {', '.join(MOTION_GENERATORS)}")
    return method, m, mg


def check_plan(method: Method, M: int | None, T: int) -> int:
    """``M`` (the method's default when None), once it and ``T`` are known to make a plan."""
    if M is None:
        M = method.default_M or DEFAULT_M
    if M < 1 or T < 1:
        raise ValueError(f"M={M} and T={T} must be >= 1")
    if method.kind == "replan" and M > T:
        raise ValueError(f"M={M} > T={T}: Algorithm 1 executes a prefix of the plan")
    return M


def make_motion_generator(name: str, world=None) -> MotionGenerator:
    if name not in MOTION_GENERATORS:
        raise ValueError(f"motion generator {name!r} is unknown; allowed: {', '.join(MOTION_GENERATORS)}")
    return MOTION_GENERATORS[name](world=world)


class NoisySearchPolicy:
    """Uniform random actions while the target is not seen, the wrapped policy once it is."""

    def __init__(self, policy, action_dim: int, seed: int = 0):
        self.policy = policy
        self.action_dim = action_dim
        self.rng = np.random.default_rng(seed)

    def reset(self, seed: int | None = None) -> None:
        self.policy.reset(seed=seed)
        if seed is not None:
            self.rng = np.random.default_rng([seed, 7])

    def act(self, obs: dict) -> np.ndarray:
        if float(obs["mask"][-1]) > 0.5:
            return self.policy.act(obs)
        return self.rng.uniform(-1.0, 1.0, self.action_dim).astype(np.float32)


# -- the abstract model's pieces -----------------------------------------------------------------

def abstract_head(env, state: AgentState, action) -> tuple[float, float]:
    """The head part of the abstract transition T(s, a), exactly as ``SearchEnv.step`` does it."""
    spec = env.spec_agent
    if not spec.head:
        return state.pitch, state.head_yaw
    a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0) * spec.action_scale()
    pitch = float(np.clip(state.pitch + a[3], *spec.pitch_limits))
    head_yaw = float(np.clip(state.head_yaw + a[4], *spec.yaw_limits))
    return pitch, head_yaw


def rollout_plan(env, policy, obs: dict, T: int) -> list[AgentState]:
    """s_0..s_T from the current state (Algorithm 1 lines 1-7); the env is left as it was.
    The rollout stops early where the abstract episode ends (success or T_max)."""
    snap = env.snapshot()
    # a policy that keeps state of its own (the modular searcher's map and plan) is put back too
    policy_snap = policy.snapshot() if hasattr(policy, "snapshot") else None
    plan = [env.state.copy()]
    o = obs
    try:
        for _ in range(T):
            o, _, terminated, truncated, _ = env.step(policy.act(o))
            plan.append(env.state.copy())
            if terminated or truncated:
                break
    finally:
        env.restore(snap)
        if policy_snap is not None:
            policy.restore(policy_snap)
    return plan


def line_plan(env, action, horizon: int) -> list[AgentState]:
    """The one-step baseline's plan: ``horizon`` steps on a straight line in the action's direction,
    with the heading and head that one action gives."""
    spec = env.spec_agent
    s = env.state
    a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0) * spec.action_scale()
    c, sn = math.cos(s.theta), math.sin(s.theta)
    dx, dy = c * a[0] - sn * a[1], sn * a[0] + c * a[1]
    theta = s.theta + a[2]
    pitch, head_yaw = abstract_head(env, s, action)
    plan = [s.copy()]
    for k in range(1, horizon + 1):
        plan.append(AgentState(s.x + k * dx, s.y + k * dy, theta, pitch, head_yaw, env.base_height))
    return plan


def place(env, pose: FullBodyPose, dq, steps: int, collisions: int, path_length: float,
          fill: bool = False) -> tuple[dict, bool]:
    """Set the abstract state from a realised pose (root, camera height, head), render it and push the
    frame into the depth history (Algorithm 1 lines 10-13). ``fill`` restarts the history with it."""
    snap = env.snapshot()
    snap["state"] = pose.abstract()
    snap["dq"] = np.asarray(dq, dtype=np.float64)
    snap["steps"], snap["collisions"], snap["path_length"] = steps, collisions, path_length
    env.restore(snap)
    obs, visible = env.observe(push=True)
    if fill:
        for _ in range(FRAME_HISTORY - 1):
            obs, visible = env.observe(push=True)
    return obs, visible


# -- one episode -------------------------------------------------------------------------------

def run_fullbody_episode(env, policy, mg: MotionGenerator, scenario: Scenario, T: int = DEFAULT_T,
                         M: int | None = DEFAULT_M, seed: int = 0, method: str | Method = "ours",
                         counter: PenetrationCounter | None = None, trace: list | None = None,
                         max_steps: int = MAX_STEPS) -> dict:
    """One episode of ``policy`` realised by ``mg`` (Algorithm 1 or a baseline). Returns a row with
    :data:`FULLBODY_COLUMNS`. ``trace``, if given, receives one dict per realised pose (``pose``, the
    abstract ``state`` set from it, ``visible``, the ``plan`` it came from and the ``obs`` the policy
    got there), the start first."""
    meth = get_method(method) if isinstance(method, str) else method
    M = check_plan(meth, M, T)
    u = env.unwrapped
    env.reset(seed=seed, options={"scenario": scenario})
    if meth.noisy:
        policy = NoisySearchPolicy(policy, u.action_space.shape[0], seed)
    policy.reset(seed=seed)
    mg.bind(u.world)
    own_counter = counter is None
    if own_counter:
        counter = PenetrationCounter(u.scene, mg.character)
    spec = u.spec_agent
    try:
        q = mg.initial_pose(u.state)
        obs, visible = place(u, q, (0.0, 0.0), 0, 0, 0.0, fill=True)
        if trace is not None:
            trace.append({"pose": q, "state": u.state.copy(), "visible": visible, "plan": None, "obs": obs})
        steps = attempts = penetrations = collisions = 0
        path = 0.0
        success = False
        while steps < max_steps and not success:
            if meth.kind == "one_step":
                plan = line_plan(u, policy.act(obs), meth.horizon)
            else:
                plan = rollout_plan(u, policy, obs, T)
            attempts += 1
            poses = mg.generate(plan, M, start=q)
            for qn in poses:
                if meth.kind == "replan":
                    # Lines 14-16: the policy sees the realised view and sets the head.
                    pitch, head_yaw = abstract_head(u, u.state, policy.act(obs))
                    qn.pitch, qn.head_yaw = mg.limit_head(q, pitch, head_yaw)
                dq = (qn.pitch - q.pitch, qn.head_yaw - q.head_yaw) if spec.head else (0.0, 0.0)
                steps += 1
                path += math.hypot(qn.x - q.x, qn.y - q.y)
                collisions += int(qn.blocked)
                penetrations += int(counter.penetrates(qn))
                obs, visible = place(u, qn, dq, steps, collisions, path)
                q = qn
                success = visible and target_distance(u.state, u.target, spec.body_radius) <= SUCCESS_DISTANCE
                if trace is not None:
                    trace.append({"pose": qn, "state": u.state.copy(), "visible": visible, "plan": plan,
                                  "obs": obs})
                if success or steps >= max_steps:
                    break
    finally:
        if own_counter:
            counter.close()
    return {
        "scenario_id": scenario.scenario_id,
        "method": meth.name,
        "mg": mg.name,
        "M": M,
        "T": meth.horizon if meth.kind == "one_step" else T,
        "success": int(success),
        "steps": steps,
        "path_length": round(path, 4),
        "shortest_path": scenario.shortest_path,
        "spl": round(episode_spl(success, scenario.shortest_path, path), 5),
        "attempts": attempts,
        "penetrations": penetrations,
        "penetration_rate": round(penetrations / steps, 5) if steps else 0.0,
        "collisions": collisions,
    }


# -- many episodes -----------------------------------------------------------------------------

def evaluate_fullbody(env_id: str, make_policy, scenarios: list[Scenario], method: str = "ours",
                      mg_name: str = "humanoid_phase", M: int | None = DEFAULT_M, T: int = DEFAULT_T,
                      seed: int = 0, progress: bool = False, env_kwargs: dict | None = None) -> list[dict]:
    """``make_policy(env)`` realised by motion generator ``mg_name`` with ``method`` on every scenario.
    ``M=None`` takes the method's default (the one-step baselines execute their whole line);
    ``env_kwargs``: the env's observation options (a trained actor's recorded ones)."""
    meth = get_method(method)
    check_plan(meth, M, T)  # before the first episode, not in it
    if mg_name not in MOTION_GENERATORS:
        raise ValueError(f"motion generator {mg_name!r} is unknown; allowed: {', '.join(MOTION_GENERATORS)}")
    rows, env, key, policy, mg, counter = [], None, None, None, None, None
    iterator = scenarios
    if progress:
        from tqdm import tqdm

        iterator = tqdm(scenarios, desc=f"{method}/{mg_name}/M={M}", unit="ep")
    try:
        for sc in iterator:
            k = (sc.layout, sc.placement, sc.height)
            if k != key:
                if env is not None:
                    env.close()
                    counter.close()
                env, key = make_env(env_id, sc, **(env_kwargs or {})), k
                policy = make_policy(env)
                mg = make_motion_generator(mg_name, env.unwrapped.world)
                counter = PenetrationCounter(env.unwrapped.scene, mg.character)
            rows.append(run_fullbody_episode(env, policy, mg, sc, T=T, M=M, seed=seed + sc.scenario_id,
                                             method=meth, counter=counter))
    finally:
        if env is not None:
            env.close()
        if counter is not None:
            counter.close()
    return rows


def write_fullbody(path: str | os.PathLike, rows: list[dict]) -> None:
    write_csv_atomic(path, FULLBODY_COLUMNS, rows)

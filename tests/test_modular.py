"""The modular searcher (lever (d)): a learned decision of where to explore and how to sweep the head,
walked by the frontier searcher. One env step is one decision; the body env's counters come through."""

import math

import gymnasium
import numpy as np
import pytest

import egosearch.envs  # noqa: F401
from egosearch.envs import env_space_dims
from egosearch.searchers.decision_envs import BODY_ENV_IDS, MODULAR_ENV_IDS, MODULAR_MAP_DIM
from egosearch.searchers.modular import GoalFrontierPolicy, ModularSearchEnv
from egosearch.sim.env import MASK_FEATURE_DIM, SearchEnv
from egosearch.sim.scenarios import generate_scenarios


@pytest.mark.parametrize("env_id", sorted(MODULAR_ENV_IDS))
def test_spaces_are_the_declared_sizes(env_id):
    env = gymnasium.make(env_id)
    dims = env_space_dims(env_id)
    head = MODULAR_ENV_IDS[env_id]["head"]
    assert env.action_space.shape == (dims["action"],) == ((4,) if head else (2,))
    assert env.observation_space["mask"].shape == (dims["mask"],) == (MASK_FEATURE_DIM + MODULAR_MAP_DIM,)
    obs, _ = env.reset(seed=3)
    assert obs["mask"].shape == (MASK_FEATURE_DIM + MODULAR_MAP_DIM,) and obs["depth"].shape == (5, 100, 100)
    # the map already holds the first frame: some floor ahead is seen
    assert obs["mask"][MASK_FEATURE_DIM:].reshape(3, 12, 12)[0].sum() > 0
    env.close()


def test_a_decision_points_in_the_body_frame_and_sets_the_sweep():
    env = SearchEnv(layout="kitchen_living")
    env.reset(seed=0)
    searcher = GoalFrontierPolicy(env)
    s = env.state
    s.theta = math.pi / 2  # facing +y: ahead is +y, left is -x
    searcher.decide(np.array([1.0, 0.5, -1.0, 1.0]))
    assert searcher.goal == pytest.approx((s.x - 1.5, s.y + 3.0))
    assert (searcher.yaw_amplitude, searcher.pitch_centre) == (0.0, 0.0)
    searcher.decide(np.array([0.0, 0.0, 1.0, -1.0]))
    assert searcher.goal == pytest.approx((s.x, s.y))
    assert searcher.yaw_amplitude == pytest.approx(1.2) and searcher.pitch_centre == pytest.approx(-0.8)
    env.close()


def test_the_chosen_frontier_is_the_one_nearest_the_decisions_point():
    env = SearchEnv(layout="kitchen_living")
    env.reset(seed=0)
    searcher = GoalFrontierPolicy(env)
    searcher.map.origin = (0.0, 0.0)
    frontier = np.zeros((20, 20), bool)
    frontier[2, 3] = frontier[2, 17] = frontier[17, 10] = True
    dist = np.full((20, 20), 1.0)
    offset = (searcher.n // 2 - 10, searcher.n // 2 - 10)  # window cell (10, 10) is the map's cell at (0.05, 0.05)
    # a point near window cell (2, 17): x = (17 - 10 + 0.5) * 0.1, y = (2 - 10 + 0.5) * 0.1
    searcher.goal = (0.7, -0.8)
    assert searcher.choose_frontier(frontier, dist, offset) == (2, 17)
    assert searcher.chosen == (2 + offset[0], 17 + offset[1])
    # equal distance to the point: the shorter path wins (PATH_WEIGHT)
    searcher.goal = (0.05, -0.75)  # window cell (2, 10): 0.7 m from (2, 3) and from (2, 17)
    dist[2, 3] = 3.0
    assert searcher.choose_frontier(frontier, dist, offset) == (2, 17)
    dist[2, 3], dist[2, 17] = 1.0, 3.0
    assert searcher.choose_frontier(frontier, dist, offset) == (2, 3)
    env.close()


def test_one_step_is_one_decision_of_the_body_steps_and_the_counters_come_through():
    scenario = generate_scenarios("kitchen_living", "everywhere", 1.05, n=1, seed=5)[0]
    env = gymnasium.make("EgoSearchModular-v0", layout=scenario.layout, placement=scenario.placement,
                         height=scenario.height)
    obs, info = env.reset(seed=0, options={"scenario": scenario})
    rng = np.random.default_rng(0)
    body_steps, total, decisions = 0, 0.0, 0
    done = False
    while not done:
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-1, 1, 4).astype(np.float32))
        decisions += 1
        searcher = env.unwrapped.searcher
        assert 1 <= info["decision_steps"] <= GoalFrontierPolicy.DECIDE_EVERY or searcher.target is not None
        body_steps += info["decision_steps"]
        total += reward
        done = terminated or truncated
        if not done and searcher.target is not None:
            raise AssertionError("a decision stopped while the target was known: the walk to it is the decision's")
    assert info["steps"] == body_steps <= 100 and decisions < body_steps
    assert env.unwrapped.scenario_id == scenario.scenario_id  # the body env's attributes read through
    assert terminated == info["success"]
    env.close()


def test_the_same_decisions_give_the_same_episode():
    scenario = generate_scenarios("bedroom_bath", "everywhere", 0.45, n=1, seed=2)[0]

    def run():
        env = ModularSearchEnv(layout=scenario.layout, placement=scenario.placement, height=scenario.height)
        env.reset(seed=0, options={"scenario": scenario})
        rows = []
        for k in range(4):
            obs, reward, term, trunc, info = env.step(np.array([0.5, -0.5 + 0.3 * k, 0.0, 0.0], np.float32))
            rows.append((info["steps"], round(reward, 6), info["pose"]))
            if term or trunc:
                break
        env.close()
        return rows

    assert run() == run()


def test_a_training_in_the_modular_env_leaves_an_actor_that_evaluation_runs(tmp_path):
    from egosearch.rl.actor import ActorPolicy
    from egosearch.rl.config import load_config
    from egosearch.rl.train import train
    from egosearch.runs.evaluate import evaluate

    cfg = load_config("smoke", {"algorithm": "sac_drq", "total_env_steps": 60, "init_steps": 20, "eval_every": 60,
                                "eval_episodes": 1, "checkpoint_every": 60, "log_every": 20, "obs_downsample": 2,
                                "critic_privileged_state": True})
    done = train("EgoSearchModular-v0", cfg, tmp_path, {"layout": "kitchen_living"}, progress=False)
    assert done["env_steps"] == 60 and done["updates"] > 0
    policy = ActorPolicy(tmp_path / "actor.pt")
    assert policy.trained_env_id() == "EgoSearchModular-v0"
    policy.check_env("EgoSearchModular-v0")
    scenarios = generate_scenarios("kitchen_living", "everywhere", 1.05, n=2, seed=4)
    rows = evaluate("EgoSearchModular-v0", lambda env: policy, scenarios, seed=0)
    assert [r["scenario_id"] for r in rows] == [s.scenario_id for s in scenarios]
    assert all(1 <= r["steps"] <= 100 for r in rows)
    # the commands run it step by step in the body env, and that is the same search
    from egosearch.cli.acting import policy_factory

    make_policy, env_id, _ = policy_factory("actor", str(tmp_path / "actor.pt"), 0)
    assert env_id == "EgoSearch-v0"
    assert evaluate(env_id, make_policy, scenarios, seed=0) == rows


class ObservationDecides:
    """A stand-in for a trained high level: a fixed function of the whole observation (the map included), so
    two runs decide alike only if they observe alike."""

    def reset(self, seed=None):
        pass

    def act(self, obs):
        m, frame = obs["mask"], obs["depth"][-1, ::10, ::10]
        return np.tanh([m[MASK_FEATURE_DIM:].sum() / 40 - 2, np.sin(m[MASK_FEATURE_DIM::7].sum()),
                        m[:MASK_FEATURE_DIM].sum() - 0.5, np.cos(frame.mean())]).astype(np.float32)


def test_the_per_step_policy_on_the_body_env_is_the_decision_env_step_for_step():
    from egosearch.runs.evaluate import evaluate
    from egosearch.runs.trace import TraceRecorder
    from egosearch.searchers.modular import ModularPolicy

    scenarios = generate_scenarios("kitchen_living", "no_low_cabinets", 1.05, n=3, seed=8)
    high = ObservationDecides()
    decisions = evaluate("EgoSearchModular-v0", lambda env: high, scenarios, seed=0)
    recorder = TraceRecorder()
    steps = evaluate(BODY_ENV_IDS["EgoSearchModular-v0"], lambda env: ModularPolicy(high, env), scenarios, seed=0,
                     recorder=recorder)
    assert decisions == steps
    assert recorder.meta["learns"] == "decisions"  # the claims about the body's steps are not read on it
    assert len({r["steps"] for r in steps}) > 1  # three different episodes, not one repeated


def test_the_replanners_look_ahead_leaves_the_modular_searcher_as_it_was():
    from egosearch.motion.replan import rollout_plan
    from egosearch.runs.evaluate import make_env
    from egosearch.searchers.modular import ModularPolicy

    scenario = generate_scenarios("kitchen_living", "everywhere", 1.05, n=1, seed=9)[0]

    def episode(look_ahead: bool):
        env = make_env("EgoSearch-v0", scenario)
        policy = ModularPolicy(ObservationDecides(), env)
        obs, _ = env.reset(seed=0, options={"scenario": scenario})
        policy.reset(seed=0)
        poses = []
        for k in range(30):
            if look_ahead and k % 5 == 0:
                plan = rollout_plan(env.unwrapped, policy, obs, 8)
                assert len(plan) > 1
            obs, _, term, trunc, info = env.step(policy.act(obs))
            poses.append(info["pose"])
            if term or trunc:
                break
        env.close()
        return poses

    assert episode(look_ahead=True) == episode(look_ahead=False)


def test_the_modular_searcher_field_trains_in_the_modular_env_of_the_variants_head():
    from egosearch.envs import observed_env_id
    from egosearch.rl.config import load_config
    from egosearch.variants import resolve_variant

    assert observed_env_id("EgoSearch-v0", False, True) == "EgoSearchModular-v0"
    assert observed_env_id("EgoSearchNoHead-v0", False, True) == "EgoSearchNoHeadModular-v0"
    assert observed_env_id("EgoSearchModular-v0", False, False) == "EgoSearchModular-v0"
    assert resolve_variant("head_off_modular", "cpu").env_id == "EgoSearchNoHeadModular-v0"
    assert resolve_variant("head_off_from_scratch", "cpu").env_id == "EgoSearchNoHeadMemory-v0"
    modular = dict(resolve_variant("head_off_modular", "cpu").variant.config)
    load_config("cpu", modular)  # the stored pair's settings are valid
    with pytest.raises(ValueError, match="target_memory"):
        load_config("cpu", {**modular, "target_memory": True})  # the frontier searcher remembers the target itself
    with pytest.raises(ValueError, match="demo_episodes"):
        load_config("cpu", {**modular, "demo_episodes": 10})


def test_a_run_stored_before_the_field_is_the_same_run_as_the_variant_that_names_it(tmp_path):
    import json
    from pathlib import Path

    from egosearch.rl.run_files import check_same_run
    from egosearch.variants import resolve_variant

    # head_on_modular's stored runs were trained before the field existed
    stored = Path(__file__).resolve().parent.parent / "results/cpu/train/head_on_modular/seed0/done.json"
    done = json.loads(stored.read_text())
    assert "modular_searcher" not in done["config"] and done["variant"] == "head_on_modular"
    resolved = resolve_variant("head_on_modular", "cpu", {"seed": 0})
    check_same_run("finished run", stored, done, done["variant"], resolved.env_id, resolved.variant.train_env,
                   resolved.config)


def test_figure_6_counts_a_modular_searchers_steps_as_decisions(tmp_path):
    """Its x axis says decisions when every curve is a modular searcher's (by the field, or by the env id of a run
    stored before the field), environment steps otherwise."""
    import json

    from egosearch.report.data import counts_decisions

    runs = {"field": {"env_id": "EgoSearch-v0", "config": {"modular_searcher": True}},
            "env_id": {"env_id": "EgoSearchNoHeadModular-v0", "config": {}},
            "body": {"env_id": "EgoSearchMemory-v0", "config": {"modular_searcher": False}}}
    for name, stored in runs.items():
        (tmp_path / name).mkdir()
        (tmp_path / name / "config.json").write_text(json.dumps(stored))
    assert [counts_decisions(tmp_path / name / "curve.csv") for name in runs] == [True, True, False]
    assert not counts_decisions(tmp_path / "missing" / "curve.csv")


@pytest.mark.parametrize("kind, body_env, dim", [("modular_random", "EgoSearch-v0", 4),
                                                 ("modular_random_head_off", "EgoSearchNoHead-v0", 2)])
def test_the_random_decision_floor_walks_the_modular_searcher_on_uniform_decisions(kind, body_env, dim):
    """`--policy modular_random[_head_off]`: the modular searcher's walk with each decision drawn at random (the
    floor a trained high level is read against): decisions of the head's size, spread over [-1, 1], the same
    episodes for the same seed and other decisions for another."""
    from egosearch.cli.acting import policy_factory
    from egosearch.runs.evaluate import evaluate

    scenarios = generate_scenarios("kitchen_living", "no_low_cabinets", 1.05, n=2, seed=8)
    decided = []

    def recording(make):
        def make_policy(env):
            policy = make(env)
            decide = policy.searcher.decide
            policy.searcher.decide = lambda d: (decided.append(np.asarray(d).copy()), decide(d))[1]
            return policy
        return make_policy

    make, env_id, _ = policy_factory(kind, None, seed=0)
    assert env_id == body_env
    first = evaluate(env_id, recording(make), scenarios, seed=0)
    ours = np.array(decided)
    assert ours.shape[1] == dim and len(ours) > 4
    assert ours.min() < -0.5 and ours.max() > 0.5 and np.all(np.abs(ours) <= 1)
    decided.clear()
    assert evaluate(env_id, recording(make), scenarios, seed=0) == first
    assert np.array_equal(np.array(decided), ours)
    decided.clear()
    make_other, _, _ = policy_factory(kind, None, seed=1)
    evaluate(env_id, recording(make_other), scenarios, seed=1)
    assert not np.array_equal(np.array(decided)[:3], ours[:3])

"""The gymnasium env: API conformance, reproducibility, bad input, oracle and random bounds."""

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from egosearch.runs.evaluate import evaluate, make_env
from egosearch.searchers.policies import OraclePolicy, RandomPolicy
from egosearch.sim.body_envs import ENV_IDS
from egosearch.sim.env import FLOOR_MAP_DIM, TARGET_MEMORY_DIM
from egosearch.sim.scenarios import generate_scenarios


@pytest.mark.parametrize("env_id", sorted(ENV_IDS))
def test_check_env(env_id):
    env = gymnasium.make(env_id, layout="kitchen_living")
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


@pytest.mark.parametrize("env_id", sorted(ENV_IDS))
def test_spaces_match_the_learner_contract(env_id):
    env = gymnasium.make(env_id)
    obs, info = env.reset(seed=0)
    assert obs["depth"].shape == (5, 100, 100) and obs["depth"].dtype == np.uint8
    options = ENV_IDS[env_id]
    extra = TARGET_MEMORY_DIM * options.get("target_memory", False) + FLOOR_MAP_DIM * options.get("floor_map", False)
    assert obs["mask"].shape == (30 + extra,) and obs["proprio"].shape == (4,)
    assert env.observation_space["mask"].shape == obs["mask"].shape
    assert env.action_space.shape == ((5,) if ENV_IDS[env_id]["head"] else (3,))
    # At reset the first frame is repeated K times.
    assert all(np.array_equal(obs["depth"][0], obs["depth"][k]) for k in range(5))
    env.close()


@pytest.mark.parametrize("env_id", sorted(ENV_IDS))
def test_reset_is_byte_identical(env_id):
    def rollout(seed):
        env = gymnasium.make(env_id, layout="bedroom_bath")
        obs, _ = env.reset(seed=seed)
        out = [obs["depth"].tobytes(), obs["mask"].tobytes(), obs["proprio"].tobytes()]
        rng = np.random.default_rng(seed)
        for _ in range(15):
            obs, reward, *_ = env.step(rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
            out += [obs["depth"].tobytes(), obs["mask"].tobytes(), np.float64(reward).tobytes()]
        env.close()
        return out

    a, b, c = rollout(3), rollout(3), rollout(4)
    assert a == b
    assert a != c


def test_bad_input_is_one_clear_line():
    with pytest.raises(ValueError, match="placement='under_the_sofa'.*everywhere"):
        gymnasium.make("EgoSearch-v0", placement="under_the_sofa")
    with pytest.raises(ValueError, match="kitchen_living"):
        gymnasium.make("EgoSearch-v0", layout="garage")
    with pytest.raises(ValueError, match="height=7.0"):
        gymnasium.make("EgoSearch-v0", height=7.0)


def test_training_height_randomisation_and_noise():
    env = gymnasium.make("EgoSearch-v0").unwrapped
    bases, offsets = [], []
    for seed in range(20):
        env.reset(seed=seed)
        bases.append(env.base_height)
        for _ in range(3):
            _, _, term, trunc, info = env.step(env.action_space.sample())
            offsets.append(info["camera_height"] - env.base_height)
    assert 1.0 <= min(bases) and max(bases) <= 1.8 and np.std(bases) > 0.1
    assert max(np.abs(offsets)) <= 0.1 and np.std(offsets) > 0.02
    env.close()


@pytest.mark.parametrize("layout", ["kitchen_living", "bedroom_bath"])
@pytest.mark.parametrize("placement", ["no_low_cabinets", "everywhere"])
def test_oracle_solves_and_random_does_not(layout, placement):
    """Proves the task solvable and the success check live (issue: oracle >= 95%)."""
    height = 1.05
    scenarios = generate_scenarios(layout, placement, height, n=12, seed=11)
    oracle = evaluate("EgoSearch-v0", OraclePolicy, scenarios)
    rate = np.mean([r["success"] for r in oracle])
    assert rate >= 11 / 12, oracle
    assert all(r["steps"] < 100 for r in oracle if r["success"])
    rand = evaluate("EgoSearch-v0", lambda env: RandomPolicy(5, seed=0), scenarios)
    assert np.mean([r["success"] for r in rand]) < rate


def test_evaluation_env_uses_the_scenario():
    sc = generate_scenarios("kitchen_living", "everywhere", 0.45, n=1, seed=5)[0]
    env = make_env("EgoSearch-v0", sc)
    obs, info = env.reset(seed=0, options={"scenario": sc})
    u = env.unwrapped
    assert (u.state.x, u.state.y) == pytest.approx((sc.start_x, sc.start_y), abs=1e-6)
    assert info["camera_height"] == 0.45
    assert u.target.center[:2] == pytest.approx((sc.target_x, sc.target_y), abs=1e-6)
    for _ in range(5):
        _, _, _, _, info = env.step(env.action_space.sample())
        assert info["camera_height"] == 0.45  # no noise in evaluation
    env.close()


def test_start_radius_curriculum_starts_near_the_target():
    import math

    from egosearch.sim.env import SearchEnv

    env = SearchEnv(layout="kitchen_living")
    far = []
    for seed in range(12):
        env.reset(seed=seed, options={"start_radius": 1.5})
        t, s = env.target.center, env.state
        assert math.hypot(t[0] - s.x, t[1] - s.y) <= 1.5 + 1e-9
        env.reset(seed=seed)
        far.append(math.hypot(env.target.center[0] - env.state.x, env.target.center[1] - env.state.y))
    assert max(far) > 3.0  # without the option, starts come from the whole home
    env.close()


def test_training_heights_of_the_cpu_profile_reach_the_lowest_evaluation_camera():
    from egosearch.rl.config import load_config
    from egosearch.rl.train_env import train_env_kwargs

    assert "train_heights" not in train_env_kwargs(load_config("paper"), {"layout": "kitchen_living"})
    kwargs = train_env_kwargs(load_config("cpu"), {"layout": "kitchen_living"})
    assert kwargs["train_heights"] == (0.45, 1.8)
    assert train_env_kwargs(load_config("cpu"), {"train_heights": (1.0, 1.2)})["train_heights"] == (1.0, 1.2)
    env = gymnasium.make("EgoSearch-v0", **kwargs).unwrapped
    bases = []
    for seed in range(30):
        env.reset(seed=seed)
        bases.append(env.base_height)
    assert 0.45 <= min(bases) < 0.8 and max(bases) <= 1.8
    env.close()
    with pytest.raises(ValueError, match="train_heights"):
        gymnasium.make("EgoSearch-v0", train_heights=(1.5, 1.0))


def test_geodesic_shaping_telescopes_to_the_change_of_the_shortest_path():
    """With ``distance_reward="geodesic"`` the r_d of an episode sums to ℓ at the start minus ℓ at
    the end (potential-based shaping), and r_c is the unclipped collision count."""
    from egosearch.sim.env import COLLISION_PENALTY_PER_HIT, SearchEnv

    env = SearchEnv(layout="kitchen_living", distance_reward="geodesic")
    env.reset(seed=0)
    start = env._geodesic_to_goal()
    rng = np.random.default_rng(0)
    total, infos = 0.0, []
    for _ in range(60):
        _, _, terminated, truncated, info = env.step(rng.uniform(-1, 1, env.action_space.shape))
        total += info["r_d"]
        infos.append(info)
        if terminated or truncated:
            break
    end = env._geodesic_to_goal()
    assert np.isfinite(start) and np.isfinite(end) and start > 0.5
    assert total == pytest.approx(start - end, abs=1e-9)
    assert any(i["r_d"] != 0.0 for i in infos if not i["visible"])      # shaped while the target is unseen
    assert infos[-1]["r_c"] == pytest.approx(COLLISION_PENALTY_PER_HIT * env.collisions)
    # seed 3 draws a shelf target that no pose near it sees at its camera height: the shaping
    # then leads to the target's surroundings, never to an infinite distance
    env.reset(seed=3)
    assert np.isfinite(env._geodesic_to_goal())
    env.close()

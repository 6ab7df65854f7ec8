"""The env's options beyond the paper: the last-seen target memory and the contact signal (observation
levers) and the training-only coverage bonus."""

import math

import gymnasium
import numpy as np
import pytest

import egosearch.sim.body_envs  # noqa: F401
from egosearch.sim.contact_signal import CONTACT_WINDOW
from egosearch.sim.env import MASK_FEATURE_DIM, PROPRIO_DIM, TARGET_MEMORY_DIM


def _run_until_seen(env, rng, max_episodes=30):
    for ep in range(max_episodes):
        obs, info = env.reset(seed=ep)
        for _ in range(100):
            obs, _, term, trunc, info = env.step(rng.uniform(-1, 1, env.action_space.shape[0]))
            if info["visible"]:
                return obs, info
            if term or trunc:
                break
    raise AssertionError("the target was never seen")


def test_target_memory_points_at_the_target_and_ages():
    env = gymnasium.make("EgoSearchMemory-v0", layout="kitchen_living", placement="everywhere")
    inner = env.unwrapped
    assert env.observation_space["mask"].shape == (MASK_FEATURE_DIM + TARGET_MEMORY_DIM,)
    obs, _ = env.reset(seed=0)
    if not obs["mask"][MASK_FEATURE_DIM - 1]:  # not seen at the start: nothing remembered
        assert obs["mask"][MASK_FEATURE_DIM:].tolist() == [0.0, 0.0, 0.0, 1.0, 0.0]
    rng = np.random.default_rng(0)
    obs, info = _run_until_seen(env, rng)
    forward, left, _, since, seen = obs["mask"][MASK_FEATURE_DIM:]
    s, t = inner.state, inner.target.center
    dx, dy = t[0] - s.x, t[1] - s.y
    c, sn = math.cos(s.theta), math.sin(s.theta)
    true_fwd, true_left = c * dx + sn * dy, -sn * dx + c * dy
    # the estimate from the depth under the mask lands on the object (targets are <= 0.3 m across)
    assert math.hypot(5 * forward - true_fwd, 5 * left - true_left) < 0.3
    assert (since, seen) == (0.0, 1.0)
    # the body moves on: the remembered point stays put in the home, so its body-frame value moves
    before = inner._memory_point.copy()
    snap = inner.snapshot()
    for _ in range(3):
        obs, _, term, trunc, info = env.step(np.array([0.0, 0.0, 1.0, 0.0, 0.0], np.float32))
        if term or trunc:
            break
        if not info["visible"]:
            assert np.allclose(inner._memory_point, before)
    inner.restore(snap)
    assert np.allclose(inner._memory_point, before)


def test_the_paper_env_is_unchanged_by_the_options():
    env = gymnasium.make("EgoSearch-v0", layout="kitchen_living")
    assert env.observation_space["mask"].shape == (MASK_FEATURE_DIM,)


def test_coverage_bonus_pays_once_per_new_cell():
    plain = gymnasium.make("EgoSearch-v0", layout="kitchen_living")
    bonus = gymnasium.make("EgoSearch-v0", layout="kitchen_living", coverage_bonus=0.5)
    plain.reset(seed=3)
    bonus.reset(seed=3)
    cells = {bonus.unwrapped._cell()}
    rng = np.random.default_rng(1)
    for _ in range(60):
        a = rng.uniform(-1, 1, 5).astype(np.float32)
        _, r0, t0, tr0, _ = plain.step(a)
        _, r1, t1, tr1, info = bonus.step(a)
        new = bonus.unwrapped._cell() not in cells
        cells.add(bonus.unwrapped._cell())
        assert r1 - r0 == pytest.approx(0.5 if new else 0.0) and info["r_cov"] == (0.5 if new else 0.0)
        if t0 or tr0:
            break
    with pytest.raises(ValueError, match="coverage_bonus"):
        gymnasium.make("EgoSearch-v0", coverage_bonus=-1.0)


def test_floor_map_marks_what_the_body_saw_and_where_it_stood():
    from egosearch.sim.env import FLOOR_MAP_CELLS, FLOOR_MAP_DIM

    env = gymnasium.make("EgoSearchMap-v0", layout="kitchen_living", placement="everywhere")
    obs, _ = env.reset(seed=4)
    start = MASK_FEATURE_DIM + TARGET_MEMORY_DIM
    assert obs["mask"].shape == (start + FLOOR_MAP_DIM,)
    seen, occupied, stood = obs["mask"][start:].reshape(3, FLOOR_MAP_CELLS, FLOOR_MAP_CELLS)
    centre = FLOOR_MAP_CELLS // 2
    # the camera looks ahead: the squares ahead are seen, the ones behind are not (row 0 is ahead)
    assert seen[:centre].sum() > seen[centre + 1:].sum() == 0
    assert stood[centre, centre] == 1.0 and stood.sum() == 1.0
    assert np.all((obs["mask"][start:] >= 0) & (obs["mask"][start:] <= 1))
    # walking forward: the square it stood on falls behind it
    inner = env.unwrapped
    before = (inner.state.x, inner.state.y)
    for _ in range(4):
        obs, *_ = env.step(np.array([1.0, 0.0, 0.0, 0.0, 0.0], np.float32))
    moved = math.hypot(inner.state.x - before[0], inner.state.y - before[1])
    stood = obs["mask"][start:].reshape(3, FLOOR_MAP_CELLS, FLOOR_MAP_CELLS)[2]
    if moved > 0.6:
        assert stood[centre + 1:].sum() >= 1.0
    snap = inner.snapshot()
    grid = inner._floor.grid.copy()
    env.step(np.array([0.0, 0.0, 1.0, 0.0, 0.0], np.float32))
    inner.restore(snap)
    assert np.array_equal(inner._floor.grid, grid)


def test_contact_signal_is_this_steps_bump_and_the_last_five_steps_count():
    """Driven forward into whatever stands ahead: the bump bit is ``info["collided"]`` of the same step, the
    count is the collided steps of the last 5 / 5 (hand-counted from the step infos), a replanner's restore
    brings the window back, and the paper's 4 values are untouched."""
    env = gymnasium.make("EgoSearch-v0", layout="kitchen_living", contact_signal=True)
    plain = gymnasium.make("EgoSearch-v0", layout="kitchen_living")
    assert env.observation_space["proprio"].shape == (PROPRIO_DIM + 2,)
    obs, _ = env.reset(seed=0)
    plain_obs, _ = plain.reset(seed=0)
    assert obs["proprio"][PROPRIO_DIM:].tolist() == [0.0, 0.0]
    bumps, snap_at, snap, seen = [], 12, None, set()
    for step in range(40):
        action = np.array([1.0, 0.0, 0.3 if step % 7 == 6 else 0.0, 0.05, 0.0], np.float32)
        obs, _, term, trunc, info = env.step(action)
        plain_obs, *_ = plain.step(action)
        np.testing.assert_array_equal(obs["proprio"][:PROPRIO_DIM], plain_obs["proprio"])
        bumps.append(int(info["collided"]))
        bit, recent = obs["proprio"][PROPRIO_DIM:]
        assert bit == bumps[-1]
        assert recent == pytest.approx(sum(bumps[-CONTACT_WINDOW:]) / CONTACT_WINDOW)
        seen.add(round(float(recent), 3))
        if step == snap_at:
            snap, at_snap = env.unwrapped.snapshot(), obs["proprio"].copy()
        if term or trunc:
            break
    assert 1 in bumps and 0 in bumps and len(seen) >= 3  # the walk did bump, and the count moved
    env.unwrapped.restore(snap)
    again, _ = env.unwrapped.observe(push=False)
    np.testing.assert_array_equal(again["proprio"], at_snap)
    obs, _ = env.reset(seed=1)  # a new episode forgets the last one's bumps
    assert obs["proprio"][PROPRIO_DIM:].tolist() == [0.0, 0.0]


def test_contact_signal_is_refused_where_nothing_reads_it():
    with pytest.raises(ValueError, match="contact_signal=1 is a int"):
        gymnasium.make("EgoSearch-v0", contact_signal=1)
    with pytest.raises(ValueError, match="does not read contact_signal"):
        gymnasium.make("EgoSearchModular-v0", contact_signal=True)


def test_a_policy_trained_with_the_contact_signal_carries_it_to_evaluation(tmp_path):
    """The option is a config field, not an env id: the training observes it, the actor file records it,
    ``policy_factory`` builds the evaluation env with it by default, and an env without it is refused in one
    line before any episode."""
    from egosearch.cli.acting import policy_factory
    from egosearch.rl.actor import ActorPolicy
    from egosearch.rl.common import AgentStateError
    from egosearch.rl.config import load_config
    from egosearch.rl.train import train
    from egosearch.runs.evaluate import evaluate
    from egosearch.sim.scenarios import generate_scenarios

    cfg = load_config("smoke", {"algorithm": "sac_drq", "total_env_steps": 40, "init_steps": 20, "eval_every": 40,
                                "eval_episodes": 1, "checkpoint_every": 40, "log_every": 20, "obs_downsample": 2,
                                "contact_signal": True})
    done = train("EgoSearch-v0", cfg, tmp_path, {"layout": "kitchen_living"}, progress=False)
    assert done["env_steps"] == 40
    actor = ActorPolicy(tmp_path / "actor.pt")
    assert actor.env_kwargs == {"contact_signal": True} and actor.trained_env_id() == "EgoSearch-v0"
    assert int(actor.arch["proprio_dim"]) == PROPRIO_DIM + 2
    make_policy, env_id, env_kwargs = policy_factory("actor", str(tmp_path / "actor.pt"), 0)
    assert (env_id, env_kwargs) == ("EgoSearch-v0", {"contact_signal": True})
    scenarios = generate_scenarios("kitchen_living", "everywhere", 1.05, n=2, seed=4)
    rows = evaluate(env_id, make_policy, scenarios, seed=0, env_kwargs=env_kwargs)
    assert all(1 <= r["steps"] <= 100 for r in rows)
    with pytest.raises(AgentStateError, match="trained in EgoSearch-v0 with contact_signal .* not in EgoSearch-v0 "):
        policy_factory("actor", str(tmp_path / "actor.pt"), 0, env_kwargs={"contact_signal": False})

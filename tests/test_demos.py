"""Demonstrations from the frontier searcher: stored as the learner's replay stores its transitions."""

from __future__ import annotations

import json

import numpy as np
import pytest

from egosearch.rl.base import pool_depth
from egosearch.rl.config import load_config
from egosearch.rl.demos import DEMO_SEED_BASE, collect_demonstrations, load_demonstrations, summary_path
from egosearch.rl.train_env import make_train_env, train_env_kwargs
from egosearch.searchers.frontier import FrontierPolicy
from egosearch.variants import load_variant

ENV = {"layout": "kitchen_living", "placement": "everywhere"}
FROM_SCRATCH = load_variant("head_on_from_scratch").config
"""The learner that demonstrations serve: the cpu profile before it became a modular searcher (the pins of its
stored variant)."""


@pytest.fixture(scope="module")
def demos(tmp_path_factory):
    cfg = load_config("cpu", {**FROM_SCRATCH, "seed": 3})
    path = tmp_path_factory.mktemp("demos") / "head_on.replay.npz"
    summary = collect_demonstrations("EgoSearch-v0", cfg, ENV, 3, path, seed=1, progress=False)
    return cfg, path, summary


def test_the_stored_transitions_are_the_teachers_own_steps(demos):
    cfg, path, summary = demos
    assert json.loads(summary_path(path).read_text()) == json.loads(json.dumps(summary))
    assert summary["env_id"] == "EgoSearchMemory-v0"  # the from-scratch learner's observation: the target memory
    assert summary["teacher_head"] and summary["episodes"] == 3
    assert list(summary["env_kwargs"]["train_heights"]) == [cfg.train_height_min, 1.8]
    replay = load_demonstrations(path, cfg)
    buf = replay.buffers[0]
    assert len(replay) == summary["transitions"] == buf.n_added
    ends = np.flatnonzero(buf.terminated[:buf.n_added] | buf.truncated[:buf.n_added])
    assert len(ends) == 3 and ends[-1] == buf.n_added - 1
    assert np.mean(buf.terminated[ends]) == pytest.approx(summary["teacher_success"], abs=1e-4)

    # the first episode again, from its seed: the teacher acts the same and sees the stored frames
    env = make_train_env("EgoSearchMemory-v0", train_env_kwargs(cfg, ENV))
    obs, _ = env.reset(seed=DEMO_SEED_BASE + 100_000 * 1)
    teacher = FrontierPolicy(env)
    stacks, _ = buf.stacks(np.arange(ends[0] + 1))
    for t in range(ends[0] + 1):
        np.testing.assert_array_equal(stacks[t], pool_depth(obs["depth"], cfg.obs_downsample))
        action = teacher.act(obs)
        np.testing.assert_allclose(buf.action[t], action, atol=1e-6)
        obs, reward, *_ = env.step(action)
        assert buf.reward[t] == pytest.approx(reward, abs=1e-5)
    env.close()


def test_demonstrations_sample_as_the_learners_replay_with_n_step_returns(demos):
    cfg, path, _ = demos
    batch = load_demonstrations(path, cfg).sample(16)
    assert batch["obs_depth"].shape == (16, cfg.frame_history, 50, 50)
    assert batch["state"].shape[1] > 0 and batch["action"].shape == (16, 5)
    assert (batch["discount"] <= cfg.gamma + 1e-6).all()
    assert (batch["discount"] >= cfg.gamma ** cfg.n_step - 1e-6).all()



def test_the_head_off_body_learns_from_the_head_fixed_searcher(tmp_path):
    """head_off's demonstrations: the frontier searcher holding its camera fixed, in the head-off env."""
    cfg = load_config("cpu", {**FROM_SCRATCH, "seed": 3})
    path = tmp_path / "head_off.replay.npz"
    summary = collect_demonstrations("EgoSearchNoHead-v0", cfg, ENV, 2, path, seed=1, progress=False)
    assert not summary["teacher_head"] and "NoHead" in summary["env_id"]
    env = make_train_env(summary["env_id"], train_env_kwargs(cfg, ENV))
    assert not FrontierPolicy(env).head
    buf = load_demonstrations(path, cfg).buffers[0]
    assert buf.action.shape[1] == env.action_space.shape[0] < 5  # no head angles to act on
    env.close()


def test_demonstrations_from_the_tuned_teacher_are_its_actions(tmp_path):
    """demo_teacher: frontier_tuned stores the tuned searcher's actions (not the untuned one's) and says so."""
    from egosearch.searchers.frontier_tuned import FrontierTunedPolicy

    cfg = load_config("cpu", {**FROM_SCRATCH, "seed": 3, "demo_episodes": 2, "demo_teacher": "frontier_tuned"})
    path = tmp_path / "tuned.replay.npz"
    summary = collect_demonstrations("EgoSearch-v0", cfg, ENV, 2, path, seed=2, progress=False)
    assert summary["teacher"] == "frontier_tuned" and summary["teacher_head"]
    buf = load_demonstrations(path, cfg).buffers[0]
    env = make_train_env(summary["env_id"], train_env_kwargs(cfg, ENV))
    differs = 0
    for episode in range(2):
        obs, _ = env.reset(seed=DEMO_SEED_BASE + 100_000 * 2 + episode)
        tuned, untuned = FrontierTunedPolicy(env), FrontierPolicy(env)
        first = 0 if episode == 0 else int(np.flatnonzero(buf.terminated | buf.truncated)[0]) + 1
        for t in range(first, buf.n_added):
            action = tuned.act(obs)
            np.testing.assert_allclose(buf.action[t], action, atol=1e-6)
            differs += not np.allclose(untuned.act(obs), action, atol=1e-6)  # the untuned one, shown the same
            obs, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                break
    env.close()
    assert differs > 0  # the untuned teacher would have acted otherwise somewhere: the test tells them apart


def test_a_teacher_is_named_only_with_demonstrations():
    from egosearch.rl.config import DEMO_TEACHERS
    from egosearch.rl.demos import TEACHERS

    assert tuple(TEACHERS) == DEMO_TEACHERS
    with pytest.raises(ValueError, match="demo_teacher='frontier_tuned' .*unless demo_episodes >= 1"):
        load_config("cpu", {**FROM_SCRATCH, "demo_teacher": "frontier_tuned"})
    with pytest.raises(ValueError, match="demo_teacher='oracle' .*allowed: frontier, frontier_tuned"):
        load_config("cpu", {**FROM_SCRATCH, "demo_episodes": 5, "demo_teacher": "oracle"})

"""Demonstrations from the frontier searcher: stored as the learner's replay stores its transitions."""

from __future__ import annotations

import json

import numpy as np
import pytest

from egosearch.rl.config import load_config
from egosearch.rl.demos import DEMO_SEED_BASE, collect_demonstrations, load_demonstrations, summary_path
from egosearch.rl.pooled import pool_depth
from egosearch.rl.train_env import make_train_env, train_env_kwargs
from egosearch.searchers.frontier import FrontierPolicy
from egosearch.variants import load_variant

ENV = {"layout": "kitchen_living", "placement": "everywhere"}
FROM_SCRATCH = load_variant("head_on_from_scratch").config
"""The learner that demonstrations serve: the cpu preset before it became a modular searcher (the pins of its
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


def test_demonstrations_are_collected_at_every_preset(tmp_path, capsys):
    """Issue 57: at the paper preset (and at smoke, a variant that pins it) the learner SAC+CURL stores the env's
    frames unpooled, and has no obs_downsample: `egosearch demos` and the `demos` rule stopped there on an
    AttributeError. (At smoke head_off has its cpu learner since issue 73, SAC-DrQ: the paper preset keeps it.)"""
    from egosearch.cli import main
    from egosearch.variants import resolve_variant

    out = tmp_path / "d.replay.npz"
    assert main(["demos", "--variant", "head_off", "--preset", "paper", "--episodes", "1", "--out", str(out)]) == 0
    cfg = resolve_variant("head_off", "paper").config
    assert not hasattr(cfg, "obs_downsample")
    summary = json.loads(summary_path(out).read_text())
    assert summary["variant"] == "head_off" and summary["image_size"] == cfg.image_size == 100
    replay = load_demonstrations(out, cfg)
    assert len(replay) == summary["transitions"] and replay.sample(2)["obs_depth"].shape[-1] == 100


def test_a_demonstrations_file_is_checked_before_it_is_read(demos, tmp_path):
    """A truncated or corrupt file, a summary that does not describe its file, and another run's
    demonstrations are each one line naming the file and what was expected."""
    import re
    import shutil

    from egosearch.rl.demos import DemonstrationsError, check_demonstrations, wanted_summary

    cfg, path, summary = demos
    copy = tmp_path / "d.replay.npz"

    def fresh():
        shutil.copy2(path, copy)
        shutil.copy2(summary_path(path), summary_path(copy))

    def refused(call, pattern):
        with pytest.raises(DemonstrationsError) as err:
            call()
        assert "\n" not in str(err.value) and str(copy) in str(err.value), str(err.value)
        assert re.search(pattern, str(err.value)), str(err.value)

    own = wanted_summary("EgoSearch-v0", cfg, ENV, seed=1, episodes=3)
    fresh()
    assert check_demonstrations(copy, own)["transitions"] == summary["transitions"]
    data = copy.read_bytes()
    copy.write_bytes(data[: len(data) // 2])
    refused(lambda: load_demonstrations(copy, cfg), r"truncated or corrupt \(BadZipFile")
    fresh()
    middle = len(data) // 2  # a member's bytes changed, the zip's directory whole: seen when the arrays are read
    copy.write_bytes(data[:middle] + bytes(b ^ 0xFF for b in data[middle:middle + 64]) + data[middle + 64:])
    refused(lambda: load_demonstrations(copy, cfg), r"expected the \.npz `egosearch demos` writes")
    fresh()
    summary_path(copy).write_text(json.dumps({**summary, "transitions": summary["transitions"] + 7}))
    refused(lambda: check_demonstrations(copy), rf"does not match its summary .*: the file holds transitions="
                                                rf"{summary['transitions']}; the summary says transitions=")
    fresh()
    refused(lambda: check_demonstrations(copy, {**own, "teacher": "frontier_tuned", "seed": 2}),
            r"holds other demonstrations than this run's: teacher='frontier', seed=1; expected "
            r"teacher='frontier_tuned', seed=2$")
    refused(lambda: load_demonstrations(copy, load_config("cpu", {**FROM_SCRATCH, "obs_downsample": 1})),
            r"holds 50 px frames .*; this learner's replay holds 100 px")
    summary_path(copy).unlink()
    refused(lambda: check_demonstrations(copy), r"its summary .*d\.json is not there")


def test_a_fresh_run_collects_its_own_where_a_left_file_is_truncated(tmp_path, monkeypatch, capsys):
    """A run stopped before its first checkpoint keeps its demonstrations to start from: one whose file was cut
    short (a full disk) is said in one line and collected again, not read into a BadZipFile."""
    from egosearch.rl import train as train_module
    from egosearch.rl.demos import wanted_summary

    small = {"device": "cpu", "num_threads": 1, "algorithm": "sac_drq", "obs_downsample": 2, "encoder_num_layers": 2,
             "encoder_stride2_layers": 2, "aug_pad": 1, "target_memory": True, "critic_privileged_state": True,
             "train_height_min": 0.45, "n_step": 3, "batch_size": 32, "seed": 4, "demo_episodes": 2,
             "bc_updates": 20, "critic_warmup_updates": 10, "demo_batch_fraction": 0.25, "bc_weight": 0.4,
             "bc_decay_steps": 200}
    cfg = load_config("smoke", small)
    left = tmp_path / "run" / "ckpt" / "demos.replay.npz"
    left.parent.mkdir(parents=True)
    left.write_bytes(b"PK\x03\x04" + bytes(100))
    summary_path(left).write_text(json.dumps({"format": "egosearch-demos-v1", "transitions": 150, "state_dim": 9,
                                              **wanted_summary("EgoSearch-v0", cfg, ENV, "run")}))

    class Collected(Exception):
        pass

    def collect(*args, **kwargs):
        raise Collected

    monkeypatch.setattr(train_module, "collect_demonstrations", collect)
    with pytest.raises(Collected):
        train_module.train("EgoSearch-v0", cfg, tmp_path / "run", ENV, lambda policy: {}, variant="run",
                           progress=False)
    said = [line for line in capsys.readouterr().out.splitlines() if line.startswith("not reused: ")]
    assert said == [f"not reused: {left}: not a readable demonstrations file, truncated or corrupt (BadZipFile: File "
                    "is not a zip file); expected the .npz `egosearch demos` writes, of 150 transitions as demos.json "
                    "says"]

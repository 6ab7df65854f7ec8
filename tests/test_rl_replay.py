"""The frame-deduplicating replay buffer rebuilds the env's stacks exactly."""

from __future__ import annotations

import sys
from pathlib import Path

import gymnasium
import numpy as np
import pytest
import torch

from egosearch.rl.replay import ReplayBuffer, frame_slots, replay_gb

sys.path.insert(0, str(Path(__file__).parent))
from test_rl_fake_env import FAKE_ENV_ID, register_fake_envs  # noqa: E402

K, S = 5, 100


class Stacker:
    """Env-like frame history: at reset the first frame is repeated K times, oldest first."""

    def __init__(self, rng):
        self.rng, self.frames = rng, None

    def _frame(self):
        return self.rng.integers(0, 256, (S, S), dtype=np.uint8)

    def _obs(self):
        return {"depth": self.frames.copy(), "mask": self.rng.normal(size=30).astype(np.float32),
                "proprio": self.rng.normal(size=4).astype(np.float32)}

    def reset(self):
        self.frames = np.repeat(self._frame()[None], K, axis=0)
        return self._obs()

    def step(self):
        self.frames = np.concatenate([self.frames[1:], self._frame()[None]])
        return self._obs()


def fill(buf: ReplayBuffer, lengths: list[int], seed: int = 0, terminate_last=True):
    """Episodes of the given lengths; returns the list of (obs, action, reward, next_obs, term, trunc)."""
    rng = np.random.default_rng(seed)
    env = Stacker(rng)
    log = []
    for length in lengths:
        obs = env.reset()
        for t in range(length):
            nxt = env.step()
            last = t == length - 1
            term = last and terminate_last and rng.random() < 0.5
            trunc = last and not term
            a = rng.uniform(-1, 1, 5).astype(np.float32)
            r = float(rng.normal())
            buf.add(obs, a, r, nxt, term, trunc)
            log.append((obs, a, r, nxt, term, trunc))
            obs = nxt
    return log


def check_all_valid(buf: ReplayBuffer, log: list) -> int:
    lo = buf.n_added - len(buf)
    n = np.arange(lo, buf.n_added)
    obs_stack, next_stack = buf.stacks(n)
    for j, k in enumerate(n):
        obs, a, r, nxt, term, trunc = log[k]
        assert np.array_equal(obs_stack[j], obs["depth"]), f"obs stack of transition {k}"
        assert np.array_equal(next_stack[j], nxt["depth"]), f"next_obs stack of transition {k}"
    batch = buf.sample(len(n), indices=n)
    for j, k in enumerate(n):
        obs, a, r, nxt, term, trunc = log[k]
        assert np.array_equal(batch["obs_depth"][j].numpy(), obs["depth"])
        assert np.array_equal(batch["next_obs_depth"][j].numpy(), nxt["depth"])
        assert np.allclose(batch["action"][j].numpy(), a)
        assert batch["reward"][j, 0].item() == pytest.approx(r)
        assert batch["not_done"][j, 0].item() == (0.0 if term else 1.0)
        assert np.array_equal(batch["mask"][j].numpy(), obs["mask"])
        assert np.array_equal(batch["next_proprio"][j].numpy(), nxt["proprio"])
    return len(n)


def test_stacks_exact_with_boundaries_and_wraparound():
    buf = ReplayBuffer(64, S, K, seed=0)
    # short episodes (shorter than K: padding), long ones, and enough to wrap the rings twice
    lengths = [1, 2, 3, 4, 5, 6, 9, 17, 3, 30, 2, 11, 40, 1, 1, 7, 25, 8]
    log = fill(buf, lengths)
    assert buf.n_added == sum(lengths) > 2 * buf.capacity
    assert check_all_valid(buf, log) == buf.capacity  # episodes average >= 8 steps here


def test_very_short_episodes_drop_overwritten_transitions_never_corrupt():
    buf = ReplayBuffer(40, S, K, seed=0)
    log = fill(buf, [1] * 120)  # 2 frames per transition: the frame ring holds fewer than 40
    n_valid = check_all_valid(buf, log)
    assert 0 < n_valid < buf.capacity
    assert n_valid == (buf.n_frames - 1) // 2  # every kept transition still has both frames
    for _ in range(20):
        idx = buf.sample_indices(8)
        assert idx.min() >= buf.n_added - n_valid


def test_matches_the_fake_env_stacks_including_resets():
    register_fake_envs()
    env = gymnasium.make(FAKE_ENV_ID, max_steps=7)
    env.action_space.seed(0)  # unseeded, the episode lengths (and so the count below) varied run to run
    buf = ReplayBuffer(30, S, K, seed=1)
    obs, _ = env.reset(seed=3)
    log = []
    for _ in range(100):
        a = env.action_space.sample()
        nxt, r, term, trunc, _ = env.step(a)
        buf.add(obs, a, r, nxt, term, trunc)
        log.append((obs, a, r, nxt, term, trunc))
        obs = env.reset()[0] if term or trunc else nxt
    # Episodes of at most 7 steps need more than the ring's 1 + 1/8 frames per transition, so the
    # oldest transitions may lose their frames: they must drop out of sampling, never come back
    # corrupted (check_all_valid compares every sampleable one with the log).
    valid = check_all_valid(buf, log)
    assert valid == len(buf) and 25 <= valid <= 30


def test_discontinuous_obs_is_an_error_and_new_episode_fixes_it():
    buf = ReplayBuffer(10, S, K)
    rng = np.random.default_rng(0)
    env = Stacker(rng)
    o0 = env.reset()
    o1 = env.step()
    buf.add(o0, np.zeros(5), 0.0, o1, False, False)
    fresh = env.reset()  # an env reset without the last transition ending its episode
    with pytest.raises(ValueError, match="new_episode"):
        buf.add(fresh, np.zeros(5), 0.0, env.step(), False, False)
    buf.new_episode()
    buf.add(fresh, np.zeros(5), 0.0, env.step(), False, False)
    assert len(buf) == 2


def test_memory_estimate_at_table2_capacity():
    gb = replay_gb(100_000)
    assert gb <= 1.5
    assert gb == pytest.approx(1.156, abs=0.01)
    small = ReplayBuffer(1000, S, K)
    assert small.nbytes == pytest.approx(replay_gb(1000) * 1e9)
    assert small.n_frames == frame_slots(1000, K)


def test_save_load_roundtrip(tmp_path):
    buf = ReplayBuffer(32, S, K, seed=5)
    log = fill(buf, [3, 10, 20, 6])
    path = buf.save(tmp_path / "replay.npz")
    other = ReplayBuffer(32, S, K, seed=99)
    other.load(path)
    assert check_all_valid(other, log) == len(buf)
    assert np.array_equal(other.sample_indices(16), buf.sample_indices(16))  # RNG state restored
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    with pytest.raises(ValueError, match="cannot read replay buffer"):
        other.load(bad)
    wrong = ReplayBuffer(16, S, K)
    with pytest.raises(ValueError, match="capacity"):
        wrong.load(path)


def test_sample_shapes_dtypes_and_views():
    buf = ReplayBuffer(50, S, K, seed=0)
    fill(buf, [20, 20])
    b = buf.sample(8)
    assert b["obs_depth"].shape == (8, K, S, S) and b["obs_depth"].dtype == torch.uint8
    assert b["next_obs_depth"].shape == (8, K, S, S)
    # obs and next_obs are two views of one (B, K+1, H, W) gather: no second copy of the stacks
    assert b["obs_depth"].untyped_storage().data_ptr() == b["next_obs_depth"].untyped_storage().data_ptr()
    assert b["reward"].shape == (8, 1) and b["not_done"].shape == (8, 1)
    assert b["action"].shape == (8, 5) and b["mask"].shape == (8, 30) and b["proprio"].shape == (8, 4)

"""The cpu preset's learner (SAC with a DrQ-v2-style update) and the lockstep-env replay."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from egosearch.rl.actor import ActorPolicy
from egosearch.rl.common import AgentStateError
from egosearch.rl.config import load_config
from egosearch.rl.pooled import PooledConvEncoder, conv_sides, pool_depth
from egosearch.rl.replay import MultiReplay
from egosearch.rl.sac_drq import SacDrqAgent, random_shift
from egosearch.rl.train import train

TESTS = Path(__file__).parent
sys.path.insert(0, str(TESTS))
from test_rl_fake_env import FAKE_ENV_ID, register_fake_envs  # noqa: E402
from test_rl_train import train_whole_and_resumed  # noqa: E402

register_fake_envs()
DRQ = {"device": "cpu", "num_threads": 1, "algorithm": "sac_drq", "obs_downsample": 2, "encoder_num_layers": 2,
       "encoder_stride2_layers": 2, "aug_pad": 2}


def test_pooling_rounds_half_up_and_acting_pools_like_the_replay():
    block = np.array([[1, 2], [3, 4]], np.uint8)  # mean 2.5 -> 3
    assert pool_depth(block, 2).tolist() == [[3]]
    assert pool_depth(np.array([[0, 0], [1, 1]], np.uint8), 2).tolist() == [[1]]  # 0.5 -> 1
    assert pool_depth(np.array([[255, 255], [255, 254]], np.uint8), 2).tolist() == [[255]]
    frames = np.random.default_rng(0).integers(0, 256, (2, 5, 100, 100), dtype=np.uint8)
    encoder = PooledConvEncoder(5, 100, 2, 2, 4, 2, "relu")
    assert np.array_equal(encoder.pool(torch.from_numpy(frames)).numpy().astype(np.uint8), pool_depth(frames, 2))


def test_conv_sides_and_random_shift():
    assert conv_sides(50, 3, 2) == [24, 11, 9]
    assert conv_sides(84, 4, 1) == [41, 39, 37, 35]  # CURL's encoder
    x = torch.arange(2 * 1 * 6 * 6, dtype=torch.float32).reshape(2, 1, 6, 6)
    torch.manual_seed(0)
    y = random_shift(x, 2)
    assert y.shape == x.shape
    for i in range(2):  # each sample is a window of the replicate-padded image
        padded = torch.nn.functional.pad(x[i:i + 1], (2, 2, 2, 2), mode="replicate")[0, 0]
        assert any(torch.equal(padded[a:a + 6, b:b + 6], y[i, 0]) for a in range(5) for b in range(5))
    assert torch.equal(random_shift(x, 0), x)


def test_channels_last_encoder_computes_the_same_features_and_gradients():
    torch.manual_seed(0)
    plain = PooledConvEncoder(5, 100, 2, 2, 8, 2, "relu")
    fast = PooledConvEncoder(5, 100, 2, 2, 8, 2, "relu")
    fast.load_state_dict(plain.state_dict())
    fast.use_channels_last()
    assert fast.convs[0].weight.is_contiguous(memory_format=torch.channels_last)
    x = torch.randint(0, 256, (4, 5, 50, 50)).float()
    a, b = plain(x), fast(x)
    assert a.shape == b.shape == (4, plain.out_dim)
    torch.testing.assert_close(a, b, rtol=1e-5, atol=1e-6)  # features in (C, H, W) order either way
    a.square().sum().backward()
    b.square().sum().backward()
    torch.testing.assert_close(plain.convs[0].weight.grad, fast.convs[0].weight.grad, rtol=1e-4, atol=1e-5)


def _obs(value: int, size: int = 8) -> dict:
    return {"depth": np.full((3, size, size), value, np.uint8), "mask": np.full(30, value, np.float32),
            "proprio": np.zeros(4, np.float32)}


def _fill_episode(replay: MultiReplay, env: int, rewards: list[float], start: int, terminated: bool) -> None:
    for t, r in enumerate(rewards):
        last = t == len(rewards) - 1
        obs = _obs(start + t)
        obs["depth"][:] = start + t  # the whole stack: only the newest frame matters to the ring
        replay.add(env, obs, np.zeros(5), r, _obs(start + t + 1), terminated and last, last and not terminated)


def test_n_step_returns_hand_worked():
    replay = MultiReplay(1, 100, image_size=8, frame_history=3, n_step=3, gamma=0.5)
    _fill_episode(replay, 0, [1, 2, 3, 4, 5], start=10, terminated=True)
    b = replay.sample_at(0, [0, 3, 4])
    # t=0: 1 + 0.5*2 + 0.25*3; bootstrap gamma^3 from the obs after step 2 (frame 13)
    assert b["reward"][:, 0].tolist() == [2.75, 6.5, 5.0]
    assert b["discount"][:, 0].tolist() == [0.125, 0.25, 0.5]
    assert b["not_done"][:, 0].tolist() == [1.0, 0.0, 0.0]  # steps 3 and 4 reach the terminal step
    assert b["next_obs_depth"][0, -1, 0, 0].item() == 13 and b["next_mask"][0, 0].item() == 13
    assert b["obs_depth"][1, -1, 0, 0].item() == 13 and b["next_obs_depth"][1, -1, 0, 0].item() == 15


def test_n_step_stops_at_truncation_but_still_bootstraps_and_rings_stay_apart():
    replay = MultiReplay(2, 200, image_size=8, frame_history=3, n_step=3, gamma=0.5)
    _fill_episode(replay, 0, [1, 1], start=10, terminated=False)  # truncated after 2 steps
    _fill_episode(replay, 0, [7, 7, 7, 7], start=50, terminated=False)
    _fill_episode(replay, 1, [100, 100, 100], start=90, terminated=True)
    b = replay.sample_at(0, [0, 1, 2])
    assert b["reward"][:, 0].tolist() == [1.5, 1.0, 7 + 3.5 + 1.75]  # never crosses into the next episode
    assert b["not_done"][:, 0].tolist() == [1.0, 1.0, 1.0]
    assert b["next_obs_depth"][0, -1, 0, 0].item() == 12  # the truncated episode's last obs
    batch = replay.sample(64)
    assert batch["reward"].shape == (64, 1)
    # each ring gave half the batch; no transition mixes the two envs' rewards
    rewards = set(batch["reward"][:, 0].tolist())
    assert rewards <= {1.5, 1.0, 12.25, 10.5, 7.0, 175.0, 150.0, 100.0}, rewards


def test_one_ring_one_step_samples_like_the_plain_buffer():
    replay = MultiReplay(1, 100, image_size=8, frame_history=3, n_step=1, seed=3)
    _fill_episode(replay, 0, [1, 2, 3], start=10, terminated=True)
    b = replay.sample(4)
    assert "discount" not in b and set(b["reward"][:, 0].tolist()) <= {1.0, 2.0, 3.0}


def test_drq_update_moves_the_critic_toward_a_fixed_target():
    cfg = load_config("smoke", {**DRQ, "batch_size": 16, "actor_update_freq": 1})
    agent = SacDrqAgent(cfg, 5)
    replay = MultiReplay(1, 64, image_size=agent.replay_image_size, frame_history=5, n_step=1)
    rng = np.random.default_rng(0)
    for _ in range(40):
        o = {"depth": rng.integers(0, 256, (5, 100, 100), dtype=np.uint8), "mask": np.zeros(30, np.float32),
             "proprio": np.zeros(4, np.float32)}
        o2 = {**o, "depth": np.concatenate([o["depth"][1:], rng.integers(0, 256, (1, 100, 100), dtype=np.uint8)])}
        replay.add(0, agent.replay_obs(o), rng.uniform(-1, 1, 5), 1.0, agent.replay_obs(o2), True, False)
    batch = replay.sample(16)
    losses = [agent.update(batch)["critic_loss"] for _ in range(60)]
    # every transition is terminal with reward 1: Q -> 1, so the TD loss must shrink a lot
    assert losses[-1] < 0.1 * losses[0], (losses[0], losses[-1])
    m = agent.update(batch)
    assert np.isnan(m["curl_loss"]) and np.isfinite(m["actor_loss"]) and agent.num_updates == 61


def _fixed_batch(agent: SacDrqAgent, n: int = 16) -> dict:
    replay = MultiReplay(1, 64, image_size=agent.replay_image_size, frame_history=5, n_step=1)
    rng = np.random.default_rng(0)
    # smooth frames (one depth per column, as a wall seen head on), so that a decoder can learn them
    ramp = np.linspace(0, 255, 100)
    for _ in range(40):
        o = {"depth": np.broadcast_to((ramp * rng.uniform(0.2, 1.0)).astype(np.uint8), (5, 100, 100)).copy(),
             "mask": np.zeros(30, np.float32), "proprio": np.zeros(4, np.float32)}
        replay.add(0, agent.replay_obs(o), rng.uniform(-1, 1, 5), 1.0, agent.replay_obs(o), True, False)
    return replay.sample(n)


def test_reconstruction_loss_trains_a_decoder_and_the_encoder_and_resumes():
    aux = load_config("smoke", {**DRQ, "batch_size": 16, "encoder_aux_loss": "reconstruction"})
    torch.manual_seed(0)
    agent = SacDrqAgent(aux, 5)
    batch = _fixed_batch(agent)
    torch.manual_seed(1)
    plain = SacDrqAgent(load_config("smoke", {**DRQ, "batch_size": 16}), 5)
    for name in ("encoder", "critic", "critic_target", "actor"):
        getattr(plain, name).load_state_dict(getattr(agent, name).state_dict())
    torch.manual_seed(2)
    first = agent.update(batch)
    torch.manual_seed(2)
    assert np.isnan(plain.update(batch)["aux_loss"])
    # the aux loss's gradient reaches the encoder: same weights, batch and noise, other encoder
    assert not all(torch.equal(a, b) for a, b in zip(agent.encoder.parameters(), plain.encoder.parameters()))
    losses = [first["aux_loss"]] + [agent.update(batch)["aux_loss"] for _ in range(80)]
    assert losses[-1] < 0.3 * losses[0], (losses[0], losses[-1])
    # its decoder and optimiser travel with the agent's state; a state without them is refused
    state = agent.state_dict()
    again = SacDrqAgent(aux, 5)
    again.load_state_dict(state)
    assert all(torch.equal(a, b) for a, b in zip(again.decoder.parameters(), agent.decoder.parameters()))
    with pytest.raises(AgentStateError, match="encoder_aux_loss"):
        again.load_state_dict(plain.state_dict())
    with pytest.raises(ValueError, match="encoder_aux_loss"):
        load_config("smoke", {"encoder_aux_loss": "reconstruction"})  # sac_curl has CURL's loss, no decoder
    with pytest.raises(ValueError, match="encoder_aux_loss"):
        load_config("smoke", {**DRQ, "encoder_aux_loss": "autoencoder"})


def test_critic_layer_norm_normalises_each_hidden_layer_of_both_q_heads_only():
    cfg = load_config("smoke", {**DRQ, "batch_size": 16, "critic_layer_norm": True})
    torch.manual_seed(0)
    agent = SacDrqAgent(cfg, 5)
    for head in (agent.critic.q1, agent.critic.q2, agent.critic_target.q1):
        norms = [m for m in head if isinstance(m, torch.nn.LayerNorm)]
        assert len(norms) == cfg.critic_num_layers - 1
        # each hidden layer's pre-activations come out with mean 0 and variance 1 per sample
        x = torch.randn(7, head[0].in_features) * 50 + 3
        hidden = head[1](head[0](x))
        assert torch.allclose(hidden.mean(-1), torch.zeros(7), atol=1e-4)
        assert torch.allclose(hidden.var(-1, unbiased=False), torch.ones(7), atol=1e-2)
    assert agent.update(_fixed_batch(agent))["critic_loss"] > 0
    plain = SacDrqAgent(load_config("smoke", {**DRQ, "batch_size": 16}), 5)
    assert not any(isinstance(m, torch.nn.LayerNorm) for m in plain.critic.q1)
    for target, source in ((plain, agent), (agent, plain)):
        with pytest.raises(AgentStateError, match="critic_layer_norm"):
            target.load_state_dict(source.state_dict())
    with pytest.raises(ValueError, match="critic_layer_norm"):
        load_config("smoke", {"critic_layer_norm": True})  # sac_curl's Q-heads do not take it


def test_drq_training_with_lockstep_envs_resumes_and_writes_a_loadable_actor(tmp_path):
    cfg = load_config("smoke", {**DRQ, "num_envs": 3, "n_step": 3, "update_every": 3, "total_env_steps": 300,
                                "checkpoint_every": 150, "eval_every": 150, "log_every": 50})

    class Stop(Exception):
        pass

    def stop_at(step):
        if step >= 200:
            raise Stop

    with pytest.raises(Stop):
        train(FAKE_ENV_ID, cfg, tmp_path, progress=False, on_step=stop_at)
    seen = []
    done = train(FAKE_ENV_ID, cfg, tmp_path, progress=False, on_step=seen.append)
    assert seen[0] == 153 and seen[-1] == 300  # resumed at the checkpoint at 150, 3 env steps a round
    # one update per multiple of update_every from init_steps on: 102, 105, ..., 300
    assert done["env_steps"] == 300 and done["updates"] == 300 // 3 - 99 // 3
    rows = (tmp_path / "train.csv").read_text().splitlines()[1:]
    assert [int(r.split(",")[0]) for r in rows] == [51, 102, 150, 201, 252, 300]
    policy = ActorPolicy(tmp_path / "actor.pt")
    obs = {"depth": np.zeros((5, 100, 100), np.uint8), "mask": np.zeros(30, np.float32),
           "proprio": np.zeros(4, np.float32)}
    assert policy.act(obs).shape == (5,) and np.array_equal(policy.act(obs), policy.act(obs))


def test_curriculum_radius_grows_linearly_then_stops():
    cfg = load_config("smoke", {"curriculum_steps": 1000})
    assert cfg.start_radius(0) == 1.0 and cfg.start_radius(500) == 6.5 and cfg.start_radius(1000) is None
    assert load_config("smoke", {}).start_radius(0) is None  # off by default (the paper has none)


def test_training_throughput_counts_env_steps_per_core_second():
    from egosearch.rl.bench_learner import training_throughput

    r = training_throughput("smoke", env_steps=120, overrides={"num_threads": 1})
    assert r["env_steps"] == 120 and r["core_s"] > 0
    assert r["env_steps_per_core_s"] == pytest.approx(120 / r["core_s"], rel=0.01)


def test_training_throughput_leaves_the_imitation_phase_out():
    """A preset that learns from the classical searcher first is timed in its RL phase alone (what the stored
    rates count), with a token imitation phase whatever the preset's (its 1,500 demonstrations would take
    many minutes of a one-minute benchmark)."""
    from egosearch.rl.bench_learner import training_throughput

    big = {**DRQ, "num_threads": 1, "demo_episodes": 500, "bc_updates": 5000, "demo_batch_fraction": 0.5,
           "critic_warmup_updates": 1000}
    r = training_throughput("smoke", env_steps=120, overrides=big)
    assert 0 < r["core_s_before_rl"] < 30  # a few episodes and a token cloning, not 500 and 5,000
    assert r["env_steps_per_core_s"] == pytest.approx(120 / r["core_s"], rel=0.01)


@pytest.mark.parametrize("overrides", [{}, DRQ, {**DRQ, "encoder_aux_loss": "reconstruction"}],
                         ids=["sac_curl", "sac_drq", "sac_drq_reconstruction"])
def test_killed_and_resumed_run_equals_the_run_that_was_not_stopped(tmp_path, overrides):
    cfg = load_config("smoke", {"device": "cpu", "num_threads": 1, **overrides,
                                "num_envs": 1 if not overrides else 3, "n_step": 1 if not overrides else 3})

    train_whole_and_resumed(cfg, tmp_path, stop_after=200)

"""The privileged critic (asymmetric actor-critic, ``critic_privileged_state``): the env's hidden
state reaches the critic through the replay, never the actor or an actor file."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from egosearch.envs import env_space_dims, observed_env_id
from egosearch.rl.actor import ActorPolicy
from egosearch.rl.config import load_config
from egosearch.rl.replay import MultiReplay, ReplayBuffer
from egosearch.rl.sac_drq import SacDrqAgent
from egosearch.rl.train import train, train_env_kwargs
from egosearch.scene.parts import Part
from egosearch.sim.body import AgentState
from egosearch.sim.env import PRIVILEGED_STATE_DIM, SearchEnv, privileged_state
from egosearch.variants import load_variant

DRQ = {"device": "cpu", "num_threads": 1, "algorithm": "sac_drq", "obs_downsample": 4, "encoder_num_layers": 2,
       "encoder_stride2_layers": 2, "aug_pad": 1}


def test_privileged_state_hand_worked():
    # body at (1, 2) facing +y, camera 1.2 m; target centred at (1, 4, 0.8): 2 m ahead, nothing left
    body = AgentState(1.0, 2.0, math.pi / 2, 0.0, 0.0, 1.2)
    target = Part("target", "box", (1.0, 4.0, 0.8), (0.1, 0.1, 0.1))
    v = privileged_state(body, target, distance=1.8, visible=True)
    expected = [0.1, 0.2, 0.0, 1.0, 0.1, 0.4, 0.08, 0.4, 0.0, 0.36, 1.2, 1.0]
    assert v.shape == (PRIVILEGED_STATE_DIM,) and v.dtype == np.float32
    np.testing.assert_allclose(v, expected, atol=1e-6)
    # the target 3 m to the body's left (x - 3 while facing +y): left = +3 / 5
    v = privileged_state(body, Part("t", "box", (-2.0, 2.0, 0.8), (0.1, 0.1, 0.1)), 2.8, False)
    np.testing.assert_allclose(v[7:9], [0.0, 0.6], atol=1e-6)
    assert v[11] == 0.0


def test_env_adds_the_state_only_when_asked():
    plain = SearchEnv()
    obs, _ = plain.reset(seed=0)
    assert "state" not in obs and "state" not in plain.observation_space.spaces
    env = SearchEnv(privileged_state=True)
    obs, info = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    x, y, theta = info["pose"][:3]
    assert obs["state"][:4].tolist() == pytest.approx([x / 10, y / 10, math.cos(theta), math.sin(theta)], abs=1e-6)
    obs, _, _, _, info = env.step(np.zeros(5, np.float32))
    assert obs["state"][9] == pytest.approx(info["distance"] / 5, abs=1e-6)
    assert obs["state"][11] == float(info["visible"])
    plain.close()
    env.close()


def _obs(value: int, with_state: bool = True) -> dict:
    obs = {"depth": np.full((3, 8, 8), value, np.uint8), "mask": np.zeros(30, np.float32),
           "proprio": np.zeros(4, np.float32)}
    if with_state:
        obs["state"] = np.full(2, value, np.float32)
    return obs


def test_replay_keeps_the_state_of_obs_and_of_the_n_step_next_obs(tmp_path):
    replay = MultiReplay(1, 100, image_size=8, frame_history=3, n_step=3, gamma=0.5, state_dim=2)
    for t in range(5):
        replay.add(0, _obs(10 + t), np.zeros(5), 1.0, _obs(11 + t), t == 4, False)
    b = replay.sample_at(0, [0, 3])
    # t=0 bootstraps from the obs after step 2 (value 13); t=3 reaches the terminal step 4 (15)
    assert b["state"][:, 0].tolist() == [10, 13] and b["next_state"][:, 0].tolist() == [13, 15]
    ring = replay.buffers[0]
    copy = ReplayBuffer(100, 8, 3, state_dim=2)
    ring.save(tmp_path / "r.replay.npz")
    copy.load(tmp_path / "r.replay.npz")
    assert np.array_equal(copy.next_state, ring.next_state)
    plain = ReplayBuffer(100, 8, 3)  # no state: samples have none, and old saves still load
    plain.add(_obs(1, False), np.zeros(5), 0.0, _obs(2, False), True, False)
    assert "state" not in plain.sample(2)
    old = plain.state_dict()
    del old["state"], old["next_state"]
    ReplayBuffer(100, 8, 3).load_state_dict(old)


def test_critic_reads_the_state_and_the_actor_does_not():
    cfg = load_config("smoke", {**DRQ, "critic_privileged_state": True})
    with pytest.raises(ValueError, match="state_dim"):
        SacDrqAgent(cfg, 5)
    agent = SacDrqAgent(cfg, 5, state_dim=3)
    torch.manual_seed(0)
    h = torch.randn(4, agent.encoder.out_dim)
    extra, action = torch.zeros(4, 34), torch.zeros(4, 5)
    q_a = agent.critic(h, torch.cat([extra, torch.zeros(4, 3)], -1), action)[0]
    q_b = agent.critic(h, torch.cat([extra, torch.ones(4, 3)], -1), action)[0]
    assert not torch.allclose(q_a, q_b)
    assert agent.actor.trunk[0].in_features == cfg.encoder_latent_dim + 34  # mask + proprio only
    with pytest.raises(ValueError, match="critic_privileged_state"):
        load_config("smoke", {"critic_privileged_state": True})  # SAC+CURL has no privileged critic


def test_training_with_a_privileged_critic_gives_an_actor_that_acts_without_it(tmp_path):
    # the from-scratch learner (body steps; its stored variant's pins), shrunk
    cfg = load_config("cpu", {**load_variant("head_on_from_scratch").config, "total_env_steps": 240, "init_steps": 80,
                              "num_envs": 4, "eval_every": 240, "eval_episodes": 1, "checkpoint_every": 240,
                              "log_every": 80, "replay_capacity": 1000, "critic_privileged_state": True})
    assert train_env_kwargs(cfg, {})["privileged_state"] is True
    done = train("EgoSearch-v0", cfg, tmp_path, progress=False)
    assert done["updates"] == 240 // 4 - 79 // 4
    policy = ActorPolicy(tmp_path / "actor.pt")
    # the from-scratch learner observes the last-seen target memory, so the actor's mask vector is that env's
    assert policy.trained_env_id() == observed_env_id("EgoSearch-v0", cfg.target_memory)
    dims = env_space_dims(policy.trained_env_id())
    obs = {"depth": np.zeros((5, 100, 100), np.uint8), "mask": np.zeros(dims["mask"], np.float32),
           "proprio": np.zeros(dims["proprio"], np.float32)}
    assert policy.act(obs).shape == (5,)

"""The memory levers' plumbing: strided depth stacks from the env through the replay, and actor snapshots."""

from __future__ import annotations

import sys
from pathlib import Path

import gymnasium
import numpy as np
import pytest
import torch

import egosearch.envs  # noqa: F401  (registers the ids)
from egosearch.rl.config import load_config
from egosearch.rl.replay import MultiReplay, ReplayBuffer
from egosearch.rl.train import snapshot_name, train
from egosearch.sim.observation_options import frame_offsets
from egosearch.sim.strided_history import STRIDED_OFFSETS

sys.path.insert(0, str(Path(__file__).parent))
from test_rl_fake_env import FAKE_ENV_ID  # noqa: E402
from test_rl_train import SMOKE  # noqa: E402


def _strided_episode(steps: int, seed: int = 3):
    env = gymnasium.make("EgoSearch-v0", strided_history=True)
    obs, _ = env.reset(seed=seed)
    env.action_space.seed(seed)
    log, newest = [], [obs["depth"][-1]]
    for _ in range(steps):
        action = env.action_space.sample()
        nxt, reward, term, trunc, _ = env.step(action)
        newest.append(nxt["depth"][-1])
        log.append((obs, action, reward, nxt, term, trunc))
        obs = nxt
        if term or trunc:
            break
    env.close()
    return log, newest


def test_strided_history_stacks_the_newest_frame_and_those_1_4_16_64_steps_before():
    assert frame_offsets({"strided_history": True}, 5) == STRIDED_OFFSETS == (64, 16, 4, 1, 0)
    assert frame_offsets({}, 5) == (4, 3, 2, 1, 0)
    log, newest = _strided_episode(80)
    assert len(log) >= 70
    for t, (obs, *_rest) in enumerate(log):
        for j, back in enumerate(STRIDED_OFFSETS):
            assert np.array_equal(obs["depth"][j], newest[max(0, t - back)]), (t, j)


def test_a_strided_replay_rebuilds_the_envs_stacks_and_refuses_a_last_k_state():
    """Every sampled obs and next_obs stack equals the env's, n-step or not, and a state saved with one kind of
    stack does not load into a buffer of the other."""
    log, _ = _strided_episode(90)
    buf = ReplayBuffer(500, 100, 5, 30, 4, 5, seed=0, frame_offsets=STRIDED_OFFSETS)
    for obs, a, r, nxt, term, trunc in log:
        buf.add(obs, a, r, nxt, term, trunc)
    n = np.arange(len(log))
    obs_stacks, next_stacks = buf.stacks(n)
    for t, (obs, _a, _r, nxt, *_) in enumerate(log):
        assert np.array_equal(obs_stacks[t], obs["depth"]) and np.array_equal(next_stacks[t], nxt["depth"]), t
    batch = buf.sample(len(log), indices=n)
    assert torch.equal(batch["obs_depth"], torch.from_numpy(obs_stacks))
    multi = MultiReplay(1, 500, 100, 5, 30, 4, 5, n_step=3, seed=0, frame_offsets=STRIDED_OFFSETS)
    for obs, a, r, nxt, term, trunc in log:
        multi.add(0, obs, a, r, nxt, term, trunc)
    three = multi.sample_at(0, np.array([10, 70]))
    assert np.array_equal(three["next_obs_depth"][0].numpy(), log[12][3]["depth"])
    assert np.array_equal(three["obs_depth"][1].numpy(), log[70][0]["depth"])
    with pytest.raises(ValueError, match="cannot start mid-episode"):
        buf.begin_mid_episode(log[0][0])
    last_k = ReplayBuffer(500, 100, 5, 30, 4, 5, seed=0)
    with pytest.raises(ValueError, match=r"holds stacks of frames \(64, 16, 4, 1, 0\) steps back"):
        last_k.load_state_dict(buf.state_dict())
    with pytest.raises(ValueError, match="decreasing, ending at 0"):
        ReplayBuffer(10, 100, 5, frame_offsets=(4, 3, 2, 1, 1))


def test_actor_snapshots_are_written_at_their_steps_and_act_as_the_run_did_then(tmp_path):
    cfg = load_config("smoke", {**SMOKE, "actor_snapshot_every": 100})
    train(FAKE_ENV_ID, cfg, tmp_path, variant="head-on", progress=False)
    snaps = sorted(p.name for p in tmp_path.glob("actor_*.pt") if p.name != "actor_start.pt")
    want = sorted(snapshot_name(s) for s in range(100, cfg.total_env_steps + 1, 100))  # the last is actor.pt's twin
    assert snaps == want and snapshot_name(50_000) == "actor_50k.pt" and snapshot_name(200) == "actor_200.pt"
    first = torch.load(tmp_path / want[0], weights_only=True)
    final = torch.load(tmp_path / "actor.pt", weights_only=True)
    assert first["metadata"]["snapshot_at"] == 100 and first["metadata"]["env_steps"] == 100
    assert any(not torch.equal(first["state_dict"][k], final["state_dict"][k]) for k in final["state_dict"])


def _map_episode(steps: int, seed: int = 4):
    env = gymnasium.make("EgoSearchMemory-v0", map_image=True, contact_signal=True)
    obs, _ = env.reset(seed=seed)
    env.action_space.seed(seed)
    log = []
    for _ in range(steps):
        action = env.action_space.sample()
        nxt, reward, term, trunc, _ = env.step(action)
        log.append((obs, action, reward, nxt, term, trunc))
        obs = nxt
        if term or trunc:
            break
    return env, log


def test_the_map_image_is_a_byte_valued_body_centred_map_of_the_episode():
    """The image ends mask, each value a multiple of 1/255: the floor seen grows, the occupied share is where depth
    hit something, the body's own cell is marked as stood in, and a replay stores and returns it exactly."""
    from egosearch.sim.map_image import MAP_CELLS, MAP_IMAGE_DIM
    from egosearch.sim.observation_options import byte_valued_tail

    env, log = _map_episode(40)
    assert env.observation_space["mask"].shape[0] == 35 + MAP_IMAGE_DIM  # 30 + target memory 5 + the image
    assert byte_valued_tail({"map_image": True, "contact_signal": True}) == MAP_IMAGE_DIM
    images = [o["mask"][-MAP_IMAGE_DIM:].reshape(4, MAP_CELLS, MAP_CELLS) for o, *_ in log]
    for img in images:
        assert np.abs(img * 255 - np.round(img * 255)).max() < 1e-4
        assert img[0].max() <= 1 and (img[0] + img[1]).max() <= 1.0 + 1e-6  # shares of one cell's floor
        centre = MAP_CELLS // 2
        assert img[2, centre - 1:centre + 1, centre - 1:centre + 1].any()  # it stands where it is
    assert images[-1][0].sum() > images[0][0].sum()  # more floor seen as the episode goes on
    env.close()
    buf = ReplayBuffer(100, 100, 5, 35 + MAP_IMAGE_DIM, env.observation_space["proprio"].shape[0], 5, seed=0,
                       mask_bytes=MAP_IMAGE_DIM)
    for obs, a, r, nxt, term, trunc in log:
        buf.add(obs, a, r, nxt, term, trunc)
    batch = buf.sample(len(log), indices=np.arange(len(log)))
    assert torch.equal(batch["mask"], torch.from_numpy(np.stack([o["mask"] for o, *_ in log])))
    assert torch.equal(batch["next_mask"], torch.from_numpy(np.stack([n["mask"] for *_x, n, _t, _u in log])))
    assert buf.mask_u8.nbytes == 100 * MAP_IMAGE_DIM  # a byte a value, not four


def test_sac_drq_reads_the_map_with_convs_of_its_own_in_actor_and_critic():
    """With map_image on, the actor and the critic each hold a map reader that turns the image into 64 features;
    the actor file records the image's place, and a policy loaded from it acts on the env's observation. Without it
    the networks are as before (no map reader key)."""
    from egosearch.rl.actor import load_any_actor_net
    from egosearch.rl.learner_registry import make_agent

    env, log = _map_episode(3)
    dims = {k: env.observation_space[k].shape[0] for k in ("mask", "proprio")}
    env.close()
    on = load_config("cpu", {"map_image": True, "contact_signal": True, "device": "cpu"})
    off = load_config("cpu", {"contact_signal": True, "device": "cpu"})
    agent = make_agent(on, 5, dims["mask"], dims["proprio"], "cpu", 12)
    plain = make_agent(off, 5, 35, dims["proprio"], "cpu", 12)
    assert agent.arch()["map_image"] == [4, 32, 32] and agent.arch()["map_offset"] == 35
    assert any(k.startswith("map_reader.") for k in agent.actor.state_dict())
    assert any(k.startswith("map_reader.") for k in agent.critic.state_dict())
    assert not any("map_reader" in k for k in plain.actor.state_dict()) and "map_image" not in plain.arch()
    # the trunk reads 64 map features instead of 4096 values
    assert agent.actor.trunk[0].in_features == plain.actor.trunk[0].in_features + 64
    net = load_any_actor_net(agent.actor_state(), "cpu")
    action = agent.act(log[-1][3], deterministic=True)
    assert action.shape == (5,) and np.all(np.abs(action) <= 1)
    with torch.inference_mode():
        from egosearch.rl.common import obs_to_tensors

        depth, extra = obs_to_tensors(log[-1][3], torch.device("cpu"), 100)
        mu, _ = net(depth.float(), extra)
    assert np.allclose(torch.tanh(mu)[0].numpy(), action, atol=2e-2)  # the float16 file acts as the agent does

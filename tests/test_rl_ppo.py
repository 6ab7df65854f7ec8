"""PPO (egosearch.rl.ppo): GAE, the clipped loss and log-probabilities by hand, an update that moves
the policy the advantages' way, the rollout the replay hands it, and a resumable training run whose
actor file evaluates like SAC-DrQ's."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from egosearch.rl.actor import ActorPolicy
from egosearch.rl.config import load_config
from egosearch.rl.ppo import PpoAgent, clipped_surrogate, gae, squashed_log_prob
from egosearch.rl.replay import MultiReplay
from egosearch.rl.sac_drq import ACTOR_FORMAT as DRQ_ACTOR_FORMAT

TESTS = Path(__file__).parent
sys.path.insert(0, str(TESTS))
from test_rl_fake_env import FAKE_ENV_ID, register_fake_envs  # noqa: E402
from test_rl_train import train_whole_and_resumed  # noqa: E402

register_fake_envs()
PPO = {"device": "cpu", "num_threads": 1, "algorithm": "ppo", "obs_downsample": 4, "encoder_num_layers": 2,
       "encoder_stride2_layers": 2, "init_steps": 0, "num_envs": 2, "update_every": 32, "replay_capacity": 64}


def test_gae_bootstraps_at_truncation_and_rollout_end_not_at_termination():
    # steps: 0 goes on, 1 terminates, 2 is truncated, 3 ends the rollout mid-episode
    value = torch.tensor([[1.0, 2.0, 3.0, 4.0]])
    next_value = torch.tensor([[2.0, 100.0, 7.0, 8.0]])  # 100: a terminal observation's, never used
    reward = torch.ones(1, 4)
    terminated = torch.tensor([[0.0, 1.0, 0.0, 0.0]])
    ended = torch.tensor([[0.0, 1.0, 1.0, 0.0]])
    adv, ret = gae(reward, value, next_value, terminated, ended, gamma=0.5, lam=0.5)
    # t3: 1 + .5*8 - 4 = 1;  t2: 1 + .5*7 - 3 = 1.5 (stops there);  t1: 1 - 2 = -1;  t0: (1 + .5*2 - 1) + .25*(-1)
    assert adv.tolist() == [[0.75, -1.0, 1.5, 1.0]]
    assert ret.tolist() == [[1.75, 1.0, 4.5, 5.0]]


def test_log_prob_inverts_the_squashed_sample_and_matches_a_hand_value():
    mu, log_std = torch.tensor([[0.3, -0.2]]), torch.tensor([[-0.5, 0.1]])
    noise = torch.tensor([[0.7, -1.1]])
    from egosearch.rl.common import squashed_sample

    action, log_pi = squashed_sample(mu, log_std, noise)
    assert torch.allclose(squashed_log_prob(mu, log_std, action), log_pi, atol=1e-4)
    a = math.tanh(0.5)  # 1-d, mu 0, std 1, u = 0.5
    hand = -0.5 * 0.25 - 0.5 * math.log(2 * math.pi) - math.log(1 - a * a + 1e-6)
    zero = torch.zeros(1, 1)
    assert squashed_log_prob(zero, zero, torch.tensor([[a]])).item() == pytest.approx(hand, abs=1e-5)
    assert torch.isfinite(squashed_log_prob(zero, zero, torch.ones(1, 1))).all()  # a float32 tanh's exact 1


def test_clipped_surrogate_hand_case_and_its_zero_gradient_where_clipped():
    ratios = torch.tensor([1.5, 1.5, 0.5, 0.5])
    adv = torch.tensor([1.0, -1.0, 1.0, -1.0])
    log_pi = ratios.log().requires_grad_(True)
    loss = clipped_surrogate(log_pi, torch.zeros(4), adv, clip=0.2)
    # min(r A, clip(r) A): 1.2, -1.5, 0.5, -0.8 -> loss = -mean
    assert loss.item() == pytest.approx(-(1.2 - 1.5 + 0.5 - 0.8) / 4)
    loss.backward()
    # d/dlogpi of -r A / 4 where unclipped; 0 where the clipped term is the min
    assert log_pi.grad.tolist() == pytest.approx([0.0, 1.5 / 4, -0.5 / 4, 0.0])


def _obs(rng) -> dict:
    return {"depth": rng.integers(0, 256, (5, 100, 100), dtype=np.uint8),
            "mask": rng.normal(size=30).astype(np.float32), "proprio": rng.normal(size=4).astype(np.float32)}


def _rollout(agent: PpoAgent, replay: MultiReplay, steps: int, seed: int = 0) -> None:
    """Each ring gets ``steps`` transitions of the agent's own actions, rewarded +1 when the first
    action value is positive, -1 otherwise, every step terminal (so the advantage is r - V)."""
    rng = np.random.default_rng(seed)
    for env in range(len(replay.buffers)):
        for _ in range(steps):
            obs = _obs(rng)
            a = agent.act(obs)
            replay.add(env, agent.replay_obs(obs), a, 1.0 if a[0] > 0 else -1.0, agent.replay_obs(_obs(rng)),
                       True, False)


def test_update_makes_advantaged_actions_more_likely():
    torch.manual_seed(0)
    cfg = load_config("smoke", {**PPO, "ppo_epochs": 4, "actor_lr": 1e-3, "critic_lr": 1e-3})
    agent = PpoAgent(cfg, 5, device="cpu")
    replay = MultiReplay(2, cfg.replay_capacity, agent.replay_image_size, 5, 30, 4, 5, seed=0)
    _rollout(agent, replay, 16)
    batch = agent.sample_batch(replay)
    assert batch["reward"].shape == (2, 16, 1) and batch["obs_depth"].shape == (2, 16, 5, 25, 25)
    obs = batch["obs_depth"].flatten(0, 1).float()
    extra = torch.cat([batch["mask"], batch["proprio"]], -1).flatten(0, 1)
    action = batch["action"].flatten(0, 1)
    good = action[:, 0] > 0
    assert 0 < good.sum() < len(good)

    def log_probs():
        with torch.no_grad():
            mu, log_std = agent.actor(agent.encoder(obs), extra)
            return squashed_log_prob(mu, log_std, action).squeeze(-1), torch.tanh(mu[:, 0]).mean().item()

    before, mean_before = log_probs()
    for _ in range(5):
        metrics = agent.update(batch)
    after, mean_after = log_probs()
    assert (after - before)[good].mean() > (after - before)[~good].mean() + 0.05
    assert mean_after > mean_before
    assert agent.num_updates == 5 * cfg.ppo_epochs * cfg.ppo_minibatches
    assert all(math.isfinite(metrics[k]) for k in ("critic_loss", "actor_loss", "entropy", "q_mean"))
    assert metrics["alpha"] == pytest.approx(cfg.entropy_coef)


def test_the_actor_starts_wide_and_independent_of_the_observation():
    torch.manual_seed(0)
    agent = PpoAgent(load_config("smoke", {**PPO, "ppo_init_std": 0.5}), 5, device="cpu")
    rng = np.random.default_rng(1)
    obs = {k: np.stack([_obs(rng)[k] for _ in range(8)]) for k in ("depth", "mask", "proprio")}
    with torch.no_grad():
        depth = torch.from_numpy(obs["depth"])
        extra = torch.from_numpy(np.concatenate([obs["mask"], obs["proprio"]], -1))
        mu, log_std = agent.actor(agent.encoder(agent.encoder.pool(depth)), extra)
    assert torch.allclose(log_std, torch.full_like(log_std, math.log(0.5)), atol=0.05)
    assert mu.abs().max() < 0.1
    assert agent.act_batch(obs).std() > 0.2  # sampled actions spread, not SAC's near-deterministic start


def test_latest_returns_the_newest_one_step_transitions_in_order():
    replay = MultiReplay(2, 20, 8, 3, 30, 4, 5, n_step=3, seed=0)
    rng = np.random.default_rng(0)
    frame = 0

    def obs():
        nonlocal frame
        frame += 1
        return {"depth": np.full((3, 8, 8), frame % 250, np.uint8), "mask": np.zeros(30, np.float32),
                "proprio": np.zeros(4, np.float32)}

    o = obs()
    for t in range(7):  # step 2 is truncated, step 4 terminates
        nxt = obs()
        replay.add(1, o, rng.uniform(-1, 1, 5), float(t), nxt, t == 4, t == 2)
        o = obs() if t in (2, 4) else nxt
    batch = replay.latest(1, 4)
    assert batch["reward"].squeeze(-1).tolist() == [3.0, 4.0, 5.0, 6.0]  # one-step rewards although n_step 3
    assert batch["index"].tolist() == [3, 4, 5, 6]
    assert batch["not_done"].squeeze(-1).tolist() == [1.0, 0.0, 1.0, 1.0]
    assert replay.latest(1, 5)["truncated"].squeeze(-1).tolist() == [1.0, 0.0, 0.0, 0.0, 0.0]
    with pytest.raises(ValueError, match="latest 8 transitions"):
        replay.latest(1, 8)
    with pytest.raises(ValueError):
        replay.latest(0, 1)  # nothing stored in ring 0


@pytest.mark.parametrize("override, field", [({"n_step": 3}, "n_step"), ({"init_steps": 100}, "init_steps"),
                                             ({"update_every": 33}, "update_every"),
                                             ({"replay_capacity": 40}, "replay_capacity"),
                                             ({"updates_per_step": 2}, "updates_per_step"),
                                             ({"ppo_init_std": 1e-6}, "ppo_init_std"),
                                             ({"gae_lambda": 1.5}, "gae_lambda")])
def test_ppo_config_rules_are_one_line_errors(override, field):
    with pytest.raises(ValueError, match=rf"^LearnerConfig\.{field}=") as err:
        load_config("smoke", {**PPO, **override})
    assert "\n" not in str(err.value)


def test_the_variant_is_valid_at_every_profile_and_ppo_at_the_cpu_profile():
    from egosearch.variants import check_learner_config, load_variant

    variant = load_variant("head_on_ppo")
    for preset in ("smoke", "cpu", "paper"):
        check_learner_config(variant, preset)
    cfg = load_config("cpu", variant.config)
    assert (cfg.algorithm, cfg.n_step, cfg.init_steps, cfg.critic_privileged_state) == ("ppo", 1, 0, True)
    assert cfg.update_every // cfg.num_envs == 128


def test_killed_and_resumed_run_equals_the_run_that_was_not_stopped_and_its_actor_evaluates(tmp_path):
    # checkpoints every 80 steps: inside a rollout of 32, so the replay carries a part of one
    cfg = load_config("smoke", {**PPO, "total_env_steps": 256, "checkpoint_every": 80, "eval_every": 128,
                                "log_every": 64, "eval_episodes": 2, "keep_checkpoint": False})

    # curve.csv's row at 128 averages the losses since the row before, and a resumed run has only those since
    # its checkpoint at 80 (train.csv's rows, every 64 steps, have no update between 64 and 80)
    train_whole_and_resumed(cfg, tmp_path, stop_after=150, logs=("train.csv",))
    a = torch.load(tmp_path / "whole" / "actor.pt", weights_only=True)
    assert a["format"] == DRQ_ACTOR_FORMAT and a["metadata"]["updates"] == 256 // 32 * 4 * 2

    policy = ActorPolicy(tmp_path / "whole" / "actor.pt")
    import gymnasium

    env = gymnasium.make(FAKE_ENV_ID)
    obs, _ = env.reset(seed=0)
    first = policy.act(obs)
    assert first.shape == (5,) and np.all(np.abs(first) <= 1) and np.array_equal(first, policy.act(obs))
    obs, *_ = env.step(first)
    assert policy.act(obs).shape == (5,)
    env.close()

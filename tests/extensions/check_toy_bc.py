"""The toy learner's own test (tests/test_toy_bc.py in the copy): it trains through the real loop and its actor
file acts through ActorPolicy."""

from __future__ import annotations

import sys
from pathlib import Path

from egosearch.rl.actor import ActorPolicy
from egosearch.rl.config import load_config, own_settings
from egosearch.rl.train import train

sys.path.insert(0, str(Path(__file__).parent))
from test_rl_fake_env import FAKE_ENV_ID, register_fake_envs  # noqa: E402

register_fake_envs()


def test_the_toy_learner_trains_and_its_actor_acts(tmp_path):
    assert own_settings("toy_bc") == ("toy_bc_lr",)
    cfg = load_config("smoke", {"algorithm": "toy_bc", "device": "cpu", "num_threads": 1, "total_env_steps": 60,
                                "init_steps": 20, "eval_every": 60, "checkpoint_every": 60, "log_every": 20,
                                "eval_episodes": 1, "batch_size": 8, "replay_capacity": 100})
    summary = train(FAKE_ENV_ID, cfg, tmp_path, progress=False)
    assert summary["updates"] > 0
    policy = ActorPolicy(tmp_path / "actor.pt", device="cpu")
    assert policy.action_dim == 5

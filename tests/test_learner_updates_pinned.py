"""The learners' updates, pinned to the bit: a few small trainings of every learner on the fake env, from a
fixed seed, end with the actor weights whose hash is written below.

The trainings run on the portable kernels (conftest.PORTABLE_KERNELS), which give the same floats on every
x86-64 host: with each host's own kernels, the hashes made on an AVX-512 host moved on an AVX2 one. The
first hashes were computed before the config was split into run settings and each learner's own settings
(issue 46, item 1), on the code that trained the stored runs. The portable ones were computed on an AVX2
host, at afc915c (where the AVX-512 hashes still held) and at the code after it, and were the same at both.
A refactor of the config or of a learner must leave them as they are: a hash that moves means an update
that computes something else. A change that is meant to change the math updates the hash, and says so in
its commit.

Each training is tiny (a few dozen env steps on the 25 px fake env, small networks, one thread), so that
the whole file runs in seconds. The hash covers every tensor of ``actor.pt``'s state dict in key order, and
the losses of train.csv (the critic, the temperature and, where a learner has it, the contrastive or PPO
losses), so that a critic that moved is seen even where the actor's weights would hide it.
"""

from __future__ import annotations

import csv
import hashlib
import sys
from pathlib import Path

import pytest
import torch

from egosearch.rl.config import load_config
from egosearch.rl.train import train

TESTS = Path(__file__).parent
sys.path.insert(0, str(TESTS))
from test_rl_fake_env import FAKE_ENV_ID, register_fake_envs  # noqa: E402

register_fake_envs()

TINY_RUN = {"device": "cpu", "num_threads": 1, "seed": 3, "total_env_steps": 48, "init_steps": 16,
            "eval_every": 48, "eval_episodes": 1, "log_every": 16, "checkpoint_every": 48, "replay_capacity": 256,
            "batch_size": 8, "actor_hidden_dim": 16, "critic_hidden_dim": 16, "encoder_num_filters": 4,
            "encoder_latent_dim": 8, "encoder_num_layers": 2}
"""What every pinned training shares: 48 env steps, 16 of them random, batches of 8, 16-unit MLPs."""

POOLED = {"obs_downsample": 4, "encoder_stride2_layers": 2, "aug_pad": 1}
"""The pooled learners' input: 100 px depth pooled to 25 px, two stride-2 convs."""

PINNED: dict[str, tuple[str, dict]] = {
    "sac_curl": ("smoke", {"curl_latent": 8}),
    "sac_curl_nstep_single_step": ("smoke", {"curl_latent": 8, "n_step": 2, "curl_double_encoder_step": False,
                                             "actor_update_freq": 1, "critic_target_update_freq": 1}),
    "sac_curl_shared_forward": ("smoke", {"curl_latent": 8, "share_encoder_forward": True, "channels_last": False}),
    "sac_drq": ("smoke", {"algorithm": "sac_drq", **POOLED, "num_envs": 2, "n_step": 3, "update_every": 2}),
    "sac_drq_ln_aux": ("smoke", {"algorithm": "sac_drq", **POOLED, "critic_layer_norm": True,
                                            "encoder_aux_loss": "reconstruction", "encoder_aux_weight": 0.5}),
    "sac_drq_recurrent": ("smoke", {"algorithm": "sac_drq_recurrent", **POOLED, "recurrent_hidden_dim": 8,
                                    "sequence_length": 4, "burn_in": 2}),
    "ppo": ("smoke", {"algorithm": "ppo", "obs_downsample": 4, "encoder_stride2_layers": 2, "init_steps": 0,
                      "num_envs": 2, "update_every": 16, "replay_capacity": 64, "ppo_epochs": 2, "ppo_minibatches": 2}),
}
"""Name -> (preset, overrides on top of :data:`TINY_RUN`): every learner, and its own options."""

EXPECTED = {
    "sac_curl": "adf3d08ee0a056e212ad41b1a33081d2f39aa4e850a559c8103db4ec503b55e3",
    "sac_curl_nstep_single_step": "b6b528526e7b0ddee15edcb4d1081f5fbf98d7747b387da96969e2a2381d8e64",
    "sac_curl_shared_forward": "b258fa102ebf390ea67fb3cc9cc267461a20e66796e66999c00b4e40ad01431c",
    "sac_drq": "2eccfc7c6e40c98f14950b8b98926910f0eb5a944c407c2d2876c74a3870e05a",
    "sac_drq_ln_aux": "04d9da7bd68b01f72618551019a4c7e0fe0908bc4e5d7f5c5c70102bcd8d12dc",
    "sac_drq_recurrent": "27bc1db9bc934f873cc0ab260b96459c0a6bb87ebb3cf143d45346f6f28a3c7e",
    "ppo": "c402436a8ad1dfdccffe65d23e760a5619711bf3a6363b0c40ec20cd18f56b02",
}
"""Name -> the sha256 of the training's actor weights and losses, on the portable kernels."""

LOSS_COLUMNS = ("updates", "train_return", "critic_loss", "actor_loss", "alpha_loss", "curl_loss", "aux_loss",
                "bc_loss", "alpha", "entropy", "q_mean")


def pinned_config(name: str):
    preset, overrides = PINNED[name]
    return load_config(preset, {**TINY_RUN, **overrides})


def training_hash(out: Path) -> str:
    """sha256 over the actor's tensors (key order) and train.csv's loss columns."""
    digest = hashlib.sha256()
    state = torch.load(out / "actor.pt", weights_only=True)["state_dict"]
    for key in sorted(state):
        digest.update(key.encode())
        digest.update(state[key].detach().cpu().contiguous().numpy().tobytes())
    with open(out / "train.csv") as f:
        for row in csv.DictReader(f):
            digest.update(repr([row.get(c) for c in LOSS_COLUMNS]).encode())
    return digest.hexdigest()


@pytest.mark.portable_kernels
@pytest.mark.parametrize("name", list(PINNED))
def test_a_learners_updates_are_pinned(name, tmp_path):
    cfg = pinned_config(name)
    torch.manual_seed(0)
    train(FAKE_ENV_ID, cfg, tmp_path, progress=False)
    assert training_hash(tmp_path) == EXPECTED[name], f"{name}: the learner's updates changed"

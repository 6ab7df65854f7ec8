"""Stacked seeds trained in one process (issue 47, item 4): each seed's folder is a complete run, a
killed stacked training resumes to the run that was not stopped, and a stacked training follows the
separate runs of its seeds."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from egosearch.rl.config import load_config
from egosearch.rl.stacked import StackingError
from egosearch.rl.train import train
from egosearch.rl.train_stacked import train_stacked

TESTS = Path(__file__).parent
sys.path.insert(0, str(TESTS))
from test_rl_fake_env import FAKE_ENV_ID, register_fake_envs  # noqa: E402
from test_rl_train import TIMING_COLUMNS, check_complete_run, read_csv  # noqa: E402

register_fake_envs()
SMOKE = {"device": "cpu", "num_threads": 1, "total_env_steps": 160, "eval_every": 80, "checkpoint_every": 80,
         "log_every": 40, "init_steps": 100}
SEEDS = (0, 1)


class Interrupt(Exception):
    pass


def configs(**overrides):
    return [load_config("smoke", {**SMOKE, **overrides, "seed": s}) for s in SEEDS]


def actor_weights(folder: Path) -> dict[str, torch.Tensor]:
    return torch.load(folder / "actor.pt", weights_only=True)["state_dict"]


def logs_without_timing(folder: Path, name: str) -> list[dict]:
    return [{k: v for k, v in r.items() if k not in TIMING_COLUMNS} for r in read_csv(folder / name)[1]]


def test_stacked_training_writes_each_seeds_run_and_resumes_to_the_same_run(tmp_path):
    cfgs = configs()
    whole = [tmp_path / "whole" / f"seed{s}" for s in SEEDS]
    resumed = [tmp_path / "resumed" / f"seed{s}" for s in SEEDS]
    summaries = train_stacked(FAKE_ENV_ID, cfgs, whole, variant="head-on", progress=False)
    for cfg, folder, summary in zip(cfgs, whole, summaries):
        assert summary == check_complete_run(folder, cfg)
        assert json.loads((folder / "config.json").read_text())["config"]["seed"] == cfg.seed
    # the seeds are different runs
    a, b = actor_weights(whole[0]), actor_weights(whole[1])
    assert not all(torch.equal(a[k], b[k]) for k in a)

    def stop(step: int) -> None:
        if step >= 120:  # after the checkpoint at step 80
            raise Interrupt(step)

    with pytest.raises(Interrupt):
        train_stacked(FAKE_ENV_ID, cfgs, resumed, variant="head-on", progress=False, on_step=stop)
    assert all((folder / "ckpt").is_dir() and not (folder / "done.json").exists() for folder in resumed)
    train_stacked(FAKE_ENV_ID, cfgs, resumed, variant="head-on", progress=False)
    for w, r in zip(whole, resumed):
        x, y = actor_weights(w), actor_weights(r)
        assert x.keys() == y.keys() and all(torch.equal(x[k], y[k]) for k in x)
        for name in ("train.csv", "curve.csv"):
            assert logs_without_timing(w, name) == logs_without_timing(r, name), name
    # finished seeds are not trained again
    assert train_stacked(FAKE_ENV_ID, cfgs, whole, variant="head-on", progress=False) == summaries


def test_a_stacked_seed_follows_its_separate_run(tmp_path):
    """The same random streams, the same batches: a seed trained stacked matches the same seed trained
    alone until float rounding (Adam's, on gradients near zero) grows, so the early rows agree closely."""
    cfgs = configs(total_env_steps=110, eval_every=110, checkpoint_every=110, log_every=110)
    stacked = [tmp_path / "stacked" / f"seed{s}" for s in SEEDS]
    train_stacked(FAKE_ENV_ID, cfgs, stacked, variant="head-on", progress=False)
    for cfg, folder in zip(cfgs, stacked):
        alone = tmp_path / "alone" / f"seed{cfg.seed}"
        train(FAKE_ENV_ID, cfg, alone, variant="head-on", progress=False)
        mine, theirs = read_csv(folder / "train.csv")[1], read_csv(alone / "train.csv")[1]
        assert [r["updates"] for r in mine] == [r["updates"] for r in theirs] == ["11"]
        for key in ("train_return", "episodes"):  # the envs saw the same actions
            assert mine[0][key] == theirs[0][key]
        for key in ("critic_loss", "actor_loss", "curl_loss", "alpha"):
            assert float(mine[0][key]) == pytest.approx(float(theirs[0][key]), rel=1e-3), key
        x, y = actor_weights(folder), actor_weights(alone)
        assert all(np.allclose(x[k].float(), y[k].float(), atol=2e-3) for k in x)


def test_seeds_that_cannot_be_stacked_are_refused(tmp_path):
    cfgs = configs()
    with pytest.raises(StackingError, match="batch_size"):
        train_stacked(FAKE_ENV_ID, [cfgs[0], load_config("smoke", {**SMOKE, "seed": 1, "batch_size": 16})],
                      [tmp_path / "a", tmp_path / "b"], progress=False)
    with pytest.raises(StackingError, match="repeated"):
        train_stacked(FAKE_ENV_ID, [cfgs[0], cfgs[0]], [tmp_path / "a", tmp_path / "b"], progress=False)
    with pytest.raises(StackingError, match="algorithm sac_drq_recurrent is not stacked"):
        train_stacked(FAKE_ENV_ID, configs(algorithm="sac_drq_recurrent", obs_downsample=2,
                                           encoder_stride2_layers=2, num_envs=2),
                      [tmp_path / "a", tmp_path / "b"], progress=False)
    assert not (tmp_path / "a").exists()  # refused before anything is written


def test_stacked_sac_drq_training_with_lockstep_envs_and_n_step_returns(tmp_path):
    drq = {"algorithm": "sac_drq", "obs_downsample": 2, "encoder_num_layers": 2, "encoder_stride2_layers": 2,
           "aug_pad": 2, "num_envs": 2, "n_step": 3, "update_every": 2}
    cfgs = configs(**drq)
    folders = [tmp_path / f"seed{s}" for s in SEEDS]
    summaries = train_stacked(FAKE_ENV_ID, cfgs, folders, variant="head-on", progress=False)
    for cfg, folder, summary in zip(cfgs, folders, summaries):
        assert summary["env_steps"] == cfg.total_env_steps and (folder / "done.json").exists()
        assert torch.load(folder / "actor.pt", weights_only=True)["format"] == "egosearch-sac-drq-actor-v1"
        rows = read_csv(folder / "train.csv")[1]
        assert int(rows[-1]["updates"]) == summary["updates"] > 0


def test_a_stacked_seeds_checkpoint_resumes_as_a_separate_run(tmp_path):
    cfgs = configs()
    folders = [tmp_path / f"seed{s}" for s in SEEDS]

    def stop(step: int) -> None:
        if step >= 120:  # after the checkpoint at step 80
            raise Interrupt(step)

    with pytest.raises(Interrupt):
        train_stacked(FAKE_ENV_ID, cfgs, folders, variant="head-on", progress=False, on_step=stop)
    summary = train(FAKE_ENV_ID, cfgs[1], folders[1], variant="head-on", progress=False)
    assert summary == check_complete_run(folders[1], cfgs[1])
    # seed 0 alone is then at another step than seed 1's finished run: the stack takes seed 0 only
    assert [s["env_steps"] for s in train_stacked(FAKE_ENV_ID, cfgs, folders, variant="head-on",
                                                  progress=False)] == [160, 160]
    check_complete_run(folders[0], cfgs[0])

"""Stacked seeds on the command line (issue 47, item 4): `egosearch train --stack-seeds` and the GPU
measurement `egosearch bench gpu --side-by-side N --stacked M`, whose figures go into the side-by-side
record (driven here with a fake runner; on a CPU the command refuses in one line)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
import torch

TESTS = Path(__file__).parent
sys.path.insert(0, str(TESTS))
from test_gpu_share import FakeRunner, _fake_mps, _train_csv  # noqa: E402


class StackedFakeRunner(FakeRunner):
    """FakeRunner, and a stacked training writes each seed's train.csv: 60 + 5 x seed env steps/s."""

    def __call__(self, trainings, timeout_s):
        if "--stack-seeds" not in trainings[0].argv:
            return super().__call__(trainings, timeout_s)
        self.batches.append(trainings)
        self.events.append("stacked")
        seeds = trainings[0].argv[trainings[0].argv.index("--stack-seeds") + 1].split(",")
        for seed in seeds:
            rate = 60.0 + 5 * int(seed)
            _train_csv(Path(trainings[0].out_dir.format(seed=seed)) / "train.csv", [900.0, rate, rate])
        return [0]


def test_the_stacked_training_is_measured_last_into_the_same_record(tmp_path):
    from egosearch.cli.side_by_side import run_side_by_side

    events = []
    runner = StackedFakeRunner(events)
    r = run_side_by_side(2, 30.0, tmp_path / "runs", variant="head_on", all_env_steps=4_500_000, all_trainings=6,
                         cores=8, runner=runner, mps=_fake_mps(tmp_path, events), say=lambda line: None, stacked=3)
    assert events == ["run 1", "start", "probe", "run 2", "stop", "stacked"]  # after the MPS daemon stopped
    stacked = runner.batches[-1][0]
    argv = " ".join(stacked.argv)
    assert "train --variant head_on --preset paper --stack-seeds 0,1,2 --threads 8" in argv
    assert "--max-wall-s 30" in argv and "--seed " not in argv
    assert stacked.out_dir == str(tmp_path / "runs" / "stacked" / "seed{seed}")
    assert r["stacked"]["per_seed_env_steps_per_s"] == [60.0, 65.0, 70.0]
    assert r["stacked"]["aggregate_env_steps_per_s"] == 195.0 and r["stacked"]["seeds"] == 3
    assert r["stacked"]["projected_all_hours"] == round(4_500_000 / 195 / 3600, 2)
    assert r["stacked"]["speedup_vs_alone"] == round(195 / 130, 2)
    assert [run["out_dir"] for run in r["runs"]["stacked"]] == [str(tmp_path / "runs" / "stacked" / f"seed{k}")
                                                                for k in range(3)]
    # the measurement without --stacked records none
    r = run_side_by_side(2, 30.0, tmp_path / "plain", variant="head_on", all_env_steps=1, all_trainings=1, cores=2,
                         runner=StackedFakeRunner([]), mps=_fake_mps(tmp_path, []), say=lambda line: None)
    assert "stacked" not in r


def test_the_commands_refuse_in_one_line(tmp_path, capsys):
    from egosearch.cli import main

    out = ["--out", str(tmp_path / "r.json")]
    cases = [
        (["bench", "gpu", "--stacked", "3", "--out-dir", str(tmp_path / "x"), *out],
         "egosearch bench: error: --stacked is measured beside the trainings side by side: give --side-by-side N"),
        (["bench", "gpu", "--side-by-side", "2", "--stacked", "1", "--out-dir", str(tmp_path / "x"), *out],
         "egosearch bench: error: --stacked=1"),
        (["bench", "learner", "--stacked", "2", *out],
         "egosearch bench: error: --stacked is read by `bench gpu` only, not by `bench learner`"),
        (["train", "--variant", "head_on", "--preset", "smoke", "--stack-seeds", "0,1", "--out-dir",
          str(tmp_path / "t")], "error: --out-dir=" + repr(str(tmp_path / "t"))
         + ": with --stack-seeds it must hold {seed} (one folder per seed)"),
        (["train", "--variant", "head_on", "--preset", "smoke", "--stack-seeds", "0,0", "--out-dir",
          str(tmp_path / "t{seed}")], "egosearch train: error: --stack-seeds='0,0': one or more seeds, none repeated"),
        (["train", "--variant", "head_on", "--preset", "smoke", "--stack-seeds", "0,x", "--out-dir",
          str(tmp_path / "t{seed}")], "egosearch train: error: --stack-seeds='0,x': comma-separated seeds"),
    ]
    if not torch.cuda.is_available():
        cases.append((["bench", "gpu", "--side-by-side", "2", "--stacked", "3", "--out-dir", str(tmp_path / "x"),
                       *out], "egosearch bench: error: bench gpu needs a CUDA GPU"))
    for argv, message in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("egosearch ") and message in err[0], (argv, err)
    assert not (tmp_path / "r.json").exists() and not (tmp_path / "t").exists()


@pytest.mark.parametrize("option", ["--stack-seeds"])
def test_train_help_names_the_option(option, capsys):
    from egosearch.cli import main

    with pytest.raises(SystemExit):
        main(["train", "--help"])
    assert option in capsys.readouterr().out


def test_bench_stacked_times_both_ways_at_small_sizes():
    from egosearch.rl.bench_learner import bench_stacked

    small = {"encoder_num_filters": 8, "encoder_latent_dim": 32, "actor_hidden_dim": 64,
             "critic_hidden_dim": 64, "batch_size": 16}
    r = bench_stacked(seeds=2, warmup=1, rounds=2, overrides=small)
    assert r["algorithm"] == "sac_drq" and r["seeds"] == 2 and r["batch_size"] == 16 and r["rounds"] == 2
    assert 0 < r["stacked_round_s_best"] <= r["stacked_round_s"] and 0 < r["separate_round_s_best"] <= r[
        "separate_round_s"]
    # the ratio of the unrounded medians: the rounded ones give it to within their rounding
    assert r["stacked_speedup"] == pytest.approx(r["separate_round_s"] / r["stacked_round_s"], rel=0.05, abs=0.01)

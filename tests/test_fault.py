"""Snakemake killed outright (SIGKILL to its whole process group) in the middle of a training job:
the same command run again finishes, with the outputs of an uninterrupted run, and no partial file
is ever taken for a finished output."""

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest
import torch

SMOKE = "preset=smoke"
TARGET = "results/smoke/eval/head_on/seed0/kitchen_living/everywhere/h1.65.csv"
RUN = "results/smoke/train/head_on/seed0"
TIMING = ["steps_per_s", "updates_per_s", "wall_s"]   # wall-clock columns: never the same twice
REPO = Path(__file__).resolve().parent.parent


@pytest.fixture
def checkout(tmp_path):
    """A copy of the suite's tracked files without results, so that runs never touch the stored ones."""
    files = subprocess.run(["git", "ls-files"], cwd=REPO, capture_output=True, text=True).stdout.split()
    dest = tmp_path / "suite"
    for name in files:
        if not name.startswith(("results/", "paper_figs/")) and (REPO / name).is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(REPO / name, dest / name)
    return dest


def _snakemake(cwd, **kw):
    # One core and the lowest priority: the test must not starve the machine.
    cmd = ["nice", "-n", "19", sys.executable, "-m", "snakemake", "--cores", "1", TARGET, "--config", SMOKE]
    return subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, **kw)


def _finish(cwd, timeout=900):
    proc = _snakemake(cwd)
    out, _ = proc.communicate(timeout=timeout)
    assert proc.returncode == 0, out[-3000:]
    return out


def _tensors_equal(a, b) -> bool:
    if isinstance(a, dict):
        return set(a) == set(b) and all(_tensors_equal(a[k], b[k]) for k in a)
    if torch.is_tensor(a):
        return torch.equal(a, b)
    return True   # metadata (versions, names) is checked through done.json and config.json


@pytest.mark.slow
def test_sigkill_mid_training_then_the_same_command_finishes_identically(checkout, tmp_path):
    twin = tmp_path / "twin"
    shutil.copytree(checkout, twin)
    _finish(twin)                                                     # the uninterrupted run

    proc = _snakemake(checkout, start_new_session=True)
    ckpt = checkout / RUN / "partial" / "ckpt" / "train_state.ckpt"
    deadline = time.monotonic() + 900
    while not ckpt.exists():                                          # half-way: the first checkpoint
        assert proc.poll() is None and time.monotonic() < deadline, "the training never checkpointed"
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    # Killed: the checkpoint and the growing CSVs are in partial/, no output where Snakemake looks.
    assert not (checkout / RUN / "actor.pt").exists() and not (checkout / RUN / "curve.csv").exists()
    assert not (checkout / TARGET).exists()
    assert list((checkout / ".snakemake" / "locks").glob("*.lock"))   # the dead run's lock is left

    out = _finish(checkout)                                           # the same command again
    assert "Removed the lock of a snakemake run that was killed" in out
    assert not (checkout / RUN / "partial").exists()
    # Seeded and deterministic: the same episodes, weights and learning curve as without the kill.
    assert (checkout / TARGET).read_bytes() == (twin / TARGET).read_bytes()
    got, want = (pd.read_csv(d / RUN / "curve.csv").drop(columns=TIMING) for d in (checkout, twin))
    pd.testing.assert_frame_equal(got, want)
    assert list(got["env_steps"]) == [0, 150, 300]
    assert _tensors_equal(*(torch.load(d / RUN / "actor.pt", weights_only=True) for d in (checkout, twin)))
    assert (checkout / RUN / "config.json").read_text() == (twin / RUN / "config.json").read_text()

"""``egosearch bench gpu --side-by-side N``: one paper-preset training alone, then N side by side on the
same GPU, each ``egosearch train --max-wall-s`` in a process and folder of its own (all the cores for the
one alone, cores / N threads each side by side), under CUDA MPS where this command can start it. With
``--baseline-seconds`` the N also run side by side without MPS first, so that both aggregates come from one
machine. The record's arithmetic (rates, aggregate, projection) is :mod:`egosearch.core.gpu_share`'s; the
runner and the MPS daemon are parameters, so that a test drives the whole path with fakes."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from egosearch.core.gpu_share import MPS_CONTROL, MpsStatus, median_rate, mps_pipe_dir, mps_status, side_by_side_result

ENTRY = "import sys; from egosearch.cli import main; sys.exit(main())"
"""``python -c ENTRY train ...``: the ``egosearch`` command in this interpreter, on PATH or not."""
PROBE = "import torch; x = torch.ones(8, device='cuda'); torch.cuda.synchronize(); print(float((2 * x).sum()))"
"""A CUDA process's smallest work: where an MPS daemon starts but its clients cannot connect (a container),
this fails, and the trainings run without MPS instead of failing."""
FOLDERS = ("alone", "without_mps", "side_by_side", "stacked")
"""The subfolders of ``--out-dir`` the trainings run in (one folder per training under the last two)."""


@dataclass
class Training:
    """One ``egosearch train`` process of the measurement."""
    out_dir: str
    log: str
    seed: int
    threads: int
    argv: list[str]
    env: dict = field(repr=False)


def training(out_dir: Path, log: Path, seed: int, threads: int, seconds: float, variant: str, env: dict) -> Training:
    """A paper-preset training of ``variant`` for ``seconds`` of wall time (stopped with a checkpoint),
    its torch, OpenMP and MKL threads ``threads``."""
    argv = [sys.executable, "-c", ENTRY, "train", "--variant", variant, "--preset", "paper", "--seed", str(seed),
            "--threads", str(threads), "--out-dir", str(out_dir), "--max-wall-s", f"{seconds:g}"]
    env = {**env, "OMP_NUM_THREADS": str(threads), "MKL_NUM_THREADS": str(threads)}
    return Training(str(out_dir), str(log), seed, threads, argv, env)


def stacked_training(out_dir: Path, log: Path, seeds: int, threads: int, seconds: float, variant: str,
                     env: dict) -> Training:
    """One process training seeds 0..``seeds``-1 of ``variant`` at the paper preset, their updates stacked
    (``egosearch train --stack-seeds``), each seed in ``out_dir/seed<k>``, for ``seconds`` of wall time."""
    run = training(out_dir / "seed{seed}", log, 0, threads, seconds, variant, env)
    at = run.argv.index("--seed")
    run.argv[at:at + 2] = ["--stack-seeds", ",".join(str(k) for k in range(seeds))]
    return run


def _measure_stacked(run: Training, seeds: int, seconds: float, runner: Callable) -> list[dict]:
    """Each stacked seed's rate, read from its own folder's train.csv."""
    code = runner([run], seconds + max(600.0, seconds))[0]
    return [{"out_dir": run.out_dir.format(seed=k), "log": run.log, "seed": k, "threads": run.threads,
             "returncode": code, **median_rate(Path(run.out_dir.format(seed=k)) / "train.csv")} for k in range(seeds)]


def run_together(trainings: list[Training], timeout_s: float) -> list[int]:
    """Start every training at once, each writing to its log; wait for all. A training still running
    ``timeout_s`` after the start is killed (its exit status then negative)."""
    started = []
    for t in trainings:
        Path(t.log).parent.mkdir(parents=True, exist_ok=True)
        log = open(t.log, "w", encoding="utf-8")
        started.append((subprocess.Popen(t.argv, env=t.env, stdout=log, stderr=subprocess.STDOUT), log))
    deadline = time.monotonic() + timeout_s
    codes = []
    for process, log in started:
        try:
            codes.append(process.wait(timeout=max(1.0, deadline - time.monotonic())))
        except subprocess.TimeoutExpired:
            process.kill()
            codes.append(process.wait())
        finally:
            log.close()
    return codes


class MpsDaemon:
    """The MPS control daemon of the measurement: one already running is used and left running; else
    ``nvidia-cuda-mps-control -d`` is started, checked with a CUDA process (:data:`PROBE`), and stopped
    (``quit``) after. ``which``, ``run`` and ``status`` are :func:`shutil.which`, :func:`subprocess.run`
    and :func:`egosearch.core.gpu_share.mps_status` unless a test gives fakes."""

    def __init__(self, env: dict | None = None, which: Callable = shutil.which, run: Callable = subprocess.run,
                 status: Callable[..., MpsStatus] = mps_status, wait_s: float = 10.0):
        self.env = dict(os.environ if env is None else env)
        self.which, self.run, self.status, self.wait_s = which, run, status, wait_s
        self.started: str | None = None  # the control program this object started, to stop

    def running_before(self) -> MpsStatus:
        return self.status(self.env)

    def start(self) -> tuple[bool, str]:
        """(whether the next CUDA processes run under MPS, what happened, in words)."""
        before = self.status(self.env)
        if before.running:
            return True, f"an MPS control daemon ran already ({before.evidence}); the command left it running"
        exe = self.which(MPS_CONTROL)
        if exe is None:
            return False, f"{MPS_CONTROL} is not installed here: the trainings side by side ran without MPS"
        pipe = mps_pipe_dir(self.env)
        self.env["CUDA_MPS_PIPE_DIRECTORY"] = str(pipe)
        if not self.env.get("CUDA_MPS_LOG_DIRECTORY") and not os.access("/var/log", os.W_OK):
            self.env["CUDA_MPS_LOG_DIRECTORY"] = str(pipe.parent / "nvidia-mps-log")  # the default needs root
        for folder in (pipe, Path(self.env.get("CUDA_MPS_LOG_DIRECTORY") or "/var/log/nvidia-mps")):
            try:
                folder.mkdir(parents=True, exist_ok=True)
            except OSError:
                pass
        try:
            done = self.run([exe, "-d"], env=self.env, capture_output=True, text=True, timeout=60)
        except (OSError, subprocess.SubprocessError) as err:
            return False, f"`{MPS_CONTROL} -d` could not run ({err}): the trainings side by side ran without MPS"
        if done.returncode != 0:
            said = (done.stderr or done.stdout or "").strip().splitlines()[-1:] or ["no message"]
            return False, (f"`{MPS_CONTROL} -d` failed (exit status {done.returncode}: {said[0]}): the trainings "
                           "side by side ran without MPS")
        self.started = exe
        deadline = time.monotonic() + self.wait_s
        while not self.status(self.env).running and time.monotonic() < deadline:
            time.sleep(0.5)
        now = self.status(self.env)
        if not now.running:
            self.stop()
            return False, (f"`{MPS_CONTROL} -d` returned but no daemon answered ({now.evidence}): the trainings "
                           "side by side ran without MPS")
        try:
            probe = self.run([sys.executable, "-c", PROBE], env=self.env, capture_output=True, text=True, timeout=300)
            failed = probe.returncode != 0
            why = ((probe.stderr or "").strip().splitlines()[-1:] or [f"exit status {probe.returncode}"])[0]
        except (OSError, subprocess.SubprocessError) as err:
            failed, why = True, str(err)
        if failed:
            self.stop()
            return False, (f"`{MPS_CONTROL} -d` started, but a CUDA process could not run under it ({why}), as in "
                           "a container without the host's MPS: the command stopped it, and the trainings side by "
                           "side ran without MPS")
        return True, (f"the command started `{MPS_CONTROL} -d` (pipe directory {pipe}) before the trainings side "
                      "by side and stopped it after")

    def stop(self) -> None:
        """Stop the daemon this object started (none: nothing to do)."""
        if self.started is None:
            return
        exe, self.started = self.started, None
        try:
            self.run([exe], input="quit\n", env=self.env, capture_output=True, text=True, timeout=60)
        except (OSError, subprocess.SubprocessError) as err:
            print(f"could not stop the MPS daemon ({err}): `echo quit | {MPS_CONTROL}` stops it", file=sys.stderr)


def available_cores() -> int:
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def check_folders(out_dir: Path) -> None:
    """A training given a folder with a checkpoint resumes it (or, finished, returns at once): the
    measurement needs folders that hold no earlier run."""
    for name in FOLDERS:
        folder = out_dir / name
        if folder.exists() and any(folder.iterdir()):
            raise ValueError(f"--out-dir={out_dir}: {folder} holds an earlier run, which a training would resume; "
                             "choose another --out-dir or remove it")


def _measure(trainings: list[Training], seconds: float, runner: Callable) -> list[dict]:
    codes = runner(trainings, seconds + max(600.0, seconds))
    return [{"out_dir": t.out_dir, "log": t.log, "seed": t.seed, "threads": t.threads, "returncode": code,
             **median_rate(Path(t.out_dir) / "train.csv")} for t, code in zip(trainings, codes)]


def run_side_by_side(n: int, seconds: float, out_dir: str | os.PathLike, *, variant: str, all_env_steps: int,
                     all_trainings: int, baseline_seconds: float = 0.0, cores: int | None = None,
                     runner: Callable = run_together, mps: MpsDaemon | None = None, say=print,
                     stacked: int = 0) -> dict:
    """The measurement (see the module's docstring): returns
    :func:`egosearch.core.gpu_share.side_by_side_result`. ``say`` reports each phase as it starts. With
    ``stacked`` >= 2, last, one process trains that many seeds with their updates stacked (all the cores,
    after the MPS daemon this command started is stopped: one process has nothing to share)."""
    if n < 2:
        raise ValueError(f"--side-by-side={n}: the trainings side by side must be >= 2")
    out = Path(out_dir)
    check_folders(out)
    cores = cores or available_cores()
    threads = max(1, cores // n)
    mps = mps or MpsDaemon()
    before = mps.running_before()
    say(f"one training alone for {seconds:g} s, {cores} threads"
        + (f" (under the MPS daemon that runs already: {before.evidence})" if before.running else ""))
    alone = _measure([training(out / "alone", out / "logs" / "alone.log", 0, cores, seconds, variant, mps.env)],
                     seconds, runner)[0]
    alone["mps"] = bool(before.running)
    without = None
    note = ""
    if baseline_seconds > 0 and before.running:
        note = "; no run without MPS (--baseline-seconds): the daemon that ran already is not this command's to stop"
    elif baseline_seconds > 0:
        if before.running is None:
            note = ("; whether a daemon outside this machine's view served the run without MPS cannot be told: "
                    f"{before.evidence}")
        say(f"{n} trainings side by side without MPS for {baseline_seconds:g} s, {threads} threads each")
        without = _measure([training(out / "without_mps" / str(i), out / "logs" / f"without_mps_{i}.log", i, threads,
                                     baseline_seconds, variant, mps.env) for i in range(n)], baseline_seconds, runner)
    try:
        under_mps, words = mps.start()
        say(f"{n} trainings side by side for {seconds:g} s, {threads} threads each; MPS: {words}")
        side = _measure([training(out / "side_by_side" / str(i), out / "logs" / f"side_by_side_{i}.log", i, threads,
                                  seconds, variant, mps.env) for i in range(n)], seconds, runner)
    finally:
        mps.stop()
    stacked_runs = None
    if stacked:
        say(f"{stacked} seeds stacked in one training for {seconds:g} s, {cores} threads")
        stacked_runs = _measure_stacked(stacked_training(out / "stacked", out / "logs" / "stacked.log", stacked,
                                                         cores, seconds, variant, mps.env), stacked, seconds, runner)
    return side_by_side_result(alone, side, all_env_steps=all_env_steps, all_trainings=all_trainings,
                               mps=under_mps, mps_note=words + note, seconds=seconds, variant=variant,
                               without_mps=without, without_mps_seconds=baseline_seconds if without else None,
                               stacked=stacked_runs)

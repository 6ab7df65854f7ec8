"""Several paper-preset trainings on one GPU (issue 47): how many the DAG runs side by side and the CPU
threads each takes, whether a CUDA MPS control daemon runs here, the one line a run says when trainings
share a GPU without one, and the arithmetic of the side-by-side measurement's record
(``egosearch bench gpu --side-by-side N``, :data:`SIDE_BY_SIDE`). Standard library only: the workflow's
rules, the cost line and the report layer all read it.

Without MPS the processes that share a GPU take turns on it (time slices); under MPS (Multi-Process
Service: ``nvidia-cuda-mps-control -d`` before they start) their kernels run at once. A CUDA process
connects to the control daemon through the pipe directory (``CUDA_MPS_PIPE_DIRECTORY``, default
``/tmp/nvidia-mps``), where the daemon keeps its ``control`` socket and its pid file
(``nvidia-cuda-mps-control.pid``); a process that finds no daemon there runs as it would without MPS.
"""

from __future__ import annotations

import csv
import json
import os
import statistics
import sys
from dataclasses import dataclass
from pathlib import Path

DEFAULT_TRAININGS_PER_GPU = 6
"""Paper-preset trainings side by side on one GPU when config ``trainings_per_gpu`` is ``auto`` and the
run is on one machine: the six trainings of ``all``, the count :data:`MEASURED` was measured with."""

MEASURED = {
    "gpu": "NVIDIA H200", "cores": 16, "trainings": 6, "threads_per_training": 2,
    "alone_env_steps_per_s": 131.0,
    "without_mps": {"per_training_env_steps_per_s": 34.7, "aggregate_env_steps_per_s": 208.0},
    "with_mps": {"per_training_env_steps_per_s": 90.0, "aggregate_env_steps_per_s": 541.0},
    "source": "issue 47's measurement: one NVIDIA H200 with 16 cores, the paper preset, `egosearch train "
              "--max-wall-s`, median env steps/s while updating; one training alone with 16 threads, then six "
              "side by side with 2 threads each, without MPS and under it",
}
"""The side-by-side rates measured once, before :data:`SIDE_BY_SIDE` was recorded (issue 47): what the
run's line about sharing says until a stored record holds both rates."""

SIDE_BY_SIDE = Path("results") / "paper" / "gpu_check" / "side_by_side.json"
"""Where ``egosearch bench gpu --side-by-side N`` stores its record, under the project root."""

DEFAULT_MPS_PIPE_DIRECTORY = "/tmp/nvidia-mps"
MPS_CONTROL = "nvidia-cuda-mps-control"
MPS_PID_FILE = "nvidia-cuda-mps-control.pid"


# ---- how many side by side, and their threads -------------------------------------------------

def resolve_trainings_per_gpu(value, local: bool) -> int:
    """Config ``trainings_per_gpu`` as a number: ``auto`` is :data:`DEFAULT_TRAININGS_PER_GPU` on one
    machine (``local``: Snakemake's local executor) and 1 under a cluster executor, where each training is a
    job of its own asking for a whole GPU. More than one under a cluster executor is refused: those jobs
    would each hold a GPU of their own."""
    if value is None or value == "auto":
        return DEFAULT_TRAININGS_PER_GPU if local else 1
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ValueError(f"config trainings_per_gpu: {value!r}; allowed: auto or an integer >= 1")
    if value > 1 and not local:
        raise ValueError(f"config trainings_per_gpu: {value} shares one GPU between trainings on the machine "
                         "snakemake runs on; under a cluster executor each training is a job of its own with a "
                         "whole GPU (gpu=1): leave it auto or 1 there, or run snakemake with --cores inside one "
                         "GPU allocation")
    return value


def train_threads(preset: str, cores: int | None, trainings_per_gpu: int) -> int:
    """The CPU threads a training job takes (its ``threads:`` and ``egosearch train --threads``): at the
    paper preset on one machine a fair share of ``cores``, ``cores // trainings_per_gpu`` (at least 1);
    1 at the other presets (their trainings run one per core) and where no ``cores`` are known (a cluster
    executor's run: ``--set-threads train=N`` gives more)."""
    if preset != "paper" or not cores:
        return 1
    return max(1, cores // max(1, trainings_per_gpu))


# ---- CUDA MPS ------------------------------------------------------------------------------------

@dataclass(frozen=True)
class MpsStatus:
    """Whether CUDA processes started here would run under MPS: ``running`` True (a control daemon
    answers at ``pipe_dir``), False (none) or None (cannot be told from here: a control socket whose daemon
    is not among this machine's visible processes, as in a container whose daemon runs outside it)."""
    running: bool | None
    pipe_dir: str
    evidence: str


def mps_pipe_dir(env=None) -> Path:
    """The pipe directory a CUDA process started with ``env`` (default this process's) looks for the MPS
    control daemon in."""
    env = os.environ if env is None else env
    return Path(env.get("CUDA_MPS_PIPE_DIRECTORY") or DEFAULT_MPS_PIPE_DIRECTORY)


def mps_control_pids(proc: Path = Path("/proc")) -> list[int]:
    """The visible processes whose program is ``nvidia-cuda-mps-control`` (``/proc/<pid>/cmdline``; the
    ``comm`` name is cut to 15 characters and reads the same for the MPS server)."""
    pids = []
    try:
        entries = list(proc.iterdir())
    except OSError:
        return []
    for entry in entries:
        if not entry.name.isdigit():
            continue
        try:
            program = (entry / "cmdline").read_bytes().split(b"\0", 1)[0].decode(errors="replace")
        except OSError:
            continue
        if Path(program).name == MPS_CONTROL:
            pids.append(int(entry.name))
    return sorted(pids)


def mps_status(env=None, proc: Path = Path("/proc")) -> MpsStatus:
    """Whether an MPS control daemon serves the pipe directory of ``env``: its ``control`` socket there,
    and its process visible (the pid in its pid file, or any ``nvidia-cuda-mps-control``)."""
    pipe_dir = mps_pipe_dir(env)
    control = pipe_dir / "control"
    has_control = control.exists()
    pid = None
    try:
        pid = int((pipe_dir / MPS_PID_FILE).read_text().strip())
    except (OSError, ValueError):
        pass
    if has_control and pid is not None and (proc / str(pid)).exists():
        return MpsStatus(True, str(pipe_dir), f"control daemon pid {pid}, pipe directory {pipe_dir}")
    pids = mps_control_pids(proc)
    if has_control and pids:
        return MpsStatus(True, str(pipe_dir), f"{MPS_CONTROL} pid {pids[0]}, pipe directory {pipe_dir}")
    if has_control:
        return MpsStatus(None, str(pipe_dir), f"{control} exists but no {MPS_CONTROL} process is visible here "
                                              "(a daemon outside this container, or one that died)")
    if pids:
        return MpsStatus(False, str(pipe_dir), f"{MPS_CONTROL} runs (pid {pids[0]}) but not on {pipe_dir}: set "
                                               "CUDA_MPS_PIPE_DIRECTORY to its pipe directory")
    return MpsStatus(False, str(pipe_dir), f"no {MPS_CONTROL} process, no control socket in {pipe_dir}")


# ---- what a run says once --------------------------------------------------------------------------

def read_side_by_side(root: Path = Path(".")) -> dict | None:
    """The stored side-by-side record under ``root`` (:data:`SIDE_BY_SIDE`), None where there is none."""
    path = Path(root) / SIDE_BY_SIDE
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def sharing_rates(record: dict | None) -> dict:
    """N trainings side by side: their aggregate env steps/s without MPS and under it, and where the
    numbers come from. The stored record's when it holds both (a run under MPS with its run without MPS,
    ``--baseline-seconds``), else :data:`MEASURED`'s."""
    if record and record.get("mps") and (record.get("without_mps") or {}).get("aggregate_env_steps_per_s"):
        return {"n": record["side_by_side"], "without": record["without_mps"]["aggregate_env_steps_per_s"],
                "with": record["aggregate_env_steps_per_s"],
                "gpu": (record.get("machine") or {}).get("gpu") or "GPU",
                "source": f"{SIDE_BY_SIDE}, {str(record.get('date_utc', '?'))[:10]}"}
    return {"n": MEASURED["trainings"], "without": MEASURED["without_mps"]["aggregate_env_steps_per_s"],
            "with": MEASURED["with_mps"]["aggregate_env_steps_per_s"], "gpu": MEASURED["gpu"],
            "source": "issue 47's measurement, egosearch.core.gpu_share.MEASURED"}


def sharing_line(trainings_per_gpu: int, status: MpsStatus, record: dict | None = None) -> str | None:
    """The line a paper-preset run says before its first job when its trainings share one GPU: under
    MPS, that they do; without it (or where that cannot be told), what it costs and how to start it.
    None when the trainings run one at a time."""
    if trainings_per_gpu <= 1:
        return None
    share = f"Up to {trainings_per_gpu} paper-preset trainings run side by side on one GPU (trainings_per_gpu)"
    if status.running:
        return f"{share}, under CUDA MPS ({status.evidence})."
    r = sharing_rates(record)
    how = ("start the daemon first, `nvidia-cuda-mps-control -d` (docs/gpu.md), or run them one at a time "
           "with --config trainings_per_gpu=1")
    if status.running is None:
        return (f"{share}; whether they run under CUDA MPS cannot be told here: {status.evidence}. Without it "
                f"they take turns on the GPU: {r['n']} side by side trained {r['without']:.0f} env steps/s in "
                f"all against {r['with']:.0f} under MPS ({r['gpu']}; {r['source']}); if no daemon serves "
                f"{status.pipe_dir}, {how}.")
    return (f"{share} without CUDA MPS ({status.evidence}): they take turns on the GPU. {r['n']} side by side "
            f"trained {r['without']:.0f} env steps/s in all against {r['with']:.0f} under MPS ({r['gpu']}; "
            f"{r['source']}); {how}.")


_SAID: set[str] = set()


def say_once(line: str | None, stream=None) -> bool:
    """Print ``line`` (to stderr by default) unless this process has said it already; True when printed."""
    if not line or line in _SAID:
        return False
    _SAID.add(line)
    print(line, file=stream or sys.stderr)
    return True


def warn_gpu_sharing(preset: str, trainings_per_gpu: int, root: Path = Path("."), env=None,
                     proc: Path = Path("/proc"), stream=None) -> bool:
    """What the Snakefile's cost line adds before a paper-preset run's first job: :func:`sharing_line`
    for this machine's MPS daemon and the stored record, once. True when a line was printed."""
    if preset != "paper" or trainings_per_gpu <= 1:
        return False
    return say_once(sharing_line(trainings_per_gpu, mps_status(env, proc), read_side_by_side(root)), stream)


# ---- the side-by-side measurement's record ------------------------------------------------------

def median_rate(train_csv: str | os.PathLike) -> dict:
    """A training's rate from its ``train.csv``: the median ``steps_per_s`` of its rows after the first
    (which holds the warm-up, env steps before the first update), the rows used and the env steps reached.
    No file or no row: a rate of None."""
    try:
        with open(train_csv, newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError:
        rows = []
    rates = [float(r["steps_per_s"]) for r in rows[1:]]
    return {"env_steps_per_s_updating": round(statistics.median(rates), 1) if rates else None,
            "train_rows_used": len(rates), "env_steps": int(float(rows[-1]["env_steps"])) if rows else None}


def projected_hours(env_steps: float, env_steps_per_s: float) -> float:
    """Hours for ``env_steps`` at ``env_steps_per_s`` (the paper ``all``'s training env steps at the
    aggregate rate of the trainings side by side)."""
    if not env_steps_per_s > 0:
        raise ValueError(f"a rate must be > 0 env steps/s, got {env_steps_per_s}")
    return env_steps / env_steps_per_s / 3600


def _rates(runs: list[dict], what: str) -> list[float]:
    rates = []
    for i, run in enumerate(runs):
        if run.get("env_steps_per_s_updating") is None:
            raise ValueError(f"{what}: training {i} ({run.get('out_dir', '?')}) ended with exit status "
                             f"{run.get('returncode', '?')} and no train.csv rate; its log: {run.get('log', '?')}")
        rates.append(float(run["env_steps_per_s_updating"]))
    return rates


def side_by_side_result(alone: dict, side: list[dict], *, all_env_steps: int, all_trainings: int, mps: bool,
                        mps_note: str, seconds: float, variant: str, without_mps: list[dict] | None = None,
                        without_mps_seconds: float | None = None, stacked: list[dict] | None = None) -> dict:
    """The record's measurement: ``alone`` (one training's run: its rate, threads, folder), ``side`` (the N
    run together, under MPS when ``mps``) and, where run, ``without_mps`` (the N together without it). The
    aggregate is the sum of the trainings' rates; ``projected_all_hours`` is ``all_env_steps`` (the paper
    ``all``'s trainings: ``all_trainings`` of them) at that aggregate."""
    alone_rate = _rates([alone], "the training alone")[0]
    rates = _rates(side, "side by side")
    aggregate = sum(rates)
    result = {
        "variant": variant, "preset": "paper", "seconds": seconds, "side_by_side": len(side),
        "threads_alone": alone.get("threads"), "threads_per_training": side[0].get("threads") if side else None,
        "alone_env_steps_per_s": round(alone_rate, 1),
        "per_training_env_steps_per_s": [round(r, 1) for r in rates],
        "aggregate_env_steps_per_s": round(aggregate, 1),
        "speedup_vs_alone": round(aggregate / alone_rate, 2),
        "mps": bool(mps), "mps_note": mps_note,
        "all_trainings": all_trainings, "all_env_steps": all_env_steps,
        "projected_all_hours": round(projected_hours(all_env_steps, aggregate), 2),
        "projected_all_hours_one_at_a_time": round(projected_hours(all_env_steps, alone_rate), 2),
    }
    runs = {"alone": alone, "side_by_side": side}
    if without_mps:
        plain = _rates(without_mps, "side by side without MPS")
        result["without_mps"] = {
            "seconds": without_mps_seconds, "per_training_env_steps_per_s": [round(r, 1) for r in plain],
            "aggregate_env_steps_per_s": round(sum(plain), 1),
            "projected_all_hours": round(projected_hours(all_env_steps, sum(plain)), 2)}
        runs["without_mps"] = without_mps
    if stacked:
        # one process, its seeds' updates one stacked model (issue 47, item 4): each seed's rate is its own
        # train.csv's, and the seeds' sum is the process's aggregate
        rates = _rates(stacked, "stacked")
        result["stacked"] = {
            "seeds": len(stacked), "threads": stacked[0].get("threads"),
            "per_seed_env_steps_per_s": [round(r, 1) for r in rates],
            "aggregate_env_steps_per_s": round(sum(rates), 1),
            "speedup_vs_alone": round(sum(rates) / alone_rate, 2),
            "projected_all_hours": round(projected_hours(all_env_steps, sum(rates)), 2)}
        runs["stacked"] = stacked
    result["runs"] = runs
    return result


def side_by_side_record(recorded: dict) -> dict:
    """``egosearch.sim.bench_env.recorded``'s record (command, date, commit, machine, load, ``result``) as the
    stored side-by-side record: the measurement's fields at the top, beside the machine's."""
    return {**{k: v for k, v in recorded.items() if k != "result"}, **recorded["result"]}

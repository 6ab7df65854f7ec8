"""Several paper-preset trainings on one GPU (issue 47): the DAG's share and threads at each preset, the
CUDA MPS detector, the line a run says once, and the side-by-side measurement's record and projection."""

import io
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from egosearch.core import gpu_share
from egosearch.core.gpu_share import (
    MEASURED,
    SIDE_BY_SIDE,
    MpsStatus,
    median_rate,
    mps_control_pids,
    mps_pipe_dir,
    mps_status,
    projected_hours,
    resolve_trainings_per_gpu,
    say_once,
    sharing_line,
    side_by_side_record,
    side_by_side_result,
    train_threads,
    warn_gpu_sharing,
)

REPO = Path(__file__).resolve().parent.parent
SNAKEMAKE = [sys.executable, "-m", "snakemake"]


# ---- the share and the threads at each preset ------------------------------------------------

def test_the_share_is_six_on_one_machine_and_a_whole_gpu_under_a_cluster_unless_the_config_says():
    assert resolve_trainings_per_gpu("auto", local=True) == 6 == gpu_share.DEFAULT_TRAININGS_PER_GPU
    assert resolve_trainings_per_gpu("auto", local=False) == 1
    assert resolve_trainings_per_gpu(None, local=True) == 6
    assert resolve_trainings_per_gpu(3, local=True) == 3
    assert resolve_trainings_per_gpu(1, local=False) == 1
    with pytest.raises(ValueError, match="under a cluster executor each training is a job of its own"):
        resolve_trainings_per_gpu(2, local=False)
    for bad in (0, -1, "two", True, 1.5):
        with pytest.raises(ValueError, match="allowed: auto or an integer >= 1"):
            resolve_trainings_per_gpu(bad, local=True)


def test_a_training_takes_a_fair_share_of_the_cores_at_the_paper_preset_only():
    assert train_threads("paper", 16, 6) == 2  # the measured setting: six trainings, 2 threads each
    assert train_threads("paper", 16, 2) == 8
    assert train_threads("paper", 16, 1) == 16  # one at a time: every core
    assert train_threads("paper", 4, 6) == 1  # never 0
    assert train_threads("paper", None, 6) == 1  # a cluster executor's run names no cores
    for preset in ("cpu", "smoke"):
        assert train_threads(preset, 16, 6) == 1


def test_the_config_key_is_validated_before_any_job():
    from egosearch.workflow.check import ConfigError, check_config

    config = yaml.safe_load((REPO / "egosearch/workflow/config.yaml").read_text())
    assert config["trainings_per_gpu"] == "auto"
    for good in ("auto", 1, 6):
        check_config({**config, "trainings_per_gpu": good})
    for bad in (0, "all", 65):
        with pytest.raises(ConfigError, match="config trainings_per_gpu"):
            check_config({**config, "trainings_per_gpu": bad})


def _dry_run(*args, pipe_dir):
    env = {**os.environ, "CUDA_MPS_PIPE_DIRECTORY": str(pipe_dir)}
    out = subprocess.run(SNAKEMAKE + ["-n", "-p", *args], cwd=REPO, capture_output=True, text=True, timeout=300,
                         env=env)
    assert out.returncode == 0, out.stderr[-3000:]
    return out.stdout + out.stderr


def _train_jobs(text):
    """(output line, threads given to egosearch train, resources line) of each train job of a dry run."""
    jobs, block = [], text.split("rule train:")[1:]
    for part in block:
        output = next(line.strip() for line in part.splitlines() if line.strip().startswith("output:"))
        resources = next(line.strip() for line in part.splitlines() if line.strip().startswith("resources:"))
        threads = int(part.split("--threads ", 1)[1].split()[0])
        jobs.append((output, threads, resources))
    return sorted(jobs)


def test_a_paper_dry_run_with_two_shares_splits_the_cores_and_says_once_that_mps_is_not_running(tmp_path):
    targets = ["results/paper/train/head_on/seed0/actor.pt", "results/paper/train/head_off/seed1/actor.pt"]
    shared = _dry_run(*targets, "--cores", "8", "--config", "preset=paper", "trainings_per_gpu=2",
                      pipe_dir=tmp_path)
    jobs = _train_jobs(shared)
    assert len(jobs) == 2
    for _, threads, resources in jobs:
        assert threads == 4  # 8 cores / 2 shares
        assert "gpu_slots=1" in resources and "gpu=1" not in resources
    lines = [line for line in shared.splitlines() if "paper-preset trainings run side by side on one GPU" in line]
    assert len(lines) == 1, lines  # once, before the DAG's jobs
    assert "Up to 2 " in lines[0] and "without CUDA MPS" in lines[0] and str(tmp_path) in lines[0]
    assert "208 env steps/s in all against 541 under MPS" in lines[0] and "nvidia-cuda-mps-control -d" in lines[0]
    # one at a time: every core, the same jobs and paths, nothing said about sharing
    alone = _dry_run(*targets, "--cores", "8", "--config", "preset=paper", "trainings_per_gpu=1", pipe_dir=tmp_path)
    assert [(o, t) for o, t, _ in _train_jobs(alone)] == [(o, 8) for o, _, _ in jobs]
    assert "side by side on one GPU" not in alone


def test_a_cpu_profile_training_keeps_one_thread_and_asks_for_no_gpu_share(tmp_path):
    target = "results/cpu/train/head_on/seed0/actor.pt"
    text = _dry_run(target, "-f", "--cores", "8", "--config", "trainings_per_gpu=4", pipe_dir=tmp_path)
    [(_, threads, resources)] = _train_jobs(text)
    assert threads == 1 and "gpu_slots" not in resources and "gpu=0" in resources
    assert "side by side on one GPU" not in text


# ---- CUDA MPS ---------------------------------------------------------------------------------------

def _proc(root: Path, processes: dict[int, bytes]) -> Path:
    proc = root / "proc"
    (proc / "self").mkdir(parents=True)
    for pid, cmdline in processes.items():
        (proc / str(pid)).mkdir()
        (proc / str(pid) / "cmdline").write_bytes(cmdline)
    return proc


DAEMON = b"/usr/bin/nvidia-cuda-mps-control\0-d\0"


def test_the_pipe_directory_is_the_environments_or_the_default():
    assert mps_pipe_dir({}) == Path("/tmp/nvidia-mps")
    assert mps_pipe_dir({"CUDA_MPS_PIPE_DIRECTORY": "/x/pipe"}) == Path("/x/pipe")


def test_only_the_control_program_counts_as_a_daemon(tmp_path):
    proc = _proc(tmp_path, {12: DAEMON, 13: b"nvidia-cuda-mps-server\0", 14: b"python\0-c\0nvidia-cuda-mps-control\0"})
    assert mps_control_pids(proc) == [12]
    assert mps_control_pids(tmp_path / "nowhere") == []


def test_the_daemon_runs_when_its_socket_and_its_process_are_both_there(tmp_path):
    pipe = tmp_path / "pipe"
    pipe.mkdir()
    env = {"CUDA_MPS_PIPE_DIRECTORY": str(pipe)}
    # nothing: no daemon
    status = mps_status(env, _proc(tmp_path / "a", {7: b"bash\0"}))
    assert status == MpsStatus(False, str(pipe), f"no nvidia-cuda-mps-control process, no control socket in {pipe}")
    # the socket and the pid file's process
    (pipe / "control").write_text("")
    (pipe / "nvidia-cuda-mps-control.pid").write_text("42\n")
    status = mps_status(env, _proc(tmp_path / "b", {42: DAEMON}))
    assert status.running is True and "pid 42" in status.evidence
    # a stale pid file, but a control process visible
    status = mps_status(env, _proc(tmp_path / "c", {43: DAEMON}))
    assert status.running is True and "pid 43" in status.evidence
    # the socket without a visible daemon (a container whose daemon runs outside): cannot be told
    status = mps_status(env, _proc(tmp_path / "d", {7: b"bash\0"}))
    assert status.running is None and "no nvidia-cuda-mps-control process is visible" in status.evidence
    # a daemon on another pipe directory serves no process started with this environment
    other = {"CUDA_MPS_PIPE_DIRECTORY": str(tmp_path / "elsewhere")}
    status = mps_status(other, _proc(tmp_path / "e", {44: DAEMON}))
    assert status.running is False and "set CUDA_MPS_PIPE_DIRECTORY" in status.evidence


# ---- the line a run says once -------------------------------------------------------------------------

NO_MPS = MpsStatus(False, "/tmp/nvidia-mps", "no nvidia-cuda-mps-control process, no control socket in /tmp/nvidia-mps")


def test_the_line_says_what_sharing_without_mps_costs_and_nothing_for_one_at_a_time():
    assert sharing_line(1, NO_MPS) is None
    line = sharing_line(6, NO_MPS)
    assert line.startswith("Up to 6 paper-preset trainings run side by side on one GPU (trainings_per_gpu) without "
                           "CUDA MPS (no nvidia-cuda-mps-control process")
    assert (f"{MEASURED['trainings']} side by side trained 208 env steps/s in all against 541 under MPS (NVIDIA H200; "
            "issue 47's measurement") in line
    assert "`nvidia-cuda-mps-control -d`" in line and "trainings_per_gpu=1" in line
    under = sharing_line(6, MpsStatus(True, "/tmp/nvidia-mps", "control daemon pid 42, pipe directory /tmp/nvidia-mps"))
    assert under.endswith("under CUDA MPS (control daemon pid 42, pipe directory /tmp/nvidia-mps).")
    unknown = sharing_line(2, MpsStatus(None, "/p", "/p/control exists but no process is visible"))
    assert "cannot be told here: /p/control exists" in unknown and "if no daemon serves /p" in unknown


def test_the_line_takes_the_stored_records_rates_when_it_holds_both():
    both = {"mps": True, "side_by_side": 4, "aggregate_env_steps_per_s": 400.0, "date_utc": "2027-01-02T00:00:00",
            "without_mps": {"aggregate_env_steps_per_s": 150.0}, "machine": {"gpu": "Some GPU"}}
    line = sharing_line(4, NO_MPS, both)
    assert ("4 side by side trained 150 env steps/s in all against 400 under MPS "
            f"(Some GPU; {SIDE_BY_SIDE}, 2027-01-02)") in line
    # a record of one kind of run only: the measured pair, not a mix of two machines
    assert "208 env steps/s in all against 541" in sharing_line(4, NO_MPS, {**both, "without_mps": None})
    assert "208 env steps/s in all against 541" in sharing_line(4, NO_MPS, {**both, "mps": False})


def test_a_run_says_it_once(monkeypatch, tmp_path):
    monkeypatch.setattr(gpu_share, "_SAID", set())
    stream = io.StringIO()
    assert say_once("a line", stream) and not say_once("a line", stream) and not say_once(None, stream)
    assert stream.getvalue() == "a line\n"
    env = {"CUDA_MPS_PIPE_DIRECTORY": str(tmp_path / "pipe")}
    proc = _proc(tmp_path, {})
    out = io.StringIO()
    assert not warn_gpu_sharing("cpu", 6, tmp_path, env, proc, out)  # no GPU sharing at the cpu preset
    assert not warn_gpu_sharing("paper", 1, tmp_path, env, proc, out)  # one at a time
    assert warn_gpu_sharing("paper", 6, tmp_path, env, proc, out)
    assert not warn_gpu_sharing("paper", 6, tmp_path, env, proc, out)
    assert out.getvalue().count("\n") == 1 and "without CUDA MPS" in out.getvalue()


def test_the_cost_line_says_it_once_however_often_it_is_printed(monkeypatch, capsys, tmp_path):
    from egosearch.cost.estimate import print_costs

    monkeypatch.setattr(gpu_share, "_SAID", set())
    monkeypatch.setenv("CUDA_MPS_PIPE_DIRECTORY", str(tmp_path))
    config = yaml.safe_load((REPO / "egosearch/workflow/config.yaml").read_text())
    for _ in range(2):
        print_costs(["table2"], config, "paper", [0], "head_on", None, trainings_per_gpu=3)
    err = capsys.readouterr().err
    assert err.count("Up to 3 paper-preset trainings run side by side") == 1


# ---- the record and its projection -----------------------------------------------------------------

def _train_csv(path: Path, rates: list[float]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    rows = ["env_steps,steps_per_s,updates_per_s"] + [f"{1000 * (i + 1)},{r},{r}" for i, r in enumerate(rates)]
    path.write_text("\n".join(rows) + "\n")


def test_a_trainings_rate_is_the_median_after_its_warm_up_row(tmp_path):
    _train_csv(tmp_path / "train.csv", [900.0, 100.0, 130.0, 110.0])  # the first row: random steps, no update
    assert median_rate(tmp_path / "train.csv") == {"env_steps_per_s_updating": 110.0, "train_rows_used": 3,
                                                   "env_steps": 4000}
    assert median_rate(tmp_path / "missing.csv") == {"env_steps_per_s_updating": None, "train_rows_used": 0,
                                                     "env_steps": None}


def test_the_aggregate_and_the_projection_by_hand():
    # 900,000 env steps at 100 + 150 = 250 env steps/s: 3600 s; one alone at 120: 7500 s
    assert math.isclose(projected_hours(900_000, 250.0), 1.0)
    assert math.isclose(projected_hours(4_500_000, 541.0), 2.3105, rel_tol=1e-4)  # issue 47's MPS figure
    with pytest.raises(ValueError, match="must be > 0"):
        projected_hours(900_000, 0.0)
    alone = {"env_steps_per_s_updating": 120.0, "threads": 8}
    side = [{"env_steps_per_s_updating": 100.0, "threads": 4}, {"env_steps_per_s_updating": 150.0, "threads": 4}]
    without = [{"env_steps_per_s_updating": 40.0}, {"env_steps_per_s_updating": 50.0}]
    r = side_by_side_result(alone, side, all_env_steps=900_000, all_trainings=6, mps=True, mps_note="started",
                            seconds=60.0, variant="head_on", without_mps=without, without_mps_seconds=30.0)
    assert r["aggregate_env_steps_per_s"] == 250.0 and r["per_training_env_steps_per_s"] == [100.0, 150.0]
    assert r["alone_env_steps_per_s"] == 120.0 and r["speedup_vs_alone"] == 2.08  # 250 / 120
    assert r["projected_all_hours"] == 1.0 and r["projected_all_hours_one_at_a_time"] == 2.08  # 7500 s
    assert r["side_by_side"] == 2 and r["threads_alone"] == 8 and r["threads_per_training"] == 4
    assert r["mps"] is True and r["all_trainings"] == 6 and r["all_env_steps"] == 900_000
    # without MPS: 40 + 50 = 90 env steps/s, 10,000 s
    assert r["without_mps"] == {"seconds": 30.0, "per_training_env_steps_per_s": [40.0, 50.0],
                                "aggregate_env_steps_per_s": 90.0, "projected_all_hours": 2.78}
    crashed = [{**side[0]}, {"env_steps_per_s_updating": None, "returncode": 1, "log": "logs/side_by_side_1.log"}]
    with pytest.raises(ValueError, match="training 1 .* exit status 1 .*logs/side_by_side_1.log"):
        side_by_side_result(alone, crashed, all_env_steps=1, all_trainings=1, mps=False, mps_note="", seconds=1.0,
                            variant="head_on")


def test_the_record_puts_the_measurement_beside_the_machine_date_and_commit():
    recorded = {"command": "egosearch bench gpu --side-by-side 2", "date_utc": "2027-01-01T00:00:00+00:00",
                "commit": "abc", "machine": {"cpu": "X", "cores": 16, "gpu": "G"}, "wall_s": 1.0,
                "result": {"aggregate_env_steps_per_s": 250.0, "per_training_env_steps_per_s": [100.0, 150.0],
                           "alone_env_steps_per_s": 120.0, "projected_all_hours": 1.0, "mps": True}}
    record = side_by_side_record(recorded)
    assert "result" not in record
    for key in ("aggregate_env_steps_per_s", "per_training_env_steps_per_s", "alone_env_steps_per_s",
                "projected_all_hours", "mps", "machine", "date_utc", "commit", "command"):
        assert key in record, key
    assert record["machine"]["gpu"] == "G" and record["aggregate_env_steps_per_s"] == 250.0


# ---- the measuring command, with a fake runner and a fake MPS daemon ------------------------------------

class FakeRunner:
    """Writes each training's train.csv as if it had run: side by side 100 + 10 x seed env steps/s."""

    def __init__(self, events):
        self.events, self.batches = events, []

    def __call__(self, trainings, timeout_s):
        self.batches.append(trainings)
        self.events.append(f"run {len(trainings)}")
        for t in trainings:
            rate = 130.0 if len(trainings) == 1 else 100.0 + 10 * t.seed
            _train_csv(Path(t.out_dir) / "train.csv", [900.0, rate, rate])
        return [0] * len(trainings)


def _fake_mps(tmp_path, events, probe_ok=True, installed=True):
    from egosearch.cli.side_by_side import MpsDaemon

    state = {"running": False}

    def status(env):
        return MpsStatus(state["running"], str(tmp_path / "pipe"), "fake")

    def run(argv, **kwargs):
        if argv[-1] == "-d":
            events.append("start")
            state["running"] = True
        elif kwargs.get("input") == "quit\n":
            events.append("stop")
            state["running"] = False
        else:
            events.append("probe")
            return subprocess.CompletedProcess(argv, 0 if probe_ok else 1, "", "" if probe_ok else "error 805")
        return subprocess.CompletedProcess(argv, 0, "", "")

    return MpsDaemon(env={"CUDA_MPS_PIPE_DIRECTORY": str(tmp_path / "pipe"), "CUDA_MPS_LOG_DIRECTORY": str(tmp_path)},
                     which=lambda name: "/usr/bin/nvidia-cuda-mps-control" if installed else None,
                     run=run, status=status, wait_s=0.0)


def test_the_measurement_runs_one_alone_then_n_side_by_side_under_mps(tmp_path):
    from egosearch.cli.side_by_side import run_side_by_side

    events = []
    runner = FakeRunner(events)
    r = run_side_by_side(2, 30.0, tmp_path / "runs", variant="head_on", all_env_steps=4_500_000, all_trainings=6,
                         baseline_seconds=20.0, cores=8, runner=runner, mps=_fake_mps(tmp_path, events),
                         say=lambda line: None)
    # alone, then without MPS (before the daemon starts), then under it; the daemon stopped after
    assert events == ["run 1", "run 2", "start", "probe", "run 2", "stop"]
    alone, without, side = runner.batches
    assert alone[0].threads == 8 and [t.threads for t in side] == [4, 4] and [t.seed for t in side] == [0, 1]
    argv = " ".join(side[1].argv)
    assert "train --variant head_on --preset paper --seed 1 --threads 4" in argv and "--max-wall-s 30" in argv
    assert side[1].out_dir == str(tmp_path / "runs" / "side_by_side" / "1") and side[1].env["OMP_NUM_THREADS"] == "4"
    assert "--max-wall-s 20" in " ".join(without[0].argv)
    assert r["mps"] is True and "started `nvidia-cuda-mps-control -d`" in r["mps_note"]
    assert r["alone_env_steps_per_s"] == 130.0 and r["aggregate_env_steps_per_s"] == 210.0  # 100 + 110
    assert r["projected_all_hours"] == round(4_500_000 / 210 / 3600, 2)
    assert r["without_mps"]["aggregate_env_steps_per_s"] == 210.0


def test_where_mps_cannot_run_the_trainings_run_without_it_and_the_record_says_so(tmp_path):
    from egosearch.cli.side_by_side import run_side_by_side

    events = []
    r = run_side_by_side(3, 10.0, tmp_path / "a", variant="head_on", all_env_steps=900_000, all_trainings=6,
                         cores=6, runner=FakeRunner(events), mps=_fake_mps(tmp_path, events, probe_ok=False),
                         say=lambda line: None)
    assert events == ["run 1", "start", "probe", "stop", "run 3"]  # the daemon stopped before the trainings
    assert r["mps"] is False and "a CUDA process could not run under it (error 805)" in r["mps_note"]
    assert r["aggregate_env_steps_per_s"] == 330.0 and "without_mps" not in r
    events.clear()
    r = run_side_by_side(2, 10.0, tmp_path / "b", variant="head_on", all_env_steps=900_000, all_trainings=6, cores=4,
                         runner=FakeRunner(events), mps=_fake_mps(tmp_path, events, installed=False),
                         say=lambda line: None)
    assert events == ["run 1", "run 2"] and r["mps"] is False
    assert r["mps_note"] == "nvidia-cuda-mps-control is not installed here: the trainings side by side ran without MPS"


def test_the_measurement_refuses_folders_with_an_earlier_run_and_fewer_than_two(tmp_path):
    from egosearch.cli.side_by_side import run_side_by_side

    (tmp_path / "alone").mkdir()
    (tmp_path / "alone" / "ckpt.pt").write_text("x")
    with pytest.raises(ValueError, match="holds an earlier run, which a training would resume"):
        run_side_by_side(2, 1.0, tmp_path, variant="head_on", all_env_steps=1, all_trainings=1,
                         runner=FakeRunner([]), mps=_fake_mps(tmp_path, []))
    with pytest.raises(ValueError, match="--side-by-side=1: the trainings side by side must be >= 2"):
        run_side_by_side(1, 1.0, tmp_path / "new", variant="head_on", all_env_steps=1, all_trainings=1)


def test_the_command_refuses_in_one_line(tmp_path, capsys):
    import torch

    from egosearch.cli import main

    out = ["--out", str(tmp_path / "r.json")]
    cases = [
        (["bench", "gpu", "--side-by-side", "1", "--out-dir", str(tmp_path / "x"), *out],
         "egosearch bench: error: --side-by-side=1: the trainings side by side on one GPU must be >= 2"),
        (["bench", "gpu", "--side-by-side", "2", "--cuda-graph", "--out-dir", str(tmp_path / "x"), *out],
         "egosearch bench: error: --cuda-graph is not read with --side-by-side: its trainings run the paper preset "
         "as the DAG does (cuda_graph on)"),
        (["bench", "learner", "--side-by-side", "2", *out],
         "egosearch bench: error: --side-by-side is read by `bench gpu` only, not by `bench learner`"),
    ]
    if not torch.cuda.is_available():
        cases.append((["bench", "gpu", "--side-by-side", "2", "--seconds", "5", "--out-dir", str(tmp_path / "x"),
                       *out], "egosearch bench: error: bench gpu needs a CUDA GPU"))
    for argv, message in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(message), (argv, err)
    assert not (tmp_path / "r.json").exists()


def test_the_command_writes_the_flat_record_where_the_docs_read_it(tmp_path, monkeypatch, capsys):
    """The CLI's path with the measurement faked: --out defaults to results/paper/gpu_check/side_by_side.json."""
    import torch

    import egosearch.cli.bench as bench_cli
    import egosearch.core.machine as machine
    from egosearch.cli import main

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    monkeypatch.setattr(machine, "gpu_model", lambda: None)
    seen = {}

    def fake(args):
        seen.update(n=args.side_by_side, seconds=args.seconds, out_dir=args.out_dir)
        return {"aggregate_env_steps_per_s": 250.0, "per_training_env_steps_per_s": [100.0, 150.0],
                "alone_env_steps_per_s": 120.0, "projected_all_hours": 1.0, "mps": True, "runs": {"alone": {}}}

    monkeypatch.setattr(bench_cli, "measure_side_by_side", fake)
    assert main(["bench", "gpu", "--side-by-side", "2", "--seconds", "30", "--out-dir", "runs", "--json"]) == 0
    assert seen == {"n": 2, "seconds": 30.0, "out_dir": "runs"}
    record = json.loads((tmp_path / SIDE_BY_SIDE).read_text())
    assert record["command"] == "egosearch bench gpu --side-by-side 2 --seconds 30"
    assert record["aggregate_env_steps_per_s"] == 250.0 and record["mps"] is True and "result" not in record
    assert {"date_utc", "commit", "machine", "runs"} <= set(record) and record["machine"]["cores"]
    printed = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert printed["projected_all_hours"] == 1.0 and "runs" not in printed


def test_all_env_steps_are_the_paper_alls_trainings(monkeypatch):
    """The projection's numerator: every variant of `all` x the paper preset's seeds, 750k env steps each."""
    import argparse

    import egosearch.cli.side_by_side as side_by_side
    from egosearch.cli.bench import measure_side_by_side

    seen = {}

    def fake(n, seconds, out_dir, **kwargs):
        seen.update(kwargs)
        return {}

    monkeypatch.setattr(side_by_side, "run_side_by_side", fake)
    measure_side_by_side(argparse.Namespace(side_by_side=6, seconds=10.0, out_dir="x", baseline_seconds=0.0))
    assert seen["all_trainings"] == 6 and seen["all_env_steps"] == 6 * 750_000 and seen["variant"] == "head_on"


# ---- the README's projection reads the record where it exists ----------------------------------------

def test_the_projection_reads_the_side_by_side_record_where_it_exists(tmp_path):
    from egosearch.report.gpu import GPU_CHECK, _side_by_side_lines, block_gpu_projection, projection

    (tmp_path / GPU_CHECK).mkdir(parents=True)
    run = {"total_env_steps": 1000, "eval_every": 500, "env_steps_per_s_updating": 10.0,
           "curve_evaluation_s_mean": 20.0, "env_steps": 100}
    (tmp_path / GPU_CHECK / "gpu_check.json").write_text(json.dumps(
        {"machine": {"cores": 4, "cpu": "x", "gpu": "G"}, "date_utc": "2026-01-01T00:00:00+00:00",
         "result": {"training": run}}))
    (tmp_path / "results" / "cpu").mkdir(parents=True)
    jobs = [{"rule": "eval", "job": "head_on/seed0/kitchen_living/everywhere/h1.05", "wall_s": 720.0, "cpu_s": 360.0},
            {"rule": "fullbody", "job": "ours-M5/seed0", "wall_s": 80.0}]
    (tmp_path / "results" / "cpu" / "provenance.json").write_text(json.dumps({"jobs": jobs}))
    before = block_gpu_projection(tmp_path, "cpu")
    assert "one at a time" in before and "side by side" not in before and "side_by_side" not in projection(tmp_path)
    assert _side_by_side_lines(tmp_path) == []
    side = {"command": "egosearch bench gpu --side-by-side 2 --seconds 60", "date_utc": "2027-02-03T04:05:06+00:00",
            "commit": "0123456789", "machine": {"cores": 8, "gpu": "H"}, "side_by_side": 2, "mps": True,
            "mps_note": "started", "threads_alone": 8, "threads_per_training": 4, "alone_env_steps_per_s": 120.0,
            "per_training_env_steps_per_s": [100.0, 150.0], "aggregate_env_steps_per_s": 250.0,
            "speedup_vs_alone": 2.08, "all_trainings": 6, "all_env_steps": 900_000, "projected_all_hours": 1.0,
            "projected_all_hours_one_at_a_time": 2.08}
    (tmp_path / SIDE_BY_SIDE).write_text(json.dumps(side))
    q = projection(tmp_path)["side_by_side"]
    # 900,000 / 250 = 3600 s of trainings; the other jobs: 360 + 9 x 80 = 1080 core-seconds over 8 cores = 135 s
    assert math.isclose(q["trainings_h"] * 3600, 3600.0) and math.isclose(q["other_h"] * 3600, 135.0)
    assert math.isclose(q["total_h"] * 3600, 3735.0) and q["n"] == 2 and q["mps"] is True
    text = block_gpu_projection(tmp_path, "cpu")
    assert text.startswith("On one H (8 CPU cores), `snakemake --cores 8 --config preset=paper all` is projected at "
                           "**about 1.0 h**: 6 trainings, 900,000 env steps in all, 2 side by side under CUDA MPS at "
                           "the measured 250 env steps/s in all (1.0 h; one training alone: 120.0 env steps/s, 2.1 h "
                           "one at a time)")
    assert f"`{SIDE_BY_SIDE}`, 2027-02-03" in text
    lines = _side_by_side_lines(tmp_path)
    assert "100.0, 150.0 env steps/s, **250.0 in all** (2.1x the one alone)" in lines[0]
    assert lines[-1].startswith("- the trainings of `all` (6, 900,000 env steps) at 250.0 env steps/s: **1.0 h**")

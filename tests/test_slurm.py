"""The DAG on a real one-node Slurm: munged, slurmctld and slurmd started here, in a folder of their own with
their own ports and slurm.conf (this host the one node), a small target of the smoke DAG run through the
workflow profile profiles/slurm (`--executor slurm`, the squeue status command of a cluster without an
accounting database), its data files compared byte for byte with the local executor's, and every daemon
stopped by its PID. `.ci/run` installs Slurm (apt-get install slurm-wlm munge); where it is not installed or
does not start, the test is skipped with the reason in one line."""

import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
SMOKE = ["--config", "preset=smoke"]
CELL = "kitchen_living/everywhere/h1.65"
SCENARIOS = f"results/smoke/scenarios/{CELL}.csv"
BOUNDS = {bound: f"results/smoke/eval/{bound}/seed0/{CELL}.csv" for bound in ("random", "oracle")}
"""The target: one smoke scenario set and two searchers evaluated on it (three jobs, two of them side by side
on the node's two CPUs), the data files compared with the local run's. Seconds of work each."""
DAEMONS = ("munged", "slurmctld", "slurmd")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _mem_total_mb() -> int:
    for line in Path("/proc/meminfo").read_text().splitlines():
        if line.startswith("MemTotal:"):
            return int(line.split()[1]) // 1024
    return 4000


def _tail(path: Path) -> str:
    try:
        lines = [line for line in path.read_text(errors="replace").splitlines() if line.strip()]
    except OSError:
        return f"{path.name}: no log"
    return lines[-1] if lines else f"{path.name}: empty log"


def _slurm_conf(folder: Path, node: str) -> str:
    # one node, this host; no cgroups (a container has none to give), so memory is enforced by polling the
    # job's processes (jobacct_gather/linux with OverMemoryKill) and time by slurmctld; no accounting database
    return "\n".join([
        "ClusterName=egosearchtest",
        f"SlurmctldHost={node}(127.0.0.1)",
        f"SlurmctldPort={_free_port()}",
        f"SlurmdPort={_free_port()}",
        "SlurmUser=root",
        "SlurmdUser=root",
        "AuthType=auth/munge",
        "CredType=cred/munge",
        f"AuthInfo=socket={folder / 'munge.socket'}",
        f"StateSaveLocation={folder / 'state'}",
        f"SlurmdSpoolDir={folder / 'spool'}",
        f"SlurmctldPidFile={folder / 'slurmctld.pid'}",
        f"SlurmdPidFile={folder / 'slurmd.pid'}",
        f"SlurmctldLogFile={folder / 'slurmctld.log'}",
        f"SlurmdLogFile={folder / 'slurmd.log'}",
        "ProctrackType=proctrack/linuxproc",
        "TaskPlugin=task/none",
        "JobAcctGatherType=jobacct_gather/linux",
        "JobAcctGatherFrequency=task=1",
        "JobAcctGatherParams=OverMemoryKill",
        "AccountingStorageType=accounting_storage/none",
        "SchedulerType=sched/backfill",
        "SelectType=select/cons_tres",
        "SelectTypeParameters=CR_Core_Memory",
        "ReturnToService=2",
        "MpiDefault=none",
        "InactiveLimit=0",
        "KillWait=5",
        "MinJobAge=300",
        f"NodeName={node} NodeAddr=127.0.0.1 CPUs={os.cpu_count()} RealMemory={int(_mem_total_mb() * 0.8)} "
        "State=UNKNOWN",
        f"PartitionName=debug Nodes={node} Default=YES MaxTime=INFINITE State=UP",
        "",
    ])


@pytest.fixture(scope="module")
def slurm():
    """A one-node Slurm of the test's own: the environment its commands need (SLURM_CONF); stopped, daemon by
    daemon, by the PIDs it started."""
    missing = [d for d in (*DAEMONS, "sbatch", "srun", "squeue", "sinfo", "scontrol", "mungekey")
               if shutil.which(d) is None]
    if missing:
        pytest.skip(f"Slurm is not installed here ({', '.join(missing)} missing; .ci/run installs slurm-wlm munge)")
    if os.geteuid() != 0:
        pytest.skip("a one-node Slurm needs root here (slurmd starts each job as its user)")
    # munged wants every folder above its socket open to all (pytest's own temporary folders are not)
    folder = Path(tempfile.mkdtemp(prefix="egosearch-slurm-"))
    folder.chmod(0o755)
    for sub in ("state", "spool"):
        (folder / sub).mkdir()
    node = socket.gethostname().split(".")[0]
    (folder / "slurm.conf").write_text(_slurm_conf(folder, node))
    # Inside each job the slurm-jobstep plugin runs the rule's command with srun, and drops every SLURM_ variable
    # but the job's identity from srun's environment, SLURM_CONF among them: a cluster's slurm.conf sits where
    # srun finds it without one (/etc/slurm), this one does not, so the jobs' srun is a wrapper that names it.
    wrappers = folder / "bin"
    wrappers.mkdir()
    srun = f"SLURM_CONF={folder / 'slurm.conf'} exec {shutil.which('srun')} \"$@\""
    (wrappers / "srun").write_text(f"#!/bin/sh\n{srun}\n")
    (wrappers / "srun").chmod(0o755)
    env = {**os.environ, "SLURM_CONF": str(folder / "slurm.conf"), "PATH": f"{wrappers}:{os.environ['PATH']}"}
    started: list[subprocess.Popen] = []
    try:
        subprocess.run(["mungekey", "--create", "--keyfile", str(folder / "munge.key")], check=True,
                       capture_output=True)
        (folder / "munge.key").chmod(0o600)
        commands = [
            ["munged", "--foreground", f"--key-file={folder / 'munge.key'}", f"--socket={folder / 'munge.socket'}",
             f"--pid-file={folder / 'munged.pid'}", f"--log-file={folder / 'munged.log'}",
             f"--seed-file={folder / 'munged.seed'}"],
            ["slurmctld", "-D", "-c", "-f", str(folder / "slurm.conf")],
            ["slurmd", "-D", "-N", node, "-f", str(folder / "slurm.conf")],
        ]
        logs = [folder / "munged.log", folder / "slurmctld.log", folder / "slurmd.log"]
        for command, log in zip(commands, logs):
            started.append(subprocess.Popen(command, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
            deadline = time.monotonic() + 30
            while command[0] == "munged" and not (folder / "munge.socket").exists():
                if started[-1].poll() is not None or time.monotonic() > deadline:
                    pytest.skip(f"munged did not start: {_tail(log)}")
                time.sleep(0.2)
        deadline = time.monotonic() + 90
        state = ""
        while state not in ("idle", "mixed", "allocated"):
            for proc, log in zip(started, logs):
                if proc.poll() is not None:
                    pytest.skip(f"{proc.args[0]} did not start: {_tail(log)}")
            if time.monotonic() > deadline:
                pytest.skip(f"the Slurm node did not come up (sinfo: {state or 'no answer'}): {_tail(logs[2])}")
            time.sleep(1)
            out = subprocess.run(["sinfo", "--noheader", "--format=%T"], env=env, capture_output=True, text=True)
            state = out.stdout.strip().rstrip("*~#")
        yield env
    finally:
        # no job of ours outlives the test, then each daemon we started, by its PID, the last one first
        subprocess.run(["scancel", "--full", "--user", "root"], env=env, capture_output=True)
        for proc in reversed(started):
            if proc.poll() is None:
                proc.terminate()
                try:
                    proc.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait()
        shutil.rmtree(folder, ignore_errors=True)


def _copy_of_the_suite(dest: Path) -> Path:
    files = subprocess.run(["git", "ls-files"], cwd=REPO, capture_output=True, text=True).stdout.split()
    for name in files:
        if not name.startswith(("results/", "paper_figs/")) and (REPO / name).is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(REPO / name, dest / name)
    return dest


def _on_slurm(cwd: Path, env: dict, *extra: str) -> subprocess.CompletedProcess:
    # the workflow profile as a user runs it; status checks from the first second (40 s by default: a cluster's
    # jobs are minutes long), which keeps squeue (MinJobAge 300 s is far above 3 x 1 s)
    cmd = [sys.executable, "-m", "snakemake", *BOUNDS.values(), "--workflow-profile", "profiles/slurm",
           "--slurm-init-seconds-before-status-checks", "1", "--latency-wait", "5", *SMOKE, *extra]
    return subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=600)


def _scontrol(job: str, env: dict) -> dict[str, str]:
    out = subprocess.run(["scontrol", "--oneliner", "show", "job", job], env=env, capture_output=True, text=True)
    return dict(field.split("=", 1) for field in out.stdout.split() if "=" in field)


@pytest.mark.slow
def test_a_smoke_target_on_slurm_equals_the_local_run_and_a_killed_job_is_one_line(slurm, tmp_path):
    suite, twin = _copy_of_the_suite(tmp_path / "suite"), _copy_of_the_suite(tmp_path / "twin")
    local_log = (tmp_path / "local.log").open("w")
    local = subprocess.Popen([sys.executable, "-m", "snakemake", "--cores", "1", *BOUNDS.values(), *SMOKE],
                             cwd=twin, stdout=local_log, stderr=subprocess.STDOUT)
    try:
        # Killed by Slurm: each evaluation asks for 50 MB, less than the job's own snakemake takes.
        killed = _on_slurm(suite, slurm, "--set-resources", "bound:mem_mb=50")
        text = killed.stdout + killed.stderr
        assert killed.returncode != 0, text[-3000:]
        lines = sorted(line for line in text.splitlines() if line.startswith("egosearch: bound ("))
        assert len(lines) == 2, text[-5000:]
        for line, path in zip(lines, sorted(BOUNDS.values(), key=lambda p: f"egosearch: bound ({p}")):
            assert re.fullmatch(
                rf"egosearch: bound \({re.escape(path)}; Slurm job \d+\) was killed by Slurm for using more memory "
                r"than it asked for \(mem_mb=50\); none of its outputs is kept; run it again with more memory "
                r"\(--set-resources bound:mem_mb=100\): it starts over", line), line
            assert not (suite / path).exists()                    # nothing of it is taken for an output
        assert (suite / SCENARIOS).is_file()                      # the job that asked enough ran

        # The same command with what the rules ask for: the rest runs, as Slurm jobs.
        done = _on_slurm(suite, slurm)
        text = done.stdout + done.stderr
        assert done.returncode == 0, text[-5000:]
        submitted = re.findall(r"has been submitted with SLURM jobid (\d+)", text)
        assert len(submitted) == 2, text[-3000:]
        assert local.wait(timeout=600) == 0, (tmp_path / "local.log").read_text()[-3000:]
    finally:
        if local.poll() is None:
            local.kill()
        local_log.close()
    for path in (SCENARIOS, *BOUNDS.values()):
        assert (suite / path).read_bytes() == (twin / path).read_bytes(), path
    # What Slurm was asked for is what the rule declares (rules/evaluate.smk: bound): 30 min, 1500 MB, 1 CPU.
    for job in submitted:
        fields = _scontrol(job, slurm)
        assert fields.get("JobState") == "COMPLETED", fields
        assert (fields["TimeLimit"], fields["MinMemoryNode"], fields["NumCPUs"]) == ("00:30:00", "1500M", "1"), fields

"""The DAG under a cluster executor (egosearch.workflow.cluster, profiles/slurm): the executor read from
snakemake's command line, what each rule asks sbatch for (a dry run prints it; checked here against the
resources Snakemake gives each job, and against what the stored run's jobs used), the checks a Slurm run
makes before its first job, and the line for a job Slurm killed. tests/test_slurm.py runs the DAG on a real
one-node Slurm."""

import json
import re
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import pytest
import yaml

from egosearch.workflow.cluster import (
    SLURM_COMMANDS,
    cluster_partitions,
    is_cluster,
    killed_job_lines,
    missing_slurm_command,
    partition_problem,
    partitions_asked,
    slurm_run_problem,
    snakemake_executor,
)

REPO = Path(__file__).resolve().parent.parent
SNAKEMAKE = [sys.executable, "-m", "snakemake"]
RUNNING_MD = REPO / "docs" / "running.md"
PLAN_HEAD = "What each job asks sbatch for (the slurm plugin adds its job name, log and account):"


def _running_md() -> str:
    """docs/running.md as one line of words (its "On a cluster" section names the options)."""
    return " ".join(RUNNING_MD.read_text(encoding="utf-8").split())


def _dry_run(*args) -> str:
    out = subprocess.run([*SNAKEMAKE, "-n", *args], cwd=REPO, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, (out.stdout + out.stderr)[-4000:]
    return out.stdout + out.stderr


def _job_blocks(text: str) -> list[dict]:
    """Each job a dry run lists: its rule, its fields (``resources``, ``benchmark``, ``threads``...)."""
    jobs, current = [], None
    for line in text.splitlines():
        head = re.fullmatch(r"(?:local)?rule (\w+):", line)
        if head:
            current = {"rule": head.group(1)}
            jobs.append(current)
        elif current is not None and line.startswith("    ") and ": " in line:
            key, value = line.strip().split(": ", 1)
            current.setdefault(key, value)
        elif not line.startswith(" "):
            current = None
    return jobs


def _resources(job: dict) -> dict[str, str]:
    return dict(item.split("=", 1) for item in job.get("resources", "").split(", ") if "=" in item)


def _plan(text: str) -> dict[str, tuple[int, str]]:
    """The dry run's closing plan: rule -> (its jobs, the sbatch options they ask for)."""
    lines = text.split(PLAN_HEAD + "\n", 1)[1].splitlines()
    plan = {}
    for line in lines:
        match = re.fullmatch(r"  (\w+) \((\d+) jobs?\): sbatch (.*)", line)
        if not match:
            break
        assert match.group(1) not in plan, f"{match.group(1)}'s jobs ask for different things: {line}"
        plan[match.group(1)] = (int(match.group(2)), match.group(3))
    return plan


def _options_of(resources: dict[str, str], threads: int) -> str:
    """The sbatch options for a job's resources, as the slurm plugin documents them: runtime (minutes) -t,
    mem_mb --mem, one task unless the job asks for GPUs, its threads as CPUs per task, gpu --gpus."""
    gpu = int(resources.get("gpu", 0) or 0)
    options = [f"-t {resources['runtime']}" if "runtime" in resources else "",
               f"--mem {resources['mem_mb']}" if "mem_mb" in resources else "",
               "" if gpu else "--ntasks=1", f"--cpus-per-task={threads}", f"--gpus={gpu}" if gpu else ""]
    return " ".join(option for option in options if option)


def _check_plan_against_the_jobs(text: str) -> dict[str, list[dict]]:
    jobs_by_rule = defaultdict(list)
    for job in _job_blocks(text):
        if job["rule"] != "all" and "resources" in job:
            jobs_by_rule[job["rule"]].append(job)
    plan = _plan(text)
    ran = {rule for rule, jobs in jobs_by_rule.items() if "<TBD>" not in _resources(jobs[0]).get("mem_mb", "")}
    assert set(plan) == ran, (set(plan) ^ ran)
    for rule, (count, options) in plan.items():
        assert count == len(jobs_by_rule[rule]), rule
        for job in jobs_by_rule[rule]:
            assert options == _options_of(_resources(job), int(job.get("threads", 1))), (rule, job)
    return jobs_by_rule


def test_a_paper_training_under_slurm_asks_for_one_gpu_and_the_dry_run_says_so():
    """`--executor slurm` on the command line: Snakemake parses the Snakefile before it hands the run its
    executor (workflow.local_exec read True there), so each paper-preset training asked for a share of this
    machine's GPU (gpu_slots=1), not a GPU of its own; now it asks sbatch for --gpus=1."""
    text = _dry_run("-p", "-F", "results/paper/train/head_on/seed0/actor.pt",
                    "results/paper/scenarios/kitchen_living/everywhere/h1.05.csv",
                    "--executor", "slurm", "--jobs", "6", "--config", "preset=paper")
    [train] = [job for job in _job_blocks(text) if job["rule"] == "train"]
    assert "gpu=1" in train["resources"].split(", ") and "gpu_slots" not in train["resources"]
    # one thread, as its job asks for (--set-threads train=N gives more)
    assert "egosearch train --force --variant head_on --preset paper --seed 0 --threads 1 " in text
    plan = _plan(text)
    assert plan["train"] == (1, "-t 720 --mem 8000 --cpus-per-task=1 --gpus=1")
    assert f"A paper-preset training asks for `{plan['train'][1]}`" in _running_md()
    assert plan["scenarios"] == (1, "-t 10 --mem 1000 --ntasks=1 --cpus-per-task=1")
    _check_plan_against_the_jobs(text)
    # on this machine the same training asks for one of the run's GPU shares, and no plan is printed
    local = _dry_run("-F", "results/paper/train/head_on/seed0/actor.pt", "--cores", "6", "--config", "preset=paper")
    [train] = [job for job in _job_blocks(local) if job["rule"] == "train"]
    assert "gpu_slots=1" in train["resources"].split(", ") and PLAN_HEAD not in local


RECORD = REPO / "results" / "cpu" / "provenance.json"
JOB_SNAKEMAKE_MB = 300
"""What a cluster job holds besides its command: the snakemake that runs it there, which parses the workflow
(250 MB measured, as `snakemake -n` does here), in the same allocation."""


def _record_key(benchmark: str) -> str:
    """A benchmark path as the provenance keys its job's folder: ``eval``, ``report/table1``, ``fresh/eval``."""
    parts = Path(benchmark).relative_to("results/cpu/benchmarks").with_suffix("").parts
    return "/".join(parts[:2]) if parts[0] in ("report", "fresh") else parts[0]


@pytest.mark.skipif(not RECORD.is_file(), reason="needs the stored cpu run's provenance")
def test_the_slurm_profile_asks_sbatch_for_what_each_job_uses():
    """profiles/slurm's dry run of everything the cpu preset stores: each rule's sbatch options follow its jobs'
    resources (the profile's default-resources where a rule declares none), and they cover what the stored run's
    jobs used: their time 1.5 times over (hosts differ), their memory and the job's own snakemake."""
    text = _dry_run("-F", "all", "fresh", "behaviour", "generalise", "budget", "--workflow-profile", "profiles/slurm")
    jobs_by_rule = _check_plan_against_the_jobs(text)
    profile = yaml.safe_load((REPO / "profiles/slurm/config.yaml").read_text())
    assert profile["executor"] == "slurm" and profile["slurm-status-command"] == "squeue"
    assert _plan(text)["table1"][1] == (f"-t {profile['default-resources']['runtime']} "
                                        f"--mem {profile['default-resources']['mem_mb']} --ntasks=1 --cpus-per-task=1")
    assert f"a cpu-preset one for `{_plan(text)['train'][1]}`" in _running_md()  # the page says what is asked
    asked = {}
    for rule, jobs in jobs_by_rule.items():
        for job in jobs:
            if "benchmark" in job:
                resources = _resources(job)
                asked.setdefault(_record_key(job["benchmark"]), []).append(
                    (rule, int(resources["runtime"]), int(resources["mem_mb"])))
    used = defaultdict(lambda: [0.0, 0.0])
    for job in json.loads(RECORD.read_text())["jobs"]:
        key = f"{job['rule']}/{job['job'].split('/')[0]}" if job["rule"] in ("report", "fresh") else job["rule"]
        used[key][0] = max(used[key][0], float(job.get("run_wall_s", job["wall_s"])))
        used[key][1] = max(used[key][1], float(job.get("max_rss_mb") or 0))
    assert {"train", "eval", "bound", "traces", "fullbody", "report/video"} <= set(used) & set(asked)
    for key in sorted(set(used) & set(asked)):
        wall_s, rss_mb = used[key]
        for rule, runtime, mem_mb in set(asked[key]):
            assert runtime * 60 >= 1.5 * wall_s, (rule, runtime, wall_s / 60)
            assert mem_mb >= rss_mb + JOB_SNAKEMAKE_MB, (rule, mem_mb, rss_mb)


# ---- which executor --------------------------------------------------------------------------------------

def test_outside_snakemakes_command_line_the_run_is_on_this_machine():
    """Snakemake's API (egosearch.workflow.dag builds the DAG through it) has no command line to read."""
    assert snakemake_executor() is None and not is_cluster(None)
    assert [is_cluster(e) for e in ("local", "dryrun", "touch", "slurm", "slurm-jobstep", "cluster-generic")] == \
        [False, False, False, True, True, True]


# ---- before the first job ----------------------------------------------------------------------------------

def test_a_slurm_run_needs_slurms_commands_here():
    present = {"sbatch": "/usr/bin/sbatch", "squeue": "/usr/bin/squeue", "sinfo": "/usr/bin/sinfo"}
    assert SLURM_COMMANDS == tuple(present)
    assert missing_slurm_command(present.get) is None
    line = missing_slurm_command({**present, "squeue": None}.get)
    assert line.startswith("--executor slurm: squeue is not on PATH here, so no job could be submitted or followed")


def _sinfo(stdout="debug*\ngpu\n", returncode=0, stderr=""):
    def run(cmd, **kwargs):
        assert cmd[0] == "sinfo"
        return subprocess.CompletedProcess(cmd, returncode, stdout, stderr)
    return run


def test_each_partition_the_run_names_must_exist():
    assert cluster_partitions(_sinfo()) == (["debug", "gpu"], "debug")
    with pytest.raises(RuntimeError, match="sinfo failed: sinfo: error: Unable to contact slurm controller"):
        cluster_partitions(_sinfo("", 1, "sinfo: error: Unable to contact slurm controller (connect failure)\n"))
    asked = partitions_asked(["tmpdir=system_tmpdir", "slurm_partition='gpu'"], {"train": {"slurm_partition": "gpux"}})
    assert asked == [("--default-resources slurm_partition", "gpu"), ("--set-resources train:slurm_partition", "gpux")]
    assert partition_problem(asked[:1], ["debug", "gpu"], "debug") is None
    assert partition_problem(asked, ["debug", "gpu"], "debug") == (
        "--set-resources train:slurm_partition=gpux: no such partition on this cluster (sinfo lists: debug, gpu); "
        "name one of them, or leave slurm_partition out (each job then goes to the cluster's default partition, "
        "debug)")
    everything = {"sbatch": "x", "squeue": "x", "sinfo": "x"}.get
    assert slurm_run_problem(False, asked, everything, _sinfo()).startswith("--set-resources train:slurm_partition")
    # a dry run plans anywhere: no Slurm here, or a controller that does not answer, is no error there
    assert slurm_run_problem(True, asked, {}.get, _sinfo()) is None
    assert slurm_run_problem(True, asked, everything, _sinfo("", 1, "sinfo: error: no controller")) is None
    assert slurm_run_problem(False, asked, everything, _sinfo("", 1, "sinfo: error: no controller")) == (
        "--executor slurm: sinfo failed: sinfo: error: no controller; run snakemake where Slurm's controller answers "
        "(a login node; SLURM_CONF names the cluster's slurm.conf)")


# ---- a job Slurm killed ------------------------------------------------------------------------------------

TRAIN = "results/smoke/train/head_on/seed0"
WHY = ("Detailed failure reason unavailable (status command is not 'sacct').For further error details see the "
       "cluster/cloud log and the log files of the involved rule(s).")
CHECK = "(check log file(s) for error details)"
SLURM_LOG = "/w/.snakemake/slurm_logs/rule_{}/{}.log"
LOG = f"""[Sat Nov 28 09:47:43 2026]
rule train:
    output: {TRAIN}/actor.pt (update), {TRAIN}/curve.csv (update)
    log: results/smoke/logs/train/head_on/seed0.log
    jobid: 3
    reason: Missing output files: {TRAIN}/actor.pt
    resources: tmpdir=<TBD>, mem_mb=1500, mem=1.5 GB, mem_mib=1431, runtime=10, gpu=0
[Sat Nov 28 09:47:43 2026]
rule bound:
    output: results/smoke/eval/random/seed0/kitchen_living/everywhere/h1.65.csv (update)
    jobid: 2
    resources: tmpdir=<TBD>, mem_mb=50, mem=50 MB, mem_mib=48, runtime=30
Job 3 has been submitted with SLURM jobid 5 (log: /w/.snakemake/slurm_logs/rule_train/smoke_head_on_0/5.log).
Job 2 has been submitted with SLURM jobid 6 (log: /w/.snakemake/slurm_logs/rule_bound/x/6.log).
[Sat Nov 28 09:58:58 2026]
Error in rule train:
    message: SLURM-job '5' failed, SLURM status is: 'TIMEOUT'. {WHY}
    jobid: 3
    output: {TRAIN}/actor.pt (update), {TRAIN}/curve.csv (update)
    log: results/smoke/logs/train/head_on/seed0.log, {SLURM_LOG.format("train/smoke_head_on_0", 5)} {CHECK}
    external_jobid: 5
[Sat Nov 28 09:47:58 2026]
Error in rule bound:
    message: SLURM-job '6' failed, SLURM status is: 'FAILED'. {WHY}
    jobid: 2
    output: results/smoke/eval/random/seed0/kitchen_living/everywhere/h1.65.csv (update)
    log: results/smoke/logs/bound/random.log, {SLURM_LOG.format("bound/x", 6)} {CHECK}
    external_jobid: 6
"""
SLURM_LOGS = {
    "run.log": LOG,
    SLURM_LOG.format("train/smoke_head_on_0", 5):
        "slurmstepd-vm: error: *** JOB 5 ON vm CANCELLED AT 2026-11-28T09:58:58 DUE TO TIME LIMIT ***\n",
    SLURM_LOG.format("bound/x", 6):
        "slurmstepd-vm: error: StepId=6.batch exceeded memory limit (126570496 > 52428800), being killed\n",
}
"""A run's Snakemake log as the slurm plugin writes it with the squeue status command (from a run on the
one-node Slurm of tests/test_slurm.py) and the Slurm logs it names: a training stopped at its time limit
(TIMEOUT), an evaluation killed for its memory (FAILED, the Slurm log saying why)."""


def _read(path):
    if str(path) not in SLURM_LOGS:
        raise OSError(path)
    return SLURM_LOGS[str(path)]


def test_a_job_slurm_killed_is_one_line_saying_what_running_it_again_does(tmp_path):
    checkpoint = tmp_path / "partial" / "ckpt" / "train_state.ckpt"
    checkpoint_of = lambda rule, outputs: checkpoint if rule == "train" else None  # noqa: E731
    before = killed_job_lines(["run.log"], checkpoint_of, _read)
    assert before == [
        f"egosearch: train ({TRAIN}/actor.pt; Slurm job 5) was stopped by Slurm at its time limit (runtime=10 min); "
        "none of its outputs is kept; run it again with more time if it needs it (--set-resources train:runtime=20): "
        "it starts over (it had written no checkpoint yet)",
        "egosearch: bound (results/smoke/eval/random/seed0/kitchen_living/everywhere/h1.65.csv; Slurm job 6) was "
        "killed by Slurm for using more memory than it asked for (mem_mb=50); none of its outputs is kept; run it "
        "again with more memory (--set-resources bound:mem_mb=100): it starts over"]
    checkpoint.parent.mkdir(parents=True)
    checkpoint.write_bytes(b"state")
    after = killed_job_lines("run.log", checkpoint_of, _read)
    assert after[0].endswith(f"(--set-resources train:runtime=20): it resumes from its checkpoint ({checkpoint})")
    assert after[1] == before[1]


def test_a_job_that_failed_on_its_own_gets_no_line():
    """A FAILED job whose Slurm log names no limit failed in its command: Snakemake's error and the rule's log
    say why, and nothing is added."""
    logs = {**SLURM_LOGS, SLURM_LOG.format("bound/x", 6): "Traceback (most recent call last):\n"}
    text = killed_job_lines("run.log", read=lambda path: logs[str(path)])
    assert len(text) == 1 and text[0].startswith("egosearch: train (")
    assert killed_job_lines("no-such.log", read=_read) == []

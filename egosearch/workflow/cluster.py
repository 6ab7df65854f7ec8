"""The DAG under a cluster executor (Slurm): which executor the run uses, the checks a Slurm run makes
before any job (Slurm's commands on PATH, the partitions it names), what each job asks ``sbatch`` for
(printed after a dry run), and one line per job that Slurm killed at its time or memory limit (printed
when the run stops, by the Snakefile's ``onerror``).

Which executor: Snakemake parses the Snakefile before it hands the run its executor
(``workflow.local_exec`` reads True there under ``--executor slurm`` too), so :func:`snakemake_executor`
reads the executor the ``snakemake`` command line resolved (``--executor``, or a profile's
``executor:``) from the command line's own parsed arguments.

Standard library only at import: the Snakefile reads this module before every run. The sbatch options are
rendered by the slurm executor plugin's own functions, imported where :func:`sbatch_options` runs.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path

LOCAL_EXECUTORS = frozenset({"local", "dryrun", "touch"})
"""Executors that run every job on the machine snakemake runs on; every other one (slurm, cluster-generic,
and slurm-jobstep, which runs one job inside its Slurm allocation) is a cluster executor."""

SLURM_COMMANDS = ("sbatch", "squeue", "sinfo")
"""What the slurm executor runs on the machine snakemake runs on: ``sbatch`` submits each job, ``squeue``
tells its state (``--slurm-status-command squeue``; ``sacct`` needs an accounting database), ``sinfo`` names
the partitions."""


def snakemake_executor() -> str | None:
    """The executor of the ``snakemake`` command line that is reading the Snakefile: ``--executor``, or the
    ``executor:`` of a profile (``--workflow-profile profiles/slurm``), ``local`` when none names one. None
    where the workflow is not run from the command line (Snakemake's API, as egosearch.workflow.dag runs it):
    a run on this machine there.

    Read from the arguments Snakemake's CLI parsed (``snakemake.cli.args_to_api``, which builds the run and,
    through it, parses the Snakefile), so profiles count exactly as Snakemake counts them."""
    args = snakemake_args()
    return None if args is None else getattr(args, "executor", None) or "local"


def snakemake_args():
    """The arguments the ``snakemake`` command line reading the Snakefile parsed (its profiles' included), None
    where the workflow is not run from the command line."""
    frame = sys._getframe(1)
    while frame is not None:
        if frame.f_code.co_name == "args_to_api" and frame.f_globals.get("__name__") == "snakemake.cli":
            return frame.f_locals.get("args")
        frame = frame.f_back
    return None


DEFAULT_WORKFLOW_PROFILE = Path("profiles/default")
"""The workflow profile Snakemake reads whenever no ``--workflow-profile`` is given: on top of a ``--profile``."""


def profile_mix_problem(profiles: Iterable[str] | None, workflow_profile: str | None,
                        default: Path = DEFAULT_WORKFLOW_PROFILE) -> str | None:
    """The line for a ``--profile`` one of whose settings :data:`DEFAULT_WORKFLOW_PROFILE` overrides without a
    word (Snakemake reads the workflow profile after it: ``--profile profiles/slurm`` ran 2 jobs at a time, not
    its 100); None where no ``--profile`` is given, a ``--workflow-profile`` is, or nothing clashes."""
    import yaml  # local: only a run with --profile reads them

    if not profiles or workflow_profile is not None or not (default / "config.yaml").is_file():
        return None
    defaults = yaml.safe_load((default / "config.yaml").read_text()) or {}
    for profile in profiles:
        path = Path(profile) / "config.yaml"
        if not path.is_file():
            continue  # a profile by name, in Snakemake's own folders: not this workflow's
        given = yaml.safe_load(path.read_text()) or {}
        clash = next((key for key in defaults if key in given and given[key] != defaults[key]), None)
        if clash:
            return (f"--profile {profile}: Snakemake reads the workflow profile {default} on top of it, and its "
                    f"{clash}: {defaults[clash]} overrides the {clash}: {given[clash]} of {profile}; use "
                    f"--workflow-profile {profile} instead (it replaces {default}; docs/running.md)")
    return None


def is_cluster(executor: str | None) -> bool:
    """Whether jobs run elsewhere than on this machine under ``executor`` (None: on this machine)."""
    return executor is not None and executor not in LOCAL_EXECUTORS


# ---- before any job -------------------------------------------------------------------------------------

def missing_slurm_command(which: Callable[[str], str | None] = shutil.which) -> str | None:
    """The line for a Slurm run where a command of :data:`SLURM_COMMANDS` is not on PATH; None when all are."""
    for command in SLURM_COMMANDS:
        if which(command) is None:
            return (f"--executor slurm: {command} is not on PATH here, so no job could be submitted or followed; run "
                    f"snakemake on a machine that submits to Slurm (a login node, where {', '.join(SLURM_COMMANDS)} "
                    "are), or leave --executor slurm (and --workflow-profile profiles/slurm) out to run on this "
                    "machine")
    return None


def _plain(value) -> str | None:
    """A resource's value as given (``gpuz``, ``'gpuz'``): its text without quotes; None for a function."""
    value = getattr(value, "raw", value)
    if value is None or callable(value):
        return None
    return str(value).strip().strip("'\"")


def partitions_asked(default_args: Iterable[str], overrides: Mapping[str, Mapping[str, object]],
                     declared: Mapping[str, Mapping[str, object]] = {}) -> list[tuple[str, str]]:
    """(where, partition) for every ``slurm_partition`` the run names: ``--default-resources`` (its
    ``key=value`` arguments, a profile's ``default-resources:`` among them), ``--set-resources RULE:...`` and a
    rule's own ``resources:``."""
    asked = []
    for arg in default_args or ():
        key, _, value = str(arg).partition("=")
        if key.strip() == "slurm_partition" and _plain(value):
            asked.append(("--default-resources slurm_partition", _plain(value)))
    for rule, resources in sorted((overrides or {}).items()):
        if _plain(resources.get("slurm_partition")):
            asked.append((f"--set-resources {rule}:slurm_partition", _plain(resources["slurm_partition"])))
    for rule, resources in sorted(declared.items()):
        if _plain(resources.get("slurm_partition")):
            asked.append((f"rule {rule}'s slurm_partition", _plain(resources["slurm_partition"])))
    return asked


SIZED_RESOURCES = {"mem_mb": "megabytes", "mem_mib": "mebibytes", "disk_mb": "megabytes", "disk_mib": "mebibytes",
                   "runtime": "minutes"}
"""The resources every job's sbatch call is sized by, as numbers: a word there failed only at exit, in the slurm
plan's atexit hook (a ResourceConversionError, the run's status 0), and runtime 0 submitted with no -t."""


def resource_problem(default_args: Iterable[str], overrides: Mapping[str, Mapping[str, object]]) -> str | None:
    """The line for the first of :data:`SIZED_RESOURCES` that the run's ``--default-resources`` (a profile's
    ``default-resources:`` among them) or ``--set-resources`` give as a word, or as a number <= 0; None when
    none does. An expression (``2 * attempt * 1000``) is Snakemake's to evaluate and passes."""
    given = [("--default-resources", *str(arg).partition("=")[::2]) for arg in default_args or ()]
    given += [(f"--set-resources {rule}:", key, value) for rule, resources in sorted((overrides or {}).items())
              for key, value in resources.items()]
    for where, key, value in given:
        key, text = key.strip(), _plain(value)
        if key not in SIZED_RESOURCES or text is None:
            continue
        where = f"{where}{key}" if where.endswith(":") else f"{where} {key}"
        unit = SIZED_RESOURCES[key]
        try:
            number = float(text)
        except ValueError:
            if re.fullmatch(r"[A-Za-z_]+", text):
                return (f"{where}={text}: not a number; allowed: a number of {unit} > 0 (e.g. {key}="
                        f"{1000 if unit != 'minutes' else 30})")
            continue
        if not number > 0:
            cut = "no time limit (sbatch without -t)" if key == "runtime" else "no memory (or disk) at all"
            return f"{where}={text}: a job would ask for {cut}; allowed: a number of {unit} > 0"
    return None


def cluster_partitions(run=subprocess.run) -> tuple[list[str], str | None]:
    """The partitions ``sinfo`` lists and the default one (``sinfo`` marks it ``*``). Raises RuntimeError with
    sinfo's first line when it cannot answer (no controller reachable)."""
    try:
        out = run(["sinfo", "--noheader", "--format=%P"], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired) as err:
        raise RuntimeError(f"sinfo did not answer ({err})") from None
    if out.returncode != 0:
        first = next((line for line in (out.stderr or out.stdout).splitlines() if line.strip()), "no output")
        raise RuntimeError(f"sinfo failed: {first.strip()}")
    names, default = [], None
    for line in out.stdout.split():
        name = line.strip().rstrip("*")
        if name and name not in names:
            names.append(name)
        if line.strip().endswith("*"):
            default = name
    return names, default


def partition_problem(asked: list[tuple[str, str]], partitions: list[str], default: str | None) -> str | None:
    """The line for the first partition the run names that the cluster does not have; None when all exist."""
    for where, name in asked:
        if name not in partitions:
            fallback = "the cluster's default partition" + (f", {default}" if default else "")
            listed = ", ".join(partitions) or "none"
            return (f"{where}={name}: no such partition on this cluster (sinfo lists: {listed}); name one of them, "
                    f"or leave slurm_partition out (each job then goes to {fallback})")
    return None


def slurm_run_problem(dryrun: bool, asked: list[tuple[str, str]], which=shutil.which, run=subprocess.run) -> str | None:
    """What stops a run under ``--executor slurm`` before its first job, in one line; None when nothing does.
    A real run needs Slurm's commands and a controller that answers; a dry run (a plan, on any machine) is
    checked where sinfo answers. Either way each partition the run names must exist."""
    if not dryrun:
        missing = missing_slurm_command(which)
        if missing:
            return missing
    elif which("sinfo") is None:
        return None
    try:
        partitions, default = cluster_partitions(run)
    except RuntimeError as err:
        if dryrun:
            return None
        return (f"--executor slurm: {err}; run snakemake where Slurm's controller answers (a login node; SLURM_CONF "
                "names the cluster's slurm.conf)")
    return partition_problem(asked, partitions, default)


# ---- what each job asks sbatch for --------------------------------------------------------------------

_BOILERPLATE = ("sbatch --parsable --job-name RUN --output LOG --export=ALL --comment COMMENT")


class _JobView:
    """A job as the plugin's sbatch functions read it (``resources``, ``threads``), with its threads as the
    cluster run gives them: a dry run caps a rule's threads at its one core, a cluster run does not."""

    def __init__(self, job, threads: int):
        self.resources, self.threads = job.resources, threads
        self.name, self.rule = job.rule.name, job.rule

    def is_group(self) -> bool:
        return False


def sbatch_options(job, threads: int) -> str:
    """The options the slurm executor plugin puts on ``sbatch`` for ``job`` (its time, memory, CPUs, GPUs,
    partition, ``slurm_extra``), rendered by the plugin's own functions; without the options every job gets
    (job name, log, ``--export``, comment, working folder) and the account it guesses."""
    from snakemake_executor_plugin_slurm.submit_string import get_submit_command
    from snakemake_executor_plugin_slurm.utils import set_gres_string

    partition = _plain(job.resources.get("slurm_partition"))
    params = {"run_uuid": "RUN", "slurm_logfile": "LOG", "comment_str": "COMMENT", "account": "",
              "partition": f"-p {partition}" if partition else "", "workdir": None}
    view = _JobView(job, threads)
    call = " ".join((get_submit_command(view, params) + set_gres_string(view)).split())
    if not call.startswith(_BOILERPLATE):
        raise RuntimeError(f"the slurm plugin's sbatch call changed its form: {call[:120]}")
    return call[len(_BOILERPLATE):].strip()


def sbatch_plan(jobs, overwrite_threads: Mapping[str, int] | None = None, local_rules: Iterable[str] = ()) -> list[str]:
    """One line per rule of ``jobs`` (a DAG's jobs) that Slurm would run: ``RULE (N jobs): sbatch OPTIONS``;
    a rule whose jobs ask differently gets a line per request. Jobs with nothing to run (``all``, a target
    rule) and ``local_rules`` are left out: snakemake runs them itself. A job's threads are its rule's (or
    ``--set-threads``'), which a dry run caps at its one core and a cluster run does not."""
    local_rules = set(local_rules)
    requests: dict[str, dict[str, int]] = {}
    for job in jobs:
        if getattr(job, "is_norun", False) or job.rule.name in local_rules:
            continue
        declared = job.rule.resources.get("_cores")
        declared = getattr(declared, "value", declared)
        threads = (overwrite_threads or {}).get(job.rule.name) or (declared if isinstance(declared, int) else None)
        options = sbatch_options(job, int(threads or job.threads))
        per_rule = requests.setdefault(job.rule.name, {})
        per_rule[options] = per_rule.get(options, 0) + 1
    lines = []
    for rule in sorted(requests):
        for options, count in requests[rule].items():
            lines.append(f"  {rule} ({count} job{'s' if count != 1 else ''}): sbatch {options}")
    return lines


def print_sbatch_plan_at_exit(workflow, file=None) -> None:
    """Print :func:`sbatch_plan` of ``workflow``'s DAG when the process exits: after a dry run has built the DAG
    and listed its jobs (Snakemake calls no hook after a dry run). Only the jobs the run would submit: nothing
    where no DAG was built, or where it has nothing to do."""
    import atexit

    def print_plan():
        dag = getattr(workflow, "dag", None)
        # every job the run needs, those the dry run has since listed (marked finished) included
        lines = sbatch_plan(dag.needrun_jobs(exclude_finished=False), workflow.resource_settings.overwrite_threads,
                            getattr(workflow, "_localrules", ())) if dag is not None else []
        if lines:
            print("What each job asks sbatch for (the slurm plugin adds its job name, log and account):", *lines,
                  sep="\n", file=file or sys.stderr)

    atexit.register(print_plan)


# ---- a job Slurm killed ------------------------------------------------------------------------------------

_TIME_SIGNS = ("DUE TO TIME LIMIT",)
_MEMORY_SIGNS = ("exceeded memory limit", "Exceeded job memory limit", "oom-kill", "oom_kill", "OUT_OF_MEMORY")
_STATUS = re.compile(r"SLURM-job '(\d+)' failed.*?SLURM status is: '([A-Z_]+)'")
_FLAGS = re.compile(r"\s+\((?:update|temp|protected|ancient|directory)(?:, \w+)*\)$")
"""The flags Snakemake's log writes after an output's path (``path (update)``): not part of the path."""


def _blocks(text: str) -> list[list[str]]:
    """The log's lines cut at each unindented line: one block per job started and per error."""
    blocks: list[list[str]] = []
    for line in text.splitlines():
        if not line.startswith((" ", "\t")) or not blocks:
            blocks.append([line])
        else:
            blocks[-1].append(line)
    return blocks


def _fields(block: list[str]) -> dict[str, str]:
    fields = {}
    for line in block[1:]:
        key, sep, value = line.strip().partition(": ")
        if sep and key.isidentifier() and key not in fields:
            fields[key] = value.strip()
    return fields


def _resource(resources: str, name: str) -> int | None:
    match = re.search(rf"(?:^|, ){name}=(\d+)(?:,|$)", resources or "")
    return int(match.group(1)) if match else None


def killed_jobs(log_text: str, read=lambda path: Path(path).read_text(errors="replace")) -> list[dict]:
    """The jobs of a Snakemake run's log that Slurm killed at a limit: each as ``rule``, ``outputs``, the Slurm
    job id, ``limit`` (``time`` or ``memory``), and the ``runtime`` and ``mem_mb`` they asked for. Told from the
    status the slurm plugin reports (``TIMEOUT``, ``OUT_OF_MEMORY``) or, where Slurm ends such a job as
    ``FAILED`` (memory enforced by polling, without cgroups), from the job's Slurm log."""
    started: dict[str, dict[str, str]] = {}
    killed = []
    for block in _blocks(log_text):
        head = block[0].strip()
        if head.startswith("rule ") or head.startswith("localrule "):
            fields = _fields(block)
            if "jobid" in fields:
                started[fields["jobid"]] = fields
            continue
        if not head.startswith("Error in rule "):
            continue
        fields = _fields(block)
        status = _STATUS.search(fields.get("message", ""))
        if not status:
            continue
        slurm_id, state = status.groups()
        slurm_log = ""
        for path in re.split(r",\s*", fields.get("log", "").split(" (check", 1)[0]):
            if path.endswith(f"/{slurm_id}.log") or path.endswith(f"{slurm_id}.log"):
                try:
                    slurm_log = read(path.strip())
                except OSError:
                    slurm_log = ""
        if state == "TIMEOUT" or any(sign in slurm_log for sign in _TIME_SIGNS):
            limit = "time"
        elif state == "OUT_OF_MEMORY" or any(sign in slurm_log for sign in _MEMORY_SIGNS):
            limit = "memory"
        else:
            continue
        asked = started.get(fields.get("jobid", ""), {}).get("resources", "")
        killed.append({"rule": head[len("Error in rule "):].rstrip(":"), "slurm_job": slurm_id, "limit": limit,
                       "outputs": [_FLAGS.sub("", p.strip()) for p in fields.get("output", "").split(",") if p.strip()],
                       "runtime": _resource(asked, "runtime"), "mem_mb": _resource(asked, "mem_mb")})
    return killed


def killed_job_line(job: dict, checkpoint: Path | None, exists=Path.exists) -> str:
    """One line for a job Slurm killed: which limit stopped it, that none of its outputs is kept (Snakemake
    deletes a failed job's outputs; a training publishes its own only once it is complete), the
    ``--set-resources`` that gives it more, and what running it again does (a training resumes from
    ``checkpoint`` where one was written)."""
    rule = job["rule"]
    what = f"{rule} ({', '.join(job['outputs'][:1]) or 'no output'}; Slurm job {job['slurm_job']})"
    if job["limit"] == "time":
        asked = f"runtime={job['runtime']} min" if job["runtime"] else "its runtime"
        stopped = f"stopped by Slurm at its time limit ({asked})"
        doubled = 2 * job["runtime"] if job["runtime"] else "MINUTES"
        more = f"with more time if it needs it (--set-resources {rule}:runtime={doubled})"
    else:
        asked = f"mem_mb={job['mem_mb']}" if job["mem_mb"] else "its mem_mb"
        stopped = f"killed by Slurm for using more memory than it asked for ({asked})"
        more = f"with more memory (--set-resources {rule}:mem_mb={2 * job['mem_mb'] if job['mem_mb'] else 'MB'})"
    if checkpoint is not None and exists(checkpoint):
        again = f"it resumes from its checkpoint ({checkpoint})"
    elif checkpoint is not None:
        again = "it starts over (it had written no checkpoint yet)"
    else:
        again = "it starts over"
    return f"egosearch: {what} was {stopped}; none of its outputs is kept; run it again {more}: {again}"


def killed_job_lines(log_paths, checkpoint_of: Callable[[str, list[str]], Path | None] = lambda rule, outputs: None,
                     read=lambda path: Path(path).read_text(errors="replace")) -> list[str]:
    """:func:`killed_job_line` for each job that Slurm killed in the run whose Snakemake log is ``log_paths`` (the
    path, or the list the Snakefile's ``onerror`` gets); ``checkpoint_of(rule, outputs)`` names the file a job of
    the rule resumes from, None for a rule that keeps none."""
    from egosearch.workflow.failures import run_log_texts

    lines = []
    for text in run_log_texts(log_paths, read):
        for job in killed_jobs(text, read):
            lines.append(killed_job_line(job, checkpoint_of(job["rule"], job["outputs"])))
    return lines

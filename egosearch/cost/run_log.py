"""A finished ``snakemake`` run read back from its log (``.snakemake/log/<date>.snakemake.log``): which
jobs it ran, when each started and finished, and how long the whole run took. What the schedule
check of :mod:`egosearch.cost.schedule_check` compares the simulation with. Text in, data out.

Snakemake prints a job's start as a ``[<date>]`` line followed by ``rule NAME:`` (``localrule`` when
it runs on this machine) and indented fields (``jobid:``, ``benchmark:``, ``wildcards:``), and its end
as a ``[<date>]`` line followed by ``Finished jobid: N (Rule: NAME)``. The dates are to the second.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path

from egosearch.core.preset_word import with_preset_wildcard

_STAMP = re.compile(r"^\[(\w{3} \w{3} +\d+ \d\d:\d\d:\d\d \d{4})\]$")
_RULE = re.compile(r"^(?:local)?rule (\w+):$")
_FIELD = re.compile(r"^\s+(jobid|benchmark|wildcards): (.*)$")
_FINISHED = re.compile(r"^Finished jobid: (\d+) \(Rule: (\w+)\)$")
_CORES = re.compile(r"^Provided cores: (\d+)$")
_COMMAND = re.compile(r"^\s*Command: (.*)$")


@dataclass
class LoggedJob:
    """One job of the run: Snakemake's job id, its rule, wildcards and ``benchmark:`` path (None without
    one), and its start and end in seconds from the run's first start."""

    jobid: int
    rule: str
    wildcards: dict[str, str] = field(default_factory=dict)
    benchmark: str | None = None
    start: float | None = None
    end: float | None = None

    @property
    def seconds(self) -> float | None:
        return None if self.start is None or self.end is None else self.end - self.start


@dataclass
class RunLog:
    """The run: its jobs by job id, the cores it was given and its command line (None where the log
    lacks them), and its elapsed time from the first job's start to the last job's end."""

    jobs: dict[int, LoggedJob]
    cores: int | None
    command: str | None

    @property
    def elapsed(self) -> float:
        ends = [j.end for j in self.jobs.values() if j.end is not None]
        return max(ends) if ends else 0.0

    def finished(self) -> list[LoggedJob]:
        return [j for j in self.jobs.values() if j.end is not None]


def _wildcards(text: str) -> dict[str, str]:
    # a log written before the preset's rename names the wildcard preset=
    return with_preset_wildcard(dict(part.split("=", 1) for part in text.split(", ") if "=" in part))


def read_run_log(path: str | Path) -> RunLog:
    """The jobs of the Snakemake log at ``path``. Raises ValueError when it holds no job that finished
    (not a Snakemake log, or a dry run)."""
    jobs: dict[int, LoggedJob] = {}
    stamp: datetime | None = None
    first: datetime | None = None
    opened: LoggedJob | None = None
    cores = command = None
    for line in Path(path).read_text(encoding="utf-8", errors="replace").splitlines():
        if m := _STAMP.match(line):
            stamp = datetime.strptime(" ".join(m.group(1).split()), "%a %b %d %H:%M:%S %Y")
            first = first or stamp
            opened = None
        elif (m := _RULE.match(line)) and stamp is not None:
            opened = LoggedJob(jobid=-1, rule=m.group(1), start=(stamp - first).total_seconds())
        elif opened is not None and (m := _FIELD.match(line)):
            key, value = m.groups()
            if key == "jobid":
                opened.jobid = int(value)
                jobs[opened.jobid] = opened
            elif key == "benchmark":
                opened.benchmark = value.strip()
            else:
                opened.wildcards = _wildcards(value.strip())
        elif (m := _FINISHED.match(line)) and stamp is not None and int(m.group(1)) in jobs:
            jobs[int(m.group(1))].end = (stamp - first).total_seconds()
        elif m := _CORES.match(line):
            cores = int(m.group(1))
        elif (m := _COMMAND.match(line)) and command is None:
            command = m.group(1).strip()
    log = RunLog(jobs=jobs, cores=cores, command=command)
    if not log.finished():
        raise ValueError(f"{path}: no finished job in it (a Snakemake run's log, .snakemake/log/*.snakemake.log, "
                         "of a run that ran jobs)")
    return log


def dag_id(job: LoggedJob, preset: str) -> str:
    """The id :func:`egosearch.workflow.dag.dag_jobs` gives the same job: its benchmark path relative to
    ``results/<preset>/benchmarks/`` without ``.tsv``, else its rule and wildcard values."""
    prefix = f"results/{preset}/benchmarks/"
    if job.benchmark and job.benchmark.startswith(prefix) and job.benchmark.endswith(".tsv"):
        return job.benchmark[len(prefix):-len(".tsv")]
    return "/".join([job.rule, *(v for k, v in job.wildcards.items() if k != "preset")])

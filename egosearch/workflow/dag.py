"""The jobs ``snakemake <target>`` would run from a fresh state, as plain data: what the schedule
simulation (:mod:`egosearch.cost.schedule`) reads.

How: a child Python process builds the DAG with Snakemake's own API, the way ``snakemake --forceall
--dry-run --d3dag --cores N <target>`` does (``Workflow._prepare_dag`` with ``forceall`` and no
lock, then ``Workflow._build_dag``), in the repository's root, and writes one JSON row per job of the
DAG: its rule, ``benchmark:`` path, threads as ``--cores N`` resolves them, the jobs it reads
outputs of, its priority and the sizes of its inputs as they are on disk now (Snakemake's greedy
scheduler weighs them). Nothing of the rules is reimplemented here. A child process, because the
Snakefile prints on start and Snakemake sets up loggers, changes directory and keeps module state:
none of it reaches the caller. About as long as a dry run (a few seconds).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
"""The repository's root: where the Snakefile is and every rule's relative paths start."""


@dataclass(frozen=True)
class DagJob:
    """One job of the DAG. ``id`` is unique in the DAG: the ``benchmark:`` path relative to
    ``results/<preset>/benchmarks/`` without ``.tsv`` (``train/head_on/seed0``), or for a job that
    writes no benchmark its rule and wildcard values (``provenance``, ``all``). ``record_rule`` and
    ``job`` split a benchmark path the way a provenance record keys its jobs (first folder, rest:
    ``eval``, ``head_on/seed0/kitchen_living/everywhere/h0.45``); both are None without a benchmark.
    ``order`` is Snakemake's job id (its order of discovery from the target)."""

    id: str
    rule: str
    job: str | None
    record_rule: str | None
    threads: int
    deps: tuple[str, ...]
    order: int
    priority: float = 0
    input_bytes: int = 0
    temp_input_bytes: int = 0
    wildcards: dict = field(default_factory=dict)

    def as_dict(self) -> dict:
        """The job as a JSON-ready dict (what :mod:`egosearch.cost.schedule` reads)."""
        return asdict(self) | {"deps": list(self.deps)}


_DECLARED_RULE = re.compile(r"^(?:rule|checkpoint) (\w+):", re.MULTILINE)


def rule_names(root: str | os.PathLike | None = None) -> list[str]:
    """Every rule the workflow declares (the Snakefile and ``egosearch/workflow/rules/*.smk``), sorted:
    the names a target may take. Read from the files' text, in a moment, without building a DAG."""
    root = Path(root or ROOT)
    files = [root / "Snakefile", *sorted((root / "egosearch" / "workflow" / "rules").glob("*.smk"))]
    return sorted({name for path in files if path.is_file()
                   for name in _DECLARED_RULE.findall(path.read_text(encoding="utf-8"))})


def _config_items(config: Mapping[str, object] | Sequence[str] | None) -> list[str]:
    if not config:
        return []
    if isinstance(config, Mapping):
        return [f"{key}={value}" for key, value in config.items()]
    return list(config)


def dag_jobs(target: str = "all", cores: int = 2, config: Mapping[str, object] | Sequence[str] | None = None,
             root: str | os.PathLike | None = None, timeout: float = 300) -> list[DagJob]:
    """The jobs ``snakemake --forceall --cores <cores> <target> --config <config>`` would run, in
    Snakemake's job-id order. ``config`` is ``{"preset": "smoke"}`` or ``["preset=smoke"]``: read
    as the command line reads it. Raises RuntimeError with Snakemake's last lines when the DAG
    cannot be built (a bad config, a missing input no rule makes)."""
    root = Path(root or ROOT)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "dag.json"
        cmd = [sys.executable, "-m", "egosearch.workflow.dag", "--target", target, "--cores", str(cores),
               "--out", str(out)]
        items = _config_items(config)
        if items:
            cmd += ["--config", *items]
        proc = subprocess.run(cmd, cwd=root, capture_output=True, text=True, timeout=timeout)
        if proc.returncode != 0 or not out.exists():
            tail = "\n".join((proc.stderr or proc.stdout).strip().splitlines()[-15:])
            raise RuntimeError(f"building the DAG of `{target}` failed (exit {proc.returncode}):\n{tail}")
        rows = json.loads(out.read_text(encoding="utf-8"))
    return [DagJob(**(row | {"deps": tuple(row["deps"])})) for row in rows]


def _benchmark_key(benchmark: str, preset_root: Path) -> str | None:
    """The benchmark path relative to ``results/<preset>/benchmarks/``, without ``.tsv``."""
    path = Path(benchmark)
    try:
        rel = path.relative_to(preset_root)
    except ValueError:
        return None
    return str(rel.with_suffix("")) if rel.suffix == ".tsv" else str(rel)


def _size(path: str) -> int:
    try:
        return os.path.getsize(path)
    except OSError:
        return 0


def _collect(target: str, cores: int, config_items: list[str]) -> list[dict]:
    """Build the DAG in this process (the child's work) and return its jobs as dicts."""
    from snakemake.api import SnakemakeApi
    from snakemake.cli import parse_config
    from snakemake.settings.types import ConfigSettings, DAGSettings, OutputSettings, Quietness, ResourceSettings

    with SnakemakeApi(OutputSettings(dryrun=True, quiet={Quietness.ALL})) as api:
        workflow_api = api.workflow(resource_settings=ResourceSettings(cores=cores),
                                    config_settings=ConfigSettings(config=parse_config(config_items)),
                                    snakefile=Path("Snakefile"))
        # the DAG API hands its settings to the workflow, which _prepare_dag reads
        workflow_api.dag(DAGSettings(targets={target}, forceall=True))
        # what --d3dag runs, but keeping the DAG: the public printers print it and return nothing
        workflow = workflow_api._workflow
        workflow._prepare_dag(forceall=True, ignore_incomplete=True, lock_warn_only=True, nolock=True)
        workflow._build_dag()
        return plan_rows(workflow.dag, workflow.config.get("preset"))


def plan_rows(dag, preset: str | None) -> list[dict]:
    """The jobs a built Snakemake DAG will run (its ``needrun_jobs``: with ``forceall`` every job), as the
    JSON rows of :class:`DagJob`, in Snakemake's job-id order; ``preset`` names the benchmark folder that
    keys them. What the child process writes, and what the Snakefile's cost line reads from the live DAG
    of a run or a dry run (:func:`plan_jobs`)."""
    benchmarks = Path("results") / str(preset) / "benchmarks"
    dag.update_priority()  # a job's priority is read from the DAG once computed (Snakemake does it later)
    jobs = sorted(dag.needrun_jobs(), key=dag.jobid)
    ids, keys, taken, wildcards = {}, {}, set(), {}
    for job in jobs:
        key = keys[job] = _benchmark_key(str(job.benchmark), benchmarks) if job.benchmark else None
        wildcards[job] = {k: str(v) for k, v in job.wildcards_dict.items()}
        ident = key or "/".join([job.rule.name, *(v for k, v in wildcards[job].items() if k != "preset")])
        if ident in taken:
            ident = f"{ident}#{dag.jobid(job)}"
        ids[job] = ident
        taken.add(ident)
    rows = []
    for job in jobs:
        key = keys[job]
        record_rule, _, record_job = key.partition("/") if key else (None, None, None)
        rows.append({
            "id": ids[job], "rule": job.rule.name, "job": record_job, "record_rule": record_rule,
            "threads": int(job.threads),
            "deps": [ids[dep] for dep in sorted(dag.dependencies[job], key=dag.jobid) if dep in ids],
            "order": dag.jobid(job), "priority": job.priority,
            "input_bytes": sum(_size(f) for f in job.input),
            "temp_input_bytes": sum(_size(f) for f in job.input if f.is_flagged("temp")),
            "wildcards": wildcards[job],
        })
    return rows


def plan_jobs(dag, preset: str | None) -> list[DagJob]:
    """:func:`plan_rows` as :class:`DagJob`: the plan of the run (or dry run) whose DAG ``dag`` is."""
    return [DagJob(**(row | {"deps": tuple(row["deps"])})) for row in plan_rows(dag, preset)]


def whole_dag(dag) -> bool:
    """Whether a built DAG runs every job it holds: nothing of it is stored yet, or all is forced (``-F``)."""
    return len(list(dag.needrun_jobs())) == len(list(dag.jobs))


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m egosearch.workflow.dag --out FILE [--target all] [--cores 2] [--config k=v ...]``:
    the child process of :func:`dag_jobs`; writes the jobs as a JSON list to FILE."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--target", default="all")
    parser.add_argument("--cores", type=int, default=2)
    parser.add_argument("--config", nargs="*", default=[])
    parser.add_argument("--out", required=True)
    args = parser.parse_args(argv)
    # the Snakefile's own prints go to stderr with Snakemake's, away from anything the parent reads
    sys.stdout = sys.stderr
    rows = _collect(args.target, args.cores, args.config)
    Path(args.out).write_text(json.dumps(rows), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())

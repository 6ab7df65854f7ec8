"""Where results came from: commit, preset, machine, date and the wall time of every rule, and
the sha256 of every stored result file, so that a file edited or truncated by hand is caught.

Reads the ``benchmark:`` files Snakemake writes per job (tab-separated, seconds in column ``s``).
"""

from __future__ import annotations

import csv
import datetime as dt
import hashlib
import json
import os
import platform
import re
import subprocess
from collections.abc import Iterable
from importlib import metadata
from pathlib import Path

from egosearch.core.machine import cpu_model, cpu_vector_unit


def _git(*args: str) -> str:
    try:
        return subprocess.run(["git", *args], capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def _version(package: str) -> str:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return "not installed"


WHOLE_RUN_SHARE = 0.9
"""A training's benchmark timed the whole run when its wall time is at least this share of the wall
time its ``curve.csv`` counts; below it, the run was resumed and the benchmark timed its last part."""


def _curve_wall_s(curve: Path) -> float | None:
    """The wall time a training's ``curve.csv`` counts from its start, across resumes (last row)."""
    try:
        with open(curve, newline="") as f:
            rows = list(csv.DictReader(f))
        return float(rows[-1]["wall_s"])
    except (OSError, IndexError, KeyError, TypeError, ValueError):
        return None


def rule_times(benchmarks_dir: Path) -> list[dict]:
    """One row per job: the rule (first folder), the job (rest of the path), its wall time and, where
    the benchmark recorded it, its CPU time (``cpu_s``). A resumed training's benchmark times only
    the part after its resume: ``run_wall_s`` then carries the whole run's wall time, from its
    ``curve.csv`` beside the benchmarks folder (``results/<preset>/train/<job>/``)."""
    rows = []
    for path in sorted(Path(benchmarks_dir).rglob("*.tsv")):
        with open(path, newline="") as f:
            records = list(csv.DictReader(f, delimiter="\t"))
        if not records:
            continue
        rel = path.relative_to(benchmarks_dir).with_suffix("")
        row = {"rule": rel.parts[0], "job": "/".join(rel.parts[1:]), "wall_s": round(float(records[-1]["s"]), 1),
               "max_rss_mb": records[-1].get("max_rss", "")}
        try:
            row["cpu_s"] = round(float(records[-1]["cpu_time"]), 1)
        except (KeyError, TypeError, ValueError):  # older Snakemake, or a job too short to sample
            pass
        if row["rule"] == "train":
            run_wall = _curve_wall_s(Path(benchmarks_dir).parent / "train" / row["job"] / "curve.csv")
            if run_wall is not None and row["wall_s"] < WHOLE_RUN_SHARE * run_wall:
                row["run_wall_s"] = round(run_wall, 1)
        rows.append(row)
    return rows


PROVENANCE_NAME = "provenance.json"
NOT_RESULTS = ("logs", "benchmarks")
"""Top-level folders of ``results/<preset>/`` that hold no results (job logs and timings)."""
WORK_PARTS = ("ckpt", "partial")
"""Folders of a run in progress (checkpoints, a training not yet finished): never a stored result."""


def stored_files(results: Path) -> list[Path]:
    """Every result file under ``results``: what the tables, figures and comparisons read (scenario
    sets, evaluations, curves, full-body runs, comparisons) and the rest of each run (actor.pt...)."""
    results = Path(results)
    out = []
    for path in sorted(results.rglob("*")):
        rel = path.relative_to(results)
        if (not path.is_file() or rel.parts[0] in NOT_RESULTS or rel == Path(PROVENANCE_NAME)
                or any(part in WORK_PARTS for part in rel.parts[:-1]) or path.name.startswith(".")):
            continue
        out.append(path)
    return out


def file_record(path: Path) -> dict:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return {"sha256": digest.hexdigest(), "bytes": Path(path).stat().st_size}


def record_files(results: Path) -> dict[str, dict]:
    """``{path relative to results: {sha256, bytes}}`` of :func:`stored_files`."""
    results = Path(results)
    return {path.relative_to(results).as_posix(): file_record(path) for path in stored_files(results)}


WHEN_AND_WHERE = ("commit", "commit_dirty", "date_utc", "machine")
"""Fields of a record that describe the run of the `provenance` command itself, not the results."""


def _same_results(old: dict, new: dict) -> bool:
    """Whether ``new`` records what ``old`` does: the same stored files (sha256), jobs and preset,
    and no new note. A regeneration that rewrites identical files must not rewrite the record: a new
    commit and date in a committed file would say the results changed when none did."""
    if new.get("note", "") != old.get("note", ""):
        return False
    keep = {key: value for key, value in old.items() if key not in (*WHEN_AND_WHERE, "note")}
    return keep == {key: value for key, value in new.items() if key not in (*WHEN_AND_WHERE, "note")}


def _read_record(path: Path) -> dict | None:
    try:
        record = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return record if isinstance(record, dict) else None


def this_machine() -> dict:
    """The machine a job ran on, as each job of a record names it: CPU model, vector unit, cores."""
    return {"cpu": cpu_model(), "vector_unit": cpu_vector_unit(), "cores": os.cpu_count()}


def _job_key(job: dict) -> tuple[str, str]:
    return job["rule"], job["job"]


def _variant_of(job: str) -> str | None:
    """The variant of a job path ``[.../]<variant>/seed<N>/...`` (the folder before its first ``seed<N>``)."""
    parts = job.split("/")
    for i, part in enumerate(parts[1:], start=1):
        if re.fullmatch(r"seed\d+", part):
            return parts[i - 1]
    return None


def _trained_as(results: Path, job: str) -> str | None:
    """The variant a job's run trained as (its ``done.json``'s), for a job path ``[.../]<variant>/seed<N>/...``."""
    variant = _variant_of(job)
    seed = next((p for p in job.split("/") if re.fullmatch(r"seed\d+", p)), None)
    if variant is None or seed is None:
        return None
    try:
        return json.loads((results / "train" / variant / seed / "done.json").read_text(encoding="utf-8"))["variant"]
    except (OSError, ValueError, KeyError, TypeError):
        return None


def mark_copies(jobs: list[dict], benchmarks_dir: Path, results: Path) -> None:
    """A job whose benchmark file is byte for byte another's was copied from it (a stored run moved under a new
    name keeps its files): it gets ``copy_of`` (``rule/job`` of its source) and is counted once, as its source.
    The source is the job whose run trained under its own name (its ``done.json``); else the first by name."""
    by_digest: dict[str, list[dict]] = {}
    for job in jobs:
        path = Path(benchmarks_dir) / job["rule"] / f"{job['job']}.tsv"
        try:
            digest = hashlib.sha256(path.read_bytes()).hexdigest()
        except OSError:
            continue
        by_digest.setdefault(digest, []).append(job)
    for group in by_digest.values():
        if len(group) < 2:
            continue
        own = [j for j in group if _trained_as(results, j["job"]) == _variant_of(j["job"])]
        source = (own or sorted(group, key=lambda j: j["job"]))[0]
        for job in group:
            if job is not source:
                job["copy_of"] = f"{source['rule']}/{source['job']}"


def counted(jobs: list[dict]) -> list[dict]:
    """The jobs that ran: every job but the copies (:func:`mark_copies`)."""
    return [job for job in jobs if "copy_of" not in job]


def attach_machines(jobs: list[dict], results: Path, previous: dict | None) -> None:
    """Give each job the machine it ran on, where that is known: a training's from its ``done.json``
    (the trainer records it); a job the previous record already held, with the same wall time, keeps
    the machine that record gave it (it has not run since); a job that is new since then, or that ran
    again (its wall time changed), ran in the workflow run that is writing this record, on this machine
    (under a cluster executor: the node that runs the provenance job, which may not be the job's).
    Otherwise ``None``: jobs recorded before records named machines are not guessed."""
    before = {_job_key(j): j for j in (previous or {}).get("jobs", [])}
    here = this_machine()
    for job in jobs:
        old = before.get(_job_key(job))
        machine = None
        if job["rule"] == "train":
            try:
                done = json.loads((Path(results) / "train" / job["job"] / "done.json").read_text(encoding="utf-8"))
                # trainings recorded before the vector unit was: None there, not a guess
                machine = {k: done["machine"].get(k) for k in ("cpu", "vector_unit", "cores")}
            except (OSError, ValueError, KeyError, TypeError):
                machine = None
        if machine is None and old is not None and old.get("wall_s") == job["wall_s"]:
            machine = old.get("machine")
        elif machine is None:
            machine = here
        job["machine"] = machine
    # a copy ran where its source ran
    by_key = {f"{j['rule']}/{j['job']}": j for j in jobs}
    for job in jobs:
        if "copy_of" in job and job["copy_of"] in by_key:
            job["machine"] = by_key[job["copy_of"]]["machine"]


def machines_of(jobs: list[dict]) -> list[dict]:
    """Every machine the jobs name, with how many jobs and how many summed wall seconds each ran (most
    first), and one entry ``{"cpu": None, ...}`` for the jobs that name none."""
    groups: dict[str, dict] = {}
    for job in counted(jobs):
        machine = job.get("machine") or {"cpu": None, "vector_unit": None, "cores": None}
        key = json.dumps(machine, sort_keys=True)
        entry = groups.setdefault(key, {**machine, "jobs": 0, "wall_s": 0.0})
        entry["jobs"] += 1
        entry["wall_s"] = round(entry["wall_s"] + float(job.get("run_wall_s", job["wall_s"])), 1)
    return sorted(groups.values(), key=lambda m: (m["cpu"] is None, -m["wall_s"]))


def write_provenance(preset: str, results: Path, out: Path, note: str = "") -> dict:
    """Write the record of ``results`` to ``out`` and return it; when ``out`` already records the same
    stored files (see :func:`_same_results`) it is left as it is and that record is returned. The
    previous record's ``note`` is kept unless a new one is given: a rewrite keeps what it does not
    recompute."""
    results = Path(results)
    out = Path(out)
    previous = _read_record(out) if out.is_file() else None
    jobs = rule_times(results / "benchmarks")
    mark_copies(jobs, results / "benchmarks", results)
    attach_machines(jobs, results, previous)
    per_rule: dict[str, float] = {}
    for job in counted(jobs):
        per_rule[job["rule"]] = round(per_rule.get(job["rule"], 0.0) + job["wall_s"], 1)
    status = _git("status", "--porcelain", "--untracked-files=no")
    record = {
        "preset": preset,
        "commit": _git("rev-parse", "HEAD"),
        "commit_dirty": bool(status) if status != "unknown" else None,
        "date_utc": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        # where this record was written; each job names its own machine, and "machines" lists them all
        "machine": {"cpu": cpu_model(), "vector_unit": cpu_vector_unit(), "cores": os.cpu_count(),
                    "platform": platform.platform(),
                    "python": platform.python_version(), "torch": _version("torch"),
                    "pybullet": _version("pybullet"), "snakemake": _version("snakemake")},
        "machines": machines_of(jobs),
        "wall_s_per_rule_summed": per_rule,
        "wall_s_all_jobs_summed": round(sum(per_rule.values()), 1),
        "jobs_counted": len(counted(jobs)),
        "jobs_copied": len(jobs) - len(counted(jobs)),
        "jobs": jobs,
        "files": record_files(results),
    }
    note = note or (previous or {}).get("note", "")
    if note:
        record["note"] = note
    if previous is not None and _same_results(previous, record):
        os.utime(out)  # bytes kept, time renewed: the workflow sees the record as newer than what it checked
        return previous
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.name + ".tmp")
    tmp.write_text(json.dumps(record, indent=2) + "\n")
    os.replace(tmp, out)
    return record


# --------------------------------------------------------------------------------------------- verify
class StoredFileError(ValueError):
    """A stored result file differs from the sha256 its provenance recorded."""


def _provenance_of(path: Path) -> Path | None:
    """The nearest ``provenance.json`` above ``path``: the record of the results folder it is in."""
    for folder in Path(path).resolve().parents:
        candidate = folder / PROVENANCE_NAME
        if candidate.is_file():
            return candidate
    return None


def _load_record(provenance: Path) -> dict[str, dict] | None:
    try:
        record = json.loads(Path(provenance).read_text(encoding="utf-8"))
    except (OSError, ValueError) as err:
        raise StoredFileError(f"cannot read {provenance}: {err}") from None
    files = record.get("files")
    return files if isinstance(files, dict) else None


def file_problem(path: Path, recorded: dict | None, provenance: Path) -> str | None:
    """What is wrong with ``path`` against its record, in words; None when it matches."""
    if recorded is None:
        return f"{path} is not in the sha256 list of {provenance} (written after it?)"
    if not Path(path).is_file():
        return f"{path} is missing (recorded in {provenance})"
    now = file_record(path)
    if now["sha256"] == recorded.get("sha256"):
        return None
    if now["bytes"] < int(recorded.get("bytes", 0)):
        return f"{path} was truncated: {now['bytes']} bytes, {recorded['bytes']} recorded in {provenance}"
    return f"{path} was edited: its sha256 differs from the one recorded in {provenance}"


def stored_problems(paths: Iterable[str | os.PathLike], require_record: bool = True) -> tuple[list, list[str]]:
    """``([(path, problem)...], unrecorded)``: each file that differs from the sha256 its results folder's
    provenance recorded, with the one-line problem; and the files no record vouches for. ``require_record``: a
    file its record does not list is a problem too (a stored result read by a table), else it passes."""
    problems, unrecorded, cache = [], [], {}
    for path in map(Path, paths):
        provenance = _provenance_of(path)
        if provenance is None:
            unrecorded.append(str(path))
            continue
        if provenance not in cache:
            cache[provenance] = _load_record(provenance)
        files = cache[provenance]
        if files is None:
            unrecorded.append(str(path))
            continue
        key = path.resolve().relative_to(provenance.parent.resolve()).as_posix()
        if key not in files and not require_record:
            continue
        problem = file_problem(path, files.get(key), provenance)
        if problem:
            problems.append((path, problem))
    return problems, unrecorded


def check_stored(paths: Iterable[str | os.PathLike], require_record: bool = True) -> list[str]:
    """Raise :class:`StoredFileError` (one line) if a file differs from the sha256 that the
    provenance of its results folder recorded (:func:`stored_problems`). Returns the files no record vouched
    for, i.e. in results folders without a record."""
    problems, unrecorded = stored_problems(paths, require_record)
    if problems:
        more = f" ({len(problems) - 1} more file(s) too)" if len(problems) > 1 else ""
        raise StoredFileError(f"{problems[0][1]}{more}; refusing to use stored results that differ from their "
                              "record: restore them (git checkout), or rerun the jobs that write them and then "
                              "the `provenance` rule; `egosearch report verify` lists every file")
    return unrecorded


def verify(results: Path) -> tuple[int, list[str]]:
    """(files that match, problems): every file recorded in ``results/provenance.json`` is there with
    its sha256, and every stored file is recorded."""
    results = Path(results)
    provenance = results / PROVENANCE_NAME
    if not provenance.is_file():
        raise FileNotFoundError(f"{provenance} not found: nothing to verify against")
    files = _load_record(provenance)
    if files is None:
        raise StoredFileError(f"{provenance} has no sha256 list (written before records had one): rerun the "
                              "`provenance` rule to write one")
    problems, ok = [], 0
    for rel in sorted(set(files) | {p.relative_to(results).as_posix() for p in stored_files(results)}):
        problem = file_problem(results / rel, files.get(rel), provenance)
        if problem:
            problems.append(problem)
        else:
            ok += 1
    return ok, problems

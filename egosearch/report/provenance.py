"""Where results came from: commit, profile, machine, date and the wall time of every rule.

Reads the ``benchmark:`` files Snakemake writes per job (tab-separated, seconds in column ``s``).
"""

from __future__ import annotations

import csv
import datetime as dt
import json
import os
import platform
import subprocess
from importlib import metadata
from pathlib import Path


def _git(*args: str) -> str:
    try:
        return subprocess.run(["git", *args], capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _version(package: str) -> str:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return "not installed"


def rule_times(benchmarks_dir: Path) -> list[dict]:
    """One row per job: the rule (first folder), the job (rest of the path) and its wall time."""
    rows = []
    for path in sorted(Path(benchmarks_dir).rglob("*.tsv")):
        with open(path, newline="") as f:
            records = list(csv.DictReader(f, delimiter="\t"))
        if not records:
            continue
        rel = path.relative_to(benchmarks_dir).with_suffix("")
        rows.append({"rule": rel.parts[0], "job": "/".join(rel.parts[1:]),
                     "wall_s": round(float(records[-1]["s"]), 1),
                     "max_rss_mb": records[-1].get("max_rss", "")})
    return rows


def write_provenance(profile: str, results: Path, out: Path, note: str = "") -> dict:
    results = Path(results)
    jobs = rule_times(results / "benchmarks")
    per_rule: dict[str, float] = {}
    for job in jobs:
        per_rule[job["rule"]] = round(per_rule.get(job["rule"], 0.0) + job["wall_s"], 1)
    status = _git("status", "--porcelain", "--untracked-files=no")
    record = {
        "profile": profile,
        "commit": _git("rev-parse", "HEAD"),
        "commit_dirty": bool(status) if status != "unknown" else None,
        "date_utc": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "machine": {"cpu": cpu_model(), "cores": os.cpu_count(), "platform": platform.platform(),
                    "python": platform.python_version(), "torch": _version("torch"),
                    "pybullet": _version("pybullet"), "snakemake": _version("snakemake")},
        "wall_s_per_rule_summed": per_rule,
        "wall_s_all_jobs_summed": round(sum(per_rule.values()), 1),
        "jobs": jobs,
    }
    if note:
        record["note"] = note
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.name + ".tmp")
    tmp.write_text(json.dumps(record, indent=2) + "\n")
    os.replace(tmp, out)
    return record

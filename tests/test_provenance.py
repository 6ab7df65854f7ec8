"""The provenance record: a rewrite keeps what it does not recompute (the note), and every job names the
machine it ran on, where that is known; and what git stores stays small enough to clone."""

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from egosearch.report import provenance

REPO = Path(__file__).resolve().parent.parent
TRACKED_FILE_LIMIT = 10 * 1024 * 1024
"""The most bytes one file tracked by git may hold (10 MB)."""


def _results(root: Path) -> Path:
    """A results folder with one stored evaluation, one finished training (its done.json names the
    machine it ran on) and the benchmark files of both jobs."""
    results = root / "results" / "p"
    (results / "eval" / "v" / "seed0").mkdir(parents=True)
    (results / "eval" / "v" / "seed0" / "h1.05.csv").write_text("scenario_id,success\n0,1\n")
    run = results / "train" / "v" / "seed0"
    run.mkdir(parents=True)
    (run / "done.json").write_text(json.dumps({"machine": {"cpu": "Far Away CPU", "vector_unit": "AVX2",
                                                           "cores": 16}}))
    (run / "curve.csv").write_text("env_steps,wall_s\n0,0.0\n100,50.0\n")
    for rule, job, seconds in (("train", "v/seed0", 50.0), ("eval", "v/seed0/h1.05", 3.0)):
        tsv = results / "benchmarks" / rule / f"{job}.tsv"
        tsv.parent.mkdir(parents=True, exist_ok=True)
        tsv.write_text(f"s\tcpu_time\n{seconds}\t{seconds}\n")
    return results


def test_a_rewrite_keeps_the_note_when_a_stored_file_changed(tmp_path):
    """`regenerate` then `snakemake all` rewrote the record after a file changed and deleted its note."""
    results = _results(tmp_path)
    record = results / "provenance.json"
    provenance.write_provenance("p", results, record, note="how the stored run was made")
    stored = results / "eval" / "v" / "seed0" / "h1.05.csv"
    stored.write_text(stored.read_text() + "1,0\n")
    rewritten = provenance.write_provenance("p", results, record)
    assert rewritten["files"] == provenance.record_files(results)
    assert json.loads(record.read_text())["note"] == "how the stored run was made"


def test_every_job_names_its_machine_and_the_header_lists_them_all(tmp_path, monkeypatch):
    results = _results(tmp_path)
    record = results / "provenance.json"
    here = {"cpu": "This CPU", "vector_unit": "AVX-512", "cores": 2}
    monkeypatch.setattr(provenance, "this_machine", lambda: dict(here))
    first = provenance.write_provenance("p", results, record)
    jobs = {j["rule"]: j for j in first["jobs"]}
    assert jobs["train"]["machine"] == {"cpu": "Far Away CPU", "vector_unit": "AVX2", "cores": 16}
    assert jobs["eval"]["machine"] == here  # ran in the workflow run that wrote the record
    assert [(m["cpu"], m["jobs"], m["wall_s"]) for m in first["machines"]] == [("Far Away CPU", 1, 50.0),
                                                                                ("This CPU", 1, 3.0)]
    # On another machine later: the evaluation has not run again, so it keeps the machine it ran on;
    # a new job is this machine's.
    monkeypatch.setattr(provenance, "this_machine", lambda: {"cpu": "Later CPU", "vector_unit": None, "cores": 4})
    tsv = results / "benchmarks" / "eval" / "v" / "seed0" / "h1.65.tsv"
    tsv.write_text("s\tcpu_time\n4.0\t4.0\n")
    (results / "eval" / "v" / "seed0" / "h1.65.csv").write_text("scenario_id,success\n0,0\n")
    later = {j["job"]: j["machine"]["cpu"] for j in provenance.write_provenance("p", results, record)["jobs"]}
    assert later == {"v/seed0": "Far Away CPU", "v/seed0/h1.05": "This CPU", "v/seed0/h1.65": "Later CPU"}
    # the evaluation run again there (a forced rerun: its benchmark rewritten) is that machine's now
    monkeypatch.setattr(provenance, "this_machine", lambda: {"cpu": "Rerun CPU", "vector_unit": None, "cores": 2})
    (results / "benchmarks" / "eval" / "v" / "seed0" / "h1.05.tsv").write_text("s\tcpu_time\n3.5\t3.4\n")
    rerun = {j["job"]: j["machine"]["cpu"] for j in provenance.write_provenance("p", results, record)["jobs"]}
    assert rerun == {"v/seed0": "Far Away CPU", "v/seed0/h1.05": "Rerun CPU", "v/seed0/h1.65": "Later CPU"}


def test_a_job_recorded_before_records_named_machines_is_not_given_one(tmp_path):
    results = _results(tmp_path)
    record = results / "provenance.json"
    old = provenance.write_provenance("p", results, record)
    for job in old["jobs"]:
        del job["machine"]
    old["files"] = {}  # and a stored file changed since, so that the record is rewritten
    record.write_text(json.dumps(old))
    jobs = {j["rule"]: j for j in provenance.write_provenance("p", results, record)["jobs"]}
    assert jobs["eval"]["machine"] is None and jobs["train"]["machine"]["cpu"] == "Far Away CPU"


def test_a_copied_run_inherits_its_sources_machine_and_is_counted_once(tmp_path, monkeypatch):
    """A stored run copied under a new name keeps its benchmark files byte for byte: the copy names its source,
    takes the source's machine (not the machine that wrote the record) and is left out of the totals."""
    results = _results(tmp_path)
    (results / "train" / "v" / "seed0" / "done.json").write_text(json.dumps(
        {"variant": "v", "machine": {"cpu": "Far Away CPU", "vector_unit": "AVX2", "cores": 16}}))
    record = results / "provenance.json"
    monkeypatch.setattr(provenance, "this_machine", lambda: {"cpu": "Old CPU", "vector_unit": None, "cores": 2})
    provenance.write_provenance("p", results, record)
    # later, on another machine: v's run copied to w (its done.json still names v)
    shutil.copytree(results / "train" / "v", results / "train" / "w")
    for rule, job in (("train", "v/seed0"), ("eval", "v/seed0/h1.05")):
        source = results / "benchmarks" / rule / f"{job}.tsv"
        copy = results / "benchmarks" / rule / f"{job.replace('v/', 'w/', 1)}.tsv"
        copy.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(source, copy)
    (results / "eval" / "w" / "seed0").mkdir(parents=True)
    (results / "eval" / "w" / "seed0" / "h1.05.csv").write_text("scenario_id,success\n0,1\n")
    monkeypatch.setattr(provenance, "this_machine", lambda: {"cpu": "New CPU", "vector_unit": None, "cores": 2})
    written = provenance.write_provenance("p", results, record)
    jobs = {(j["rule"], j["job"]): j for j in written["jobs"]}
    assert jobs[("eval", "w/seed0/h1.05")]["copy_of"] == "eval/v/seed0/h1.05"
    assert jobs[("train", "w/seed0")]["copy_of"] == "train/v/seed0"
    assert "copy_of" not in jobs[("eval", "v/seed0/h1.05")]
    assert jobs[("eval", "w/seed0/h1.05")]["machine"]["cpu"] == "Old CPU"  # where its source ran
    assert (written["jobs_counted"], written["jobs_copied"]) == (2, 2)
    assert written["wall_s_all_jobs_summed"] == 53.0 and sum(m["jobs"] for m in written["machines"]) == 2


def _tracked_files() -> list[str]:
    """The files git tracks in this checkout, relative to its root; skips the test without git or a checkout."""
    if shutil.which("git") is None:
        pytest.skip("git is not installed")
    top = subprocess.run(["git", "rev-parse", "--show-toplevel"], cwd=REPO, capture_output=True, text=True)
    if top.returncode != 0 or Path(top.stdout.strip()).resolve() != REPO:
        pytest.skip(f"{REPO} is not the root of a git checkout")
    listed = subprocess.run(["git", "ls-files", "-z"], cwd=REPO, capture_output=True, text=True, check=True)
    return [name for name in listed.stdout.split("\0") if name]


def test_every_tracked_file_stays_under_10_mb():
    """A stored result, figure or weight file over 10 MB is one git keeps in every clone for good: store it
    smaller (or leave it out of git) instead."""
    names = _tracked_files()
    assert names, "git lists no tracked file"
    sizes = {name: (REPO / name).stat().st_size for name in names
             if (REPO / name).is_file() and not (REPO / name).is_symlink()}
    over = sorted(((size, name) for name, size in sizes.items() if size >= TRACKED_FILE_LIMIT), reverse=True)
    assert not over, (f"{len(over)} tracked file(s) of {TRACKED_FILE_LIMIT / 2**20:g} MB or more: "
                      + "; ".join(f"{name} ({size / 2**20:.1f} MB, {size:,} bytes)" for size, name in over))

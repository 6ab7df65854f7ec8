"""The provenance record: a rewrite keeps what it does not recompute (the note), and every job names the
machine it ran on, where that is known."""

import json
from pathlib import Path

from egosearch.report import provenance


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

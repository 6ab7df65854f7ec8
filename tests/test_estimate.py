"""`egosearch estimate all`: the DAG's schedule from the stored record, scaled to a machine's rate."""

import json
from pathlib import Path

import pytest

from egosearch.cli import main
from egosearch.cli.estimate import estimate_all

REPO = Path(__file__).resolve().parent.parent
RECORD = REPO / "results" / "cpu" / "provenance.json"


@pytest.mark.skipif(not RECORD.exists(), reason="no stored cpu run")
def test_the_estimate_simulates_the_schedule_and_scales_trainings_to_the_machine(monkeypatch):
    monkeypatch.chdir(REPO)
    record = json.loads(RECORD.read_text())
    slow = estimate_all(record, RECORD.parent, 2, "cpu", rate=100.0)
    fast = estimate_all(record, RECORD.parent, 2, "cpu", rate=200.0)
    # waiting and imperfect packing: the schedule is never shorter than CPU time / cores
    assert slow["hours_as_recorded"] >= slow["hours_cpu_over_cores"]
    assert slow["hours_at_slowest_recorded_rate"] >= slow["hours_as_recorded"]
    assert fast["hours_here"] < slow["hours_here"]
    # the trainings, scaled, still dominate: the slowest jobs are trainings
    assert all(name.startswith("train/") for name, _ in fast["slowest_jobs_here"])
    one_core = estimate_all(record, RECORD.parent, 1, "cpu", rate=200.0)
    assert one_core["hours_here"] > fast["hours_here"]


def test_bad_estimate_inputs_are_one_line(capsys):
    assert main(["estimate", "all", "--cores", "0"]) == 2
    assert main(["estimate", "all", "--rate", "-5"]) == 2
    assert main(["estimate", "all", "--rate", "5", "--from-bench"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 3 and "--cores=0" in err and "--rate=-5" in err and "give one" in err

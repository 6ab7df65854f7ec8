"""A finished Snakemake run read back from its log, and the schedule check that sets it beside the
simulation of its own jobs (`egosearch estimate check`)."""

import json

import pytest

from egosearch.cli import main
from egosearch.cost.run_log import dag_id, read_run_log


def _start(stamp, rule, jobid, wildcards, benchmark=None):
    lines = [f"[{stamp}]", f"localrule {rule}:", "    input: a.csv", f"    jobid: {jobid}"]
    lines += [f"    benchmark: {benchmark}"] if benchmark else []
    lines += [f"    wildcards: {wildcards}"] if wildcards else []
    return lines + ["    resources: tmpdir=/tmp"]


def _finish(stamp, rule, jobid):
    return [f"[{stamp}]", f"Finished jobid: {jobid} (Rule: {rule})"]


def test_a_log_gives_each_jobs_start_and_end_and_the_runs_elapsed_time(tmp_path):
    bench = "results/p/benchmarks/eval/v/seed0/kitchen_living/everywhere/h1.05.tsv"
    text = "\n".join(
        ["  Command: snakemake --cores 2 all", "Provided cores: 2", "Execute 2 jobs..."]
        + _start("Fri Nov 27 07:58:54 2026", "evaluate", 42,
                 "preset=p, variant=v, seed=0, layout=kitchen_living, placement=everywhere, height=1.05", bench)
        + _start("Fri Nov 27 07:58:54 2026", "table2", 7, "preset=p")
        + _finish("Fri Nov 27 07:58:58 2026", "table2", 7)
        + _start("Fri Nov 27 07:58:59 2026", "provenance", 3, "")
        + _finish("Fri Nov 27 07:59:48 2026", "evaluate", 42)
        + ["1 of 3 steps (33%) done"])                                      # jobid 3 never finished
    (tmp_path / "run.log").write_text(text + "\n")
    log = read_run_log(tmp_path / "run.log")
    assert log.cores == 2 and log.command == "snakemake --cores 2 all"
    assert [(j.jobid, j.start, j.end) for j in log.finished()] == [(42, 0.0, 54.0), (7, 0.0, 4.0)]
    assert log.jobs[3].end is None and log.jobs[3].seconds is None and log.elapsed == 54.0
    assert dag_id(log.jobs[42], "p") == "eval/v/seed0/kitchen_living/everywhere/h1.05"   # the benchmark's key
    assert dag_id(log.jobs[7], "p") == "table2"                                          # rule and wildcards
    (tmp_path / "dry.log").write_text("Building DAG of jobs...\nJob stats:\n")
    with pytest.raises(ValueError, match="no finished job"):
        read_run_log(tmp_path / "dry.log")


def test_the_check_sets_a_run_beside_the_simulation_of_its_own_jobs(tmp_path, monkeypatch, capsys):
    """Three one-thread jobs of 60 s on 2 cores: the record predicts 2 min; the run took 3 min because two
    jobs ran 2 min each; its own times simulated give that back, and their sum / 2 is the old lower bound."""
    from egosearch.workflow.dag import dag_jobs

    jobs = [j for j in dag_jobs("table1", 2, {"preset": "smoke"}) if j.record_rule == "bound"][:3]
    assert len(jobs) == 3  # each reads a scenarios job's output, which the run did not make: left out
    lines = ["Provided cores: 2"]
    ends = ("08:01:00", "08:02:00", "08:03:00")
    starts = ("08:00:00", "08:00:00", "08:01:00")
    for n, (job, start) in enumerate(zip(jobs, starts)):
        wildcards = ", ".join(f"{k}={v}" for k, v in {"preset": "smoke", **job.wildcards}.items())
        lines += _start(f"Fri Nov 27 {start} 2026", "bound", n, wildcards,
                        f"results/smoke/benchmarks/{job.record_rule}/{job.job}.tsv")
    for n, end in sorted(enumerate(ends), key=lambda x: x[1]):
        lines += _finish(f"Fri Nov 27 {end} 2026", "bound", n)
    (tmp_path / "run.log").write_text("\n".join(lines) + "\n")
    record = {"jobs": [{"rule": j.record_rule, "job": j.job, "wall_s": 60.0} for j in jobs]}
    (tmp_path / "record.json").write_text(json.dumps(record))
    out = tmp_path / "check.json"
    asked = []
    monkeypatch.setattr("egosearch.cost.schedule_check.dag_jobs",
                        lambda target, cores, config: asked.append(config) or [])
    assert main(["estimate", "check", "--log", str(tmp_path / "run.log"), "--record", str(tmp_path / "record.json"),
                 "--target", "all", "--out", str(out)]) == 2
    assert "none of the 3 jobs it ran is in the DAG of `all` at the smoke preset" in capsys.readouterr().err
    assert asked == [{"preset": "smoke"}]                      # the run's own preset, read off its jobs
    monkeypatch.setattr("egosearch.cost.schedule_check.dag_jobs", lambda target, cores, config: jobs)
    assert main(["estimate", "check", "--log", str(tmp_path / "run.log"), "--record", str(tmp_path / "record.json"),
                 "--target", "table1", "--out", str(out)]) == 0
    figures = json.loads(out.read_text())
    assert figures["jobs"] == 3 and figures["elapsed_s"] == 180.0
    assert figures["predicted_s"] == 120.0 and figures["own_times_simulated_s"] == 180.0
    assert figures["own_times_over_cores_s"] == 150.0 and figures["machine"]["cores"] and figures["command"]
    assert main(["estimate", "all", "--log", "x.log"]) == 2 and main(["estimate", "check"]) == 2
    err = capsys.readouterr().err
    assert "--log is read by `estimate check` only" in err and "estimate check needs --log" in err

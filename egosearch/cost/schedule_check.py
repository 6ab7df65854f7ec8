"""The schedule simulation held to a finished run (``egosearch estimate check``): the jobs its Snakemake
log shows (:mod:`egosearch.cost.run_log`), laid out at a provenance record's times and at their own,
beside the run's elapsed time.
"""

from __future__ import annotations

import statistics
from dataclasses import replace
from pathlib import Path

from egosearch.cost.run_log import RunLog, dag_id, read_run_log
from egosearch.cost.schedule import durations_from_provenance, simulate
from egosearch.workflow.dag import dag_jobs


def run_preset(run_log: RunLog) -> str | None:
    """The preset the logged jobs ran at, read off their wildcards (every rule's paths hold it)."""
    named = [job.wildcards["preset"] for job in run_log.finished() if "preset" in job.wildcards]
    return statistics.mode(named) if named else None


def schedule_check(log_path: str | Path, record: dict, preset: str, target: str, cores: int,
                   record_path: str | Path = "the record", run_log: RunLog | None = None) -> dict:
    """A finished run against the simulation of its own jobs (:mod:`egosearch.cost.run_log`): the jobs
    the log says it ran, with their dependencies among them in ``target``'s DAG, laid out on the run's
    cores (``cores`` where the log does not say; its preset where its jobs name one, else ``preset``)
    at the wall times ``record`` held for them (what the
    estimate would have predicted), and at the wall times the run itself logged (the schedule's model
    alone); beside the elapsed time the log shows."""
    run = run_log or read_run_log(log_path)
    cores = run.cores or cores
    # the run's own preset where its jobs name it (every rule's paths hold the preset wildcard)
    preset = run_preset(run) or preset
    ran = {dag_id(job, preset): job for job in run.finished()}
    dag = dag_jobs(target, cores, config={"preset": preset})
    keep = {job.id for job in dag if job.id in ran}
    unknown = sorted(set(ran) - keep)
    if not keep:
        raise ValueError(f"{log_path}: none of the {len(ran)} jobs it ran is in the DAG of `{target}` at the "
                         f"{preset} preset: give the run's --target and --preset")
    jobs = [replace(job, deps=tuple(d for d in job.deps if d in keep)) for job in dag if job.id in keep]
    from_record = durations_from_provenance(record, jobs)
    predicted = simulate(jobs, cores, from_record)
    own = simulate(jobs, cores, {job.id: ran[job.id].seconds for job in jobs})
    elapsed = run.elapsed
    lines = [
        f"{Path(log_path).name}: {len(ran)} jobs finished on {cores} cores in {_minutes(elapsed)} "
        f"(first start to last end{'; ' + run.command if run.command else ''})",
        f"  predicted from {record_path}'s job times, simulated: {_minutes(predicted.makespan)} "
        f"({predicted.makespan / elapsed:.2f} x the run; {from_record.note()})" if elapsed else "",
        f"  the run's own job times, simulated: {_minutes(own.makespan)} ({own.makespan / elapsed:.2f} x the run: "
        "the schedule's model alone)" if elapsed else "",
        f"  the jobs' own times summed / {cores}: {_minutes(own.packing_bound)} (the old lower bound)",
    ]
    if unknown:
        lines.append(f"  {len(unknown)} logged jobs are not in the DAG of `{target}` and were left out: "
                     + ", ".join(unknown[:5]) + (" ..." if len(unknown) > 5 else ""))
    return {"log": str(log_path), "target": target, "preset": preset, "cores": cores, "jobs": len(jobs),
            "elapsed_s": elapsed, "predicted_s": predicted.makespan, "own_times_simulated_s": own.makespan,
            "own_times_over_cores_s": own.packing_bound, "record": str(record_path),
            "record_note": from_record.note(), "left_out": unknown, "lines": [line for line in lines if line]}


def _minutes(seconds: float) -> str:
    return f"{seconds / 60:.1f} min"

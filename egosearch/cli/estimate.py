"""``egosearch estimate all``: how long ``snakemake --cores N all`` takes from a fresh clone, on this
machine, from the stored run's job times laid out on N cores (:mod:`egosearch.report.schedule`).

The trainings dominate and their speed differs most between machines, so they are scaled to this
machine: a minute of the learner benchmark (``egosearch bench learner``'s short real training) gives
this machine's env steps per CPU-second, and the ratio between a stored training and the benchmark
on the same kind of machine turns that into a training's rate. Every other job keeps the wall time
the stored run recorded (evaluations and reports are a small share; the estimate says so).

``egosearch estimate check`` holds the simulation to a finished run: the jobs its Snakemake log shows, laid out
at the record's times and at their own, beside the run's elapsed time (:func:`schedule_check`).
"""

from __future__ import annotations

import contextlib
import difflib
import io
import json
import math
import os
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

from egosearch.cli.checks import read_json_object
from egosearch.core.machine import (
    cpu_model,
    cpu_seconds_all,
    cpu_vector_unit,
    measured_on,
    own_cpu_seconds,
    with_machine,
)
from egosearch.core.outputs import check_outputs, check_overwrites
from egosearch.report.data import counts_decisions
from egosearch.report.run_log import RunLog, dag_id, read_run_log
from egosearch.report.schedule import (
    TRAIN,
    durations_from_provenance,
    env_steps_of,
    machine_key,
    scale_to_rate,
    simulate,
)
from egosearch.report.workflow_jobs import job_cost_s, workflow_config, workflow_heights
from egosearch.rl.config import BODY_STEPS, DECISIONS, load_config
from egosearch.workflow.dag import dag_jobs, rule_names

CALIBRATION_CACHE = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "egosearch" / "learner_rate.json"
"""This machine's last calibration, so that ``snakemake all`` can print the estimate without a minute's wait."""


CHECK_ONLY = {"log": "--log", "record": "--record", "target": "--target"}
"""Options that ``estimate check`` reads and ``estimate all`` does not (and the reverse below)."""
ALL_ONLY = {"rate": "--rate", "from_bench": "--from-bench", "bench": "--bench"}

MAX_CORES = 1024
"""Most cores an estimate is made for: snakemake's ``--cores`` on one machine (the DAG has a few hundred
jobs; a larger figure is a typo, and the estimate would be the DAG's longest chain without a word)."""
RECORD_FILE = ("a provenance record is the JSON file `egosearch report provenance` writes "
               "(results/<profile>/provenance.json)")
BENCH_FILE = "a learner benchmark record is the JSON file `egosearch bench learner --out` writes"
BUSY_CORES = 0.25
"""Other processes' CPU use during a calibration (cores) above which the estimate says it was measured on
a busy machine: the calibration counts this process's CPU time, but shared caches and memory slow it."""


def run(args) -> None:
    args.out = with_machine(args.out)
    if args.cores < 1:
        raise ValueError(f"--cores={args.cores}: the estimate needs at least 1 core")
    if args.cores > MAX_CORES:
        raise ValueError(f"--cores={args.cores}: at most {MAX_CORES}, the cores of one machine snakemake schedules "
                         f"on (this one has {os.cpu_count()})")
    unread = ALL_ONLY if args.what == "check" else CHECK_ONLY
    for name, flag in unread.items():
        # `is not`: 0 equals False, so `--rate 0` would pass for an option not given
        if getattr(args, name) is not None and getattr(args, name) is not False:
            # an option the command never reads would leave a record that seems to say it was used
            raise ValueError(f"{flag} is read by `estimate {'all' if args.what == 'check' else 'check'}` only, not "
                             f"by `estimate {args.what}`")
    if args.what == "check" and not args.log:
        raise ValueError("estimate check needs --log: a finished run's .snakemake/log/<date>.snakemake.log")
    if args.rate is not None and not (args.rate > 0 and math.isfinite(args.rate)):
        raise ValueError(f"--rate={args.rate}: env steps per CPU-second must be a positive, finite number")
    if args.rate is not None and args.from_bench:
        raise ValueError("--rate and --from-bench both name the rate: give one")
    check_outputs(files={"--out": args.out})
    check_overwrites(files={"--out": args.out}, inputs={"--bench": args.bench, "--log": args.log,
                                                        "--record": args.record}, force=args.force)
    if args.what == "check":
        check_target(args.target)
        run_log = read_log(args.log)
        profile = checked_run_profile(args.log, run_log, args.profile)
    else:
        run_log, profile = None, args.profile or "cpu"
    results = Path("results") / profile
    record_path = Path(args.record) if args.record else results / "provenance.json"
    if not args.record and not record_path.is_file() and args.what == "check":
        raise FileNotFoundError(f"{record_path} not found: the jobs of {args.log} ran at the {profile} profile, and "
                                "the check judges them against that profile's recorded job times: give --record, a "
                                f"record of the {profile} profile")
    if not args.record and not record_path.is_file():
        raise FileNotFoundError(f"{record_path} not found: the estimate scales the stored run's job times "
                                "(run it in the project's root, at a profile with a stored run)")
    record = read_record("--record" if args.record else "the stored record", record_path)
    if not record.get("jobs"):
        # every job would be taken at 0 s: "about 0.0 h" (results/paper/ holds its GPU check, not a run)
        raise ValueError(f"{record_path} records no job's time: the {profile} profile has no stored run to "
                         "scale" + ("" if args.record else " (--profile cpu has one)"))
    if args.what == "check":
        if record.get("profile") not in (None, profile):
            raise ValueError(f"--record: {record_path} holds the {record['profile']} profile's job times, but the "
                             f"jobs of {args.log} ran at the {profile} profile: give a record of the {profile} "
                             "profile")
        figures = schedule_check(args.log, record, profile, args.target or "all", args.cores, record_path,
                                 run_log=run_log)
    else:
        figures = _estimate_all_here(args, record, results)
    for line in figures["lines"]:
        print(line)
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        # when, where and how: an estimate calibrated on one machine is that machine's (docs/speed.md's table)
        made = {"command": _command(args), **measured_on()}
        Path(args.out).write_text(json.dumps({**made, **figures}, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {args.out}", file=sys.stderr)
    if args.json:
        print(json.dumps({k: v for k, v in figures.items() if k != "lines"}))


def read_record(option: str, path: Path) -> dict:
    """The provenance record at ``path``: a JSON object whose ``jobs`` is a list of rows, each naming its
    ``rule`` and ``job`` (what the schedule reads)."""
    record = read_json_object(option, path, RECORD_FILE)
    jobs = record.get("jobs", [])
    if not isinstance(jobs, list) or not all(isinstance(row, dict) and "rule" in row and "job" in row
                                             for row in jobs):
        raise ValueError(f"{option}: {path} holds no list of jobs with their rule and job ('jobs'); {RECORD_FILE}")
    return record


def read_bench(option: str, path: Path) -> dict:
    """The learner benchmark record at ``path``: a JSON object whose ``result`` is an object."""
    bench = read_json_object(option, path, BENCH_FILE)
    if not isinstance(bench.get("result", {}), dict) or not isinstance(bench.get("machine", {}), dict):
        raise ValueError(f"{option}: {path} holds no benchmark result ('result' and 'machine' must be objects); "
                         f"{BENCH_FILE}")
    return bench


def read_log(path: str) -> RunLog:
    """``--log``: the finished run's Snakemake log."""
    if Path(path).is_dir():
        raise ValueError(f"--log: {path} is a folder; a Snakemake log is .snakemake/log/<date>.snakemake.log")
    if not Path(path).is_file():
        raise FileNotFoundError(f"--log: {path} not found; a Snakemake log is .snakemake/log/<date>.snakemake.log")
    try:
        return read_run_log(path)
    except ValueError as err:
        raise ValueError(f"--log: {err}") from None


def check_target(target: str | None) -> None:
    """``--target`` is a rule of the workflow: Snakemake otherwise fails with a traceback
    (``MissingRuleException``) once the DAG is built."""
    if target is None:
        return
    rules = rule_names()
    if target not in rules:
        close = difflib.get_close_matches(target, rules, n=1)
        hint = f" (did you mean {close[0]}?)" if close else ""
        raise ValueError(f"--target={target!r} is not a rule of the workflow{hint}; the run's target, e.g. all, "
                         "table1 or screen (`snakemake --list-target-rules` lists them)")


def run_profile(run_log: RunLog) -> str | None:
    """The profile the logged jobs ran at, read off their wildcards (every rule's paths hold it)."""
    named = [job.wildcards["profile"] for job in run_log.finished() if "profile" in job.wildcards]
    return statistics.mode(named) if named else None


def checked_run_profile(log_path: str, run_log: RunLog, asked: str | None) -> str:
    """The profile ``estimate check`` judges the run at: the one its jobs ran at, which ``--profile``, when
    given, must be (a run at another profile judged against this one's job times reads as a slow or fast
    run without a word), else ``--profile``, else cpu."""
    ran = run_profile(run_log)
    if asked and ran and asked != ran:
        raise ValueError(f"--profile={asked}: the jobs of {log_path} ran at the {ran} profile (their paths say so): "
                         f"leave --profile out, or give the log of a {asked} run")
    return ran or asked or "cpu"


def _estimate_all_here(args, record: dict, results: Path) -> dict:
    bench_path = Path(args.bench) if args.bench else results / "bench" / "learner.json"
    if args.bench or bench_path.is_file():
        bench = read_bench("--bench" if args.bench else "the stored learner benchmark", bench_path)
    else:
        bench = {}
    rate, how, where = args.rate, "given", "on this machine"
    if rate is None and args.from_bench:
        rate = bench.get("result", {}).get("env_steps_per_core_s_cpu_profile")
        if not rate:
            raise FileNotFoundError(f"--from-bench: {bench_path} holds no learner benchmark "
                                    "(egosearch bench learner --out writes one)")
        profile = args.profile or "cpu"
        if steps_of_bench(bench) != steps_of_profile(profile):
            raise ValueError(f"--from-bench: {bench_path} timed the cpu profile's {steps_of_bench(bench)}, but the "
                             f"{profile} profile's env steps are {steps_of_profile(profile)} "
                             "(egosearch bench learner --out times today's profile)")
        how = f"recorded in {bench_path}"
        where = f"on {machine_key(bench.get('machine'))}"
    busy = None
    if rate is None:
        print("calibrating: a short cpu-profile training (about a minute, as `egosearch bench learner` times) ...",
              file=sys.stderr, flush=True)
        rate, busy = calibrate()
        how = "measured now"
        where = f"on this machine ({machine_key(this_machine())})"
    figures = estimate_all(record, results, args.cores, args.profile or "cpu", rate=rate, rate_source=how,
                           bench=bench_path, where=where)
    if busy is not None:
        figures["other_load_cores_while_calibrating"] = busy
        if busy > BUSY_CORES:
            figures["lines"].insert(2, f"  the machine was busy while it calibrated: other processes used {busy:.1f} "
                                       "cores meanwhile, so the rate here may be low and the estimate long (calibrate "
                                       "again when it is idle)")
    return figures


def schedule_check(log_path: str | Path, record: dict, profile: str, target: str, cores: int,
                   record_path: str | Path = "the record", run_log: RunLog | None = None) -> dict:
    """A finished run against the simulation of its own jobs (:mod:`egosearch.report.run_log`): the jobs
    the log says it ran, with their dependencies among them in ``target``'s DAG, laid out on the run's
    cores (``cores`` where the log does not say; its profile where its jobs name one, else ``profile``)
    at the wall times ``record`` held for them (what the
    estimate would have predicted), and at the wall times the run itself logged (the schedule's model
    alone); beside the elapsed time the log shows."""
    run = run_log or read_run_log(log_path)
    cores = run.cores or cores
    # the run's own profile where its jobs name it (every rule's paths hold the profile wildcard)
    profile = run_profile(run) or profile
    ran = {dag_id(job, profile): job for job in run.finished()}
    dag = dag_jobs(target, cores, config={"profile": profile})
    keep = {job.id for job in dag if job.id in ran}
    unknown = sorted(set(ran) - keep)
    if not keep:
        raise ValueError(f"{log_path}: none of the {len(ran)} jobs it ran is in the DAG of `{target}` at the "
                         f"{profile} profile: give the run's --target and --profile")
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
    return {"log": str(log_path), "target": target, "profile": profile, "cores": cores, "jobs": len(jobs),
            "elapsed_s": elapsed, "predicted_s": predicted.makespan, "own_times_simulated_s": own.makespan,
            "own_times_over_cores_s": own.packing_bound, "record": str(record_path),
            "record_note": from_record.note(), "left_out": unknown, "lines": [line for line in lines if line]}


def _minutes(seconds: float) -> str:
    return f"{seconds / 60:.1f} min"


def _command(args) -> str:
    """The estimate's command as a user would type it again (what it was calibrated or given)."""
    # check without --profile judges the run at its own profile: the command says what was typed
    profile = args.profile or ("cpu" if args.what == "all" else None)
    words = ["egosearch estimate", args.what, f"--cores {args.cores}"] + ([f"--profile {profile}"] if profile else [])
    words += [f"--rate {args.rate:g}"] if args.rate is not None else []
    words += ["--from-bench"] if args.from_bench else []
    for flag, value in (("--bench", args.bench), ("--log", args.log), ("--record", args.record),
                        ("--target", args.target)):
        words += [f"{flag} {value}"] if value else []
    return " ".join(words + [f"--out {args.out}"])


def steps_of_profile(profile: str) -> str:
    """What an env step of ``profile``'s trainings counts (:data:`DECISIONS` at a modular searcher's
    profile, the cpu profile's since it became one; else :data:`BODY_STEPS`)."""
    return load_config(profile, {}).env_step_unit


def steps_of_bench(bench: dict) -> str:
    """What the learner benchmark's ``env_steps_per_core_s_cpu_profile`` counts (records made before the
    cpu profile became a modular searcher say nothing: body steps)."""
    return bench.get("result", {}).get("cpu_profile_steps", BODY_STEPS)


def stored_training_rates(record: dict, results: Path, steps_kind: str = BODY_STEPS) -> dict[str, float]:
    """Every stored training's env steps per CPU-second of its learner (lever screens too: one may share
    the learner benchmark's machine), by job key, of the trainings whose env step is ``steps_kind``
    (:data:`DECISIONS`: the modular searchers'). A training that learned from the classical searcher
    counts the CPU time of its RL phase only (its run's, less the teacher's episodes and the cloning that
    its ``done.json`` records); one that recorded no cloning time is left out: its env steps per
    CPU-second would mix the teacher's cost into the learner's rate."""
    jobs = [r for r in record.get("jobs", []) if r.get("rule") == TRAIN]
    steps = env_steps_of(results, [r["job"] for r in jobs])
    out = {}
    for row in jobs:
        outside = cpu_s_outside_rl(results / "train" / row["job"])
        if (row["job"] not in steps or outside is None
                or (DECISIONS if modular_run(results / "train" / row["job"]) else BODY_STEPS) != steps_kind):
            continue
        cost = job_cost_s(row) - outside
        if cost > 0:
            out[row["job"]] = steps[row["job"]] / cost
    return out


def cpu_s_outside_rl(run_dir: Path) -> float | None:
    """CPU seconds a training spent before its RL phase: 0 for one from scratch; for one that learned
    from the classical searcher (its config.json's ``demo_episodes``), its demonstrations' and its
    imitation's (cloning, DAgger) ``cpu_s`` from its ``done.json``, None when it recorded no imitation."""
    if not learned_from_teacher(run_dir):
        return 0.0
    try:
        done = json.loads((run_dir / "done.json").read_text(encoding="utf-8"))
        if "imitation" in done:
            imitation = float(done["imitation"]["cpu_s"])
        elif done["config"].get("bc_updates"):
            return None  # cloned before trainings recorded the cloning's time
        else:
            imitation = 0.0  # demonstrations in replay, no cloning
        return float(done["demonstrations"]["cpu_s"]) + imitation
    except (OSError, ValueError, KeyError):
        return None


def stored_cpu_s_per_step(record: dict, results: Path, steps_kind: str) -> float | None:
    """The median CPU seconds per env step of the stored trainings whose env step is ``steps_kind``, on
    whatever machines they ran, None when none is stored: the price of a variant whose steps the
    calibration (the profile's kind) does not measure."""
    rates = stored_training_rates(record, results, steps_kind)
    return statistics.median(1.0 / r for r in rates.values()) if rates else None


def modular_run(run_dir: Path) -> bool:
    """Whether the training in ``run_dir`` is a modular searcher's: one env step per decision."""
    return counts_decisions(run_dir / "curve.csv")


def learned_from_teacher(run_dir: Path) -> bool:
    """Whether the training in ``run_dir`` collected demonstrations (its config.json's ``demo_episodes``)."""
    try:
        return bool(json.loads((run_dir / "config.json").read_text(encoding="utf-8"))["config"].get("demo_episodes"))
    except (OSError, ValueError, KeyError):
        return False


def benchmark_ratio(record: dict, rates: dict[str, float], bench: dict,
                    steps_kind: str = BODY_STEPS) -> tuple[float, str] | None:
    """A stored training's rate over the learner benchmark's, on the same kind of machine (CPU and
    vector unit), and that machine; None when the record holds no training from the benchmark's machine,
    or the benchmark timed another kind of env step than ``rates`` count."""
    if steps_of_bench(bench) != steps_kind:
        return None
    machine = bench.get("machine", {})
    same = [rates[row["job"]] for row in record.get("jobs", [])
            if row.get("rule") == TRAIN and row.get("job") in rates and row.get("machine")
            and machine_key(row["machine"]) == machine_key(machine)]
    bench_rate = bench.get("result", {}).get("env_steps_per_core_s_cpu_profile")
    if not same or not bench_rate:
        return None
    return statistics.median(same) / float(bench_rate), machine_key(machine)


def this_machine() -> dict:
    """This machine as records name one: its CPU, vector unit and cores."""
    return {"cpu": cpu_model(), "vector_unit": cpu_vector_unit(), "cores": os.cpu_count()}


def calibrate() -> tuple[float, float | None]:
    """This machine's env steps per CPU-second in a short real cpu-profile training (~a minute),
    remembered in :data:`CALIBRATION_CACHE` for this machine, and the cores other processes kept busy
    meanwhile (as ``egosearch bench learner`` records it; None where the system does not say). The
    training's own lines (its evaluations, its config) are held back: the estimate is the answer."""
    # local: loads torch and the simulator, which an estimate from a given --rate never needs
    from egosearch.rl.bench import cpu_profile_run_steps, training_throughput

    busy0, own0, wall0 = cpu_seconds_all(), own_cpu_seconds(), time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        rate = float(training_throughput("cpu", env_steps=cpu_profile_run_steps())["env_steps_per_core_s"])
    wall, busy1, own = time.perf_counter() - wall0, cpu_seconds_all(), own_cpu_seconds() - own0
    other = (round(max(0.0, busy1 - busy0 - own) / wall, 2)
             if busy0 is not None and busy1 is not None and wall > 0 else None)
    try:
        CALIBRATION_CACHE.parent.mkdir(parents=True, exist_ok=True)
        CALIBRATION_CACHE.write_text(json.dumps({"machine": machine_key(this_machine()), "rate": rate,
                                                 "steps": steps_of_profile("cpu"), "other_load_cores": other}))
    except OSError:
        pass  # a read-only home: the next estimate calibrates again
    return rate, other


def cached_rate() -> float | None:
    """This machine's last calibration (None when it has none, it was another machine's, or it timed
    another kind of env step than the cpu profile's today)."""
    try:
        cached = json.loads(CALIBRATION_CACHE.read_text())
    except (OSError, ValueError):
        return None
    here = machine_key(this_machine())
    same = cached.get("machine") == here and cached.get("steps", BODY_STEPS) == steps_of_profile("cpu")
    return float(cached["rate"]) if same and cached.get("rate") else None


def print_costs(targets, config: dict, profile: str, seeds: list[int], reference: str, cores: int) -> None:
    """What ``snakemake`` prints before the first job of ``targets`` (the Snakefile's ``onstart``, and a
    dry run's start): `all`'s whole DAG from scratch, simulated on ``cores`` (:func:`print_before_a_run`),
    and a comparison's trainings and evaluations still to run (:func:`print_variant_cost`: every one of
    ``seeds`` for compare, ``screen_seed`` for screen). Where no estimate can be made, a line says why."""
    if "all" in targets:
        print_before_a_run(profile, cores)
    for target in ("compare", "screen"):
        if target in targets and config.get("variant"):
            chosen = seeds if target == "compare" else [config["screen_seed"]]
            print_variant_cost(profile, target, config["variant"], chosen, reference, cores)


def print_before_a_run(profile: str, cores: int) -> None:
    """What ``snakemake ... all`` prints before its first job (the Snakefile's ``onstart``): the
    estimate of the whole DAG from scratch, on this machine when it has been calibrated, else as the
    stored run recorded it, with the command that calibrates. Never stops the run."""
    record_path = Path("results") / profile / "provenance.json"
    if no_record(profile, record_path):
        print(f"(no estimate of the run's time: {no_record(profile, record_path)})", file=sys.stderr)
        return
    try:
        record = json.loads(record_path.read_text(encoding="utf-8"))
        rate = cached_rate()
        lines = estimate_all(record, record_path.parent, cores, profile, rate=rate,
                             rate_source="this machine's last calibration",
                             where=f"on this machine ({machine_key(this_machine())})")["lines"][:-2]
        if rate is None:
            lines.append(f"  for this machine: egosearch estimate all --cores {cores} --profile {profile} (a minute)")
    except (OSError, ValueError, RuntimeError, KeyError) as err:
        lines = [f"(no estimate of the run's time: {err})"]
    for line in lines:
        print(line, file=sys.stderr)


def no_record(profile: str, record_path: Path) -> str | None:
    """Why no estimate can be made at ``profile``, in words (it has no stored run to scale: no record, or
    one of no job, as the paper profile's GPU check); None when one can."""
    try:
        jobs = json.loads(record_path.read_text(encoding="utf-8")).get("jobs")
    except (OSError, ValueError, AttributeError):
        jobs = None
    if jobs:
        return None
    there = "records no job" if record_path.is_file() else "is not there"
    why = f"the {profile} profile has no stored run whose job times an estimate scales ({record_path} {there})"
    if profile == "smoke":
        why += "; a smoke run is plumbing only, minutes long"
    return why


def _hours(seconds: float) -> str:
    return f"{seconds / 3600:.1f} h"


def estimate_all(record: dict, results: Path, cores: int, profile: str, rate: float | None,
                 rate_source: str = "given", bench: str | Path | None = None, where: str = "on this machine") -> dict:
    """The simulated schedule of ``snakemake --cores <cores> all`` (fresh clone) as the stored run
    recorded it, with every training at the slowest recorded rate, and on a machine whose learner
    benchmark gives ``rate`` (left out when None). Returns the figures and the lines to print."""
    jobs = dag_jobs("all", cores, config={"profile": profile})
    stored = durations_from_provenance(record, jobs)
    kind = steps_of_profile(profile)
    all_rates = stored_training_rates(record, results, kind)
    rates = {j.job: all_rates[j.job] for j in jobs if j.record_rule == TRAIN and j.job in all_rates}
    as_recorded = simulate(jobs, cores, stored)
    slowest_rate = min(rates.values()) if rates else None
    at_slowest = simulate(jobs, cores, scale_to_rate(stored, rates, slowest_rate)) if rates else None
    in_dag = {(j.record_rule, j.job) for j in jobs}
    cpu_over_cores = sum(job_cost_s(r) for r in record.get("jobs", []) if (r["rule"], r["job"]) in in_dag) / cores
    bench_path = Path(bench) if bench else results / "bench" / "learner.json"
    ratio = (benchmark_ratio(record, all_rates, json.loads(bench_path.read_text()), kind)
             if bench_path.is_file() else None)
    k = ratio[0] if ratio else 1.0
    here = None
    if rate is not None:
        here = simulate(jobs, cores, scale_to_rate(stored, rates, k * rate)) if rates else as_recorded
    lines = [
        f"snakemake --cores {cores} all from a fresh clone, {profile} profile ({len(jobs)} jobs, simulated on "
        f"{cores} cores with snakemake's greedy rule):"]
    if here is not None:
        lines += [
            f"  {where}: about {_hours(here.makespan)} (learner benchmark {rate:.0f} {kind} per "
            f"CPU-second, {rate_source}"
            + (f"; a training runs at {k:.2f} x its benchmark, as on {ratio[1]} in the stored run" if ratio else
               "; no stored training shares the benchmark record's machine: trainings taken at the benchmark's rate")
            + ")",
            "  slowest jobs here: " + ", ".join(f"{name} {_hours(s)}" for name, s in here.slowest(5))]
    lines += [
        f"  as the stored run recorded it: {_hours(as_recorded.makespan)}"
        + (f"; every training at the slowest recorded rate ({slowest_rate:.0f} {kind} per CPU-second): "
           f"{_hours(at_slowest.makespan)}" if at_slowest else ""),
        f"  (the old figure, CPU time / {cores}: {_hours(cpu_over_cores)}, assumes perfect packing and no waiting)",
        "  " + stored.note() + " Only trainings are scaled to this machine.",
    ]
    return {"cores": cores, "profile": profile, "steps": kind, "hours_here": here.makespan / 3600 if here else None,
            "hours_as_recorded": as_recorded.makespan / 3600,
            "hours_at_slowest_recorded_rate": at_slowest.makespan / 3600 if at_slowest else None,
            "hours_cpu_over_cores": cpu_over_cores / 3600, "bench_rate": rate,
            "training_over_bench": k, "slowest_recorded_rate": slowest_rate,
            "slowest_jobs_here": here.slowest(5) if here else None, "rate_source": rate_source, "where": where,
            "recorded_training_rates": {job: round(r, 1) for job, r in sorted(rates.items())},
            "note": stored.note(), "lines": lines}


def print_variant_cost(profile: str, target: str, variant: str, seeds: list[int], reference: str,
                       cores: int) -> None:
    """What ``snakemake compare``/``screen`` prints before its first job: the trainings and evaluations
    of ``variant`` it still has to run (their files are missing), each at this machine's rate (its last
    calibration, else the stored learner benchmark's machine, said which), and the wall time on
    ``cores`` cores (one-thread jobs side by side). Never stops the run."""
    # local: the variants layer loads gymnasium's registry; only a comparison's start reads a variant
    from egosearch.variants import resolve_variant

    results = Path("results") / profile
    if no_record(profile, results / "provenance.json"):
        print(f"(no estimate of the {target}'s cost: {no_record(profile, results / 'provenance.json')})",
              file=sys.stderr)
        return
    try:
        record = json.loads((results / "provenance.json").read_text(encoding="utf-8"))
        bench_path = results / "bench" / "learner.json"
        bench = json.loads(bench_path.read_text(encoding="utf-8")) if bench_path.is_file() else {}
        kind = steps_of_profile(profile)
        ratio = benchmark_ratio(record, stored_training_rates(record, results, kind), bench, kind)
        rate, where = cached_rate(), "this machine (its last calibration)"
        if rate is None and steps_of_bench(bench) != kind:
            bench = {}  # it timed the profile before it became what it is
        if rate is None:
            rate = bench.get("result", {}).get("env_steps_per_core_s_cpu_profile")
            where = f"{machine_key(bench.get('machine'))} (the stored learner benchmark; `egosearch estimate all` " \
                    "calibrates this machine)"
        config_of_variant = resolve_variant(variant, profile).config
        steps = config_of_variant.total_env_steps
        trainings = [s for s in seeds if not (results / "train" / variant / f"seed{s}" / "done.json").exists()]
        evals = [r["wall_s"] for r in record.get("jobs", []) if r.get("rule") == "eval"]
        per_eval = statistics.median(evals) if evals else 0.0
        config = workflow_config()
        n_evals = sum(not (results / "eval" / variant / f"seed{s}" / home / placement / f"h{height}.csv").exists()
                      for s in seeds for home in config["homes"] for placement in config["placements"]
                      for height in workflow_heights(config))
        per_training = steps / ((ratio[0] if ratio else 1.0) * rate) if rate else float("nan")
        variant_kind = config_of_variant.env_step_unit
        if variant_kind != kind or not rate:
            # no calibration of this kind of env step: priced from the stored runs of its kind
            per_step = stored_cpu_s_per_step(record, results, variant_kind)
            per_training = steps * per_step if per_step else float("nan")
            where = f"the stored trainings' machines (their CPU time per env step, {variant_kind})"
        teacher = ""
        if config_of_variant.demo_episodes:
            # the rates above are the RL phase's: a training that learns from the classical searcher first
            # runs its episodes and clones them (training_time_line adds them the same way)
            extra = teacher_cost_s(config_of_variant, results, bench, rate) if rate else None
            if extra is not None:
                per_training += extra
                teacher = (f", of which about {extra / 3600:.1f} h the teacher's {config_of_variant.demo_episodes} "
                           "episodes and the cloning")
            else:
                teacher = (f", plus the teacher's {config_of_variant.demo_episodes} episodes and the cloning (no "
                           "stored measurement prices them)")
        hours = (math.ceil(len(trainings) / cores) * per_training + n_evals * per_eval / cores) / 3600
        print(f"{target} of {variant} against {reference}: {len(trainings)} training(s) of {steps} env steps, about "
              f"{per_training / 3600:.1f} h each on {where}{teacher}, and {n_evals} evaluations of about "
              f"{per_eval:.0f} s: about {hours:.1f} h on {cores} core(s)", file=sys.stderr)
    except (OSError, ValueError, KeyError, TypeError) as err:
        print(f"(no estimate of the {target}'s cost: {err})", file=sys.stderr)


def training_time_line(steps: int, profile: str, config=None) -> str | None:
    """What ``egosearch train`` says at its start: how long ``steps`` env steps take on this machine,
    from its last calibration (a cpu-profile training: None at other profiles, whose steps cost
    otherwise), and the command that makes one when it has none. With a ``config`` that learns from the
    classical searcher, the teacher's episodes and the cloning steps are added (:func:`teacher_cost_s`)."""
    if profile != "cpu":
        return None
    results = Path("results") / profile
    kind = steps_of_profile(profile)
    ratio, bench, record = None, {}, {}
    try:
        bench = json.loads((results / "bench" / "learner.json").read_text(encoding="utf-8"))
        record = json.loads((results / "provenance.json").read_text(encoding="utf-8"))
        ratio = benchmark_ratio(record, stored_training_rates(record, results, kind), bench, kind)
    except (OSError, ValueError, KeyError):
        pass
    if config is not None and config.env_step_unit != kind:
        # the calibration times the profile's kind of env step, not this training's
        other = BODY_STEPS if kind == DECISIONS else DECISIONS
        per_step = stored_cpu_s_per_step(record, results, other)
        line = (f"estimate: about {_hours(steps * per_step)} of CPU time for {steps} env steps ({other}), as the "
                "stored trainings of its kind ran on their machines" if per_step else
                f"estimate: none (no stored training's env steps are {other}, as this one's)")
        if getattr(config, "demo_episodes", 0):
            line += f", plus the teacher's {config.demo_episodes} episodes and the cloning (not priced here)"
        return line
    rate = cached_rate()
    if rate is None:
        return "estimate: this machine has no calibration yet (`egosearch estimate all` makes one in a minute)"
    k = ratio[0] if ratio else 1.0
    line = (f"estimate: about {_hours(steps / (k * rate))} of CPU time for {steps} env steps on this machine "
            f"(calibrated at {rate:.0f} {kind} per CPU-second"
            + (f", a training at {k:.2f} x that as in the stored run" if ratio else "") + ")")
    if config is not None and getattr(config, "demo_episodes", 0):
        extra = teacher_cost_s(config, results, bench, rate)
        line += (f", plus about {_hours(extra)} for the teacher's {config.demo_episodes} episodes and the cloning"
                 if extra is not None else
                 f", plus the teacher's {config.demo_episodes} episodes and the cloning (no stored measurement)")
    return line


def teacher_cost_s(config, results: Path, bench: dict, rate: float) -> float | None:
    """CPU seconds of a training's imitation phase on a machine calibrated at ``rate``: its demonstration
    episodes and its DAgger rounds' episodes at the stored trainings' measured CPU-s per demonstration
    episode (their ``done.json``), and its cloning steps (``bc_updates`` after the demonstrations and after
    each DAgger round) at the learner benchmark's update rate; all
    scaled from the benchmark's machine to this one by the two calibrations. None without a measurement."""
    per_episode = [d["demonstrations"]["cpu_s"] / d["demonstrations"]["episodes"]
                   for d in _stored_done(results) if d.get("demonstrations", {}).get("episodes")]
    updates_per_s = bench.get("result", {}).get("updates_per_s_cpu_profile")
    bench_rate = bench.get("result", {}).get("env_steps_per_core_s_cpu_profile")
    if not per_episode or not updates_per_s or not bench_rate:
        return None
    cloning = config.bc_updates * (1 + config.dagger_rounds) / updates_per_s
    dagger = config.dagger_rounds * config.dagger_episodes * statistics.median(per_episode)
    return (config.demo_episodes * statistics.median(per_episode) + dagger + cloning) * bench_rate / rate


def _stored_done(results: Path) -> list[dict]:
    out = []
    for path in sorted(results.glob("train/*/seed*/done.json")):
        try:
            out.append(json.loads(path.read_text(encoding="utf-8")))
        except (OSError, ValueError):
            continue
    return out

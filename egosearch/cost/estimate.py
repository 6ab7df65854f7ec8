"""How long ``snakemake --cores N all`` takes from a fresh clone, on this machine, from the stored run's job
times laid out on N cores (:mod:`egosearch.cost.schedule`); what a comparison's or a screen's trainings
and evaluations still cost; how long one training takes here. ``egosearch estimate all`` prints the
first, the Snakefile's ``onstart`` (and a dry run) all of them before the first job, ``egosearch train``
the last at its start.

The trainings dominate and their speed differs most between machines, so they are scaled to this
machine: a minute of the learner benchmark (``egosearch bench learner``'s short real training,
:mod:`egosearch.cost.calibration`) gives this machine's env steps per CPU-second, and the ratio between a
stored training and the benchmark on the same kind of machine (:mod:`egosearch.cost.rates`) turns that
into a training's rate. Every other job keeps the wall time the stored run recorded (evaluations and
reports are a small share; the estimate says so).
"""

from __future__ import annotations

import json
import math
import statistics
import sys
from pathlib import Path

from egosearch.core.gpu_share import warn_gpu_sharing
from egosearch.cost.calibration import cached_busy_line, cached_rate, this_machine
from egosearch.cost.rates import (
    benchmark_ratio,
    cpu_s_outside_rl,
    steps_of_bench,
    steps_of_profile,
    stored_cpu_s_per_step,
    stored_training_rates,
    teacher_cost_s,
)
from egosearch.cost.schedule import (
    TRAIN,
    durations_from_provenance,
    env_steps_of,
    machine_key,
    simulate,
    trainings_at_rate,
)
from egosearch.report.workflow_jobs import job_cost_s, workflow_config, workflow_heights
from egosearch.rl.config import BODY_STEPS, DECISIONS
from egosearch.workflow.dag import dag_jobs


def print_costs(targets, config: dict, profile: str, seeds: list[int], reference: str, cores: int | None,
                trainings_per_gpu: int = 1) -> None:
    """What ``snakemake`` prints before the first job of ``targets`` (the Snakefile's ``onstart``, and a
    dry run's start): `all`'s whole DAG from scratch, simulated on ``cores`` (:func:`print_before_a_run`),
    and a comparison's trainings and evaluations still to run (:func:`print_variant_cost`: every one of
    ``seeds`` for compare; for screen ``screen_seeds`` seeds from ``screen_seed`` and the reference's
    missing spread seeds, then the screen's power, :func:`print_screen_power`). Where no estimate can be
    made, a line says why:
    ``cores`` None (a cluster executor's run, which lays its jobs out itself) has no schedule to simulate.
    First, once, where paper-profile trainings share one GPU (``trainings_per_gpu`` > 1): whether they do
    under CUDA MPS, and what running without it costs (:func:`egosearch.core.gpu_share.warn_gpu_sharing`)."""
    warn_gpu_sharing(profile, trainings_per_gpu)
    if cores is None:
        if "all" in targets or ({"compare", "screen"} & set(targets) and config.get("variant")):
            print("(no estimate of the cost: a cluster executor's run lays its jobs out itself, on no cores of this "
                  "machine to simulate)", file=sys.stderr)
        return
    if "all" in targets:
        print_before_a_run(profile, cores)
    for target in ("compare", "screen"):
        if target in targets and config.get("variant"):
            if target == "compare":
                print_variant_cost(profile, target, config["variant"], seeds, reference, cores)
                continue
            chosen = list(range(config["screen_seed"], config["screen_seed"] + config.get("screen_seeds", 1)))
            spread = config["profiles"][profile].get("spread_seeds", seeds)
            print_variant_cost(profile, target, config["variant"], chosen, reference, cores,
                               reference_seeds=spread)
            print_screen_power(profile, reference, len(chosen))


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
        elif cached_busy_line():
            lines.append(f"  {cached_busy_line()}")
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
    # At a rate, each job on a core of its own (what --cores N gives a one-thread job): its CPU time,
    # and a training its env steps at the rate plus its imitation phase. The record's wall times keep
    # the waits of its own runs, which shared the cores with more than the DAG's jobs.
    own_cores = durations_from_provenance(record, jobs, own_cores=True)
    kind = steps_of_profile(profile)
    all_rates = stored_training_rates(record, results, kind)
    rates = {j.job: all_rates[j.job] for j in jobs if j.record_rule == TRAIN and j.job in all_rates}
    steps = env_steps_of(results, rates)
    before_rl = {job: cpu_s_outside_rl(results / "train" / job) for job in rates}
    before_rl = {job: s for job, s in before_rl.items() if s is not None}
    as_recorded = simulate(jobs, cores, stored)
    slowest_rate = min(rates.values()) if rates else None
    at_slowest_durations = trainings_at_rate(own_cores, steps, before_rl, slowest_rate) if rates else None
    at_slowest = simulate(jobs, cores, at_slowest_durations) if rates else None
    in_dag = {(j.record_rule, j.job) for j in jobs}
    cpu_over_cores = sum(job_cost_s(r) for r in record.get("jobs", []) if (r["rule"], r["job"]) in in_dag) / cores
    bench_path = Path(bench) if bench else results / "bench" / "learner.json"
    ratio = (benchmark_ratio(record, all_rates, json.loads(bench_path.read_text()), kind)
             if bench_path.is_file() else None)
    k = ratio[0] if ratio else 1.0
    here = None
    if rate is not None:
        here = (simulate(jobs, cores, trainings_at_rate(own_cores, steps, before_rl, k * rate)) if rates
                else as_recorded)
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
        "  as recorded: " + stored.note(),
        *(["  at a rate: " + at_slowest_durations.note() + " Only trainings are scaled to this machine."]
          if at_slowest_durations else []),
    ]
    return {"cores": cores, "profile": profile, "steps": kind, "hours_here": here.makespan / 3600 if here else None,
            "hours_as_recorded": as_recorded.makespan / 3600,
            "hours_at_slowest_recorded_rate": at_slowest.makespan / 3600 if at_slowest else None,
            "hours_cpu_over_cores": cpu_over_cores / 3600, "bench_rate": rate,
            "training_over_bench": k, "slowest_recorded_rate": slowest_rate,
            "slowest_jobs_here": here.slowest(5) if here else None, "rate_source": rate_source, "where": where,
            "recorded_training_rates": {job: round(r, 1) for job, r in sorted(rates.items())},
            "note": stored.note(), "lines": lines}


def print_screen_power(profile: str, reference: str, n_seeds: int) -> None:
    """What ``snakemake -n screen`` prints after its cost: the smallest success difference a screen of
    ``n_seeds`` seeds detects at 1.05 m (80% power, 5% level before Holm) at the reference's stored seed spread
    (``results/<profile>/compare/seed_spread_<reference>.json``, from ``snakemake seed_spread``)."""
    from egosearch.report.null_screen import POWER_CELL, detectable_from_summary

    path = Path("results") / profile / "compare" / f"seed_spread_{reference}.json"
    if not path.is_file():
        print(f"(no power line: {path} is not there; `snakemake --cores 2 seed_spread` measures the seed spread)",
              file=sys.stderr)
        return
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
        detectable = detectable_from_summary(summary, n_seeds)
        print(f"a screen of {n_seeds} seed(s) against {reference}'s {summary['n_seeds']} spread seeds detects a "
              f"success difference of {detectable:.3f} at {POWER_CELL[0]} m with 80% power (seed sd "
              f"{summary['pooled_seed_sd']:.3f}; the recommended screen_seeds={summary['recommended_screen_seeds']} "
              f"detects {summary['detectable_at_recommended']:.3f}; {path})", file=sys.stderr)
    except (OSError, ValueError, KeyError) as err:
        print(f"(no power line: {path}: {err})", file=sys.stderr)


def print_variant_cost(profile: str, target: str, variant: str, seeds: list[int], reference: str,
                       cores: int, reference_seeds: list[int] = ()) -> None:
    """What ``snakemake compare``/``screen`` prints before its first job: the trainings and evaluations
    of ``variant`` it still has to run (their files are missing), and of ``reference`` on
    ``reference_seeds`` (a screen's spread seeds) where those are missing, each at this machine's rate (its
    last calibration, else the stored learner benchmark's machine, said which), and the wall time on
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
        runs = [(variant, s) for s in seeds] + [(reference, s) for s in reference_seeds]
        trainings = [(v, s) for v, s in runs if not (results / "train" / v / f"seed{s}" / "done.json").exists()]
        evals = [r["wall_s"] for r in record.get("jobs", []) if r.get("rule") == "eval"]
        per_eval = statistics.median(evals) if evals else 0.0
        config = workflow_config()
        n_evals = sum(not (results / "eval" / v / f"seed{s}" / home / placement / f"h{height}.csv").exists()
                      for v, s in runs for home in config["homes"] for placement in config["placements"]
                      for height in workflow_heights(config))
        of_reference = sum(v == reference for v, _ in trainings)
        counted = f" ({of_reference} of them the reference's spread seeds)" if of_reference else ""
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
        print(f"{target} of {variant} against {reference}: {len(trainings)} training(s){counted} of {steps} env "
              f"steps, about "
              f"{per_training / 3600:.1f} h each on {where}{teacher}, and {n_evals} evaluations of about "
              f"{per_eval:.0f} s: about {hours:.1f} h on {cores} core(s)", file=sys.stderr)
        if where.startswith("this machine") and cached_busy_line():
            print(f"  {cached_busy_line()}", file=sys.stderr)
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
    if cached_busy_line():
        line += f"; {cached_busy_line()}"
    return line

"""How long ``snakemake --cores N all`` takes from a fresh clone, on this machine, from the stored run's job
times laid out on N cores (:mod:`egosearch.cost.schedule`); what the plan of a run (its DAG's jobs still to
run, a comparison's or a screen's trainings and evaluations, the reference's included) costs; how long one
training takes here. ``egosearch estimate all`` prints the first, the Snakefile's ``onstart`` (and a dry
run, once its DAG is built) the second before the first job, ``egosearch train`` the last at its start.

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
    steps_of_preset,
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
from egosearch.report.workflow_jobs import job_cost_s
from egosearch.rl.config import BODY_STEPS, DECISIONS
from egosearch.rl.training_aids import demonstration_settings
from egosearch.workflow.dag import dag_jobs


def print_costs(targets, config: dict, preset: str, seeds: list[int], reference: str, cores: int | None,
                trainings_per_gpu: int = 1, plan: list | None = None, whole: bool = False) -> None:
    """What ``snakemake`` prints before the first job of ``targets`` (the Snakefile's ``onstart``, and a
    dry run once its DAG is built): the cost of ``plan``, the jobs this invocation runs (as
    :func:`egosearch.workflow.dag.plan_jobs` reads them from its DAG), every one of them counted by rule as
    Snakemake's job stats count them, trainings priced at this machine's rate and the other jobs at their
    recorded times (:func:`print_plan_cost`); for `all` from scratch (``whole``: the plan is the whole DAG,
    nothing stored or all forced) the simulated schedule of ``egosearch estimate all`` instead
    (:func:`print_before_a_run`); for a screen then its power (:func:`print_screen_power`). An empty plan
    prints nothing (Snakemake says "Nothing to be done"). Where no estimate can be made, a line says why:
    ``cores`` None (a cluster executor's run, which lays its jobs out itself) has no schedule to simulate.
    First, once, where paper-preset trainings share one GPU (``trainings_per_gpu`` > 1): whether they do
    under CUDA MPS, and what running without it costs (:func:`egosearch.core.gpu_share.warn_gpu_sharing`).
    ``seeds`` is the preset's (what a comparison trains), kept for callers; the plan says what runs."""
    warn_gpu_sharing(preset, trainings_per_gpu)
    if plan is not None and not plan:
        return
    variant = config.get("variant")
    if cores is None:
        if "all" in targets or ({"compare", "screen"} & set(targets) and variant):
            print("(no estimate of the cost: a cluster executor's run lays its jobs out itself, on no cores of this "
                  "machine to simulate)", file=sys.stderr)
        return
    if plan is None:
        return
    if "all" in targets and whole:
        print_before_a_run(preset, cores)
    elif "all" in targets or ({"compare", "screen"} & set(targets) and variant) or any(
            job_rule(j) not in UNPRICED_RULES for j in plan):
        target = next((t for t in ("screen", "compare") if t in targets and variant), None)
        what = f"{target} of {variant} against {reference}" if target else " ".join(sorted(map(str, targets)))
        cost = f"the {target}'s cost" if target else "the run's time"
        print_plan_cost(what, plan, preset, cores, reference, cost_name=cost,
                        scenarios_per_cell=scenarios_per_cell_of(config))
    if "screen" in targets and variant:
        chosen = list(range(config["screen_seed"], config["screen_seed"] + config.get("screen_seeds", 1)))
        print_screen_power(preset, reference, len(chosen))


def scenarios_per_cell_of(config: dict) -> dict[str, int]:
    """Each budget preset's scenarios per Table 1 cell, from the workflow config (none it does not give)."""
    return {name: budget["scenarios_per_cell"] for name, budget in (config.get("presets") or {}).items()
            if isinstance(budget, dict) and "scenarios_per_cell" in budget}


PRICED_FROM = {"smoke": "cpu"}
"""A preset that stores no run (a smoke run's results are git-ignored: plumbing only) -> the preset whose stored
run prices its plan: its trainings at this machine's rate for their own env steps and teacher (the smoke config's,
capped: :func:`egosearch.rl.config.load_variant_config`), its other jobs at that run's times scaled by the
scenarios a cell has at each preset."""

JOB_START_S = 3.0
"""CPU seconds an ``egosearch`` job spends before its work (importing torch, pybullet and the package): 2.8 CPU-s
measured on the 2-core reference machine (AMD EPYC, AVX-512). A job priced from another preset's run keeps it
whole, however few its scenarios or env steps: at smoke sizes it is most of a job."""

IN_MINUTES = ("smoke",)
"""Presets whose cost line gives minutes, not hours: a smoke run is minutes long."""

UNPRICED_RULES = ("all", "provenance")
"""Rules of no cost of their own (a target's inputs, the record): a plan of these alone prints no cost line."""


def job_rule(job) -> str:
    """A plan job's rule (a :class:`egosearch.workflow.dag.DagJob`, or its dict)."""
    return job["rule"] if isinstance(job, dict) else job.rule


def _wildcards(job) -> dict:
    return (job.get("wildcards") if isinstance(job, dict) else getattr(job, "wildcards", None)) or {}


def plan_counts(plan: list) -> dict[str, int]:
    """The plan's jobs per rule, as Snakemake's "Job stats" table counts them, its total under ``total``."""
    counts: dict[str, int] = {}
    for job in plan:
        counts[job_rule(job)] = counts.get(job_rule(job), 0) + 1
    return {**dict(sorted(counts.items())), "total": len(plan)}


def print_before_a_run(preset: str, cores: int) -> None:
    """What ``snakemake ... all`` prints before its first job (the Snakefile's ``onstart``): the
    estimate of the whole DAG from scratch, on this machine when it has been calibrated, else as the
    stored run recorded it, with the command that calibrates. Never stops the run."""
    record_path = Path("results") / preset / "provenance.json"
    if no_record(preset, record_path):
        print(f"(no estimate of the run's time: {no_record(preset, record_path)})", file=sys.stderr)
        return
    try:
        record = json.loads(record_path.read_text(encoding="utf-8"))
        rate = cached_rate()
        lines = estimate_all(record, record_path.parent, cores, preset, rate=rate,
                             rate_source="this machine's last calibration",
                             where=f"on this machine ({machine_key(this_machine())})")["lines"][:-2]
        if rate is None:
            lines.append(f"  for this machine: egosearch estimate all --cores {cores} --preset {preset} (a minute)")
        elif cached_busy_line():
            lines.append(f"  {cached_busy_line()}")
    except (OSError, ValueError, RuntimeError, KeyError) as err:
        lines = [f"(no estimate of the run's time: {err})"]
    for line in lines:
        print(line, file=sys.stderr)


def no_record(preset: str, record_path: Path) -> str | None:
    """Why no estimate can be made at ``preset``, in words (it has no stored run to scale: no record, or
    one of no job, as the paper preset's GPU check); None when one can."""
    try:
        jobs = json.loads(record_path.read_text(encoding="utf-8")).get("jobs")
    except (OSError, ValueError, AttributeError):
        jobs = None
    if jobs:
        return None
    there = "records no job" if record_path.is_file() else "is not there"
    why = f"the {preset} preset has no stored run whose job times an estimate scales ({record_path} {there})"
    if preset == "smoke":
        why += "; a smoke run is plumbing only, minutes long"
    return why


def _hours(seconds: float) -> str:
    return f"{seconds / 3600:.1f} h"


def _minutes(seconds: float) -> str:
    return f"{seconds / 60:.1f} min"


def estimate_all(record: dict, results: Path, cores: int, preset: str, rate: float | None,
                 rate_source: str = "given", bench: str | Path | None = None, where: str = "on this machine") -> dict:
    """The simulated schedule of ``snakemake --cores <cores> all`` (fresh clone) as the stored run
    recorded it, with every training at the slowest recorded rate, and on a machine whose learner
    benchmark gives ``rate`` (left out when None). Returns the figures and the lines to print."""
    jobs = dag_jobs("all", cores, config={"preset": preset})
    stored = durations_from_provenance(record, jobs)
    # At a rate, each job on a core of its own (what --cores N gives a one-thread job): its CPU time,
    # and a training its env steps at the rate plus its imitation phase. The record's wall times keep
    # the waits of its own runs, which shared the cores with more than the DAG's jobs.
    own_cores = durations_from_provenance(record, jobs, own_cores=True)
    kind = steps_of_preset(preset)
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
        f"snakemake --cores {cores} all from a fresh clone, {preset} preset ({len(jobs)} jobs, simulated on "
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
    return {"cores": cores, "preset": preset, "steps": kind, "hours_here": here.makespan / 3600 if here else None,
            "hours_as_recorded": as_recorded.makespan / 3600,
            "hours_at_slowest_recorded_rate": at_slowest.makespan / 3600 if at_slowest else None,
            "hours_cpu_over_cores": cpu_over_cores / 3600, "bench_rate": rate,
            "training_over_bench": k, "slowest_recorded_rate": slowest_rate,
            "slowest_jobs_here": here.slowest(5) if here else None, "rate_source": rate_source, "where": where,
            "recorded_training_rates": {job: round(r, 1) for job, r in sorted(rates.items())},
            "note": stored.note(), "lines": lines}


def print_screen_power(preset: str, reference: str, n_seeds: int) -> None:
    """What ``snakemake -n screen`` prints after its cost: the smallest success difference a screen of
    ``n_seeds`` seeds detects at 1.05 m (80% power, 5% level before Holm) at the reference's stored seed spread
    (``results/<preset>/compare/seed_spread_<reference>.json``, from ``snakemake seed_spread``)."""
    from egosearch.report.null_screen import POWER_CELL, detectable_from_summary

    path = Path("results") / preset / "compare" / f"seed_spread_{reference}.json"
    if not path.is_file():
        print(f"(no power line: {path} is not there; `snakemake --cores 2 seed_spread` measures the seed spread)",
              file=sys.stderr)
        return
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
        detectable = detectable_from_summary(summary, n_seeds)
        print(f"a screen of {n_seeds} seed(s) against {reference}'s {summary['n_seeds']} spread seeds detects a "
              f"success difference of {detectable:.3f} at {POWER_CELL[0]} m with 80% power (one seed's mean spreads "
              f"by sd {summary['power_cell_seed_mean_sd']:.3f} there; the recommended "
              f"screen_seeds={summary['recommended_screen_seeds']} detects {summary['detectable_at_recommended']:.3f}; "
              f"{path})", file=sys.stderr)
    except (OSError, ValueError, KeyError) as err:
        print(f"(no power line: {path}: {err})", file=sys.stderr)


class _Pricing:
    """How this machine's trainings are priced, read once per cost line: the calibrated rate (this machine's
    last calibration, else the stored learner benchmark's machine's, said which), the stored trainings'
    ratio to the benchmark, and the record and benchmark the teacher's cost reads."""

    def __init__(self, preset: str, results: Path, record: dict):
        bench_path = results / "bench" / "learner.json"
        self.bench = json.loads(bench_path.read_text(encoding="utf-8")) if bench_path.is_file() else {}
        self.preset, self.results, self.record = preset, results, record
        self.kind = steps_of_preset(preset)
        self.ratio = benchmark_ratio(record, stored_training_rates(record, results, self.kind), self.bench, self.kind)
        self.rate, self.where = cached_rate(), "this machine (its last calibration)"
        if self.rate is None and steps_of_bench(self.bench) != self.kind:
            self.bench = {}  # it timed the preset before it became what it is
        if self.rate is None:
            self.rate = self.bench.get("result", {}).get("env_steps_per_core_s_cpu_profile")
            self.where = (f"{machine_key(self.bench.get('machine'))} (the stored learner benchmark; `egosearch "
                          "estimate all` calibrates this machine)")

    def training(self, variant: str) -> tuple[float, str, str, int]:
        """One training of ``variant`` at this preset: (CPU seconds, on what machine's rate, what its
        teacher's phase adds in words, its env steps)."""
        # local: the variants layer loads gymnasium's registry; only a cost line with trainings reads a variant
        from egosearch.variants import resolve_variant

        config = resolve_variant(variant, self.preset).config
        steps, rate, where = config.total_env_steps, self.rate, self.where
        seconds = steps / ((self.ratio[0] if self.ratio else 1.0) * rate) if rate else float("nan")
        if config.env_step_unit != self.kind or not rate:
            # no calibration of this kind of env step: priced from the stored runs of its kind
            per_step = stored_cpu_s_per_step(self.record, self.results, config.env_step_unit)
            seconds = steps * per_step if per_step else float("nan")
            where = f"the stored trainings' machines (their CPU time per env step, {config.env_step_unit})"
        teacher = ""
        if demonstration_settings(config).demo_episodes:  # a learner without demonstrations: the aid's default
            # the rates above are the RL phase's: a training that learns from the classical searcher first
            # runs its episodes and clones them (training_time_line adds them the same way)
            extra = teacher_cost_s(config, self.results, self.bench, rate) if rate else None
            if extra is not None:
                seconds += extra
                teacher = f"the teacher's {config.demo_episodes} episodes and the cloning"
                span = _minutes if self.preset in IN_MINUTES else _hours
                teacher = f", of which about {span(extra)} {teacher}"
            else:
                teacher = (f", plus the teacher's {config.demo_episodes} episodes and the cloning (no stored "
                           "measurement prices them)")
        return seconds, where, teacher, steps


def print_plan_cost(what: str, plan: list, preset: str, cores: int, reference: str,
                    cost_name: str = "the run's time", scenarios_per_cell: dict[str, int] | None = None) -> None:
    """The cost line of a plan (the jobs a run or dry run will run: :func:`egosearch.workflow.dag.plan_jobs`),
    opened by ``what``: its jobs per rule as Snakemake's job stats count them; its trainings, those of
    ``reference`` counted apart, each at this machine's rate (:class:`_Pricing`); its evaluations at the
    record's time; and the plan laid out on ``cores`` cores (:func:`egosearch.cost.schedule.simulate`, every
    other job at its recorded time or its rule's median). Never stops the run.

    A preset without a stored run of its own (:data:`PRICED_FROM`: smoke) is priced from another's: its
    trainings at their own (capped) config, every other job at that run's time scaled by ``scenarios_per_cell``
    (each preset's, the workflow config's), and the line says so; at :data:`IN_MINUTES` presets, in minutes."""
    source = preset
    if (no_record(preset, Path("results") / preset / "provenance.json") and preset in PRICED_FROM
            and not no_record(PRICED_FROM[preset], Path("results") / PRICED_FROM[preset] / "provenance.json")):
        source = PRICED_FROM[preset]
    results = Path("results") / source
    if no_record(preset, results / "provenance.json"):
        print(f"(no estimate of {cost_name}: {no_record(preset, results / 'provenance.json')})", file=sys.stderr)
        return
    span = _minutes if preset in IN_MINUTES else _hours
    cells = scenarios_per_cell or {}
    # an evaluation's (and a scenario set's) time grows with its scenarios; without both counts, taken as recorded
    other_scale = cells[preset] / cells[source] if source != preset and preset in cells and source in cells \
        else 1.0
    try:
        record = json.loads((results / "provenance.json").read_text(encoding="utf-8"))
        durations = dict(durations_from_provenance(record, plan))
        if source != preset:
            untimed = {_job_id(j) for j in plan if job_rule(j) in UNPRICED_RULES}
            durations = {job: s if job in untimed or not s else JOB_START_S + max(s - JOB_START_S, 0.0) * other_scale
                         for job, s in durations.items()}
        trainings = [j for j in plan if job_rule(j) == "train"]
        evaluations = [j for j in plan if job_rule(j) == "evaluate"]
        pricing = _Pricing(preset, results, record) if trainings else None
        prices = {}
        for job in trainings:
            variant = _wildcards(job)["variant"]
            if variant not in prices:
                prices[variant] = pricing.training(variant)
                if source != preset:
                    prices[variant] = (prices[variant][0] + JOB_START_S, *prices[variant][1:])
            durations[_job_id(job)] = prices[variant][0]
        priced = all(math.isfinite(p[0]) for p in prices.values())
        counts = plan_counts(plan)
        parts = [f"{len(plan)} job{'s' if len(plan) != 1 else ''} to run ("
                 + ", ".join(f"{n} {rule}" for rule, n in counts.items() if rule != "total") + ")"]
        if trainings:
            of_reference = sum(_wildcards(j).get("variant") == reference for j in trainings)
            spans_each = list(dict.fromkeys(span(s) for s in sorted(p[0] for p in prices.values()
                                                                    if math.isfinite(p[0]))))
            steps = " or ".join(str(n) for n in sorted({p[3] for p in prices.values()}))
            wheres = list(dict.fromkeys(p[1] for p in prices.values()))
            teachers = list(dict.fromkeys(p[2] for p in prices.values() if p[2]))
            each = (spans_each[0] if len(spans_each) == 1 else
                    f"{spans_each[0].split()[0]} to {spans_each[-1]}" if spans_each else "an unknown time")
            each += "" if priced else " (no calibration, and no stored training of its kind of env step, prices it)"
            parts.append(f"{len(trainings)} training(s)"
                         + (f" ({of_reference} of them {reference}'s, the reference's)" if of_reference else "")
                         + f" of {steps} env steps, about {each} each on {' and '.join(wheres)}"
                         + (teachers[0] if len(teachers) == 1 else ""))
        if evaluations:
            per_eval = statistics.median(durations[_job_id(j)] for j in evaluations)
            of_reference = sum(_wildcards(j).get("variant") == reference for j in evaluations)
            parts.append(f"{len(evaluations)} evaluations"
                         + (f" ({of_reference} of them {reference}'s)" if of_reference else "")
                         + f" of about {per_eval:.0f} s")
        total = (f"about {span(simulate(plan, cores, durations).makespan)} on {cores} core(s)" if priced else
                 f"its time on {cores} core(s) unknown")
        if source != preset:
            total += (f" (the {preset} preset stores no run: priced from the {source} preset's, its other jobs "
                      f"at {other_scale:g} x their recorded time for {cells.get(preset, '?')} scenarios a cell, "
                      f"each job's {JOB_START_S:g} s start kept whole)")
        print(f"{what}: " + ", ".join(parts) + f": {total}", file=sys.stderr)
        if pricing is not None and any(p[1].startswith("this machine") for p in prices.values()) \
                and cached_busy_line():
            print(f"  {cached_busy_line()}", file=sys.stderr)
    except (OSError, ValueError, KeyError, TypeError) as err:
        print(f"(no estimate of {cost_name}: {err})", file=sys.stderr)


def _job_id(job) -> str:
    return job["id"] if isinstance(job, dict) else job.id


def training_time_line(steps: int, preset: str, config=None) -> str | None:
    """What ``egosearch train`` says at its start: how long ``steps`` env steps take on this machine,
    from its last calibration (a cpu-preset training: None at other presets, whose steps cost
    otherwise), and the command that makes one when it has none. With a ``config`` that learns from the
    classical searcher, the teacher's episodes and the cloning steps are added (:func:`teacher_cost_s`)."""
    if preset != "cpu":
        return None
    results = Path("results") / preset
    kind = steps_of_preset(preset)
    ratio, bench, record = None, {}, {}
    try:
        bench = json.loads((results / "bench" / "learner.json").read_text(encoding="utf-8"))
        record = json.loads((results / "provenance.json").read_text(encoding="utf-8"))
        ratio = benchmark_ratio(record, stored_training_rates(record, results, kind), bench, kind)
    except (OSError, ValueError, KeyError):
        pass
    if config is not None and config.env_step_unit != kind:
        # the calibration times the preset's kind of env step, not this training's
        other = BODY_STEPS if kind == DECISIONS else DECISIONS
        per_step = stored_cpu_s_per_step(record, results, other)
        line = (f"estimate: about {_hours(steps * per_step)} of CPU time for {steps} env steps ({other}), as the "
                "stored trainings of its kind ran on their machines" if per_step else
                f"estimate: none (no stored training's env steps are {other}, as this one's)")
        if demonstration_settings(config).demo_episodes:
            line += f", plus the teacher's {config.demo_episodes} episodes and the cloning (not priced here)"
        return line
    rate = cached_rate()
    if rate is None:
        return "estimate: this machine has no calibration yet (`egosearch estimate all` makes one in a minute)"
    k = ratio[0] if ratio else 1.0
    line = (f"estimate: about {_hours(steps / (k * rate))} of CPU time for {steps} env steps on this machine "
            f"(calibrated at {rate:.0f} {kind} per CPU-second"
            + (f", a training at {k:.2f} x that as in the stored run" if ratio else "") + ")")
    if config is not None and demonstration_settings(config).demo_episodes:
        extra = teacher_cost_s(config, results, bench, rate)
        line += (f", plus about {_hours(extra)} for the teacher's {config.demo_episodes} episodes and the cloning"
                 if extra is not None else
                 f", plus the teacher's {config.demo_episodes} episodes and the cloning (no stored measurement)")
    if cached_busy_line():
        line += f"; {cached_busy_line()}"
    return line

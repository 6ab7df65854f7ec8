"""How long ``snakemake --cores N <target>`` takes: its DAG's jobs, each at its recorded duration,
laid out on N cores the way Snakemake's scheduler starts them.

Data in, numbers out: the jobs come from :func:`egosearch.workflow.dag.dag_jobs` (or any list of
dicts or objects with its fields), the durations from a provenance record. No Snakemake here.

How close to Snakemake (``snakemake/scheduling/``): each time jobs finish (and at the start),
Snakemake selects among the ready jobs (every dependency done) those to start on the free cores.
Its default ``--scheduler ilp`` maximises the summed priority of the started jobs first, then the
cores they use, then how many temp files they let it delete; when the solver fails it falls back to
``greedy`` (Akcay, Li and Xu's multidimensional knapsack heuristic), which takes the ready job of
highest reward (priority, then bytes of temp input files, then bytes of all input files) while it
fits, then the next, skipping those that do not fit. :func:`simulate` is that greedy rule with
Snakemake's job id as the last tie-break. Where it differs:

- The ILP is indifferent among selections of equal priority that use as many cores: with every job
  of this workflow at one thread and priority 0, any ready jobs that fill the free cores are
  optimal, and which the solver returns is its own (job order inside a Python set). The greedy order
  simulated is one of those optimal selections, not necessarily the one a run makes.
- Input sizes are those on disk when the DAG was read (a fresh clone: the stored results, about the
  sizes a new run writes), not those at the moment a job becomes ready.
- A job takes its recorded wall time whatever runs beside it: no slowdown from sharing memory
  bandwidth beyond what the record's own runs saw, no start-up latency between jobs. With
  ``own_cores`` it takes its recorded CPU time instead: a core of its own, none of the record's waits.
"""

from __future__ import annotations

import copy
import csv
import heapq
import math
import random
import statistics
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from egosearch.report.workflow_jobs import job_cost_s

TRAIN = "train"
"""The provenance rule (benchmark folder) of the learner-bound jobs that ``scale`` multiplies."""
UNTIMED_RULES = ("report",)
"""Provenance rules whose jobs missing from a record count 0 s (seconds each) instead of a median."""


@dataclass(frozen=True)
class SimJob:
    """A job as the simulation reads it: the fields of :class:`egosearch.workflow.dag.DagJob`."""

    id: str
    rule: str
    threads: int = 1
    deps: tuple[str, ...] = ()
    order: int = 0
    priority: float = 0
    input_bytes: int = 0
    temp_input_bytes: int = 0
    record_rule: str | None = None
    job: str | None = None


def _get(job, name: str, default=None):
    return job.get(name, default) if isinstance(job, Mapping) else getattr(job, name, default)


def as_jobs(jobs: Iterable) -> list[SimJob]:
    """The jobs as :class:`SimJob`: from DagJobs, dicts (``DagJob.as_dict()``, JSON) or SimJobs.
    ``order`` defaults to the position in ``jobs``; ``rule`` to the id's first folder."""
    out = []
    for i, job in enumerate(jobs):
        ident = str(_get(job, "id"))
        out.append(SimJob(id=ident, rule=str(_get(job, "rule") or ident.split("/")[0]),
                          threads=int(_get(job, "threads", 1) or 1), deps=tuple(_get(job, "deps", ()) or ()),
                          order=int(i if _get(job, "order") is None else _get(job, "order")),
                          priority=_get(job, "priority", 0) or 0, input_bytes=int(_get(job, "input_bytes", 0) or 0),
                          temp_input_bytes=int(_get(job, "temp_input_bytes", 0) or 0),
                          record_rule=_get(job, "record_rule"), job=_get(job, "job")))
    return out


@dataclass
class Schedule:
    """Where each job ran in time on ``cores`` cores. ``critical_path`` is the chain that set the
    makespan, back from the last job to finish: each link is the dependency that finished last
    before the next started or, where a job waited for cores, the job whose end freed them.
    ``longest_chain`` is the longest chain of dependencies alone (the makespan with unlimited cores)."""

    cores: int
    makespan: float
    start: dict[str, float]
    end: dict[str, float]
    duration: dict[str, float]
    threads: dict[str, int]
    rules: dict[str, str]
    critical_path: list[str]
    longest_chain: list[str]

    @property
    def core_seconds(self) -> float:
        """Summed duration x threads: what the jobs occupy."""
        return sum(self.duration[j] * self.threads[j] for j in self.duration)

    @property
    def packing_bound(self) -> float:
        """Core-seconds / cores: the makespan if the jobs packed the cores perfectly."""
        return self.core_seconds / self.cores

    @property
    def longest_chain_s(self) -> float:
        """Length of :attr:`longest_chain`: the makespan with as many cores as jobs."""
        return sum(self.duration[j] for j in self.longest_chain)

    @property
    def lower_bound(self) -> float:
        """No schedule on these cores is shorter than this: the packing bound or the longest chain."""
        return max(self.packing_bound, self.longest_chain_s)

    @property
    def utilisation(self) -> float:
        """Share of the cores' time (cores x makespan) the jobs used."""
        return self.core_seconds / (self.cores * self.makespan) if self.makespan > 0 else 1.0

    def slowest(self, n: int = 5) -> list[tuple[str, float]]:
        """The ``n`` longest jobs as (id, seconds), longest first."""
        return sorted(self.duration.items(), key=lambda kv: (-kv[1], kv[0]))[:n]

    def rows(self) -> list[dict]:
        """One dict per job (id, rule, threads, start, end, duration), in order of start."""
        return [{"id": j, "rule": self.rules[j], "threads": self.threads[j], "start": self.start[j],
                 "end": self.end[j], "duration": self.duration[j]}
                for j in sorted(self.start, key=lambda j: (self.start[j], self.end[j], j))]


def simulate(jobs: Iterable, cores: int, durations: Mapping[str, float] | None = None, *,
             input_sizes: bool = True, tie_break: Mapping[str, float] | None = None) -> Schedule:
    """Lay ``jobs`` out on ``cores`` cores as Snakemake's greedy scheduler would (module docstring):
    at time 0 and whenever jobs finish, go through the ready jobs by (priority, temp input bytes,
    input bytes, Snakemake's job id) and start each whose threads fit in the free cores. A job asking
    more threads than ``cores`` gets ``cores`` (as ``--cores`` resolves it). Each job takes
    ``durations[id]`` seconds (default: its own ``duration`` field). ``input_sizes=False`` leaves the
    bytes out (the ILP's objective has none without temp files); ``tie_break`` (id -> key) replaces
    the job id as the last key (:func:`spread` draws it at random). Raises ValueError on a dependency
    that is not a job, a duration missing, or a cycle."""
    if cores < 1:
        raise ValueError(f"cores must be at least 1, not {cores}")
    raw = list(jobs)
    sim = as_jobs(raw)
    by_id = {j.id: j for j in sim}
    if len(by_id) != len(sim):
        raise ValueError("job ids are not unique")
    if durations is None:
        durations = {j.id: _get(r, "duration") for j, r in zip(sim, raw)}
    duration = {}
    for j in sim:
        d = durations.get(j.id)
        if d is None or not math.isfinite(float(d)) or float(d) < 0:
            raise ValueError(f"no usable duration for job {j.id!r}: {d!r}")
        duration[j.id] = float(d)
    threads = {j.id: min(max(j.threads, 1), cores) for j in sim}
    # greedy's reward (priority, temp input bytes, input bytes), highest first; then the tie-break
    rank = {j.id: (-j.priority, -j.temp_input_bytes if input_sizes else 0, -j.input_bytes if input_sizes else 0,
                   j.order if tie_break is None else tie_break[j.id], j.order) for j in sim}
    waiting = {}
    dependents: dict[str, list[str]] = {j.id: [] for j in sim}
    for j in sim:
        unknown = [d for d in j.deps if d not in by_id]
        if unknown:
            raise ValueError(f"job {j.id!r} depends on {unknown[0]!r}, which is not a job")
        waiting[j.id] = set(j.deps)
        for d in waiting[j.id]:
            dependents[d].append(j.id)
    ready = [j.id for j in sim if not waiting[j.id]]
    running: list[tuple[float, int, str]] = []
    start: dict[str, float] = {}
    end: dict[str, float] = {}
    free, now = cores, 0.0
    while True:
        ready.sort(key=rank.__getitem__)
        left = []
        for i in ready:
            if threads[i] <= free:
                free -= threads[i]
                start[i] = now
                heapq.heappush(running, (now + duration[i], by_id[i].order, i))
            else:
                left.append(i)
        ready = left
        if not running:
            break
        now = running[0][0]
        while running and running[0][0] == now:
            _, _, i = heapq.heappop(running)
            end[i] = now
            free += threads[i]
            for k in dependents[i]:
                waiting[k].discard(i)
                if not waiting[k]:
                    ready.append(k)
    if len(end) != len(sim):
        stuck = sorted(set(by_id) - set(end))
        raise ValueError(f"{len(stuck)} jobs never became ready (a dependency cycle?), e.g. {stuck[0]!r}")
    makespan = max(end.values(), default=0.0)
    return Schedule(cores=cores, makespan=makespan, start=start, end=end, duration=duration, threads=threads,
                    rules={j.id: j.rule for j in sim}, critical_path=_critical_path(sim, start, end),
                    longest_chain=_longest_chain(sim, duration))


def spread(jobs: Iterable, cores: int, durations: Mapping[str, float] | None = None, runs: int = 200,
           seed: int = 0) -> list[float]:
    """Makespans of ``runs`` simulations in which jobs of equal priority start in a random order and
    input sizes count for nothing, sorted: the range the default ILP scheduler spans, whose choice
    among selections that fill the cores alike is the solver's (module docstring)."""
    raw = list(jobs)
    sim = as_jobs(raw)
    if durations is None:
        durations = {j.id: _get(r, "duration") for j, r in zip(sim, raw)}
    rng = random.Random(seed)
    return sorted(simulate(sim, cores, durations, input_sizes=False,
                           tie_break={j.id: rng.random() for j in sim}).makespan for _ in range(runs))


def _critical_path(sim: list[SimJob], start: dict, end: dict) -> list[str]:
    if not end:
        return []
    by_end: dict[float, list[str]] = {}
    for i, t in end.items():
        by_end.setdefault(t, []).append(i)
    order = {j.id: j.order for j in sim}
    deps = {j.id: j.deps for j in sim}
    # the last to finish; among ties the longest, so that a zero-second job at the end (``all``)
    # does not hide what it waited for
    current = max(end, key=lambda i: (end[i], end[i] - start[i], -order[i]))
    path = [current]
    while start[current] > 0:
        t = start[current]
        released = [d for d in deps[current] if end[d] == t]
        # a dependency that finished at its start released it; otherwise it waited for a core
        candidates = released or [i for i in by_end.get(t, []) if i != current]
        if not candidates:
            break
        current = max(candidates, key=lambda i: (end[i] - start[i], -order[i]))
        path.append(current)
    return path[::-1]


def _longest_chain(sim: list[SimJob], duration: Mapping[str, float]) -> list[str]:
    by_id = {j.id: j for j in sim}
    best: dict[str, tuple[float, str | None]] = {}

    def visit(i: str) -> float:
        # iterative post-order: a DAG of thousands of jobs would overflow recursion
        stack = [i]
        while stack:
            k = stack[-1]
            if k in best:
                stack.pop()
                continue
            todo = [d for d in by_id[k].deps if d not in best]
            if todo:
                stack.extend(todo)
                continue
            prev = max(by_id[k].deps, key=lambda d: best[d][0], default=None)
            best[k] = (duration[k] + (best[prev][0] if prev is not None else 0.0), prev)
            stack.pop()
        return best[i][0]

    if not sim:
        return []
    last = max((j.id for j in sim), key=lambda i: (visit(i), -by_id[i].order))
    chain = []
    while last is not None:
        chain.append(last)
        last = best[last][1]
    return chain[::-1]


@dataclass
class Durations(Mapping):
    """Seconds per DAG job id, and where each came from: ``from_record`` (the record's row),
    ``missing`` (a benchmark the record lacks: its rule's median, or 0 s for report rules),
    ``untimed`` (no benchmark, e.g. ``all`` and ``provenance``: 0 s), ``scaled`` (factor applied to
    each scaled job) and ``unscaled`` (trainings a rate scaling could not place)."""

    seconds: dict[str, float]
    from_record: list[str] = field(default_factory=list)
    missing: list[str] = field(default_factory=list)
    untimed: list[str] = field(default_factory=list)
    scaled: dict[str, float] = field(default_factory=dict)
    unscaled: list[str] = field(default_factory=list)
    cpu_time: bool = False
    """Whether the record's jobs are timed by their CPU time (each on a core of its own) rather than
    their wall time."""
    at_rate: list[str] = field(default_factory=list)
    """Trainings timed by their env steps at a rate and their imitation phase (:func:`trainings_at_rate`)."""

    def __getitem__(self, key: str) -> float:
        return self.seconds[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self.seconds)

    def __len__(self) -> int:
        return len(self.seconds)

    def trainings(self) -> list[str]:
        """The ids of the training jobs (``train/<variant>/seed<k>``)."""
        return [ident for ident in self.seconds if ident.startswith(TRAIN + "/")]

    def note(self) -> str:
        """One sentence on what the durations rest on, for the estimate to say."""
        parts = [f"{len(self.from_record)} of {len(self.seconds)} jobs timed by the record "
                 + ("(CPU time: each on a core of its own)" if self.cpu_time else "(wall time)")]
        if self.at_rate:
            parts.append(f"{len(self.at_rate)} trainings at the rate (env steps / rate + their imitation phase)")
        if self.missing:
            parts.append(f"{len(self.missing)} not in the record, at their rule's median")
        if self.untimed:
            parts.append(f"{len(self.untimed)} without a benchmark, at 0 s")
        if self.scaled:
            factors = sorted(set(round(f, 3) for f in self.scaled.values()))
            parts.append(f"{len(self.scaled)} scaled (x{factors[0]:g}" + (f" to x{factors[-1]:g})" if len(factors) > 1
                                                                           else ")"))
        if self.unscaled:
            parts.append(f"{len(self.unscaled)} trainings left unscaled (no rate for their machine)")
        return "; ".join(parts) + "."


def _record_seconds(row: Mapping) -> float:
    # a resumed training's benchmark timed its last part; run_wall_s is the whole run's wall time
    run_wall = row.get("run_wall_s")
    return float(run_wall) if run_wall is not None else float(row["wall_s"])


def durations_from_provenance(record: Mapping, jobs: Iterable, scale: float | None = None,
                              other_scale: float = 1.0, own_cores: bool = False) -> Durations:
    """Each DAG job's duration from a provenance record (``results/<preset>/provenance.json``): the
    wall time of the record's row with the job's (rule, job) key, the whole run's (``run_wall_s``)
    for a resumed training. Wall time, not CPU time: the time a user waits, as the record's runs
    spent it (a job that shared its core counts its waits). ``scale`` multiplies the learner-bound
    jobs (provenance rule ``train``: a machine measured that much slower, > 1, or faster, < 1, at
    training than the one that made the record); ``other_scale`` every other timed job. A DAG job
    the record lacks gets the median of its rule's jobs found in the record (of the record's jobs of
    that rule when the DAG has none there), 0 s for report rules; a job without a benchmark 0 s.
    The result says which (``missing``, ``untimed``; :meth:`Durations.note`).

    ``own_cores``: each job at its CPU time instead (:func:`job_cost_s`), what it takes on a core of
    its own, as ``snakemake --cores N`` gives each one-thread job. The record's wall times count the
    waits of its own runs, which shared two cores with more work than the DAG's (several snakemake
    runs at once, tests), waits a fresh ``snakemake --cores 2 all`` does not have."""
    sim = as_jobs(jobs)
    seconds_of = job_cost_s if own_cores else _record_seconds
    rows = {(r["rule"], r["job"]): seconds_of(r) for r in record.get("jobs", [])}
    out = Durations(seconds={}, cpu_time=own_cores)
    found: dict[str, list[float]] = {}
    for j in sim:
        if j.record_rule is None:
            out.seconds[j.id] = 0.0
            out.untimed.append(j.id)
        elif (j.record_rule, j.job) in rows:
            out.seconds[j.id] = rows[(j.record_rule, j.job)]
            out.from_record.append(j.id)
            found.setdefault(j.rule, []).append(out.seconds[j.id])
    by_record_rule: dict[str, list[float]] = {}
    for (rule, _), seconds in rows.items():
        by_record_rule.setdefault(rule, []).append(seconds)
    for j in sim:
        if j.id in out.seconds:
            continue
        pool = [] if j.record_rule in UNTIMED_RULES else found.get(j.rule) or by_record_rule.get(j.record_rule, [])
        out.seconds[j.id] = statistics.median(pool) if pool else 0.0
        out.missing.append(j.id)
    for j in sim:
        if j.id in out.untimed:
            continue
        factor = (scale if scale is not None else 1.0) if j.record_rule == TRAIN else other_scale
        if factor != 1.0:
            out.seconds[j.id] *= factor
            out.scaled[j.id] = factor
    return out


def env_steps_of(results: str | Path, train_jobs: Iterable[str]) -> dict[str, int]:
    """Env steps each stored training ran (job key such as ``head_on/seed0`` -> steps), from the
    last row of ``<results>/train/<job>/curve.csv``; a training without one is left out."""
    out = {}
    for job in train_jobs:
        try:
            with open(Path(results) / "train" / job / "curve.csv", newline="") as f:
                rows = list(csv.DictReader(f))
            out[job] = int(float(rows[-1]["env_steps"]))
        except (OSError, IndexError, KeyError, ValueError):
            continue
    return out


def training_rates(record: Mapping, env_steps: Mapping[str, int]) -> dict[str, float]:
    """Env steps per CPU-second of each stored training in ``env_steps`` (job key -> steps): its
    steps over its whole run's CPU time (the benchmark's ``cpu_s``, scaled to the whole run by wall
    time for a resumed one: :func:`egosearch.report.workflow_jobs.job_cost_s`). CPU time rather than
    the curve's ``steps_per_s``: wall time counts the waits of a training that shared its core, and
    ``egosearch bench learner`` reports core-seconds too. Trainings the record lacks are left out."""
    out = {}
    for row in record.get("jobs", []):
        if row.get("rule") == TRAIN and row.get("job") in env_steps:
            cost = job_cost_s(row)
            if cost > 0:
                out[row["job"]] = env_steps[row["job"]] / cost
    return out


def machine_key(machine: Mapping | None) -> str:
    """A machine as one string (``AMD EPYC / AVX-512 / 2 cores``; ``?`` for what it did not record,
    ``unknown`` without a machine): the keys of ``rate_by_machine``."""
    if not machine:
        return "unknown"
    cores = machine.get("cores")
    return f"{machine.get('cpu') or '?'} / {machine.get('vector_unit') or '?'} / {cores or '?'} cores"


def machine_rates(record: Mapping, rates: Mapping[str, float]) -> dict[str, float]:
    """The median rate (:func:`training_rates`) of the trainings each machine of ``record`` ran,
    keyed by :func:`machine_key` (``unknown`` for trainings recorded without one)."""
    groups: dict[str, list[float]] = {}
    for row in record.get("jobs", []):
        if row.get("rule") == TRAIN and row.get("job") in rates:
            groups.setdefault(machine_key(row.get("machine")), []).append(rates[row["job"]])
    return {key: statistics.median(values) for key, values in groups.items()}


def trainings_at_rate(durations: Durations, steps_by_job: Mapping[str, int],
                      before_rl_s_by_job: Mapping[str, float], rate: float) -> Durations:
    """Each training of ``durations`` whose job is in ``steps_by_job`` and ``before_rl_s_by_job`` (job
    key -> its env steps; the CPU seconds of its imitation phase, demonstrations and cloning) timed as
    ``steps / rate + before_rl`` on a core of its own; the others go to ``unscaled``. Unlike
    :func:`scale_to_rate` nothing of the record's wall time stays, waits included."""
    if rate <= 0:
        raise ValueError(f"rate must be positive, not {rate}")
    out = copy.deepcopy(durations)
    for ident in out.trainings():
        job = ident[len(TRAIN) + 1:]
        if job in steps_by_job and job in before_rl_s_by_job:
            out.seconds[ident] = steps_by_job[job] / rate + before_rl_s_by_job[job]
            out.at_rate.append(ident)
        else:
            out.unscaled.append(ident)
    return out


def scale_to_rate(durations: Durations, rate_by_job: Mapping[str, float], target_rate: float) -> Durations:
    """Each training in ``rate_by_job`` (job key -> env steps per CPU-second it ran at) at
    ``target_rate`` instead: its duration times rate / target (wall time taken to scale with CPU
    time). Other jobs as they were; trainings of the durations without a rate go to ``unscaled``."""
    if target_rate <= 0:
        raise ValueError(f"target_rate must be positive, not {target_rate}")
    out = copy.deepcopy(durations)
    for ident in out.trainings():
        rate = rate_by_job.get(ident[len(TRAIN) + 1:])
        if rate is None or rate <= 0:
            out.unscaled.append(ident)
            continue
        factor = rate / target_rate
        if factor != 1.0:
            out.seconds[ident] *= factor
            out.scaled[ident] = out.scaled.get(ident, 1.0) * factor
    return out


def scale_trainings(durations: Durations, jobs_record: Iterable[Mapping], rate_by_machine: Mapping[str, float],
                    target_rate: float) -> Durations:
    """Each training at the rate of a target machine: a training's duration times the rate of the
    machine it ran on (``rate_by_machine[machine_key(its machine)]``) over ``target_rate``.
    ``jobs_record`` is a record's ``jobs`` (each training may name its ``machine``). Both rates must
    be measured alike: for "the slowest host of the stored run", ``machine_rates`` of the stored
    trainings and its minimum; for "a host where ``egosearch bench learner`` gives R", the bench's
    rate on the recording machine and R (a short bench run is faster per step than a whole training,
    so never mix the two). Trainings whose machine has no rate are left as they are (``unscaled``)."""
    rate_by_job = {}
    for row in jobs_record:
        if row.get("rule") == TRAIN:
            rate = rate_by_machine.get(machine_key(row.get("machine")))
            if rate is not None:
                rate_by_job[row["job"]] = rate
    return scale_to_rate(durations, rate_by_job, target_rate)

"""What the stored run says a training costs: each stored training's env steps per CPU-second of its
learner (its RL phase alone when it learned from the classical searcher first), the ratio between those
and the learner benchmark on the same kind of machine, and the CPU time of a training's imitation phase.

The estimate (:mod:`egosearch.cost.estimate`) scales the stored run's trainings to a machine with them;
what an env step counts (body steps, or a modular searcher's decisions) keeps rates of different kinds
apart.
"""

from __future__ import annotations

import json
import statistics
from pathlib import Path

from egosearch.cost.schedule import TRAIN, env_steps_of, machine_key
from egosearch.report.data import counts_decisions
from egosearch.report.workflow_jobs import job_cost_s
from egosearch.rl.config import BODY_STEPS, DECISIONS, field_defaults, load_config


def steps_of_preset(preset: str) -> str:
    """What an env step of ``preset``'s trainings counts (:data:`DECISIONS` at a modular searcher's
    preset, the cpu preset's while it was one; else :data:`BODY_STEPS`, every preset's today)."""
    return load_config(preset, {}).env_step_unit


def steps_of_bench(bench: dict) -> str:
    """What the learner benchmark's ``env_steps_per_core_s_cpu_profile`` counts (records made before the
    cpu preset became a modular searcher say nothing: body steps)."""
    return bench.get("result", {}).get("cpu_profile_steps", BODY_STEPS)


def stored_training_rates(record: dict, results: Path, steps_kind: str = BODY_STEPS) -> dict[str, float]:
    """Every stored training's env steps per CPU-second of its learner (lever screens too: one may share
    the learner benchmark's machine), by job key, of the trainings whose env step is ``steps_kind``
    (:data:`DECISIONS`: the modular searchers'). A training that learned from the classical searcher
    counts the CPU time of its RL phase only (its run's, less the teacher's episodes and the cloning that
    its ``done.json`` records, a cloning it did not time priced as :func:`cpu_s_outside_rl` says); one
    whose cloning cannot be priced is left out: its env steps per CPU-second would mix the teacher's cost
    into the learner's rate."""
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
    imitation's (cloning, DAgger) ``cpu_s`` from its ``done.json``. A run that cloned before trainings
    recorded the cloning's time gets its cloning steps at the median CPU-s per cloning step of the runs
    stored beside it that recorded theirs (:func:`cloning_cpu_s_per_update`); None when none did."""
    if not learned_from_teacher(run_dir):
        return 0.0
    try:
        done = json.loads((run_dir / "done.json").read_text(encoding="utf-8"))
        if "imitation" in done:
            imitation = float(done["imitation"]["cpu_s"])
        elif done["config"].get("bc_updates"):
            per_update = cloning_cpu_s_per_update(run_dir.parents[2])
            if per_update is None:
                return None
            config = done["config"]
            # a run recorded before the field existed had its declared default (no DAgger round)
            rounds = config.get("dagger_rounds", field_defaults()["dagger_rounds"])
            imitation = per_update * config["bc_updates"] * (1 + rounds)
        else:
            imitation = 0.0  # demonstrations in replay, no cloning
        return float(done["demonstrations"]["cpu_s"]) + imitation
    except (OSError, ValueError, KeyError, IndexError):
        return None


def cloning_cpu_s_per_update(results: Path) -> float | None:
    """The median CPU seconds per cloning step (DAgger rounds' episodes included) of the stored
    trainings under ``results`` that recorded their imitation phase; None when none did."""
    per_update = [d["imitation"]["cpu_s"] / d["imitation"]["bc_updates"] for d in _stored_done(results)
                  if d.get("imitation", {}).get("bc_updates")]
    return statistics.median(per_update) if per_update else None


def stored_cpu_s_per_step(record: dict, results: Path, steps_kind: str) -> float | None:
    """The median CPU seconds per env step of the stored trainings whose env step is ``steps_kind``, on
    whatever machines they ran, None when none is stored: the price of a variant whose steps the
    calibration (the preset's kind) does not measure."""
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

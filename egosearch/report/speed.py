"""The docs' speed figures, generated from stored benchmark records and training curves.

``egosearch bench env|learner --out results/<preset>/bench/{env,learner}.json`` stores a benchmark's
result with its command, date, commit, CPU and the machine's load (:func:`egosearch.sim.bench_env.recorded`);
:func:`block_speed` renders them, and the env steps per core-second of the stored trainings from
their ``curve.csv``, so that no speed figure in the docs is typed. CSV and JSON in, Markdown out.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pandas as pd

from egosearch.core.machine import MACHINE_PLACEHOLDER, machine_folder_name
from egosearch.report.data import counts_decisions
from egosearch.report.provenance import WHOLE_RUN_SHARE
from egosearch.report.workflow_jobs import claims_pairs, variants_of_all, workflow_config
from egosearch.searchers import searcher_registry as searchers

ENV_TARGETS = {"sensor_frames_per_s": 1000.0, "env_steps_per_s": 700.0}
"""The issue's one-core targets for the sensor and the env."""
UPDATES_TARGET = 12.0
"""The issue's target for SAC+CURL updates/s at Table 2 settings."""
CORE_S_TARGET = 200.0
"""The budget issue's target for the learner benchmark's env steps per core-second of a cpu-preset training."""
CORE_S_TARGET_AVX2 = 170.0
"""The same under ``ONEDNN_MAX_CPU_ISA=AVX2`` on the same AVX-512 host."""

LEARNER_KEYS = (
    ("naive", "CURL's update line by line"),
    ("table2", "fused Adam, channels-last, uint8 crops on device, shared passes where CURL's order allows; "
               "same math"),
    ("table2_shared", "also reuses the critic's encoder pass for CURL and the actor: one optimiser step stale, "
                      "off by default"),
    ("table2_1thread", "the same on one thread"),
    # the cpu preset's row, keyed as the stored records spell it (egosearch.core.preset_word)
    ("cpu_profile", "SAC-DrQ with the privileged critic, batch 64, one thread"),
    ("cpu_profile_avx2", "the same with oneDNN limited to AVX2, in its own process"),
)


def _bench_command(preset: str, what: str) -> str:
    return f"egosearch bench {what} --json --out results/{preset}/bench/{what}.json"


def _missing(root: Path, path: Path, preset: str, what: str) -> str:
    return (f"*Not measured yet: `{path.relative_to(root)}` is missing (on an otherwise idle machine: "
            f"`{_bench_command(preset, what)}`).*")


def _measured_on(record: dict) -> str:
    machine = record.get("machine", {})
    load = record.get("load_average_before")
    other = record.get("other_load_cores")
    busy = ("other processes used " + (f"{other:.2f}" if other is not None else "?") + " cores meanwhile"
            + (f", load average {load[0]:.2f} before" if load else ""))
    commit = (record.get("commit") or "unknown")[:7] + (" with local changes" if record.get("commit_dirty") else "")
    return (f"`{record.get('command', '?')}` on {record.get('date_utc', '?')[:10]}, commit `{commit}`, "
            f"{machine.get('cpu', '?')}" + (f" ({machine['vector_unit']})" if machine.get("vector_unit") else "")
            + f" with {machine.get('cores', '?')} cores ({busy}; {record.get('wall_s', '?')} s "
            "in all)")


def _met(value: float, target: float) -> str:
    return "met" if value >= target else "not met"


def _env_lines(root: Path, preset: str) -> list[str]:
    path = root / "results" / preset / "bench" / "env.json"
    if not path.exists():
        return [_missing(root, path, preset, "env")]
    record = json.loads(path.read_text(encoding="utf-8"))
    r = record["result"]
    return [f"Env and sensor, one pinned core, `{r['layout']}` ({r['triangles']:,} triangles): "
            f"**{r['sensor_frames_per_s']:,.0f} sensor frames/s** ({r['sensor_ms_per_frame']} ms a frame; target "
            f"1,000: {_met(r['sensor_frames_per_s'], ENV_TARGETS['sensor_frames_per_s'])}) and "
            f"**{r['env_steps_per_s']:,.0f} env steps/s** ({r['env_ms_per_step']} ms a step, "
            f"{r['env_resets_included']} resets included; target 700: "
            f"{_met(r['env_steps_per_s'], ENV_TARGETS['env_steps_per_s'])}). Measured by "
            + _measured_on(record) + f"; from `{path.relative_to(root)}`."] + _reward_lines(root, preset)


def _reward_lines(root: Path, preset: str) -> list[str]:
    """What the geodesic progress reward (a training lever) costs per env step against the preset's progress
    reward, timed side by side on the same actions in one run (``results/<preset>/bench/env_rewards.json``)."""
    path = root / "results" / preset / "bench" / "env_rewards.json"
    if not path.exists():
        return []
    record = json.loads(path.read_text(encoding="utf-8"))
    r = record["result"]
    by = r["env_ms_per_step_by_reward"]
    ratio = r["geodesic_over_progress"]
    return ["", f"The geodesic progress reward (`train_distance_reward: geodesic`) costs **{ratio:.2f}x** "
            f"the progress reward per env step ({by['geodesic']} against {by['progress']} ms, the same actions timed "
            "side by side in one run, so the ratio holds on a busy machine), measured by " + _measured_on(record)
            + f"; from `{path.relative_to(root)}`."]


MEMORY_LEVER_RECORDS = ("env_memory_levers.json", "learner_memory_levers.json")
"""The records of what the memory levers' observations cost, each a ratio measured in one run (so that it holds
on a busy machine): ``egosearch bench env --out results/<preset>/bench/env_memory_levers.json`` (per env step)
and ``egosearch bench learner --memory-levers --out results/<preset>/bench/learner_memory_levers.json`` (per env
step of a short real training, acting and updates in)."""


def _memory_lever_lines(root: Path, preset: str) -> list[str]:
    """What each memory lever's observation costs against the plain one, per env step and per training, from the
    two records of :data:`MEMORY_LEVER_RECORDS` (none when neither is stored)."""
    env_path, learner_path = (root / "results" / preset / "bench" / name for name in MEMORY_LEVER_RECORDS)
    if not env_path.exists() and not learner_path.exists():
        return []
    lines = ["What the memory levers' observations cost against the plain observation, each a ratio of the two "
             "measured side by side in one run (so that it holds on a busy machine):", "",
             "| option | env step (`bench env`) | training's RL phase (`bench learner --memory-levers`) |",
             "|---|---|---|"]
    env = json.loads(env_path.read_text(encoding="utf-8")) if env_path.exists() else None
    learner = json.loads(learner_path.read_text(encoding="utf-8")) if learner_path.exists() else None
    env_ratios = (env or {}).get("result", {}).get("option_over_none", {})
    env_ms = (env or {}).get("result", {}).get("env_ms_per_step_by_option", {})
    levers = (learner or {}).get("result", {}).get("memory_levers", {})
    for option in dict.fromkeys([*env_ratios, *(k[:-len("_cost_ratio")] for k in levers if k.endswith("_cost_ratio"))]):
        step = (f"**{env_ratios[option]:.2f}x** ({env_ms[option]} against {env_ms['none']} ms)"
                if option in env_ratios else "–")
        rl = (f"**{levers[option + '_cost_ratio']:.2f}x** ({levers['env_steps_per_core_s_' + option]} against "
              f"{levers['env_steps_per_core_s_plain']} env steps per core-second)"
              if option + "_cost_ratio" in levers else "–")
        lines.append(f"| `{option}` | {step} | {rl} |")
    for record, path in ((env, env_path), (learner, learner_path)):
        if record is not None:
            lines += ["", f"Measured by {_measured_on(record)}; from `{path.relative_to(root)}`."]
    return lines


def _learner_lines(root: Path, preset: str) -> list[str]:
    path = root / "results" / preset / "bench" / "learner.json"
    if not path.exists():
        return [_missing(root, path, preset, "learner")]
    record = json.loads(path.read_text(encoding="utf-8"))
    r = record["result"]
    lines = ["Learner (Table 2 settings: batch 32, 5×84×84, all cores unless stated; updates/s from the median "
             "update time, the fastest in brackets), measured by " + _measured_on(record) + ":", "",
             "| key | updates/s |", "|---|---|"]
    for key, meaning in LEARNER_KEYS:
        if f"updates_per_s_{key}" in r:
            lines.append(f"| `updates_per_s_{key}` ({meaning}) | {r[f'updates_per_s_{key}']} "
                         f"({r.get(f'updates_per_s_{key}_best', '–')}) |")
    if "replay_gb_100k" in r:
        lines.append(f"| `replay_gb_100k` | {r['replay_gb_100k']} GB |")
    lines.append("")
    table2 = r.get("updates_per_s_table2")
    if table2 is not None:
        lines.append(f"Table 2 updates/s against the issue's target of {UPDATES_TARGET:g}: "
                     f"{_met(table2, UPDATES_TARGET)}.")
    rate, run = r.get("env_steps_per_core_s_cpu_profile"), r.get("cpu_profile_run", {})
    # the budget issue's targets count body steps: a modular searcher's env step is a decision of several
    decisions = r.get("cpu_profile_steps") == "decisions"
    unit = "decisions" if decisions else "env steps"
    if rate is not None:
        steps = f"{run['env_steps']:,}" if "env_steps" in run else "short"
        target = (f"the budget issue's target of {CORE_S_TARGET:g} counts the body steps of a learner that acts at "
                  "every step, not comparable" if decisions else
                  f"the issue's target of {CORE_S_TARGET:g}: {_met(rate, CORE_S_TARGET)}")
        lines.append(f"**`env_steps_per_core_s_cpu_profile` {rate}**: {unit} per core-second of a "
                     f"{steps}-{'decision' if decisions else 'step'} real training run of the `cpu` preset"
                     + (" (a modular searcher: each decision walks several body steps, planned by the frontier "
                        "searcher)" if decisions else "") + " in `kitchen_living` "
                     f"(building the envs and writing its checkpoint, env stepping, acting and updates all in; "
                     f"core-seconds are the process's own CPU time, {run.get('core_s', '?')} s"
                     + (f", its RL phase's: a token imitation phase first, a few demonstrations and cloning steps, "
                        f"{run['core_s_before_rl']} s left out, as the stored trainings' rates leave theirs out"
                        if run.get("core_s_before_rl") else "") + f"); {target}.")
    avx2 = r.get("env_steps_per_core_s_cpu_profile_avx2")
    if avx2 is not None:
        lines.append(f"The same training with oneDNN limited to AVX2 (`ONEDNN_MAX_CPU_ISA=AVX2`, its own process): "
                     f"**{avx2}** {unit} per core-second"
                     + ("." if decisions else f"; the issue's target of {CORE_S_TARGET_AVX2:g}: "
                        f"{_met(avx2, CORE_S_TARGET_AVX2)}."))
    return lines + ["", f"From `{path.relative_to(root)}`."]


def _benchmark_cpu_s(path: Path, run_wall_s: float) -> float | None:
    """The CPU time a training job's benchmark recorded, when that job was the whole run: a resumed
    run's benchmark covers only its last part (its wall time falls well short of the curve's)."""
    if not path.exists():
        return None
    try:
        last = pd.read_csv(path, sep="\t").iloc[-1]
        wall, cpu = float(last["s"]), float(last["cpu_time"])
    except (KeyError, IndexError, TypeError, ValueError):
        return None
    return cpu if cpu > 0 and wall >= WHOLE_RUN_SHARE * run_wall_s else None


def _training_lines(root: Path, preset: str, variants: list[str]) -> list[str]:
    """Env steps per core-second of every stored training of ``variants``: final env steps over the
    final ``wall_s`` of its curve.csv times its torch threads, and over its job's CPU time where the
    benchmark recorded the whole run. Wall time counts the time a job waited for a core while more
    jobs ran than cores; CPU time does not."""
    rows = []
    for variant in variants:
        for curve in sorted((root / "results" / preset / "train" / variant).glob("seed*/curve.csv")):
            last = pd.read_csv(curve).sort_values("env_steps").iloc[-1]
            threads = 1
            done = curve.parent / "done.json"
            if done.exists():
                threads = int(json.loads(done.read_text()).get("config", {}).get("num_threads") or 1) or 1
            if not math.isnan(last.get("wall_s", math.nan)):
                benchmark = root / "results" / preset / "benchmarks" / "train" / variant / f"{curve.parent.name}.tsv"
                rows.append((variant, curve.parent.name, int(last.env_steps), float(last.wall_s), threads,
                             _benchmark_cpu_s(benchmark, float(last.wall_s)), counts_decisions(curve)))
    if not rows:
        return []
    lines = ["Stored trainings (whole runs: start-up weighs less than in the benchmark's short run):", "",
             "| variant | seed | env steps | wall s | threads | env steps per core-second | CPU s | "
             "env steps per CPU-second |",
             "|---|---|---|---|---|---|---|---|"]
    for variant, seed, steps, wall, threads, cpu, decisions in rows:
        lines.append(f"| `{variant}` | {seed.removeprefix('seed')} | {steps:,}{' decisions' if decisions else ''} | "
                     f"{wall:,.0f} | {threads} | "
                     f"{steps / (wall * threads):.0f} | {'–' if cpu is None else f'{cpu:,.0f}'} | "
                     f"{'–' if cpu is None else f'{steps / cpu:.0f}'} |")
    return lines + ["", f"From `results/{preset}/train/<variant>/seed<N>/curve.csv` (last row's `wall_s`) and the "
                        f"training job's CPU time in `results/{preset}/benchmarks/train/` (– where it does not "
                        "cover the whole run: a resumed run's covers its last part). A training that shared its "
                        "core waited part of its wall time; its CPU time is what it cost. A modular searcher's env "
                        "step is a decision (several body steps each), so its rates count decisions."]


HOSTS = "hosts"
"""``results/<preset>/bench/hosts/<machine>/`` (:func:`egosearch.core.machine.machine_folder_name`): the
learner benchmark (``learner.json``) and the estimate calibrated there (``estimate_all.json``) of a machine
other than the stored run's benchmark machine."""


def machine_words(m: dict) -> str:
    """A machine record as words: ``Intel(R) Xeon(R) Processor (AVX-512), 2 cores`` (and its GPU, if any)."""
    return (f"{m.get('cpu') or '?'}" + (f" ({m['vector_unit']})" if m.get("vector_unit") else "")
            + f", {m.get('cores') or '?'} cores" + (f", {m['gpu']}" if m.get("gpu") else ""))


def _hosts_lines(root: Path, preset: str) -> list[str]:
    """The learner benchmark and the simulated ``all`` on every machine measured: the stored run's benchmark
    machine (``bench/learner.json``, its estimate ``bench/estimate_all.json``) and each under ``bench/hosts/``."""
    bench = root / "results" / preset / "bench"
    hosts = sorted((bench / HOSTS).glob("*/learner.json"))
    if not hosts:
        return []
    rows = [(bench / "learner.json", bench / "estimate_all.json", "the stored run's benchmark machine")]
    rows += [(path, path.with_name("estimate_all.json"), f"`{path.parent.relative_to(root)}/`") for path in hosts]
    lines = ["The learner benchmark on every machine measured, each otherwise idle (other processes' cores in "
             "brackets), and `snakemake --cores N all` simulated there (`egosearch estimate all`, trainings scaled "
             "by the calibration it ran on that machine):", "",
             "| machine | records | measured | cpu-preset training per core-second (AVX2) | cpu-preset "
             "updates/s | Table 2 updates/s | `all` simulated |",
             "|---|---|---|---|---|---|---|"]
    for learner, estimate, where in rows:
        if not learner.exists():
            continue
        record = json.loads(learner.read_text(encoding="utf-8"))
        r = record["result"]
        unit = "decisions" if r.get("cpu_profile_steps") == "decisions" else "env steps"
        rate = r.get("env_steps_per_core_s_cpu_profile")
        avx2 = r.get("env_steps_per_core_s_cpu_profile_avx2")
        other = record.get("other_load_cores")
        cost = "–"
        if estimate.exists():
            e = json.loads(estimate.read_text(encoding="utf-8"))
            if e.get("hours_here") is not None:
                cost = (f"{e['hours_here']:.1f} h on {e['cores']} cores (calibrated at {e['bench_rate']:.1f} "
                        f"{e.get('steps', 'env steps')} per CPU-second, {e['rate_source']})")
        lines.append(f"| {machine_words(record.get('machine', {}))} | {where} | {record.get('date_utc', '?')[:10]} "
                     f"({'?' if other is None else f'{other:.2f}'}) | "
                     f"{'–' if rate is None else f'{rate} {unit}'}"
                     + (f" ({avx2})" if avx2 is not None else "") + f" | {r.get('updates_per_s_cpu_profile', '–')} | "
                     f"{r.get('updates_per_s_table2', '–')} | {cost} |")
    folder = f"results/{preset}/bench/{HOSTS}/{MACHINE_PLACEHOLDER}"
    return lines + ["", f"Another machine's row: on it, otherwise idle, `egosearch bench learner --json --out "
                        f"{folder}/learner.json` and `egosearch estimate all --cores 2 --out "
                        f"{folder}/estimate_all.json` "
                        f"(`{MACHINE_PLACEHOLDER}` becomes the machine's folder, such as "
                        f"`{machine_folder_name({'cpu': 'AMD EPYC', 'vector_unit': 'AVX-512', 'cores': 2})}`)."]


SCHEDULE_CHECKS = "schedule_check*.json"
"""``results/<preset>/bench/schedule_check*.json``: ``egosearch estimate check --out`` of a finished run."""


def _schedule_check_lines(root: Path, preset: str) -> list[str]:
    """Each stored run set beside the simulation of its own jobs: its elapsed time, the prediction from the
    record before it, and its own job times laid out by the simulation."""
    lines = []
    for path in sorted((root / "results" / preset / "bench").glob(SCHEDULE_CHECKS)):
        c = json.loads(path.read_text(encoding="utf-8"))
        elapsed = c["elapsed_s"]
        lines.append(
            f"- A real run against the simulation (`{c['command']}`, {c['date_utc'][:10]}, "
            f"{machine_words(c.get('machine', {}))}): {c['jobs']} jobs of `{c['target']}` on {c['cores']} cores took "
            f"**{elapsed / 60:.1f} min**; predicted from the record before the run **{c['predicted_s'] / 60:.1f} "
            f"min** ({c['predicted_s'] / elapsed:.2f} x; {c['record_note']}); its own job times laid out by the "
            f"simulation {c['own_times_simulated_s'] / 60:.1f} min ({c['own_times_simulated_s'] / elapsed:.2f} x); "
            f"their sum / {c['cores']}, the old lower bound, {c['own_times_over_cores_s'] / 60:.1f} min "
            f"(`{path.relative_to(root)}`).")
    return ["Checks of the schedule simulation against finished runs (`egosearch estimate check`):", ""] + lines \
        if lines else []


def block_speed(root: Path, preset: str) -> str:
    config = workflow_config()
    # the preset's pair, and the pairs its claims are also read on (at the cpu preset, the from-scratch one)
    paired = [v for pair in claims_pairs({**config, "preset": preset}) for v in pair if v not in searchers.bounds()]
    sections = [_env_lines(root, preset), _learner_lines(root, preset), _memory_lever_lines(root, preset),
                _hosts_lines(root, preset),
                _schedule_check_lines(root, preset),
                _training_lines(root, preset, list(dict.fromkeys(variants_of_all(config) + paired)))]
    return "\n\n".join("\n".join(lines) for lines in sections if lines) + "\n"

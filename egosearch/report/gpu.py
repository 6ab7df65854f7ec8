"""The paper preset on a GPU: the stored GPU check and the projection of the paper preset's ``all``.

``egosearch bench gpu --seconds S --out-dir DIR --out results/paper/gpu_check/gpu_check.json`` on a
GPU machine stores the learner benchmarks and a paper-preset training of S seconds (its curve.csv
and train.csv beside it); ``pytest -m gpu tests/test_cuda.py`` there writes ``cuda_tests.log`` and
``cuda_report.json``. This module renders them, and projects the wall time of
``snakemake --config preset=paper all`` on one such machine from the measured rates, so that no
figure of it is typed. JSON and CSV in, Markdown out.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

from egosearch.core.gpu_share import SIDE_BY_SIDE, projected_hours, read_side_by_side
from egosearch.report.speed import HOSTS
from egosearch.report.workflow_jobs import job_cost_s, job_study, variants_of_all, workflow_config

GPU_CHECK = Path("results") / "paper" / "gpu_check"
"""Where the GPU check is stored, under the project root."""
CPU_PRESET_GPU_CHECK = Path("results") / "cpu" / "gpu_check"
"""Where the CUDA tests of a later tree are stored, the default (``cpu``) preset's training among them:
``cuda_tests.log`` and ``cuda_report.json`` as above (``pytest -q``: the summary line, no test names)."""


def _missing(root: Path) -> str:
    return (f"*Not measured yet: `{GPU_CHECK / 'gpu_check.json'}` is missing (on a GPU machine: "
            f"`egosearch bench gpu --seconds 300 --out-dir <a folder> --out {GPU_CHECK / 'gpu_check.json'}`).*\n")


def _record(root: Path) -> dict | None:
    path = root / GPU_CHECK / "gpu_check.json"
    return json.loads(path.read_text(encoding="utf-8")) if path.exists() else None


def fullbody_jobs(preset_config: dict) -> int:
    """Full-body runs per setting of a preset: motion generators x seeds (rules/fullbody.smk)."""
    fullbody = preset_config["fullbody"]
    return len(fullbody["motion_generators"]) * len(fullbody["seeds"])


def projection(root: Path) -> dict | None:
    """Hours of ``snakemake --config preset=paper all`` on the GPU check's machine: its trainings one
    at a time at the measured rate (curve evaluations included), plus the other jobs of ``all``, CPU
    jobs, from the stored cpu run's recorded costs (the full-body ones scaled to the paper preset's
    count of runs) spread over the machine's cores. None without a GPU check."""
    record = _record(root)
    if record is None:
        return None
    run = record["result"]["training"]
    config = workflow_config()
    paper = config["presets"]["paper"]
    evaluations = run["total_env_steps"] // run["eval_every"] + 1
    train_s = run["total_env_steps"] / run["env_steps_per_s_updating"] + evaluations * run["curve_evaluation_s_mean"]
    trainings = len(variants_of_all(config)) * len(paper["seeds"])
    scale = fullbody_jobs(paper) / fullbody_jobs(config["presets"]["cpu"])
    other_s, provenance = 0.0, root / "results" / "cpu" / "provenance.json"
    if provenance.exists():
        for job in json.loads(provenance.read_text(encoding="utf-8"))["jobs"]:
            if job["rule"] != "train" and job_study(job, config, "cpu") == "all":
                other_s += job_cost_s(job) * (scale if job["rule"].startswith("fullbody") else 1.0)
    cores = int(record["machine"]["cores"])
    out = {"train_h": train_s / 3600, "trainings": trainings, "trainings_h": trainings * train_s / 3600,
           "other_core_h": other_s / 3600, "other_h": other_s / cores / 3600, "cores": cores,
           "fullbody_scale": scale, "total_h": (trainings * train_s + other_s / cores) / 3600,
           "evaluations": evaluations}
    side = read_side_by_side(root)
    if side is not None:
        # the trainings side by side (egosearch bench gpu --side-by-side N): their env steps at the measured
        # aggregate rate, then the other jobs over that machine's cores
        side_cores = int((side.get("machine") or {}).get("cores") or cores)
        trainings_h = projected_hours(side["all_env_steps"], side["aggregate_env_steps_per_s"])
        out["side_by_side"] = {"n": side["side_by_side"], "mps": bool(side["mps"]), "cores": side_cores,
                               "trainings_h": trainings_h, "other_h": other_s / side_cores / 3600,
                               "total_h": trainings_h + other_s / side_cores / 3600}
    return out


def _machine(record: dict) -> str:
    m = record["machine"]
    return (f"{m.get('gpu', 'no GPU')} ({m.get('gpu_memory_gib', '?')} GiB), {m['cpu']} with {m['cores']} cores, "
            f"torch {m.get('torch', '?')}, CUDA {m.get('cuda', '?')}")


def _commit(record: dict) -> str:
    return record["commit"][:7]


def block_gpu_projection(root: Path, preset: str) -> str:
    """The README's lines: the projected wall time of the paper preset's ``all`` on one GPU."""
    record, p = _record(root), projection(root)
    if record is None or p is None:
        return _missing(root)
    if "side_by_side" in p:
        return _side_by_side_projection(root, p)
    run = record["result"]["training"]
    return (f"On one {record['machine'].get('gpu', 'GPU')} ({record['machine']['cores']} CPU cores), "
            f"`snakemake --cores {p['cores']} --config preset=paper all` is projected at **about "
            f"{p['total_h']:.0f} h**: {p['trainings']} trainings of {run['total_env_steps']:,} env steps, one at a "
            f"time, at the measured {run['env_steps_per_s_updating']:.1f} env steps/s"
            + f" ({p['train_h']:.1f} h each" + ("; the update recorded as CUDA graphs, as the preset does"
                                                if _graphed(run) else "") + "), "
            f"plus about {p['other_h']:.1f} h of CPU jobs. Derived from the stored GPU check "
            f"(`{GPU_CHECK}/`, {record['date_utc'][:10]}); how, and what `--executor slurm` needs: "
            "[docs/gpu.md](docs/gpu.md).\n")


def _under_mps(side: dict) -> str:
    return "under CUDA MPS" if side["mps"] else "without CUDA MPS"


def _side_by_side_projection(root: Path, p: dict) -> str:
    """The README's lines where a side-by-side record is stored: the trainings of ``all`` side by side at its
    aggregate rate, and the CPU jobs."""
    side, q = read_side_by_side(root), p["side_by_side"]
    machine = side.get("machine") or {}
    return (f"On one {machine.get('gpu', 'GPU')} ({q['cores']} CPU cores), `snakemake --cores {q['cores']} --config "
            f"preset=paper all` is projected at **about {q['total_h']:.1f} h**: {side['all_trainings']} trainings, "
            f"{side['all_env_steps']:,} env steps in all, {q['n']} side by side {_under_mps(side)} at the measured "
            f"{side['aggregate_env_steps_per_s']:.0f} env steps/s in all ({q['trainings_h']:.1f} h; one training "
            f"alone: {side['alone_env_steps_per_s']:.1f} env steps/s, "
            f"{side['projected_all_hours_one_at_a_time']:.1f} h one at a time), plus about {q['other_h']:.1f} h of "
            "CPU jobs. Derived from the stored side-by-side "
            f"measurement (`{SIDE_BY_SIDE}`, {str(side.get('date_utc', '?'))[:10]}); how, and what `--executor slurm` "
            "needs: [docs/gpu.md](docs/gpu.md).\n")


def _side_by_side_lines(root: Path) -> list[str]:
    """docs/gpu.md: the side-by-side measurement (``egosearch bench gpu --side-by-side N``), where stored."""
    side = read_side_by_side(root)
    if side is None:
        return []
    machine = side.get("machine") or {}
    per = ", ".join(f"{r:.1f}" for r in side["per_training_env_steps_per_s"])
    lines = [f"Trainings side by side (`{side.get('command', '?')}` on {machine.get('gpu', 'a GPU')} with "
             f"{machine.get('cores', '?')} cores, {str(side.get('date_utc', '?'))[:16]} UTC, commit "
             f"`{str(side.get('commit', '?'))[:7]}`; `{SIDE_BY_SIDE}`): one training alone with "
             f"{side.get('threads_alone')} threads, {side['alone_env_steps_per_s']:.1f} env steps/s while updating; "
             f"{side['side_by_side']} side by side with {side.get('threads_per_training')} threads each "
             f"{_under_mps(side)}, {per} env steps/s, **{side['aggregate_env_steps_per_s']:.1f} in all** "
             f"({side['speedup_vs_alone']:.1f}x the one alone). MPS: {side.get('mps_note', '?')}."]
    if side.get("without_mps"):
        w = side["without_mps"]
        lines.append(f"- the same {side['side_by_side']} side by side without MPS, run first for "
                     f"{w.get('seconds') or 0:g} s: {', '.join(f'{r:.1f}' for r in w['per_training_env_steps_per_s'])} "
                     f"env steps/s, {w['aggregate_env_steps_per_s']:.1f} in all ({w['projected_all_hours']:.1f} h "
                     "for the trainings of `all`)")
    lines.append(f"- the trainings of `all` ({side['all_trainings']}, {side['all_env_steps']:,} env steps) at "
                 f"{side['aggregate_env_steps_per_s']:.1f} env steps/s: **{side['projected_all_hours']:.1f} h**, "
                 f"against {side['projected_all_hours_one_at_a_time']:.1f} h one at a time (curve evaluations "
                 "left out: a few minutes)")
    return lines


def _compile_line(root: Path) -> str | None:
    path = root / GPU_CHECK / "compile_bench.txt"
    if not path.exists():
        return None
    found = [line for line in path.read_text(encoding="utf-8").splitlines() if line.startswith("{")]
    if not found:
        return None
    r = json.loads(found[-1])
    if "compiled" not in r:
        return f"- `compile: true` (torch.compile) failed there: {r.get('compiled_error', '?')}."
    plain, compiled = r["plain"]["median_s"], r["compiled"]["median_s"]
    verdict = "faster" if compiled < plain else "no faster"
    return (f"- `compile: true` (torch.compile of the networks, default mode), measured in an earlier GPU "
            f"session: {1 / compiled:.1f} updates/s against {1 / plain:.1f} without it, median of 40 Table 2 "
            f"updates each, in one run (`{GPU_CHECK}/compile_bench.txt`): {verdict}.")


def _tests_lines(root: Path) -> list[str]:
    log, report = root / GPU_CHECK / "cuda_tests.log", root / GPU_CHECK / "cuda_report.json"
    if not log.exists():
        return []
    text = log.read_text(encoding="utf-8")
    results = re.findall(r"^tests/test_cuda\.py::(\S+) (PASSED|FAILED|SKIPPED|ERROR)", text, flags=re.M)
    summary = re.findall(r"=+ (.+) in [\d.]+s", text)
    commit = re.search(r"^commit ([0-9a-f]{7})", text, flags=re.M)
    lines = ["CUDA tests (`pytest -m gpu tests/test_cuda.py` on that machine"
             + (f", commit `{commit.group(1)}`" if commit else "") + f"; `{GPU_CHECK}/cuda_tests.log`): "
             + (summary[-1] if summary else "no summary line") + "."]
    lines += [f"- `{name}`: {status.lower()}" for name, status in results]
    if report.exists():
        r = json.loads(report.read_text(encoding="utf-8"))
        for key, label in (("update_paper", "SAC+CURL at Table 2 sizes"), ("update_cpu", "SAC-DrQ, the cpu preset")):
            if key in r:
                u = r[key]
                lines.append(f"- one update, CUDA against CPU from the same weights, optimiser state and batch, TF32 "
                             f"off ({label}, {u['tensors']} weight tensors): largest relative difference of a "
                             f"tensor's change {u['max_relative_update_difference']:.1e} (tolerance 1e-3), of a "
                             f"loss {u['max_relative_metric_difference']:.1e} (tolerance 1e-4)")
        if "graph_vs_eager" in r:
            g = r["graph_vs_eager"]
            lines.append(f"- the update recorded as CUDA graphs against the eager update, each of {g['updates']} "
                         f"Table 2 updates from the same state and batch, TF32 off ({g['tensors']} weight tensors; "
                         "graphs warmed up, recorded, replayed, dropped by a loaded state and recorded again): "
                         f"largest relative difference of a tensor's change {g['max_relative_update_difference']:.1e} "
                         f"(tolerance 1e-3), of a loss {g['max_relative_metric_difference']:.1e} (tolerance 1e-4)")
        if "resume" in r:
            same = "bit for bit the same" if r["resume"]["actor_bitwise_equal"] else (
                f"not bit for bit the same (largest difference {r['resume']['actor_max_abs_difference']:.1e})")
            lines.append(f"- the CUDA training stopped at 200 env steps and resumed from its checkpoint at 150 "
                         f"(deterministic algorithms on): its actor is {same} as the run never stopped")
    return lines


def _graphed(run: dict) -> bool:
    """Whether a training recorded its update as CUDA graphs (older records name only the override)."""
    return bool(run.get("cuda_graph", run.get("overrides", {}).get("cuda_graph", False)))


def _baseline_sentence(base: dict, run: dict) -> str:
    return (f" The same training with the update launched eagerly (`cuda_graph: false`), run next for "
            f"{base['wall_s']:.0f} s on the same machine (`baseline/`): {base['env_steps_per_s_updating']:.1f} env "
            f"steps/s while updating (median of {base['train_rows_used']} rows), so "
            f"{run['env_steps_per_s_updating'] / base['env_steps_per_s_updating']:.1f}x.")


def block_gpu(root: Path, preset: str) -> str:
    """docs/gpu.md: the machine, the CUDA tests, the learner's speed there, the training, the projection."""
    record, p = _record(root), projection(root)
    if record is None or p is None:
        return _missing(root)
    result, run = record["result"], record["result"]["training"]
    learner = result["learner"]
    sections = [
        [f"Machine: {_machine(record)}. Recorded by `{record['command']}` on {record['date_utc'][:16]} UTC, "
         f"commit `{_commit(record)}` ({record['wall_s']:.0f} s in all; `{GPU_CHECK}/gpu_check.json`)."
         + (f" {record['commit_note'][0].upper()}{record['commit_note'][1:]}." if record.get("commit_note") else "")],
        _tests_lines(root),
        ["Learner on the GPU (updates/s from the median update, the fastest in brackets):", "",
         "| key | updates/s |", "|---|---|"]
        + [f"| `updates_per_s_{key}` | {learner[f'updates_per_s_{key}']} ({learner[f'updates_per_s_{key}_best']}) |"
           for key in ("naive", "table2", "table2_shared", "table2_1thread", "table2_graph", "cpu_profile")
           if f"updates_per_s_{key}" in learner]
        + ([""] if "speedup_graph_vs_table2" in learner else [])
        + ([f"- `table2_graph` is the Table 2 update recorded as CUDA graphs and replayed (`cuda_graph`): "
            f"{learner['speedup_graph_vs_table2']}x the eager update's rate, in the same run."]
           if "speedup_graph_vs_table2" in learner else [])
        + [f"- Host-device synchronisations per update (torch's sync debug mode, replay sampling excluded): "
           f"{result['host_syncs_per_update_table2']} at Table 2"
           + (f" ({result['host_syncs_per_update_table2_graph']} with the graphs)"
              if "host_syncs_per_update_table2_graph" in result else "")
           + f", {result['host_syncs_per_update_cpu_profile']} for the cpu preset's learner. One is the update's "
           "metrics, read back together; where the other comes from was not traced there (on the CPU, nothing "
           "else in an update reads a tensor back)."]
        + ([line] if (line := _compile_line(root)) else []),
        [f"Paper-preset training (`{run['variant']}`, seed {run['seed']}, its envs on the machine's CPU, one env as "
         f"Table 2{', the update recorded as CUDA graphs' if _graphed(run) else ''}): "
         f"{run['env_steps']:,} env steps and {run['updates']:,} updates in "
         f"{run['wall_s']:.0f} s, stopped there with a checkpoint (`--max-wall-s`). "
         f"**{run['env_steps_per_s_updating']:.1f} env steps/s** while updating (one update per env step; the median "
         f"of {run['train_rows_used']} train.csv rows), {run['env_steps_per_s_overall']:.1f} over the whole run; a "
         f"curve evaluation ({run['eval_episodes']} episodes) took {run['curve_evaluation_s_mean']:.1f} s. "
         "`curve.csv`, `train.csv` and `config.json` are beside the record."
         + (_baseline_sentence(result["training_baseline"], run) if "training_baseline" in result else "")],
        ["Projection of `snakemake --config preset=paper all` on one such machine:", "",
         f"- {p['trainings']} trainings (the `all` variants x the paper preset's seeds) of "
         f"{run['total_env_steps']:,} env steps at {run['env_steps_per_s_updating']:.1f} env steps/s, with "
         f"{p['evaluations']} curve evaluations each: {p['train_h']:.1f} h a training, {p['trainings_h']:.1f} h "
         "one at a time;",
         f"- the other jobs of `all` are CPU jobs: {p['other_core_h']:.1f} core-hours by the stored cpu run's "
         f"recorded costs (`results/cpu/provenance.json`, full-body runs x{p['fullbody_scale']:.0f} for the paper "
         f"preset's motion generators and seeds), {p['other_h']:.1f} h on {p['cores']} cores;",
         f"- **about {p['total_h']:.0f} h in all**, an estimate from the measured rates, not a measured run."],
    ]
    sections.append(_side_by_side_lines(root))
    sections.append(_cpu_profile_lines(root))
    return "\n\n".join("\n".join(lines) for lines in sections if lines) + "\n"


def _cpu_profile_lines(root: Path) -> list[str]:
    """The CUDA tests rerun on a later tree (:data:`CPU_PRESET_GPU_CHECK`), and the learner benchmark made on
    that machine (a ``bench/hosts/`` record with a GPU)."""
    log, report = root / CPU_PRESET_GPU_CHECK / "cuda_tests.log", root / CPU_PRESET_GPU_CHECK / "cuda_report.json"
    if not log.exists():
        return []
    summary = re.findall(r"^=*\s*(\d+ (?:passed|failed).*?) in [\d.]+s", log.read_text(encoding="utf-8"), flags=re.M)
    lines = [f"**The CUDA tests on a later tree** (`{CPU_PRESET_GPU_CHECK}/cuda_tests.log`): "
             + (summary[-1] if summary else "no summary line") + "."]
    r = json.loads(report.read_text(encoding="utf-8")) if report.exists() else {}
    if "modular_cpu_profile" in r:
        m = r["modular_cpu_profile"]
        lines.append(f"- the `cpu` preset of the time, a modular searcher, trained on CUDA in the decision env "
                     f"({m['env_steps']} decisions, {m['updates']} updates), and its actor walked the body env on the "
                     "CPU as evaluation runs it")
    if "cpu_profile" in r:
        m = r["cpu_profile"]
        lines.append(f"- the default `cpu` preset (the frontier searcher's demonstrations, the clone, then SAC "
                     f"fine-tuning at every body step) trained on CUDA ({m['bc_updates']} cloning steps, "
                     f"{m['env_steps']} env steps, {m['updates']} updates), and its actor and start walked the body "
                     "env on the CPU as evaluation runs them")
    for key, label in (("update_paper", "SAC+CURL at Table 2 sizes"), ("update_cpu", "SAC-DrQ, the cpu preset")):
        if key in r:
            u = r[key]
            lines.append(f"- one update, CUDA against CPU ({label}): largest relative difference of a tensor's "
                         f"change {u['max_relative_update_difference']:.1e}, of a loss "
                         f"{u['max_relative_metric_difference']:.1e}")
    for learner in sorted((root / "results" / "cpu" / "bench" / HOSTS).glob("*/learner.json")):
        record = json.loads(learner.read_text(encoding="utf-8"))
        gpu = record.get("machine", {}).get("gpu")
        if not gpu:
            continue
        res = record["result"]
        lines.append(f"- `egosearch bench learner` there ({gpu}, {record['machine'].get('cores')} cores, "
                     f"{record['date_utc'][:10]}; `{learner.relative_to(root)}`): the `cpu` preset's update "
                     f"{res.get('updates_per_s_cpu_profile')} updates/s on the GPU, its short training "
                     f"**{res.get('env_steps_per_core_s_cpu_profile')} "
                     f"{'decisions' if res.get('cpu_profile_steps') == 'decisions' else 'env steps'} per "
                     "core-second** (the envs and the frontier searcher's planning stay on the CPU; the CPU "
                     "machines' rates are in [Speed](speed.md))")
    return lines

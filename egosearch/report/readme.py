"""Keep the README's and the docs' results equal to the stored results, so that no number in them is typed.

The README and the pages under ``docs/`` mark generated blocks with HTML comments::

    <!-- egosearch:begin table1 -->
    ... replaced by `egosearch report readme` ...
    <!-- egosearch:end table1 -->

Each block name maps to a function that renders Markdown from files under ``paper_figs/<preset>/``
and ``results/<preset>/`` (paths relative to the project root, whichever page the block is in).
A block may sit in any page (:func:`pages`), or in several. ``egosearch report readme --check``
fails when a block differs from what the stored files give (a test runs it), so no page can drift
from the results.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd

from egosearch.core.preset_word import recorded_preset
from egosearch.report.behaviour import block_claims
from egosearch.report.gpu import block_gpu, block_gpu_projection
from egosearch.report.speed import HOSTS, block_speed, machine_words
from egosearch.report.stats import cell_contrast
from egosearch.report.tables import BOTH_HOMES, PAPER_TABLE1
from egosearch.report.workflow_jobs import job_cost_s, job_study, preset_seeds, workflow_config

BLOCK = re.compile(r"(<!-- egosearch:begin (?P<name>[a-z0-9_]+) -->\n)(?P<body>.*?)(<!-- egosearch:end (?P=name) -->)",
                   re.DOTALL)


def _missing(root: Path, path: Path) -> str:
    return f"*Not generated yet: `{path.relative_to(root)}` is missing (run `snakemake --cores 2 all`).*\n"


def _fmt(x: float, digits: int = 2) -> str:
    return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.{digits}f}"


def block_table1(root: Path, preset: str) -> str:
    path = root / "paper_figs" / preset / "table1.md"
    if not path.exists():
        return _missing(root, path)
    return path.read_text(encoding="utf-8").rstrip("\n") + "\n"


def block_table1_pooled(root: Path, preset: str) -> str:
    """Table 1 with both homes pooled, its notes, and where each home alone is (the README's block)."""
    path = root / "paper_figs" / preset / "table1.md"
    if not path.exists():
        return _missing(root, path)
    text = path.read_text(encoding="utf-8")
    pooled = text.split("\nTable 1 in ", 1)[0].rstrip("\n")
    return pooled + ("\n\nEach home alone: [Results](docs/results.md#table-1-success-rate-by-head-height-and-"
                     f"placement-head-on-policy) (`{path.relative_to(root)}`).\n")


def stored_teacher(root: Path, preset: str, variant: str) -> str | None:
    """The searcher a stored variant learned from: its first seed's recorded config's ``demo_teacher`` (its
    done.json), head moving (the reference's body); None when it learned from no demonstrations."""
    from egosearch.searchers import searcher_registry as searchers

    done = root / "results" / preset / "train" / variant / "seed0" / "done.json"
    if not done.exists():
        return None
    config = json.loads(done.read_text(encoding="utf-8")).get("config", {})
    if not config.get("demo_episodes") or not config.get("demo_teacher"):
        return None
    return searchers.with_head(config["demo_teacher"], True)


def block_standing(root: Path, preset: str) -> str:
    """Per Table 1 cell (both homes pooled): the reference against the paper (is the paper's value inside its
    interval?), against Table 1's classical frontier searcher (the stored ``<reference>_vs_frontier.csv``) and
    against the searcher it learned from (its config's ``demo_teacher``: ``<reference>_vs_<teacher>.csv``), and
    the stuck shares."""
    from egosearch.report.tables import BOTH_HOMES

    reference = _reference(root)
    table = root / "paper_figs" / preset / "table1.csv"
    versus = root / "results" / preset / "compare" / f"{reference}_vs_frontier.csv"
    teacher = stored_teacher(root, preset, reference)
    by_teacher = root / "results" / preset / "compare" / f"{reference}_vs_{teacher}.csv" if teacher else None
    for path in (table, versus, by_teacher):
        if path is not None and not path.exists():
            return _missing(root, path)
    t = pd.read_csv(table)
    t = t[t["home"] == BOTH_HOMES]
    v = pd.read_csv(versus)
    v = v[v["metric"] == "success"]
    w = None
    if by_teacher is not None and teacher != "frontier":
        w = pd.read_csv(by_teacher)
        w = w[w["metric"] == "success"]
    teacher_head = f" | against its teacher `{teacher}` (difference [95% CI], Holm)" if w is not None else ""
    lines = [f"| cell | `{reference}` [95% CI] | paper | the paper's value | against the frontier searcher "
             f"(difference [95% CI], Holm){teacher_head} | stuck: ours / frontier |",
             "|---|---|---|---|---|" + ("---|" if w is not None else "") + "---|"]

    def verdict_of(frame: pd.DataFrame, r) -> str:
        c = frame[(frame["height"] == r.height) & (frame["placement"] == r.placement)].iloc[0]
        verdict = c["verdict"] if "verdict" in frame.columns else ("different" if c["significant_holm"] else "same")
        return f"{c['difference']:+.3f} [{c['ci_low']:+.3f}, {c['ci_high']:+.3f}], {verdict}"

    for r in t.itertuples(index=False):
        cell = f"{r.height:g} m {'excl. low cabinets' if r.placement == 'no_low_cabinets' else 'everywhere'}"
        inside = ("inside" if r.ci_low <= r.paper_success_rate <= r.ci_high else
                  "above" if r.paper_success_rate > r.ci_high else "below")
        against_teacher = f" | {verdict_of(w, r)}" if w is not None else ""
        lines.append(f"| {cell} | {r.success_rate:.2f} [{r.ci_low:.2f}, {r.ci_high:.2f}] | {r.paper_success_rate:.2f} "
                     f"| {inside} the interval | {verdict_of(v, r)}{against_teacher} | "
                     f"{r.stuck_share * 100:.1f} % / {r.frontier_stuck_share * 100:.1f} % |")
    files = f"`{versus.relative_to(root)}`" + (f" and `{by_teacher.relative_to(root)}`" if w is not None else "")
    learned = (f" `{reference}` learned from `{teacher}` (its config's `demo_teacher`); `frontier` is Table 1's "
               "classical row, which it did not learn from." if w is not None else "")
    return ("\n".join(lines) + f"\n\nFrom `{table.relative_to(root)}`, {files} (`snakemake versus_teacher`; "
            f"stuck: failed with 50 or more collisions).{learned} A verdict of no difference detected is not "
            "equality: each row's `detectable_80` in the comparison file is the difference it detects with 80 % "
            "power.\n")


def _rise(last, first) -> str:
    """The rise from a curve's first point to ``last``, with its paired interval where fig6.csv holds one."""
    rise = last.success_rate - first.success_rate
    low, high = last.get("rise_low", math.nan), last.get("rise_high", math.nan)
    if pd.isna(low) or pd.isna(high) or last.get("ci_unit") == "episodes (Wilson)":
        return f"{rise:+.2f}"
    return f"{rise:+.2f} [{low:+.2f}, {high:+.2f}]"


def block_fig6(root: Path, preset: str) -> str:
    """Per variant: success at the first and the last evaluation, the rise between them (what the curve
    says learning adds to its start), and the best mean along the way."""
    path = root / "paper_figs" / preset / "fig6.csv"
    if not path.exists():
        return _missing(root, path)
    df = pd.read_csv(path)
    lines = ["| variant | seeds | success at step 0 | success at the last step (95% CI) | rise (95% CI, paired) | "
             "CI resamples | "
             "best mean |",
             "|---|---|---|---|---|---|---|"]
    for variant, g in df.groupby("variant", sort=False):
        g = g.sort_values("env_steps")
        first, last = g.iloc[0], g.iloc[-1]
        best = g.loc[g["success_rate"].idxmax()]
        lines.append(f"| {variant} | {int(last.n_seeds)} | {_fmt(first.success_rate)} | "
                     f"{_fmt(last.success_rate)} [{_fmt(last.low)}, {_fmt(last.high)}] at {int(last.env_steps):,} | "
                     f"{_rise(last, first)} | "
                     f"{last.get('ci_unit', 'seeds')} | {_fmt(best.success_rate)} at {int(best.env_steps):,} |")
    return "\n".join(lines) + f"\n\nFrom `{path.relative_to(root)}`.\n"


def block_fig7(root: Path, preset: str, name: str = "fig7") -> str:
    path = root / "paper_figs" / preset / f"{name}.csv"
    if not path.exists():
        return _missing(root, path)
    df = pd.read_csv(path)
    lines = ["| character / MG | method | episodes | success | SPL (95% CI) | attempts (95% CI) | penetration rate |",
             "|---|---|---|---|---|---|---|"]
    for r in df.itertuples():
        lines.append(f"| {r.mg} | {r.label} | {r.n_episodes} | {_fmt(r.success_rate)} | "
                     f"{_fmt(r.spl, 3)} [{_fmt(r.spl_low, 3)}, {_fmt(r.spl_high, 3)}] | "
                     f"{_fmt(r.attempts, 1)} [{_fmt(r.attempts_low, 1)}, {_fmt(r.attempts_high, 1)}] | "
                     f"{_fmt(r.penetration_rate, 3)} |")
    return "\n".join(lines) + f"\n\nFrom `{path.relative_to(root)}`.\n"


def block_provenance(root: Path, preset: str) -> str:
    path = root / "results" / preset / "provenance.json"
    if not path.exists():
        return _missing(root, path)
    record = json.loads(path.read_text(encoding="utf-8"))
    machine = record.get("machine", {})
    per_rule = record.get("wall_s_per_rule_summed", {})
    cores = int(machine.get("cores") or 1)
    config = workflow_config()
    summed = {"all": 0.0, "generalise": 0.0, "other": 0.0}
    ran = [job for job in record["jobs"] if "copy_of" not in job]  # a copied run is counted once, as its source
    for job in ran:
        summed[job_study(job, config, recorded_preset(record))] += job_cost_s(job)
    lines = [f"- Preset `{recorded_preset(record)}`, provenance written at commit `{record['commit'][:7]}` on "
             f"{record['date_utc'][:16].replace('T', ' ')} UTC on {machine_words(machine)}, "
             f"torch {machine.get('torch', '?')}.",
             f"- {len(ran)} jobs, {record['wall_s_all_jobs_summed'] / 3600:.2f} h of job wall time summed"
             + (f" (and {len(record['jobs']) - len(ran)} copies of stored jobs under other names, counted once as "
                "their sources)" if len(ran) < len(record["jobs"]) else "") + ": "
             + ", ".join(f"{rule} {seconds / 60:.1f} min" for rule, seconds in sorted(per_rule.items())) + "."]
    machines = record.get("machines")
    if machines:
        known = [m for m in machines if m.get("cpu")]
        unknown = sum(m["jobs"] for m in machines if not m.get("cpu"))
        lines.append("- The jobs ran on: " + "; ".join(
            f"{machine_words(m)} ({m['jobs']} jobs, {m['wall_s'] / 3600:.1f} h)" for m in known)
            + (f"; {unknown} jobs name no machine (recorded before jobs did)" if unknown else "") + ".")
    estimate_path = root / "results" / preset / "bench" / "estimate_all.json"
    if estimate_path.exists():
        e = json.loads(estimate_path.read_text(encoding="utf-8"))
        rates = sorted(e.get("recorded_training_rates", {}).values())
        steps = e.get("steps", "env steps")
        slowest = e.get("hours_at_slowest_recorded_rate")
        lines.append(
            f"- `snakemake --cores {e['cores']} all` from a fresh clone, its DAG's schedule simulated on "
            f"{e['cores']} cores (`egosearch estimate all`), each job on a core of its own (its recorded CPU time) "
            + (f"and every training at the slowest recorded rate ({e['slowest_recorded_rate']:.0f} {steps} per "
               f"CPU-second; the stored trainings ran at {rates[0]:.0f} to {rates[-1]:.0f}) plus its imitation "
               f"phase: **{slowest:.1f} h**" if slowest else "")
            + (f"; {e['hours_here']:.1f} h on a machine whose learner benchmark gives {e['bench_rate']:.0f} "
               f"{steps} per CPU-second ({e['rate_source']})" if e.get("hours_here") else "")
            + f"; {e['hours_as_recorded']:.1f} h at the wall times the stored run's jobs recorded, which count the "
            "waits of runs that shared the two cores with more work than the DAG's"
            + f". The jobs' CPU time / {e['cores']}, the lower bound this page used to give: "
            f"{e['hours_cpu_over_cores']:.1f} h. `egosearch estimate all --cores N` calibrates for your machine "
            f"in a minute (from `{estimate_path.relative_to(root)}`).")
        hosts = _host_estimates(root, preset)
        if hosts:
            lines.append("- The same DAG calibrated on the other machines measured (docs/speed.md): " + "; ".join(hosts)
                         + ".")
    else:
        lines.append(
            f"- Lower bound of `snakemake --cores {cores} all` from a fresh clone (its jobs' summed CPU time / "
            f"{cores}, as if they packed perfectly): {summed['all'] / cores / 3600:.2f} h; "
            f"`egosearch estimate all --cores {cores}` simulates the schedule.")
    if summed["generalise"] > 0 or summed["other"] > 0:
        lines.append(f"- Outside `all`: `snakemake --cores {cores} generalise` {summed['generalise'] / 3600:.2f} h of "
                     f"job CPU time; comparisons and studies (compare, budget, fresh, the traces) "
                     f"{summed['other'] / 3600:.2f} h.")
    if record.get("note"):
        lines.append(f"- Note kept in the record: {record['note']}")
    return "\n".join(lines) + f"\n\nFrom `{path.relative_to(root)}`.\n"


def _host_estimates(root: Path, preset: str) -> list[str]:
    """Each ``bench/hosts/<machine>/estimate_all.json`` as words: the machine, the hours, the calibration."""
    out = []
    for path in sorted((root / "results" / preset / "bench" / HOSTS).glob("*/estimate_all.json")):
        e = json.loads(path.read_text(encoding="utf-8"))
        if e.get("hours_here") is None:
            continue
        out.append(f"{machine_words(e.get('machine', {}))}: {e['hours_here']:.1f} h on {e['cores']} cores "
                   f"(calibrated at {e['bench_rate']:.1f} {e.get('steps', 'env steps')} per CPU-second on "
                   f"{e.get('date_utc', '?')[:10]}; `{path.relative_to(root)}`)")
    return out


BY_LENGTH = "_by_length"
"""Suffix of a comparison's split by shortest path, written beside its per-cell CSV."""


def _cell_comparisons(folder: Path) -> list[Path]:
    return sorted(p for p in folder.glob("*_vs_*.csv") if not p.stem.endswith((BY_LENGTH, "_aggregate", "_stuck")))


def _by_length_line(path: Path, root: Path) -> str | None:
    split = path.with_name(path.stem + BY_LENGTH + ".csv")
    if not split.exists():
        return None
    df = pd.read_csv(split)
    succ = df[df["metric"] == "success"]
    bins = "; ".join(f"{r.length_bin} m {r.difference:+.3f} [{r.ci_low:+.3f}, {r.ci_high:+.3f}]"
                     f"{' *' if r.p_holm < 0.05 else ''}" for r in succ.itertuples())
    return f"By shortest path ℓ (success, every cell pooled; `{split.relative_to(root)}`): {bins}."


ABLATION_FAMILIES: dict[str, tuple[str, ...]] = {
    "references": ("head_on", "head_off", "head_off_25px", "head_off_from_scratch", "frontier_tuned",
                   "frontier_tuned_head_off", "head_on_paper_homes"),
    "resolution": ("head_on_memory_50px", "head_off_memory_50px", "head_on_50px", "head_on_memory_50px_200k",
                   "head_on_from_scratch", "head_on_encoder_aux", "head_on_ppo", "head_on_ppo_no_entropy"),
    "memory": ("head_on_target_memory", "head_on_floor_map", "head_on_recurrent", "head_on_recurrent_geodesic",
               "head_on_map_image", "head_on_strided_history"),
    "shaping": ("head_on_coverage", "head_on_geodesic", "head_on_geodesic_50px"),
    "imitation": ("head_on_imitation", "head_on_imitation_map", "head_on_imitation_dagger", "head_on_demo_replay",
                  "head_on_imitation_finetune", "head_on_imitation_finetune_100k", "head_on_imitation_finetune_map",
                  "head_on_imitation_finetune_critic_ln", "head_on_imitation_finetune_5k_demos",
                  "head_on_imitation_finetune_tuned_teacher", "head_on_imitation_finetune_bc_200k"),
    "modular": ("head_on_modular", "head_off_modular", "head_on_modular_rerun_on_intel_xeon"),
    "stuck": ("head_on_geodesic_finetune", "head_on_contact_signal", "head_on_cloning_floor",
              "head_on_recurrent_imitation", "head_on_tuned_teacher_geodesic_contact",
              "head_off_tuned_teacher_geodesic_contact", "head_on_dagger_contact"),
}
"""Each page of ``docs/ablations/`` (its file name's stem) and the candidates whose stored comparisons it shows:
a comparison sits with the lever it reads, whatever its reference. A candidate no family names is shown on the
index page, ``docs/ablations.md`` (block ``compare_unfiled``), until a family takes it."""

ABLATION_COMPARISONS: dict[str, str] = {
    # the redone pair read against the pair it replaced: the stuck student's result, not the reference's
    "head_on_vs_head_on_imitation_finetune": "stuck",
    "head_off_vs_head_off_imitation_finetune": "stuck",
}
"""Comparisons (file stems) shown on another family's page than their candidate's."""

SCREEN_SEEDS = re.compile(r"_seeds?\d+(-\d+)?$")


def comparison_family(stem: str) -> str | None:
    """The ``docs/ablations/`` page a stored comparison ``<candidate>_vs_<reference>`` is shown on
    (:data:`ABLATION_FAMILIES`); None when no family claims it."""
    if stem in ABLATION_COMPARISONS:
        return ABLATION_COMPARISONS[stem]
    candidate = SCREEN_SEEDS.sub("", stem.split("_vs_", 1)[0].removeprefix("screen_"))
    return next((family for family, levers in ABLATION_FAMILIES.items() if candidate in levers), None)


def block_compare(root: Path, preset: str, family: str | None = None, unfiled: bool = False) -> str:
    """Every stored comparison (``results/<preset>/compare/<variant>_vs_<reference>.csv``) of one family of
    levers (:func:`comparison_family`; ``unfiled``: those of none; neither: all), each with its split by shortest
    path where stored."""
    folder = root / "results" / preset / "compare"
    paths = _cell_comparisons(folder)
    if family is not None or unfiled:
        paths = [p for p in paths if comparison_family(p.stem) == family]
    if not paths:
        if unfiled:
            return "*None: every stored comparison is on its family's page.*\n"
        return (f"*No stored comparison of these levers yet under `{folder.relative_to(root)}/` "
                "(`snakemake --cores 2 compare --config variant=NAME`).*\n")
    parts = []
    for path in paths:
        candidate, reference = path.stem.split("_vs_", 1)
        df = pd.read_csv(path)
        where = f" in {', '.join(sorted(set(df['homes'])))}" if "homes" in df.columns else ""
        seeds = ""
        if {"n_seeds_ref", "n_seeds_cand"} <= set(df.columns):
            n_cand, n_ref = int(df["n_seeds_cand"].max()), int(df["n_seeds_ref"].max())
            seeds = f"; {n_cand} seeds each" if n_cand == n_ref else f"; {n_cand} seed(s) against {n_ref}"
            if n_cand == n_ref == 1:
                seeds = ("; one seed each, so the interval and p resample the scenarios only and do not count how "
                         "much another training seed would differ")
        lines = [f"`{candidate}` vs `{reference}`{where} (difference = {candidate} - {reference}{seeds}; from "
                 f"`{path.relative_to(root)}`):", "",
                 "| height | placement | metric | reference | candidate | difference (95% CI) | p (one cell) "
                 "| p (Holm) |",
                 "|---|---|---|---|---|---|---|---|"]
        for r in df.itertuples():
            lines.append(f"| {r.height:g} | {r.placement} | {r.metric} | {r.reference:.3f} | {r.candidate:.3f} | "
                         f"{r.difference:+.3f} [{r.ci_low:+.3f}, {r.ci_high:+.3f}] | {r.p_uncorrected:.3g} | "
                         f"{r.p_holm:.3g}{' *' if r.p_holm < 0.05 else ''} |")
        by_length = _by_length_line(path, root)
        if by_length:
            lines += ["", by_length]
        parts.append("\n".join(lines) + "\n")
    note = ("\\* Holm-adjusted p < 0.05 (over every row of its file). CI: paired two-level bootstrap (scenarios, "
            "then each side's seeds); p (one cell): the same bootstrap's draws read as a two-sided test, uncorrected "
            "(p < 0.05 exactly when the 95% CI excludes 0; Holm only raises p, so a starred row's CI excludes 0).")
    return "\n".join(parts) + "\n" + note + "\n"


def block_power(root: Path, preset: str) -> str:
    """What each stored comparison can detect: ``detectable_80`` of its success rows."""
    folder = root / "results" / preset / "compare"
    paths = _cell_comparisons(folder)
    lines = []
    for path in paths:
        df = pd.read_csv(path)
        if "detectable_80" not in df.columns:
            lines.append(f"- `{path.stem}`: written before `detectable_80` existed (`{path.relative_to(root)}`).")
            continue
        succ = df[df["metric"] == "success"]
        lo, hi = int(succ["n_scenarios"].min()), int(succ["n_scenarios"].max())
        homes = ", ".join(sorted(set(succ["homes"])))
        smallest, largest = _fmt(succ["detectable_80"].min()), _fmt(succ["detectable_80"].max())
        one_seed = (succ["n_seeds_ref"] == 1).all() and (succ["n_seeds_cand"] == 1).all() and (
            succ.get("method", pd.Series(["bootstrap"])) != "seed spread").all()
        lines.append(f"- `{path.stem}`: {lo if lo == hi else f'{lo}–{hi}'} scenarios per cell ({homes}); a success "
                     f"difference of {smallest if smallest == largest else f'{smallest}–{largest}'} is "
                     "detected with 80% power"
                     + (" by the scenarios alone (one seed a side: another seed's difference is not counted)"
                        if one_seed else "") + f" (`{path.relative_to(root)}`).")
    return "\n".join(lines) + "\n" if lines else "*No stored comparison yet.*\n"


def block_departures(root: Path, preset: str) -> str:
    """The generated Table 2's list of the preset's learner settings that are not the paper's."""
    path = root / "paper_figs" / preset / "table2.md"
    if not path.exists():
        return _missing(root, path)
    lines = path.read_text(encoding="utf-8").splitlines()
    start = next((i for i, line in enumerate(lines) if line.startswith("Where this preset departs")), None)
    if start is None:
        return f"*`{path.relative_to(root)}` lists no departure: this preset is the paper's Table 2.*\n"
    return "\n".join(lines[start:]).rstrip("\n") + f"\n\nFrom `{path.relative_to(root)}`.\n"


GENERALISE_SCREEN = "generalise_seed0"
"""The generalisation table of one seed per policy, stored before `snakemake generalise`'s three."""


def block_generalise(root: Path, preset: str) -> str:
    """The generalisation table (`snakemake generalise`), or its stored one-seed screen, said so."""
    figs = root / "paper_figs" / preset
    full, screen = figs / "generalise.md", figs / f"{GENERALISE_SCREEN}.md"
    if full.exists():
        text, source = full.read_text(encoding="utf-8"), full
    elif screen.exists():
        text = ("*One seed per policy (seed 0), run with the `generalise` rule's command: the three-seed "
                "`snakemake --cores 2 generalise` is not stored yet.*\n\n" + screen.read_text(encoding="utf-8"))
        source = screen
    else:
        return _missing(root, full).replace("snakemake --cores 2 all", "snakemake --cores 2 generalise")
    return (text.rstrip("\n") + f"\n\nFrom `{source.relative_to(root)}`, drawn in "
            f"`{source.with_suffix('.png').relative_to(root)}`.\n")


def block_fresh(root: Path, preset: str) -> str:
    """The fresh-set check (`snakemake fresh`): the reference's actors on sets drawn with another seed."""
    path = root / "paper_figs" / preset / "fresh.md"
    if not path.exists():
        return _missing(root, path).replace("snakemake --cores 2 all", "snakemake --cores 2 fresh")
    return path.read_text(encoding="utf-8").rstrip("\n") + f"\n\nFrom `{path.relative_to(root)}`.\n"


def block_budget(root: Path, preset: str) -> str:
    """The budget study's table: success at its cell, env steps and core-hours per learner setting."""
    path = root / "paper_figs" / preset / "budget.csv"
    if not path.exists():
        return _missing(root, path).replace("snakemake --cores 2 all", "snakemake --cores 2 budget")
    df = pd.read_csv(path)
    lines = ["| setting | seeds | env steps per run | core-hours per run | env steps per core-second | "
             "success, 1.05 m excl. low cabinets (95% CI) | trained on | trained in |",
             "|---|---|---|---|---|---|---|---|"]
    for r in df.itertuples(index=False):
        lines.append(f"| `{r.setting}` | {int(r.n_seeds)} | {int(r.env_steps):,} | {_fmt(r.core_hours_per_seed)} | "
                     f"{r.env_steps_per_core_s:.0f} | {_fmt(r.success_rate)} [{_fmt(r.low)}, {_fmt(r.high)}] | "
                     f"{r.machine} | {r.trained_in} |")
    return "\n".join(lines) + f"\n\nFrom `{path.relative_to(root)}`.\n"


def _versus(a: float, a_low: float, a_high: float, b: float, b_low: float, b_high: float) -> str:
    """"above", "below" or "overlapping": where interval a lies against interval b."""
    if a_low > b_high:
        return "above"
    if a_high < b_low:
        return "below"
    return "overlapping"


def _apart(*intervals) -> str:
    return "intervals overlap" if _versus(*intervals) == "overlapping" else "intervals apart"


def _contrast_text(res: dict | None, intervals: tuple) -> str:
    if not res:
        return _apart(*intervals)
    side = "excludes 0" if res["ci_low"] > 0 or res["ci_high"] < 0 else "includes 0"
    return (f"95% interval of the difference [{_fmt(res['ci_low'])}, {_fmt(res['ci_high'])}] {side}, "
            f"paired on the {res['n_shared']} draws both cells share")


def table1_contrast(root: Path, preset: str, variant: str = "head_on") -> Callable[[tuple, tuple], dict | None]:
    """Cell-minus-cell contrasts of ``variant`` from its stored per-episode files, over every Table 1
    home it was evaluated in (not the generalisation groups) and the preset's seeds (Table 1's:
    :func:`preset_seeds`, not the reference's spread seeds stored beside them), each episode joined to
    its scenario's draw (home, start, target)."""
    config = workflow_config()
    homes, seeds = set(config["homes"]), preset_seeds(config, preset)

    def cell(height: float, placement: str) -> pd.DataFrame | None:
        frames = []
        runs = root / "results" / preset / "eval" / variant
        for seed in seeds:
            for path in sorted((runs / f"seed{seed}").glob(f"*/{placement}/h{height:g}.csv")):
                home = path.parent.parent.name
                if home not in homes:
                    continue
                scen = root / "results" / preset / "scenarios" / home / placement / path.name
                if not scen.exists():
                    return None
                eps = pd.read_csv(path).merge(pd.read_csv(scen), on="scenario_id", validate="one_to_one")
                frames.append(eps.assign(seed=seed))
        return pd.concat(frames, ignore_index=True) if frames else None

    def contrast(first: tuple, second: tuple) -> dict | None:
        a, b = cell(*first), cell(*second)
        if a is None or b is None or set(a["seed"]) != set(b["seed"]):
            return None
        return cell_contrast(a, b)

    return contrast


def _reading_table1(df: pd.DataFrame, contrast: Callable[[tuple, tuple], dict | None] | None = None) -> list[str]:
    """``contrast((height, placement), (height, placement))``: the first cell minus the second from the
    per-episode files (:func:`stats.cell_contrast`), or None where they are not stored; without it the
    comparisons fall back to whether the cells' own intervals overlap."""
    if "home" in df.columns:  # the rows set beside the paper's column: every home pooled, or the only one
        homes = set(df["home"])
        df = df[df["home"] == (BOTH_HOMES if BOTH_HOMES in homes else sorted(homes)[0])]
    df = df.assign(height=df["height"].round(2))
    cell = {(r.height, r.placement): r for r in df.itertuples(index=False)}
    out = []
    close = [(h, pl) for (h, pl), r in cell.items()
             if abs(r.success_rate - PAPER_TABLE1.get((h, pl), math.nan)) <= 0.10]
    far = ", ".join(f"{h:g} m {pl.replace('_', ' ')} {_fmt(r.success_rate)} vs {_fmt(PAPER_TABLE1[(h, pl)])}"
                    for (h, pl), r in cell.items() if (h, pl) not in close)
    out.append(f"- **Table 1 against the paper:** within 0.10 of the paper's success rate in {len(close)} of "
               f"{len(cell)} cells" + (f"; further off in the others (ours vs paper): {far}." if far else "."))
    if {"random_success_rate", "oracle_success_rate"} <= set(df.columns):
        floor = df["random_success_rate"]
        share = (df["success_rate"] - floor) / (df["oracle_success_rate"] - floor)
        out.append(f"- **Between the bounds:** every cell sits {_fmt(share.min())}–{_fmt(share.max())} of the way "
                   "from the random searcher to the privileged oracle.")
    for pl in ("no_low_cabinets", "everywhere"):
        low, tall = cell.get((0.45, pl)), [cell[(h, pl)] for h in (1.05, 1.65) if (h, pl) in cell]
        if low is None or not tall:
            continue
        ours = np.mean([t.success_rate for t in tall]) - low.success_rate
        paper = np.mean([PAPER_TABLE1[(t.height, pl)] for t in tall]) - PAPER_TABLE1[(0.45, pl)]
        taller = " and ".join(f"{t.height:g}" for t in tall)
        sides = [f"{t.height:g} m minus 0.45 m {t.success_rate - low.success_rate:+.2f}: " + _contrast_text(
                     contrast and contrast((t.height, pl), (0.45, pl)),
                     (t.success_rate, t.ci_low, t.ci_high, low.success_rate, low.ci_low, low.ci_high))
                 for t in tall]
        out.append(f"- **Height, {pl.replace('_', ' ')}** (paper: tall cameras see more, a drop for the shortest): "
                   f"the mean of {taller} m minus 0.45 m is {ours:+.2f} (paper: {paper:+.2f}); "
                   + "; ".join(sides) + ".")
    moves = []
    for h in (0.45, 1.05, 1.65):
        a, b = cell.get((h, "everywhere")), cell.get((h, "no_low_cabinets"))
        if a is None or b is None:
            continue
        paper = PAPER_TABLE1[(h, "everywhere")] - PAPER_TABLE1[(h, "no_low_cabinets")]
        apart = _contrast_text(contrast and contrast((h, "everywhere"), (h, "no_low_cabinets")),
                               (a.success_rate, a.ci_low, a.ci_high, b.success_rate, b.ci_low, b.ci_high))
        moves.append(f"{h:g} m {a.success_rate - b.success_rate:+.2f} (paper {paper:+.2f}; {apart})")
    if moves:
        out.append("- **Cabinets** (paper: tall cameras lose when targets may be inside low cabinets, the shortest "
                   "gains): everywhere minus excluding cabinets, " + "; ".join(moves) + ".")
    return out


def _reading_head(root: Path, preset: str) -> list[str]:
    """Head on against head off on every Table 1 scenario (the stored ``head_off_vs_head_on.csv``), per cell."""
    path = root / "results" / preset / "compare" / "head_off_vs_head_on.csv"
    if not path.exists():
        return []
    df = pd.read_csv(path)
    df = df[df["metric"] == "success"]
    cells = []
    lower = 0
    for r in df.itertuples(index=False):
        on_minus_off = -r.difference
        lower += int(bool(r.significant_holm) and r.difference < 0)
        where = "excl." if r.placement == "no_low_cabinets" else "everywhere"
        cells.append(f"{r.height:g} m {where} {on_minus_off:+.3f} [{-r.ci_high:+.3f}, {-r.ci_low:+.3f}]")
    return ["- **Head on vs head off** (paper: head movement gives a 20% higher success rate): on every Table 1 "
            "scenario, head-on minus head-off is " + "; ".join(cells) + f" (95% intervals); head-off is lower after "
            f"Holm in {lower} of {len(cells)} cells (`{path.relative_to(root)}`; Figure 6's curves read "
            f"{_curve_points_text(root, preset)} and cannot tell)."]


def _curve_points_text(root: Path, preset: str) -> str:
    """How many episodes a point of ``head_on``'s stored curve reads (its first seed's first point), in words."""
    episodes = root / "results" / preset / "train" / "head_on" / "seed0" / "curve_episodes.csv"
    if not episodes.exists():
        return "fewer episodes than Table 1"
    steps = pd.read_csv(episodes, usecols=["env_steps"])["env_steps"]
    return f"{int((steps == steps.min()).sum())} episodes a point"


def _reading_fig7(df: pd.DataFrame) -> list[str]:
    ours = df[df["method"] == "ours"].sort_values("M")
    base = df[df["method"] != "ours"]
    if ours.empty or base.empty:
        return []
    out = []
    verdicts = []
    for b in base.itertuples(index=False):
        apart = sum(_versus(o.spl, o.spl_low, o.spl_high, b.spl, b.spl_low, b.spl_high) == "above"
                    for o in ours.itertuples(index=False))
        verdicts.append(f"{b.label} {_fmt(b.spl)} (ours' interval above theirs at {apart} of {len(ours)} M)")
    out.append(f"- **Ours vs the baselines** (paper: ours about 40% higher SPL than 1-step and than noisy search): "
               f"ours has SPL {_fmt(ours['spl'].min())}–{_fmt(ours['spl'].max())} over M; " + "; ".join(verdicts) + ".")
    first, last = ours.iloc[0], ours.iloc[-1]
    if len(ours) > 1:
        trend = "falls" if last.spl < first.spl else "rises"
        side = _apart(first.spl, first.spl_low, first.spl_high, last.spl, last.spl_low, last.spl_high)
        attempts = "fall" if last.attempts < first.attempts else "rise"
        out.append(f"- **M** (paper: smaller M gives higher SPL, at the cost of more attempts): SPL {trend} from "
                   f"{_fmt(first.spl)} at M={int(first.M)} to {_fmt(last.spl)} at M={int(last.M)} ({side}); "
                   f"attempts {attempts} from {first.attempts:.1f} to {last.attempts:.1f}.")
    return out


def block_reading(root: Path, preset: str) -> str:
    """The stored run read against the paper's sentences, written from Table 1's and Figure 7's data and the
    stored head-on against head-off comparison: which claims it reproduces, by how much, and whether the 95%
    intervals are apart."""
    figs = root / "paper_figs" / preset
    paths = [figs / "table1.csv", figs / "fig7.csv"]
    missing = [p for p in paths if not p.exists()]
    if missing:
        return _missing(root, missing[0])
    lines = (_reading_table1(pd.read_csv(paths[0]), table1_contrast(root, preset))
             + _reading_head(root, preset) + _reading_fig7(pd.read_csv(paths[1])))
    return ("\n".join(lines) + "\n\nFrom `" + "`, `".join(str(p.relative_to(root)) for p in paths)
            + f"`; the height and cabinet contrasts from `results/{preset}/eval/head_on/` and the scenario sets.\n")


def _reference(root: Path) -> str:
    import yaml

    return yaml.safe_load((root / "egosearch/workflow/config.yaml").read_text(encoding="utf-8"))["reference_variant"]


def block_seed_spread(root: Path, preset: str) -> str:
    """The reference's seed spread, its null screen before and after the spread counts, the screen's test's
    simulated false-positive rates and the difference a screen of N seeds detects (``snakemake seed_spread``)."""
    reference = _reference(root)
    folder = root / "results" / preset / "compare"
    summary_path, null_path = folder / f"seed_spread_{reference}.json", folder / f"null_screen_{reference}.csv"
    if not summary_path.exists() or not null_path.exists():
        return _missing(root, summary_path if not summary_path.exists() else null_path)
    sm = json.loads(summary_path.read_text(encoding="utf-8"))
    null = pd.read_csv(null_path)
    succ = null[null["metric"] == "success"]
    called = ("lower", "higher")
    pairs = succ[~succ["screen"].str.endswith("the_others")]
    rest = succ[succ["screen"].str.endswith("the_others")]
    lines = [f"`{reference}`, {sm['n_seeds']} seeds ({', '.join(map(str, sm['seeds']))}), both homes, "
             f"{sm['n_scenarios']} scenarios per cell. Per cell, the spread of one "
             "seed's cell mean, what a screen's test counts, and its split: the seeds' own part and the part the "
             "scenarios' draw alone explains:", "",
             "| height | placement | one seed's mean (sd): the test's | seeds' own part (sd) | scenarios' part (sd) |",
             "|---|---|---|---|---|"]
    lines += [f"| {c['height']:g} | {c['placement']} | {c['seed_mean_sd']:.3f} | {c['seed_sd']:.3f} | "
              f"{c['scenario_part_sd']:.3f} |" for c in sm["cells"]]
    held_out = pairs["spread_seeds"].astype(str).str.count(r"\+").max() + 1 if len(pairs) else 0
    lines += ["", f"A seed's means correlate {sm['cell_correlation']:.2f} between cells on average.", "",
              f"**The null screen, a consistency check** (`{null_path.relative_to(root)}`): each seed screened as a "
              "candidate against each other seed and against the rest, the spread estimated from the seeds on "
              f"neither side ({held_out} for a pair). So few seeds, shared by the screens, make it no calibration "
              "(the simulation below is one); success cells:", "",
              "| screens | cells | called different, scenarios only (before) | called different, seed-spread test "
              "(now) |", "|---|---|---|---|",
              f"| one seed against another seed | {len(pairs)} | {int(pairs['scenarios_verdict'].isin(called).sum())} "
              f"| {int(pairs['verdict'].isin(called).sum())} |",
              f"| one seed against the rest | {len(rest)} | {int(rest['scenarios_verdict'].isin(called).sum())} | "
              f"{int(rest['verdict'].isin(called).sum())} |", ""]
    rates = pd.DataFrame(sm["false_positive_rate"])
    counts = sorted(rates["n_candidate"].unique())
    lines += [f"**The test's level, simulated** (`egosearch.report.calibration`): {sm['simulations']:,} screens per "
              f"setting, the candidate the reference's own config, seeds drawn from the model fitted to the stored "
              f"episodes; the share of success cells called different at p < {sm['alpha']} before Holm, over every "
              "cell (and in the cell where it is highest), for screens of N candidate seeds against the "
              f"{sm['n_seeds']} stored:", "",
              "| seed effects | spread truth | ρ | " + " | ".join(f"N = {n}" for n in counts) + " |",
              "|---|---|---|" + "---|" * len(counts)]
    for (law, truth, rho), g in rates.groupby(["law", "truth", "rho"], sort=False):
        g = g.set_index("n_candidate")
        lines.append(f"| {'t (3 df)' if law == 't3' else law} | {truth} | {rho:g} | " + " | ".join(
            f"{g.loc[n, 'rate']:.3f} ({g.loc[n, 'highest_cell_rate']:.3f})" for n in counts) + " |")
    worst = sm["worst_setting"]
    plain = rates[rates["n_candidate"] == 1]
    lines += ["", f"The highest rate is {worst['rate']:.3f} ({'t (3 df)' if worst['law'] == 't3' else worst['law']} "
              f"seed effects, {worst['truth']} spread, ρ {worst['rho']:g}, N = {worst['n_candidate']}); the highest "
              f"cell's {rates['highest_cell_rate'].max():.3f}. Every setting and cell at or below "
              f"{sm['level_claim']:g}: **{'yes' if sm['level_holds'] else 'no'}**. A one-seed screen whose p were "
              f"not taken 1.5 times (the plain prediction interval) would call up to "
              f"{plain['rate_without_one_seed_factor'].max():.3f} over the cells and "
              f"{plain['highest_cell_rate_without_one_seed_factor'].max():.3f} in one cell: why it is.", ""]
    power = pd.DataFrame(sm["detectable_80"])
    lines += [f"**Power**: the success difference the test detects with 80% power (5% level, before Holm) in a "
              f"screen of N candidate seeds against the {sm['n_seeds']} stored seeds, at each cell's stored spread "
              "(the formula of a screen's `detectable_80`):", "",
              "| height | placement | " + " | ".join(f"N = {n}" for n in sorted(power["n_candidate"].unique())) + " |",
              "|---|---|" + "---|" * power["n_candidate"].nunique()]
    for (h, pl), g in power.groupby(["height", "placement"], sort=False):
        values = g.sort_values("n_candidate")["detectable_80"]
        lines.append(f"| {h:g} | {pl} | " + " | ".join(f"{v:.3f}" for v in values) + " |")
    day = (f"a user's day ({sm['day_hours']:g} h on {sm['day_cores']} cores) holds {sm['seeds_per_day']} seeds at "
           f"{sm['hours_per_seed']:.2f} h each (the slowest recorded training of the reference and 12 evaluations)")
    target = f"a difference of {sm['power_target']:g} at {sm['power_cell'][0]:g} m ({sm['power_cell'][1]})"
    if sm["detectable_at_recommended"] <= sm["power_target"]:
        verdict = (f"{target.capitalize()} is detected with {sm['recommended_screen_seeds']} seeds, within reach: "
                   f"{day}.")
    else:
        verdict = (f"{target.capitalize()} is out of reach: {day}, and those detect "
                   f"{sm['detectable_at_a_days_seeds']:.3f} (the reference's own {sm['n_seeds']} seeds bound it). "
                   f"The recommendation is then the fewest seeds within {sm['knee'] * 100:.0f} % of that, past which "
                   "more seeds barely help.")
    lines += ["", verdict + f" The recommended `screen_seeds` is **{sm['recommended_screen_seeds']}**, which detects "
              f"{sm['detectable_at_recommended']:.3f} there.", "", f"From `{summary_path.relative_to(root)}`."]
    return "\n".join(lines) + "\n"


def block_failures(root: Path, preset: str) -> str:
    """The failure-kind table (``paper_figs/<preset>/failures.md``, rule ``failures``) without its title."""
    path = root / "paper_figs" / preset / "failures.md"
    if not path.exists():
        return _missing(root, path)
    lines = path.read_text(encoding="utf-8").splitlines()
    return "\n".join(line for line in lines if not line.startswith("# ")).strip("\n") + "\n"


def block_memory_window(root: Path, preset: str) -> str:
    """How much memory the search asks for (``paper_figs/<preset>/memory_window.md``, rule ``memory_window``)."""
    path = root / "paper_figs" / preset / "memory_window.md"
    if not path.exists():
        return _missing(root, path)
    return path.read_text(encoding="utf-8").strip("\n") + f"\n\nFrom `{path.relative_to(root)}`.\n"


def block_teacher_tuning(root: Path, preset: str) -> str:
    """The tuned searcher's tuning run again (``results/<preset>/teacher_tuning/record.json``, rule
    ``tune_teacher``): each candidate on the fit split against the untuned searcher, the choice, and the choice
    against the untuned searcher on the held-out split; success paired by scenario, 95% bootstrap intervals."""
    path = root / "results" / preset / "teacher_tuning" / "record.json"
    if not path.exists():
        return (f"*Not run yet: `{path.relative_to(root)}` is missing (`snakemake --cores 1 teacher_tuning`, about "
                "13,000 episodes).*\n")
    record = json.loads(path.read_text(encoding="utf-8"))
    modes = list(record["held_out"])
    splits = record["splits"]
    lines = [f"Fit split: {splits['fit']['scenarios']} scenarios a head mode; held-out split: "
             f"{splits['held_out']['scenarios']}. Success, each candidate minus the untuned searcher on the same "
             "scenarios [95% interval]:", "",
             "| candidate | " + " | ".join(f"fit, {mode}" for mode in modes) + " | mean over both |",
             "|---|" + "---|" * (len(modes) + 1)]
    for name, row in record["candidates"].items():
        cells = [f"{row[f'fit_{mode}']['candidate']:.3f} ({row[f'fit_{mode}']['difference']:+.3f} "
                 f"[{row[f'fit_{mode}']['low']:+.3f}, {row[f'fit_{mode}']['high']:+.3f}])" for mode in modes]
        mark = " **(chosen)**" if name == record["chosen"] else ""
        lines.append(f"| `{name}`{mark} | " + " | ".join(cells) + f" | {row['fit_mean_over_head_modes']:.3f} |")
    lines += ["", f"Chosen on the fit split: `{record['chosen']}`"
              + (" (the shipped parameters)." if record["chosen_is_shipped"] else
                 " (**not** the shipped parameters, which the stored runs use).")]
    for mode, r in record["held_out"].items():
        lines.append(f"- held out, {mode}: untuned {r['reference']:.3f} -> chosen {r['candidate']:.3f}, "
                     f"{r['difference']:+.3f} [{r['low']:+.3f}, {r['high']:+.3f}] ({r['scenarios']} scenarios)")
    return "\n".join(lines) + f"\n\nFrom `{path.relative_to(root)}`.\n"


def _called_cells(rows: pd.DataFrame, column: str) -> str:
    picked = [f"{h:g} {'excl.' if p == 'no_low_cabinets' else 'every'} {v}" for h, p, v
              in zip(rows["height"], rows["placement"], rows[column]) if v in ("higher", "lower")]
    return ", ".join(picked) or "none"


def _reread_conclusion(before: list[str], now: list[str]) -> str:
    if before == now:
        return "unchanged"
    if not now:
        return "within the seed spread now"
    if not before:
        return "called different now"
    return "fewer cells" if set(now) < set(before) else "other cells"


def block_screens_reread(root: Path, preset: str) -> str:
    """Every stored screen, its stored verdict and the seed-spread test's (``screens_reread.csv``)."""
    path = root / "results" / preset / "compare" / "screens_reread.csv"
    if not path.exists():
        return _missing(root, path)
    df = pd.read_csv(path)
    lines = ["| screen (candidate vs reference) | seeds (candidate / reference) | spread counted | stored test "
             "| called different as stored (success cells) | called different now | conclusion |",
             "|---|---|---|---|---|---|---|"]
    for screen, g in df.groupby("screen", sort=True):
        if g["metric"].isna().all():
            lines.append(f"| `{screen}` | | | | | | {g['verdict'].iloc[0]} |")
            continue
        s = g[g["metric"] == "success"]
        before, now = _called_cells(s, "old_verdict"), _called_cells(s, "verdict")
        conclusion = _reread_conclusion([] if before == "none" else before.split(", "),
                                        [] if now == "none" else now.split(", "))
        first = s.iloc[0]
        lines.append(f"| `{screen}` | {first['candidate_seeds']} / {first['reference_seeds']} | "
                     f"{first['spread_from']} ({first['spread_seeds']}) | {first['old_method']} | {before} | {now} | "
                     f"{conclusion} |")
    return "\n".join(lines) + f"\n\nFrom `{path.relative_to(root)}` (`snakemake seed_spread`).\n"


BLOCKS: dict[str, Callable[[Path, str], str]] = {
    "departures": block_departures,
    "budget": block_budget,
    "generalise": block_generalise,
    "fresh": block_fresh,
    "table1": block_table1,
    "table1_pooled": block_table1_pooled,
    "standing": block_standing,
    "fig6": block_fig6,
    "fig7": block_fig7,
    "fig7_oracle": lambda root, preset: block_fig7(root, preset, "fig7_oracle"),
    "provenance": block_provenance,
    # the stored comparisons, one block per page of docs/ablations/ and the index's for those of no family
    **{f"compare_{family}": (lambda root, preset, family=family: block_compare(root, preset, family))
       for family in ABLATION_FAMILIES},
    "compare_unfiled": lambda root, preset: block_compare(root, preset, unfiled=True),
    "power": block_power,
    "seed_spread": block_seed_spread,
    "failures": block_failures,
    "memory_window": block_memory_window,
    "teacher_tuning": block_teacher_tuning,
    "screens_reread": block_screens_reread,
    "reading": block_reading,
    "claims": block_claims,  # the paper's behaviour sentences against the per-step traces
    "speed": block_speed,  # the stored benchmark records and trainings' speed
    "gpu": block_gpu,  # the stored GPU check and the paper preset's projection
    "gpu_projection": block_gpu_projection,
}

DOCS = "docs"
"""The folder of the documentation pages, beside the README (``mkdocs.yml``'s ``docs_dir``)."""


def pages(root: Path) -> list[Path]:
    """Every page whose blocks are generated: ``README.md`` and each ``docs/**/*.md`` under ``root``."""
    root = Path(root)
    found = [root / "README.md"] if (root / "README.md").is_file() else []
    return found + sorted((root / DOCS).rglob("*.md"))


def page_root(page: Path) -> Path:
    """The project root a page's blocks read from: the page's own folder, or the one above ``docs/``
    for a docs page."""
    page = Path(page).resolve()
    for folder in page.parents:
        if folder.name == DOCS:
            return folder.parent
    return page.parent


def render_readme(text: str, root: Path, preset: str) -> str:
    """``text`` with every marked block replaced by what the stored files give."""
    def replace(match: re.Match) -> str:
        name = match.group("name")
        if name not in BLOCKS:
            raise ValueError(f"README block {name!r} is unknown; known: {', '.join(BLOCKS)}")
        return match.group(1) + BLOCKS[name](root, preset) + match.group(4)

    return BLOCK.sub(replace, text)


def update_readme(readme: Path, preset: str, check: bool = False, root: Path | None = None) -> bool:
    """Rewrite the marked blocks of the page ``readme`` (or with ``check`` only compare), reading the stored
    files under ``root`` (default: :func:`page_root`); True when it was up to date."""
    readme = Path(readme)
    text = readme.read_text(encoding="utf-8")
    rendered = render_readme(text, Path(root) if root is not None else page_root(readme), preset)
    if rendered == text:
        return True
    if not check:
        readme.write_text(rendered, encoding="utf-8")
    return False


def update_pages(root: Path, preset: str, check: bool = False) -> list[Path]:
    """:func:`update_readme` on every page of :func:`pages`; the pages that were out of date."""
    return [page for page in pages(root) if not update_readme(page, preset, check=check, root=root)]

"""Figures 6 and 7 of the paper from the result CSVs: 300-dpi PNG + vector PDF (+ the numbers as CSV).

Uses matplotlib's object API (``matplotlib.figure.Figure``, Agg canvas), never pyplot, so it neither
needs a display nor changes the global backend; the style is applied per figure with
``matplotlib.rc_context``.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterable, Mapping
from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Patch
from matplotlib.ticker import FuncFormatter, MultipleLocator

from egosearch.report.data import (
    CURVE_LEVEL_COLUMNS,
    counts_decisions,
    output_base,
    read_checked_csv,
    read_curves,
    read_fullbody,
    seed_from_path,
    suffixed,
)
from egosearch.report.stats import bootstrap_ci, cluster_bootstrap_mean, scenario_seed_matrix, two_level_ci, wilson_ci
from egosearch.searchers import searcher_registry as searchers

PathLike = str | os.PathLike

OKABE_ITO = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442", "#000000")
"""Colour-blind-safe palette (Okabe & Ito 2008)."""

STYLE = {
    "font.family": "serif",
    "font.serif": ["STIXGeneral", "DejaVu Serif"],
    "mathtext.fontset": "stix",
    "font.size": 9, "axes.labelsize": 9, "axes.titlesize": 9, "legend.fontsize": 8,
    "xtick.labelsize": 8, "ytick.labelsize": 8,
    "axes.spines.top": False, "axes.spines.right": False, "axes.linewidth": 0.8,
    "axes.grid": True, "grid.color": "#b0b0b0", "grid.alpha": 0.35, "grid.linewidth": 0.5,
    "axes.axisbelow": True, "legend.frameon": False,
    "lines.linewidth": 1.6, "errorbar.capsize": 2.5,
    "savefig.dpi": 300, "savefig.bbox": "tight", "savefig.pad_inches": 0.03,
    "pdf.fonttype": 42, "ps.fonttype": 42,
}
"""Paper-like look: Times-like serif (STIX ships with matplotlib), light grid, no top/right spines."""

FIG6_LABELS = {"head_on": "with head movement", "head_off": "without head movement"}

BASELINES = ("one_step_short", "one_step_long", "noisy_search")
METHOD_LABELS = {"one_step_short": "1-step short", "one_step_long": "1-step long", "noisy_search": "Noisy search",
                 "ours": "Ours"}
MG_LABELS = {"humanoid_phase": "Humanoid, phase MG", "humanoid_matching": "Humanoid, matching MG",
             "fetch": "Fetch"}
MG_ORDER = ("humanoid_phase", "humanoid_matching", "fetch")
PLANNER_TITLES = {"actor": None, "oracle": "Planner: privileged oracle (knows the target; not the learned policy)"}
"""Figure 7's title per planner: the paper's figure (the learned policy) has none."""

RANDOM = "random"
"""Figure 6's row name of the random searcher (a dashed line: the level a policy must rise above)."""


def fig6_levels() -> dict[str, tuple]:
    """Figure 6's levels, searchers that do not train (a horizontal line each: label, line style, colour): the
    registered searchers with a ``fig6_level`` (:mod:`egosearch.searchers.searcher_registry`), the floor a policy must
    rise above and the classical searcher its learning is read against. The row name is the searcher's, read
    from its episodes' path (:func:`level_searcher`)."""
    return {s.name: s.fig6_level for s in searchers.SEARCHERS.values() if s.fig6_level}


START_LABEL = "policy at step 0"
"""Legend text of the dotted line at each curve's first point (its start: untrained, or cloned)."""
FIG6_COLUMNS = ("variant", "label", "env_steps", "n_seeds", "n_scenarios", "success_rate", "low", "high", "ci_unit",
                "rise", "rise_low", "rise_high")
"""``rise``: the success rate at this step minus the curve's first (its start), with the 95 % interval of that
difference paired on the same episodes and seeds (two-level bootstrap; NaN where the episodes are not stored)."""
CI_TWO_LEVEL, CI_SEEDS, CI_WILSON = "scenarios, then seeds", "seeds", "episodes (Wilson)"
FIG7_COLUMNS = ("mg", "method", "label", "M", "T", "baseline", "n_episodes", "n_scenarios", "n_seeds",
                "success_rate", "spl", "spl_low", "spl_high", "attempts", "attempts_low", "attempts_high",
                "penetration_rate", "collisions", "ci_unit")


def _steps_formatter(x: float, _pos=None) -> str:
    if x == 0:
        return "0"
    if abs(x) >= 1e6:
        return f"{x / 1e6:g}M"
    if abs(x) >= 1e3:
        return f"{x / 1e3:g}k"
    return f"{x:g}"


PDF_METADATA = {"CreationDate": None}
"""The PDF writer stamps the time by default: without it, regenerating a figure from the same CSV
changed the tracked PDF on every run (the PNG writer stamps none)."""


def save_figure(fig: Figure, base: Path) -> list[Path]:
    """Write ``fig`` to ``{base}.png`` (300 dpi) and ``{base}.pdf`` (no time stamp); return the two paths."""
    FigureCanvasAgg(fig)
    outs = [suffixed(base, ".png"), suffixed(base, ".pdf")]
    fig.savefig(outs[0], dpi=300)
    fig.savefig(outs[1], metadata=PDF_METADATA)
    return outs


# --------------------------------------------------------------------------------------------- Figure 6
def _curve_episodes(curve_paths: list) -> pd.DataFrame | None:
    """The episodes behind every seed's curve (``curve_episodes.csv`` beside each ``curve.csv``), with
    ``seed`` and ``scenario_set`` (home and height: scenario ids restart in each); None unless every
    run kept them."""
    frames = []
    for i, path in enumerate(curve_paths):
        sibling = Path(path).with_name("curve_episodes.csv")
        if not sibling.exists():
            return None
        try:
            s = seed_from_path(path)
        except ValueError:
            s = i
        eps = pd.read_csv(sibling)
        frames.append(eps.assign(seed=s, scenario_set=eps["home"] + "/h" + eps["height"].map("{:g}".format)))
    return pd.concat(frames, ignore_index=True) if frames else None


CURVE_LEVELS_DIR = "eval_curve"
"""Where the levels' episodes lie: ``{results}/eval_curve/{searcher}/{variant}.csv``, written by
``egosearch evaluate --curve-of VARIANT --policy SEARCHER`` on the scenarios of the variant's curve."""


def level_searcher(path: PathLike) -> str:
    """The searcher whose episodes on a curve's scenarios ``path`` holds (``.../eval_curve/{searcher}/{variant}.csv``),
    one of :func:`fig6_levels`; ValueError otherwise."""
    parts = Path(path).parts
    name = parts[-2] if len(parts) >= 3 and parts[-3] == CURVE_LEVELS_DIR else ""
    levels = fig6_levels()
    if name not in levels:
        raise ValueError(f"figure6: {path} is no level's episodes on a curve's scenarios (.../{CURVE_LEVELS_DIR}/"
                         f"SEARCHER/VARIANT.csv from `egosearch evaluate --curve-of VARIANT --policy SEARCHER`, "
                         f"SEARCHER one of {', '.join(levels)})")
    return name


def read_curve_levels(paths: list) -> pd.DataFrame:
    """A level's episodes on a curve's scenarios (:data:`egosearch.runs.evaluate.CURVE_LEVEL_COLUMNS`), stacked."""
    frames = []
    for path in paths:
        df = read_checked_csv(path, CURVE_LEVEL_COLUMNS, "level's episodes on a curve's scenarios")
        if df.empty:
            raise ValueError(f"{path}: no episodes")
        frames.append(df)
    return pd.concat(frames, ignore_index=True)


def _scenario_keys(df: pd.DataFrame) -> set:
    return {(h, round(float(z), 3), int(i), round(float(ell), 3))
            for h, z, i, ell in zip(df["home"], df["height"], df["scenario_id"], df["shortest_path"])}


def figure6_frame(curves: Mapping[str, Iterable[PathLike]], labels: Mapping[str, str] | None = None,
                  confidence: float = 0.95, n_resamples: int = 10_000, seed: int = 0,
                  level_files: Iterable[PathLike] | None = None) -> pd.DataFrame:
    """Numbers behind Figure 6: per variant and evaluation step, the mean success rate over seeds and a
    95% band. Where every seed's run kept the episodes behind its curve (``curve_episodes.csv`` beside
    ``curve.csv``), the band is the two-level bootstrap over the evaluation's scenarios, then the seeds
    (``ci_unit`` says which); otherwise a percentile bootstrap over the seeds' rates (NaN where fewer
    than 2 seeds were evaluated at that step).

    Seeds are aligned on ``env_steps``; at each step only the seeds that have it count.
    ``level_files``: the episodes of searchers that do not train (:func:`fig6_levels`: the random
    searcher, the classical searchers; which one a file is comes from its path, :func:`level_searcher`)
    on the curves' own scenarios, seeded as the curves' episodes are (``egosearch evaluate --curve-of``):
    each searcher's success rate and Wilson interval become rows named after it, one at every step of
    the curves (the same level throughout). ValueError when a level ran other scenarios than a curve's
    episodes: a level must be read on the episodes its curves are.
    """
    labels = {**FIG6_LABELS, **(labels or {})}
    if not curves:
        raise ValueError("figure6: no training curves given")
    rows, curve_episode_sets = [], {}
    for variant, paths in curves.items():
        paths = [paths] if isinstance(paths, (str, os.PathLike)) else list(paths)
        if not paths:
            raise ValueError(f"figure6: variant {variant!r} has no curve files")
        df = read_curves(paths)
        if df.empty:
            raise ValueError(f"figure6: the curves of {variant!r} have no evaluated rows")
        episodes = _curve_episodes(paths)
        if episodes is not None:
            curve_episode_sets[variant] = episodes[episodes["env_steps"] == episodes["env_steps"].min()]
        start_matrix, start_rate = None, None
        for step, g in df.groupby("env_steps", sort=True):
            v = g["success_rate"].to_numpy(dtype=float)
            start_rate = float(v.mean()) if start_rate is None else start_rate
            at = None if episodes is None else episodes[episodes["env_steps"] == step]
            rise_lo = rise_hi = math.nan
            if at is not None and set(at["seed"]) == set(g["seed"]) and not at.empty:
                m, keys = scenario_seed_matrix(at, "success")
                _, lo, hi = two_level_ci(m, confidence, n_resamples, seed)
                unit, n_scen = CI_TWO_LEVEL, m.shape[0]
                if start_matrix is None:
                    start_matrix = (m, keys)
                elif start_matrix[1] == keys and start_matrix[0].shape == m.shape:
                    # the same episodes and seeds as the start: the rise's interval is paired on them
                    _, rise_lo, rise_hi = two_level_ci(m - start_matrix[0], confidence, n_resamples, seed)
                if start_matrix[0] is m:
                    rise_lo = rise_hi = 0.0
            else:
                lo, hi = (bootstrap_ci(v, np.mean, confidence, n_resamples, seed) if v.size >= 2
                          else (math.nan, math.nan))
                unit, n_scen = CI_SEEDS, math.nan
            rows.append({"variant": variant, "label": labels.get(variant, variant), "env_steps": int(step),
                         "n_seeds": int(v.size), "n_scenarios": n_scen, "success_rate": float(v.mean()),
                         "low": lo, "high": hi, "ci_unit": unit, "rise": float(v.mean()) - start_rate,
                         "rise_low": rise_lo, "rise_high": rise_hi})
    by_level: dict[str, list] = {}
    for path in level_files or []:
        by_level.setdefault(level_searcher(path), []).append(path)
    levels = fig6_levels()
    curve_keys = {variant: _scenario_keys(eps) for variant, eps in curve_episode_sets.items()}
    for name in sorted(by_level, key=list(levels).index):
        if name in curves:
            raise ValueError(f"figure6: a variant may not be called {name!r}, the {levels[name][0]}'s row")
        eps = read_curve_levels(by_level[name])
        for variant, keys in curve_keys.items():
            if _scenario_keys(eps) != keys:
                raise ValueError(f"figure6: {name}'s episodes ({', '.join(map(str, by_level[name]))}) ran other "
                                 f"scenarios than {variant}'s curve: a level is read on the curve's own "
                                 "(`egosearch evaluate --curve-of VARIANT --policy SEARCHER`)")
        k, n = int(eps["success"].astype(int).sum()), len(eps)
        lo, hi = wilson_ci(k, n, confidence)
        for step in sorted({r["env_steps"] for r in rows}):
            rows.append({"variant": name, "label": levels[name][0], "env_steps": step,
                         "n_seeds": 1, "n_scenarios": n, "success_rate": k / n,
                         "low": lo, "high": hi, "ci_unit": CI_WILSON, "rise": 0.0, "rise_low": math.nan,
                         "rise_high": math.nan})
    return pd.DataFrame(rows, columns=list(FIG6_COLUMNS))


def imitation_phases(curve_path: PathLike) -> list[tuple[int, str]]:
    """Where a training's learning from the teacher changes phase, read from the ``config.json`` beside its
    ``curve.csv``: (env step, label) for the first RL step of the actor after behaviour cloning (after the
    warm-up and the critic's warm-up: ``bc_updates``, ``critic_warmup_updates``), and for the end of the
    decaying cloning term (``bc_decay_steps``, where it reaches 0 or its ``bc_weight_floor``). Empty for a
    training without a teacher (or no config)."""
    try:
        recorded = json.loads((Path(curve_path).parent / "config.json").read_text(encoding="utf-8"))["config"]
    except (OSError, ValueError, KeyError):
        return []
    # a field that did not exist when the run was stored: the run trained without it, as its off value says (the
    # report layer reads files, not the learner config: tests/test_layout.py)
    cfg = {"critic_warmup_updates": 0, "bc_decay_steps": 0, "bc_weight_floor": 0.0, **recorded}
    phases = []
    if cfg.get("bc_updates"):
        first_update = -(-max(cfg["init_steps"], 1) // cfg["update_every"]) * cfg["update_every"]
        warmup_steps = -(-cfg["critic_warmup_updates"] // cfg["updates_per_step"]) * cfg["update_every"]
        start = first_update + warmup_steps
        if start <= cfg["total_env_steps"]:
            phases.append((start, "imitation ends: RL steps the actor"))
    if cfg.get("bc_weight") and cfg["bc_decay_steps"] <= cfg["total_env_steps"]:
        floor = cfg["bc_weight_floor"]
        phases.append((int(cfg["bc_decay_steps"]), f"cloning term reaches {floor:g}"))
    return phases


def figure6(curves: Mapping[str, Iterable[PathLike]], out_prefix: PathLike, labels: Mapping[str, str] | None = None,
            confidence: float = 0.95, n_resamples: int = 10_000, seed: int = 0,
            level_files: Iterable[PathLike] | None = None) -> list[Path]:
    """Figure 6: evaluation success rate vs environment steps, one line per variant (mean over seeds) with a
    bootstrap band over seeds where at least 2 seeds were evaluated.

    ``curves``: ``{variant: [curve.csv per seed]}``; ``labels``: legend text per variant (default:
    ``head_on`` -> "with head movement", ``head_off`` -> "without head movement"). Writes
    ``{prefix}.png`` (300 dpi), ``{prefix}.pdf`` and ``{prefix}.csv`` (the plotted numbers; a directory
    prefix gets ``fig6.*``) and returns the paths. ValueError on no curves / no evaluated rows.
    ``level_files`` (see :func:`figure6_frame`) add the random and classical searchers as horizontal lines,
    and each curve's start (its step-0 point: the untrained or cloned policy) is a dotted line in its colour,
    so that what learning adds reads against both. A training that learned from the classical searcher
    marks where its imitation phase ends (:func:`imitation_phases`). A modular searcher's curve counts
    decisions (the x axis says so).
    """
    df = figure6_frame(curves, labels, confidence, n_resamples, seed, level_files=level_files)
    base = output_base(out_prefix, "fig6")
    df.to_csv(suffixed(base, ".csv"), index=False, float_format="%.6g")
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=(3.5, 2.5))
        ax = fig.add_subplot()
        levels = fig6_levels()
        for name, (level_label, style, level_colour) in levels.items():
            level = df[df["variant"] == name]
            if not level.empty:
                ax.axhline(level["success_rate"].iloc[0], color=level_colour, linestyle=style, linewidth=1.1,
                           label=level_label)
        trained = df[~df["variant"].isin(list(levels))]
        for i, (_variant, g) in enumerate(trained.groupby("variant", sort=False)):
            colour = OKABE_ITO[i % len(OKABE_ITO)]
            x, y = g["env_steps"].to_numpy(), g["success_rate"].to_numpy()
            n_seeds = int(g["n_seeds"].max())
            label = g["label"].iloc[0] + (f" ({n_seeds} seeds)" if n_seeds > 1 else "")
            ax.plot(x, y, color=colour, label=label, marker="o" if len(x) == 1 else None, markersize=3)
            if len(x) > 1:  # where learning starts from: a level, so the rise reads at a glance
                ax.axhline(y[0], color=colour, linestyle=":", linewidth=0.9,
                           label=START_LABEL if i == 0 else None)
            band = g["low"].notna().to_numpy()
            if band.any():
                ax.fill_between(x, g["low"].to_numpy(), g["high"].to_numpy(), where=band, color=colour,
                                alpha=0.2, linewidth=0, interpolate=False)
        phases, decisions = {}, []
        for variant_paths in curves.values():
            paths = [variant_paths] if isinstance(variant_paths, (str, os.PathLike)) else list(variant_paths)
            for step, label in (imitation_phases(paths[0]) if paths else []):
                phases.setdefault((step, label), None)
            decisions += [counts_decisions(p) for p in paths]
        for (step, label), style in zip(phases, (":", "-.", (0, (1, 3)), (0, (3, 1, 1, 1)))):
            ax.axvline(step, color="#333333", linestyle=style, linewidth=0.9, label=label)
        # a modular searcher's env step is a decision of where to go, several body steps each
        ax.set_xlabel("Decisions" if decisions and all(decisions) else
                      "Environment steps (decisions of a modular searcher)" if any(decisions) else
                      "Environment steps")
        ax.set_ylabel("Success rate")
        ax.set_ylim(0, 1.02)
        ax.set_xlim(left=0)
        ax.yaxis.set_major_locator(MultipleLocator(0.2))
        ax.xaxis.set_major_formatter(FuncFormatter(_steps_formatter))
        # Beside the axes: inside, any corner would hide a curve or a level at some preset's success rates.
        ax.legend(loc="center left", bbox_to_anchor=(1.02, 0.5), borderaxespad=0.0)
        outs = save_figure(fig, base)
    return [*outs, suffixed(base, ".csv")]


# --------------------------------------------------------------------------------------------- Figure 7
def _method_label(method: str, M, T, multi_m: bool, multi_t: bool) -> str:
    name = METHOD_LABELS.get(method, method)
    parts = []
    if method == "ours" or multi_m:
        parts.append(f"M={M:g}" if isinstance(M, float) else f"M={M}")
    if multi_t:
        parts.append(f"T={T}")
    return f"{name} {' '.join(parts)}".strip()


def figure7_frame(fullbody_files: Iterable[PathLike], confidence: float = 0.95, n_resamples: int = 10_000,
                  seed: int = 0) -> pd.DataFrame:
    """Numbers behind Figure 7: one row per (mg, method, M, T), baselines first, then ``ours`` by M.

    Means are over all episodes pooled over seeds; CIs are percentile bootstraps that resample
    scenarios (each scenario's seeds averaged first; ``ci_unit`` = ``scenario``). If a scenario id
    repeats within one seed of a group (several scenario files pooled into one CSV) scenarios cannot be
    told apart and episodes are resampled instead (``ci_unit`` = ``episode``). ``attempts`` is the mean
    number of abstract trajectories planned per episode over all episodes (failed ones included).
    """
    paths = [fullbody_files] if isinstance(fullbody_files, (str, os.PathLike)) else list(fullbody_files)
    if not paths:
        raise ValueError("figure7: no full-body CSVs given")
    df = read_fullbody(paths)
    if df.empty:
        raise ValueError("figure7: the full-body CSVs have no episodes")
    rows = []
    for method, gm in df.groupby("method", sort=False):
        multi_m = gm["M"].nunique() > 1 and method != "ours"
        multi_t = gm["T"].nunique() > 1
        for (mg, M, T), g in gm.groupby(["mg", "M", "T"], sort=True):
            if g.duplicated(["seed", "scenario_id"]).any():
                unit, gg, cl = "episode", g.reset_index(drop=True).rename_axis("episode").reset_index(), "episode"
            else:
                unit, gg, cl = "scenario", g, "scenario_id"
            spl, spl_lo, spl_hi = cluster_bootstrap_mean(gg, "spl", cl, confidence, n_resamples, seed)
            att, att_lo, att_hi = cluster_bootstrap_mean(gg, "attempts", cl, confidence, n_resamples, seed)
            rows.append({"mg": mg, "method": method, "label": _method_label(method, M, T, multi_m, multi_t),
                         "M": M, "T": T, "baseline": method != "ours", "n_episodes": len(g),
                         "n_scenarios": int(g["scenario_id"].nunique()), "n_seeds": int(g["seed"].nunique()),
                         "success_rate": float(g["success"].mean()), "spl": spl, "spl_low": spl_lo,
                         "spl_high": spl_hi, "attempts": att, "attempts_low": att_lo, "attempts_high": att_hi,
                         "penetration_rate": float(g["penetration_rate"].mean()),
                         "collisions": float(g["collisions"].mean()), "ci_unit": unit})
    out = pd.DataFrame(rows, columns=list(FIG7_COLUMNS))
    border = {m: i for i, m in enumerate(BASELINES)}
    out["_o1"] = [0 if b else 1 for b in out["baseline"]]
    out["_o2"] = [border.get(m, len(BASELINES)) for m in out["method"]]
    mgo = {m: i for i, m in enumerate(MG_ORDER)}
    out["_o3"] = [mgo.get(m, len(MG_ORDER)) for m in out["mg"]]
    out = out.sort_values(["_o1", "_o2", "method", "M", "T", "_o3", "mg"], kind="stable")
    return out.drop(columns=["_o1", "_o2", "_o3"]).reset_index(drop=True)


def _yerr(mean, lo, hi) -> np.ndarray:
    lo = np.where(np.isnan(lo), mean, lo)
    hi = np.where(np.isnan(hi), mean, hi)
    return np.vstack([np.maximum(mean - lo, 0), np.maximum(hi - mean, 0)])


def figure7(fullbody_files: Iterable[PathLike], out_prefix: PathLike, confidence: float = 0.95,
            n_resamples: int = 10_000, seed: int = 0, title: str | None = None) -> list[Path]:
    """Figure 7: left, SPL per method (bars, bootstrap CI over scenarios; baselines left of a dashed line,
    then ours for each M); right, abstract-trajectory attempts vs M for ours (mean and CI). ``title``
    goes above both panels (e.g. which planner drove the search).

    Several motion generators (``mg``) are shown as grouped bars / separate lines with one colour each.
    Writes ``{prefix}.png`` (300 dpi), ``{prefix}.pdf`` and ``{prefix}.csv`` (:func:`figure7_frame`; a
    directory prefix gets ``fig7.*``) and returns the paths. ValueError on no files / no episodes.
    """
    df = figure7_frame(fullbody_files, confidence, n_resamples, seed)
    base = output_base(out_prefix, "fig7")
    df.to_csv(suffixed(base, ".csv"), index=False, float_format="%.6g")
    with matplotlib.rc_context(STYLE):
        outs = save_figure(figure7_figure(df, title), base)
    return [*outs, suffixed(base, ".csv")]


ALL_ZERO_NOTE = "every SPL is 0: no method found the target in any episode"
"""Said on Figure 7 when every bar is 0, so that an empty-looking axis is not read as a broken plot."""


def figure7_figure(df: pd.DataFrame, title: str | None = None) -> Figure:
    """The Figure 7 plot of a :func:`figure7_frame`; call it inside ``matplotlib.rc_context(STYLE)``."""
    mgs = sorted(df["mg"].unique(), key=lambda m: (MG_ORDER.index(m) if m in MG_ORDER else len(MG_ORDER), m))
    cats = list(dict.fromkeys(df["label"]))
    n_base = int(df.drop_duplicates("label")["baseline"].sum())
    single = len(mgs) == 1
    fig = Figure(figsize=(7.0, 2.7))
    gs = fig.add_gridspec(1, 2, width_ratios=[1.9, 1.0], wspace=0.28)
    ax, ax2 = fig.add_subplot(gs[0]), fig.add_subplot(gs[1])
    width = 0.8 / len(mgs)
    for j, mg in enumerate(mgs):
        g = df[df["mg"] == mg].set_index("label").reindex(cats)
        present = g["spl"].notna().to_numpy()
        x = np.arange(len(cats)) + (j - (len(mgs) - 1) / 2) * width
        if single:
            colours = ["#a6a6a6" if b else OKABE_ITO[0] for b in g["baseline"].fillna(True)]
        else:
            colours = [OKABE_ITO[j % len(OKABE_ITO)]] * len(cats)
        spl = g["spl"].to_numpy(dtype=float)
        err = _yerr(spl, g["spl_low"].to_numpy(dtype=float), g["spl_high"].to_numpy(dtype=float))
        ax.bar(x[present], spl[present], width * 0.92, color=np.array(colours)[present],
               yerr=err[:, present], ecolor="#333333", error_kw={"elinewidth": 0.8}, edgecolor="none")
    if 0 < n_base < len(cats):
        ax.axvline(n_base - 0.5, color="#333333", linestyle="--", linewidth=0.9)
    ax.set_xticks(np.arange(len(cats)), [c.replace(" ", "\n", 1) for c in cats])
    ax.tick_params(axis="x", length=0)
    ax.set_ylabel("SPL")
    ax.set_xlim(-0.6, len(cats) - 0.4)
    top = float(np.nanmax(np.r_[df["spl_high"].to_numpy(dtype=float), df["spl"].to_numpy(dtype=float)]))
    ax.set_ylim(0, max(0.1, min(1.0, top * 1.15)) if np.isfinite(top) else 1.0)
    ax.grid(axis="x", visible=False)
    spl_all = df["spl"].to_numpy(dtype=float)
    if np.isfinite(spl_all).any() and np.nanmax(np.abs(spl_all)) == 0:
        ax.text(0.5, 0.5, ALL_ZERO_NOTE, ha="center", va="center", transform=ax.transAxes,
                bbox={"facecolor": "white", "edgecolor": "#333333", "linewidth": 0.6, "boxstyle": "round"})
    if single:
        handles = [Patch(color="#a6a6a6", label="baselines")] if n_base else []
        if n_base < len(cats):
            handles.append(Patch(color=OKABE_ITO[0], label=f"ours ({MG_LABELS.get(mgs[0], mgs[0])})"))
    else:
        handles = [Patch(color=OKABE_ITO[j % len(OKABE_ITO)], label=MG_LABELS.get(m, m))
                   for j, m in enumerate(mgs)]
    ax.legend(handles=handles, loc="lower left", bbox_to_anchor=(0.0, 1.01), ncol=len(handles),
              borderaxespad=0.0, handlelength=1.2, columnspacing=1.2)

    ours = df[df["method"] == "ours"]
    ms = sorted(ours["M"].unique()) if not ours.empty else [0]
    dodge = 0.015 * (max(ms) - min(ms)) if len(ms) > 1 else 0.1  # x offset between MGs' markers
    if ours.empty:
        ax2.text(0.5, 0.5, "no 'ours' runs", ha="center", va="center", transform=ax2.transAxes)
    else:
        for j, mg in enumerate(mgs):
            g = ours[ours["mg"] == mg].groupby("M", sort=True).first().reset_index()
            if g.empty:
                continue
            colour = OKABE_ITO[0] if single else OKABE_ITO[j % len(OKABE_ITO)]
            m = g["M"].to_numpy(dtype=float)
            a = g["attempts"].to_numpy(dtype=float)
            err = _yerr(a, g["attempts_low"].to_numpy(dtype=float), g["attempts_high"].to_numpy(dtype=float))
            shift = 0.0 if single else (j - (len(mgs) - 1) / 2) * dodge
            ax2.errorbar(m + shift, a, yerr=err, color=colour, marker="o", markersize=3.5, ecolor=colour)
        ax2.set_xticks(ms, [f"{v:g}" for v in ms])
        top = np.nanmax(np.r_[ours["attempts_high"].to_numpy(dtype=float), ours["attempts"].to_numpy(dtype=float)])
        ax2.set_ylim(0, top * 1.08 if np.isfinite(top) and top > 0 else 1.0)
    ax2.set_xlabel("M (executed steps per plan)")
    ax2.set_ylabel("Attempts (abstract trajectories)")
    if title:
        fig.suptitle(title, y=1.08)
    return fig


fig6 = figure6
fig7 = figure7

"""The generalisation benchmark's table and figure: trained-on x evaluated-on.

CSV in, files out. Each policy is read in groups of homes (a group is the ``{home}`` directory of
its evaluation paths: ``generated_heldout``, ``generated_train``, ``kitchen_living``,
``bedroom_bath``), its placement schemes pooled. Per (variant, group):

- success and SPL with the two-level bootstrap interval (scenarios, then seeds);
- the random searcher's and the oracle's success on the same scenarios (one seed);
- the normalised score ``(policy - random) / (oracle - random)``: 0 is the random searcher, 1 the
  oracle. Its interval resamples the scenarios once for the three searchers (they ran the same
  scenarios) and the policy's seeds;
- for the generated-homes variant, ``gap_to_train``: its normalised score in the group minus the
  one in its own training split, with an interval that resamples each group's scenarios and the
  seeds once (the same training runs read in both);
- for the generated-homes variant in each paper home, ``vs_reference``: its normalised score minus
  the reference's, a policy trained in those homes (the issue's aim: within 0.05), paired: one draw
  of the scenarios for both (they ran the same ones, beside the same bounds), each policy's seeds
  drawn apart (different training runs).
"""

from __future__ import annotations

import math
import os
import textwrap
from collections.abc import Iterable, Mapping
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from egosearch.report.data import output_base, parse_eval_path, read_episodes, suffixed
from egosearch.report.stats import quantile_interval, scenario_seed_matrix

GROUP_ORDER = ("generated_train", "generated_heldout", "kitchen_living", "bedroom_bath")
GROUP_LABELS = {"generated_train": "generated homes (training split)",
                "generated_heldout": "generated homes (held out)",
                "kitchen_living": "kitchen_living (paper)", "bedroom_bath": "bedroom_bath (paper)"}
COLUMNS = ("variant", "trained_on", "group", "n_scenarios", "n_seeds", "success", "success_low", "success_high",
           "spl", "spl_low", "spl_high", "random_success", "oracle_success", "normalised", "normalised_low",
           "normalised_high", "gap_to_train", "gap_low", "gap_high", "vs_reference", "vs_reference_low",
           "vs_reference_high")
PAPER_GROUPS = ("kitchen_living", "bedroom_bath")

PathLike = str | os.PathLike


def _by_variant_group(paths: Iterable[PathLike]) -> dict[tuple[str, str], list[Path]]:
    out: dict[tuple[str, str], list[Path]] = {}
    for path in paths:
        info = parse_eval_path(path)
        out.setdefault((info["variant"], info["layout"]), []).append(Path(path))
    return out


def _aligned(policy: pd.DataFrame, bound: pd.DataFrame, value: str, what: str) -> np.ndarray:
    """The bound's per-scenario ``value`` in the policy's scenario order (one seed)."""
    keys = ["scenario_set", "scenario_id"]
    per = bound.groupby(keys)[value].mean()
    wanted = policy.drop_duplicates(keys).set_index(keys).sort_index().index
    missing = wanted.difference(per.index)
    if len(missing):
        raise ValueError(f"generalise: the {what} did not run {len(missing)} of the policy's scenarios "
                         f"(e.g. {missing[0]})")
    return per.loc[wanted].to_numpy(dtype=float)


def _draws(n: int, size: int, rng) -> np.ndarray:
    return rng.integers(0, size, (n, size))


def _normalised(p, r, o):
    with np.errstate(divide="ignore", invalid="ignore"):
        out = (p - r) / (o - r)
    return np.where(o - r > 0, out, np.nan)


def _boot_group(m: np.ndarray, rnd: np.ndarray, orc: np.ndarray, rows: np.ndarray, cols: np.ndarray):
    """Per resample: the policy's mean over the drawn scenarios and seeds, and the bounds' over the scenarios."""
    col_sums = m[rows].sum(axis=1)
    p = np.take_along_axis(col_sums, cols, axis=1).mean(axis=1) / m.shape[0]
    return p, rnd[rows].mean(axis=1), orc[rows].mean(axis=1)


def generalise_frame(policy_files: Iterable[PathLike], bound_files: Iterable[PathLike],
                     trained_on: Mapping[str, str] | None = None, generated: str | None = None,
                     confidence: float = 0.95, n_resamples: int = 10_000, seed: int = 0,
                     reference: str | None = None) -> pd.DataFrame:
    """One row per (variant, group) with :data:`COLUMNS` (see the module docstring)."""
    policies = _by_variant_group(policy_files)
    bounds = _by_variant_group(bound_files)
    if not policies:
        raise ValueError("generalise: no policy evaluation files given")
    rng = np.random.default_rng(seed)
    variants = list(dict.fromkeys(v for v, _ in policies))
    groups = sorted({g for _, g in policies}, key=lambda g: (GROUP_ORDER.index(g) if g in GROUP_ORDER else 99, g))
    rows, boots = [], {}
    for variant in variants:
        for group in groups:
            if (variant, group) not in policies:
                continue
            df = read_episodes(policies[(variant, group)])
            success, _ = scenario_seed_matrix(df, "success")
            spl, _ = scenario_seed_matrix(df, "spl")
            bound = {}
            for name in ("random", "oracle"):
                if (name, group) not in bounds:
                    raise ValueError(f"generalise: no {name} searcher evaluation for group {group!r}")
                bound[name] = _aligned(df, read_episodes(bounds[(name, group)]), "success", f"{name} searcher")
            n_s, n_k = success.shape
            row_draws, col_draws = _draws(n_resamples, n_s, rng), _draws(n_resamples, n_k, rng)
            p, r, o = _boot_group(success, bound["random"], bound["oracle"], row_draws, col_draws)
            spl_b = np.take_along_axis(spl[row_draws].sum(axis=1), col_draws, axis=1).mean(axis=1) / n_s
            norm_b = _normalised(p, r, o)
            boots[(variant, group)] = (success, bound, col_draws)
            mean_p, mean_r, mean_o = success.mean(), bound["random"].mean(), bound["oracle"].mean()
            rows.append({"variant": variant, "trained_on": (trained_on or {}).get(variant, ""), "group": group,
                         "n_scenarios": n_s, "n_seeds": n_k, "success": float(mean_p),
                         **dict(zip(("success_low", "success_high"), quantile_interval(p, confidence))),
                         "spl": float(spl.mean()),
                         **dict(zip(("spl_low", "spl_high"), quantile_interval(spl_b, confidence))),
                         "random_success": float(mean_r), "oracle_success": float(mean_o),
                         "normalised": float(_normalised(np.array(mean_p), np.array(mean_r), np.array(mean_o))),
                         **dict(zip(("normalised_low", "normalised_high"), quantile_interval(norm_b, confidence))),
                         "gap_to_train": math.nan, "gap_low": math.nan, "gap_high": math.nan,
                         "vs_reference": math.nan, "vs_reference_low": math.nan, "vs_reference_high": math.nan})
    if generated is not None and (generated, "generated_train") in boots:
        train_m, train_b, _ = boots[(generated, "generated_train")]
        for row in rows:
            if row["variant"] != generated or row["group"] == "generated_train":
                continue
            m, b, cols = boots[(generated, row["group"])]
            if m.shape[1] != train_m.shape[1]:
                continue
            # the same seeds (training runs) in both groups; each group's scenarios drawn on their own
            gp = _boot_group(m, b["random"], b["oracle"], _draws(n_resamples, m.shape[0], rng), cols)
            tp = _boot_group(train_m, train_b["random"], train_b["oracle"],
                             _draws(n_resamples, train_m.shape[0], rng), cols)
            gap = _normalised(*gp) - _normalised(*tp)
            train_row = next(r for r in rows if r["variant"] == generated and r["group"] == "generated_train")
            row["gap_to_train"] = row["normalised"] - train_row["normalised"]
            row["gap_low"], row["gap_high"] = quantile_interval(gap, confidence)
    if generated is not None and reference is not None:
        for row in rows:
            group = row["group"]
            if row["variant"] != generated or group not in PAPER_GROUPS or (reference, group) not in boots:
                continue
            gen_m, b, _ = boots[(generated, row["group"])]
            ref_m = boots[(reference, row["group"])][0]
            scenarios = _draws(n_resamples, gen_m.shape[0], rng)
            gen_b = _boot_group(gen_m, b["random"], b["oracle"], scenarios, _draws(n_resamples, gen_m.shape[1], rng))
            ref_b = _boot_group(ref_m, b["random"], b["oracle"], scenarios, _draws(n_resamples, ref_m.shape[1], rng))
            ref_row = next(r for r in rows if r["variant"] == reference and r["group"] == row["group"])
            row["vs_reference"] = row["normalised"] - ref_row["normalised"]
            row["vs_reference_low"], row["vs_reference_high"] = quantile_interval(
                _normalised(*gen_b) - _normalised(*ref_b), confidence)
    return pd.DataFrame(rows, columns=list(COLUMNS))


def _fmt(x: float, lo: float | None = None, hi: float | None = None) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if lo is None or (isinstance(lo, float) and math.isnan(lo)):
        return f"{x:.2f}"
    return f"{x:.2f} [{lo:.2f}, {hi:.2f}]"


def generalise_report(policy_files: Iterable[PathLike], bound_files: Iterable[PathLike], out_prefix: PathLike,
                      trained_on: Mapping[str, str] | None = None, generated: str | None = None,
                      confidence: float = 0.95, n_resamples: int = 10_000, seed: int = 0,
                      reference: str | None = None) -> list[Path]:
    """Write ``{prefix}.csv``, ``.md`` and ``.png``; return their paths."""
    df = generalise_frame(policy_files, bound_files, trained_on, generated, confidence, n_resamples, seed, reference)
    base = output_base(out_prefix, "generalise")
    csv, md_path, png = suffixed(base, ".csv"), suffixed(base, ".md"), suffixed(base, ".png")
    df.to_csv(csv, index=False, float_format="%.6g")
    pct = f"{confidence * 100:g}%"
    md = ["Generalisation: each policy (rows) read in four groups of homes (columns): normalised score "
          "(policy − random) / (oracle − random), 0 = the random searcher, 1 = the privileged oracle.", "",
          "| variant (trained on) | " + " | ".join(GROUP_LABELS.get(g, g) for g in _groups(df)) + " |",
          "|---|" + "---|" * len(_groups(df))]
    for variant, g in df.groupby("variant", sort=False):
        cells = []
        for group in _groups(df):
            r = g[g["group"] == group]
            cells.append(_fmt(*r.iloc[0][["normalised", "normalised_low", "normalised_high"]]) if len(r) else "–")
        md.append(f"| {variant} ({g.iloc[0]['trained_on'] or '?'}) | " + " | ".join(cells) + " |")
    md += ["", "Success rate and SPL (the policy; the random searcher / the oracle on the same scenarios):", "",
           "| variant | group | scenarios × seeds | success | SPL | random | oracle |", "|---|---|---|---|---|---|---|"]
    for r in df.itertuples(index=False):
        md.append(f"| {r.variant} | {r.group} | {r.n_scenarios} × {r.n_seeds} | "
                  f"{_fmt(r.success, r.success_low, r.success_high)} | {_fmt(r.spl, r.spl_low, r.spl_high)} | "
                  f"{_fmt(r.random_success)} | {_fmt(r.oracle_success)} |")
    gaps = df[np.isfinite(df["gap_to_train"])]
    if len(gaps):
        md += ["", f"`{generated}`: its normalised score in each group minus the one in its own training split:", ""]
        md += [f"- {GROUP_LABELS.get(r.group, r.group)}: {r.gap_to_train:+.2f} [{r.gap_low:+.2f}, {r.gap_high:+.2f}]"
               for r in gaps.itertuples(index=False)]
    versus = df[np.isfinite(df["vs_reference"])]
    if len(versus):
        md += ["", f"`{generated}` against `{reference}`, which trained in the paper homes: normalised score of "
               f"`{generated}` minus `{reference}`'s (paired: the same scenarios; each policy's seeds apart):", ""]
        md += [f"- {GROUP_LABELS.get(r.group, r.group)}: {r.vs_reference:+.2f} "
               f"[{r.vs_reference_low:+.2f}, {r.vs_reference_high:+.2f}]" for r in versus.itertuples(index=False)]
    md += ["", f"Brackets: {pct} two-level bootstrap (scenarios, then seeds); the two placement schemes pooled. "
           f"From `{csv.name}`.", ""]
    md_path.write_text("\n".join(md), encoding="utf-8")
    _figure(df, png, pct)
    return [csv, md_path, png]


def _groups(df: pd.DataFrame) -> list[str]:
    return sorted(set(df["group"]), key=lambda g: (GROUP_ORDER.index(g) if g in GROUP_ORDER else 99, g))


def _figure(df: pd.DataFrame, path: Path, pct: str) -> None:
    matplotlib.use("Agg")
    groups, variants = _groups(df), list(dict.fromkeys(df["variant"]))
    width = 0.8 / max(1, len(variants))
    fig, ax = plt.subplots(figsize=(8, 3.6), dpi=120)
    for i, variant in enumerate(variants):
        g = df[df["variant"] == variant].set_index("group")
        xs = [k + (i - (len(variants) - 1) / 2) * width for k in range(len(groups))]
        ys = [g.loc[grp, "normalised"] if grp in g.index else np.nan for grp in groups]
        lo = [g.loc[grp, "normalised"] - g.loc[grp, "normalised_low"] if grp in g.index else 0 for grp in groups]
        hi = [g.loc[grp, "normalised_high"] - g.loc[grp, "normalised"] if grp in g.index else 0 for grp in groups]
        label = f"{variant} (trained on {g['trained_on'].iloc[0]})" if g["trained_on"].iloc[0] else variant
        ax.bar(xs, ys, width, yerr=[np.nan_to_num(lo), np.nan_to_num(hi)], capsize=3, label=label)
    ax.axhline(1.0, color="0.3", ls="--", lw=1)
    ax.axhline(0.0, color="0.3", ls=":", lw=1)
    ax.set_xticks(range(len(groups)), [textwrap.fill(GROUP_LABELS.get(g, g), 16) for g in groups], fontsize=8)
    ax.set_ylabel("normalised score\n(policy − random) / (oracle − random)", fontsize=8)
    ax.set_title(f"Evaluated in (columns) vs trained on (bars); {pct} two-level bootstrap", fontsize=9)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.25), ncol=min(2, len(variants)), frameon=False)
    fig.tight_layout()
    fig.savefig(path, bbox_inches="tight")   # the legend sits below the axes
    plt.close(fig)

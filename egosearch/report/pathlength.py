"""Success by how far the target is: by the shortest path ℓ and by the detour it forces.

CSV in, files out. Each episode of a variant's evaluation CSVs is joined to its scenario (start,
target, ℓ) and binned:

- by ℓ, the scenario's shortest path (the geodesic length from the start to the nearest pose that
  satisfies success; ``egosearch.sim.scenarios``): :data:`LENGTH_BINS`, in metres;
- by the detour ``ℓ − max(0, |start − target| − r)``: how much longer the shortest path is than
  the straight line from the start to the ring of radius ``r`` around the target where success
  becomes possible (``r`` = the success distance plus the body radius: success is measured from
  the body's surface). A detour is walls and furniture in the way, or a target that must be
  looked at from one side (inside a cabinet). :data:`DETOUR_BINS`, in metres. ℓ is measured to
  grid cells padded by half a diagonal, so a straight approach can give a detour a few
  centimetres below zero: the first bin holds them.

Per bin: the success rate with the two-level bootstrap interval of
:func:`~egosearch.report.stats.two_level_ci` (the bin's scenarios resampled, then the seeds), over
every Table 1 cell pooled (each home, height and placement) and per camera height (placements and
homes pooled). Pooled is the reading with the most scenarios per bin; per height says whether a
trend over ℓ is the camera's (ℓ grows where the target must be seen from low down).

:func:`compare_by_length` is the same split for ``egosearch report compare``: candidate minus
reference per ℓ bin, every cell pooled, with :func:`~egosearch.report.stats.compare_cells`.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Mapping
from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from egosearch.report.data import HEIGHT_FILE, output_base, parse_eval_path, read_checked_csv, read_episodes, suffixed
from egosearch.report.figures import OKABE_ITO, STYLE, save_figure
from egosearch.report.stats import METRICS, compare_cells, scenario_seed_matrix, two_level_ci
from egosearch.report.tables import holm_and_write, searcher_label
from egosearch.searchers import searcher_registry as searchers

PathLike = str | os.PathLike

LENGTH_BINS = (0.0, 2.0, 4.0, 6.0, 8.0, math.inf)
"""Edges (m) of the ℓ bins, each ``[low, high)``: 0-2, 2-4, 4-6, 6-8, 8 and more."""
DETOUR_BINS = (-math.inf, 0.25, 1.0, 2.5, math.inf)
"""Edges (m) of the detour bins, each ``[low, high)``: under 0.25 m (a straight approach), 0.25-1 m
(around a table or a door frame), 1-2.5 m (round a room's furniture), 2.5 m and more (through
another room or round a wall)."""
BINNINGS = {"length": LENGTH_BINS, "detour": DETOUR_BINS}
BY_LABELS = {"length": "shortest path ℓ (m)", "detour": "detour ℓ − straight line to the success ring (m)"}
ALL_HEIGHTS = "all"
"""The ``height`` of the rows that pool every Table 1 cell."""
SCENARIO_COLUMNS = ("scenario_id", "start_x", "start_y", "target_x", "target_y", "shortest_path")
PATHLENGTH_COLUMNS = ("searcher", "height", "by", "bin", "bin_low", "bin_high", "n_scenarios", "n_seeds",
                      "n_episodes", "success_rate", "ci_low", "ci_high")
BY_LENGTH_COLUMNS = ("length_bin", "length_low", "length_high", "metric", "reference", "candidate", "difference",
                     "ci_low", "ci_high", "p_uncorrected", "p_holm", "significant_holm", "n_scenarios",
                     "n_seeds_ref", "n_seeds_cand", "detectable_80", "method")
"""``egosearch report compare``'s second CSV: one row per ℓ bin and metric, every cell pooled.
``p_holm`` is Holm's adjustment over the rows of this file alone."""
L_TOLERANCE = 1e-3
"""Largest |ℓ| difference (m) between an evaluation CSV and its scenario file (both round ℓ)."""
DEFAULT_STYLE = ("#777777", "--", "x")
"""The line of a reference searcher without a ``path_style`` of its own (colour, line style, marker)."""


def searcher_style(name: str) -> tuple:
    """A reference searcher's line in the figure: its registered ``path_style``, else :data:`DEFAULT_STYLE`."""
    searcher = searchers.SEARCHERS.get(name)
    return searcher.path_style if searcher is not None and searcher.path_style else DEFAULT_STYLE


def bin_labels(edges: tuple[float, ...]) -> list[str]:
    """``(0, 2, inf)`` -> ``["0-2", "2+"]``; ``(-inf, 0.25, ...)`` -> ``["<0.25", ...]``."""
    labels = []
    for lo, hi in zip(edges, edges[1:]):
        if math.isinf(lo):
            labels.append(f"<{hi:g}")
        elif math.isinf(hi):
            labels.append(f"{lo:g}+")
        else:
            labels.append(f"{lo:g}-{hi:g}")
    return labels


def bin_of(values, edges: tuple[float, ...]) -> np.ndarray:
    """Index of the ``[low, high)`` bin of each value (NaN values: -1)."""
    v = np.asarray(values, dtype=float)
    idx = np.searchsorted(np.asarray(edges[1:-1]), v, side="right")
    return np.where(np.isnan(v), -1, idx)


def detour(df: pd.DataFrame, success_radius: float) -> pd.Series:
    """ℓ minus the straight-line distance from the start to the ring of ``success_radius`` (m) around
    the target: ``shortest_path − max(0, hypot(start − target) − success_radius)``."""
    straight = np.hypot(df["start_x"] - df["target_x"], df["start_y"] - df["target_y"])
    return df["shortest_path"] - np.maximum(0.0, straight - success_radius)


def _scenario_set(path: PathLike) -> str:
    """``.../{home}/{placement}/h{height}.csv`` -> ``{home}/{placement}/h{height}.csv``: the key an
    evaluation CSV's episodes carry (``data.scenario_set_from_path``)."""
    parts = Path(path).parts
    if len(parts) < 3 or not HEIGHT_FILE.match(parts[-1]):
        raise ValueError(f"{path}: expected a scenario file .../{{home}}/{{placement}}/h{{height}}.csv")
    return "/".join(parts[-3:])


def read_with_scenarios(eval_files: Iterable[PathLike], scenario_files: Iterable[PathLike]) -> pd.DataFrame:
    """Per-episode rows (``data.read_episodes``: ``seed``, ``scenario_set``) joined to their
    scenario's start and target, with ``home``, ``placement`` and ``height`` from the path.

    ValueError (one line) when an evaluated scenario set has no scenario file, a scenario id is
    missing from it, or the file's ℓ differs from the evaluation's (another scenario set)."""
    eps = read_episodes(list(eval_files))
    scenarios: dict[str, Path] = {}
    for path in scenario_files:
        key = _scenario_set(path)
        if key in scenarios:
            raise ValueError(f"two scenario files for {key}: {scenarios[key]} and {path}")
        scenarios[key] = Path(path)
    frames = []
    for sset, part in eps.groupby("scenario_set", sort=True):
        if sset not in scenarios:
            raise ValueError(f"no scenario file for the evaluated set {sset} (pass .../scenarios/{sset})")
        scen = read_checked_csv(scenarios[sset], SCENARIO_COLUMNS, "scenario")[list(SCENARIO_COLUMNS)]
        joined = part.merge(scen, on="scenario_id", how="left", suffixes=("", "_scenario"), validate="many_to_one")
        lost = joined["start_x"].isna()
        if lost.any():
            raise ValueError(f"{scenarios[sset]} lacks scenario {int(joined.loc[lost, 'scenario_id'].iloc[0])} "
                             f"of the evaluation of {sset}")
        off = (joined["shortest_path"] - joined["shortest_path_scenario"]).abs() > L_TOLERANCE
        if off.any():
            r = joined[off].iloc[0]
            raise ValueError(f"{scenarios[sset]} is not the scenario set evaluated in {sset}: scenario "
                             f"{int(r.scenario_id)} has ℓ {r.shortest_path_scenario:g} there, "
                             f"{r.shortest_path:g} in the evaluation")
        home, placement, name = sset.split("/")
        frames.append(joined.drop(columns="shortest_path_scenario").assign(
            home=home, placement=placement, height=float(HEIGHT_FILE.match(name).group(1))))
    return pd.concat(frames, ignore_index=True)


def _searcher_of(paths: list[PathLike], what: str) -> dict[str, list[PathLike]]:
    out: dict[str, list[PathLike]] = {}
    for path in paths:
        out.setdefault(parse_eval_path(path)["variant"], []).append(path)
    if what == "policy" and len(out) != 1:
        raise ValueError(f"pathlength: evaluation files of {len(out)} variants {sorted(out)}; give one variant's")
    return out


def _binned_rows(df: pd.DataFrame, searcher: str, height: str, confidence: float, n_resamples: int,
                 seed: int) -> list[dict]:
    rows = []
    for by, edges in BINNINGS.items():
        index = bin_of(df[by], edges)
        for i, label in enumerate(bin_labels(edges)):
            part = df[index == i]
            row = {"searcher": searcher, "height": height, "by": by, "bin": label, "bin_low": edges[i],
                   "bin_high": edges[i + 1], "n_scenarios": 0, "n_seeds": int(df["seed"].nunique()),
                   "n_episodes": len(part), "success_rate": math.nan, "ci_low": math.nan, "ci_high": math.nan}
            if len(part):
                m, keys = scenario_seed_matrix(part, "success")
                rate, lo, hi = two_level_ci(m, confidence, n_resamples, seed)
                row.update(n_scenarios=len(keys), success_rate=rate, ci_low=lo, ci_high=hi)
            rows.append(row)
    return rows


def pathlength_frame(eval_files: Iterable[PathLike], scenario_files: Iterable[PathLike], success_radius: float,
                     bound_files: Iterable[PathLike] = (), confidence: float = 0.95, n_resamples: int = 10_000,
                     seed: int = 0) -> pd.DataFrame:
    """One row per (searcher, height, binning, bin) with :data:`PATHLENGTH_COLUMNS`.

    ``eval_files``: one variant's evaluation CSVs (``.../{variant}/seed{N}/{home}/{placement}/h{height}.csv``);
    ``bound_files``: the reference searchers' on the same scenario sets (``.../eval/{random|oracle|...}/...``,
    one seed: their interval resamples the scenarios only); ``scenario_files``: the scenario sets
    they ran (``.../scenarios/{home}/{placement}/h{height}.csv``); ``success_radius``: the distance
    (m) from the target's centre to the body's axis within which success is possible.
    ``height`` is :data:`ALL_HEIGHTS` for every cell pooled, else the camera height (``0.45``...).
    Empty bins keep their row (0 scenarios, NaN rate)."""
    if success_radius < 0:
        raise ValueError(f"success_radius={success_radius}: must be >= 0")
    scenario_files = list(scenario_files)
    searchers = _searcher_of(list(eval_files), "policy")
    policy = next(iter(searchers))
    for bound, files in _searcher_of(list(bound_files), "bound").items():
        if bound == policy:
            raise ValueError(f"pathlength: {policy!r} is both the policy and a bound")
        searchers[bound] = files
    rows, policy_sets = [], None
    for searcher, files in searchers.items():
        df = read_with_scenarios(files, scenario_files)
        sets = set(df["scenario_set"])
        if policy_sets is None:
            policy_sets = sets
        elif not sets <= policy_sets:
            raise ValueError(f"pathlength: {searcher} ran scenario sets {policy} did not, e.g. "
                             f"{sorted(sets - policy_sets)[0]}: a reference searcher must run the policy's")
        df = df.assign(length=df["shortest_path"], detour=detour(df, success_radius))
        rows += _binned_rows(df, searcher, ALL_HEIGHTS, confidence, n_resamples, seed)
        if searcher == policy:
            for h, part in df.groupby("height", sort=True):
                rows += _binned_rows(part, searcher, f"{h:g}", confidence, n_resamples, seed)
    return pd.DataFrame(rows, columns=list(PATHLENGTH_COLUMNS))


# --------------------------------------------------------------------------------------------- files
def _cell(r) -> str:
    if not r.n_scenarios:
        return "–"
    if math.isnan(r.ci_low):
        return f"{r.success_rate:.2f}"
    return f"{r.success_rate:.2f} [{r.ci_low:.2f}, {r.ci_high:.2f}]"


def _markdown(df: pd.DataFrame, policy: str, success_radius: float, pct: str, csv_name: str) -> str:
    heights = [h for h in dict.fromkeys(df.loc[df["searcher"] == policy, "height"]) if h != ALL_HEIGHTS]
    bounds = [s for s in dict.fromkeys(df["searcher"]) if s != policy]
    mine = df[df["searcher"] == policy]
    n_seeds = int(mine["n_seeds"].max())
    md = []
    for by in BINNINGS:
        part = df[df["by"] == by]
        head = (["bin (m)", "scenarios", f"{policy}, all cells"] + [f"{policy}, {h} m" for h in heights]
                + [f"{searcher_label(b)}, all cells" for b in bounds])
        md += [f"Success by {BY_LABELS[by]}, {policy}.", "", "| " + " | ".join(head) + " |",
               "|---" * len(head) + "|"]
        for label in bin_labels(BINNINGS[by]):
            rows = part[part["bin"] == label]
            pooled = rows[(rows["searcher"] == policy) & (rows["height"] == ALL_HEIGHTS)].iloc[0]
            cells = [label, str(int(pooled.n_scenarios)), _cell(pooled)]
            cells += [_cell(rows[(rows["searcher"] == policy) & (rows["height"] == h)].iloc[0]) for h in heights]
            cells += [_cell(rows[(rows["searcher"] == b) & (rows["height"] == ALL_HEIGHTS)].iloc[0]) for b in bounds]
            md.append("| " + " | ".join(cells) + " |")
        md.append("")
    md += [f"Bins are [low, high) in metres. ℓ: the scenario's shortest path to a pose that satisfies success. "
           f"Detour: ℓ minus the straight-line distance from the start to the ring of {success_radius:g} m "
           "around the target (the success distance plus the body's radius), 0 where the start is inside it; "
           "ℓ is measured to grid cells padded by half a diagonal, so a straight approach may show a few "
           f"centimetres below 0. Brackets: {pct} two-level bootstrap interval (the bin's scenarios resampled, "
           f"then the {n_seeds} seed(s)); 'all cells' pools every home, height and placement evaluated, a "
           f"height column its placements and homes. Reference searchers: one seed, the same scenarios. "
           f"Scenario counts per height are in {csv_name}.", ""]
    return "\n".join(md)


def _figure(df: pd.DataFrame, policy: str, base: Path) -> list[Path]:
    heights = [h for h in dict.fromkeys(df.loc[df["searcher"] == policy, "height"]) if h != ALL_HEIGHTS]
    bounds = [s for s in dict.fromkeys(df["searcher"]) if s != policy]
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=(7.0, 2.8))
        axes = fig.subplots(1, 2, sharey=True)
        for ax, by in zip(axes, BINNINGS):
            part = df[df["by"] == by]
            labels = bin_labels(BINNINGS[by])
            x = np.arange(len(labels))
            series = [(policy, ALL_HEIGHTS, f"{policy}, all cells", "#000000", "-", "o", 0.0, 1.8)]
            offsets = np.linspace(-0.18, 0.18, len(heights)) if len(heights) > 1 else [0.0]
            series += [(policy, h, f"{policy}, {h} m camera", OKABE_ITO[i % len(OKABE_ITO)], "-", "o", offsets[i],
                        0.9) for i, h in enumerate(heights)]
            series += [(b, ALL_HEIGHTS, searcher_label(b), *searcher_style(b), 0.0, 0.9) for b in bounds]
            handles = []
            for searcher, height, label, colour, ls, marker, dx, lw in series:
                rows = part[(part["searcher"] == searcher) & (part["height"] == height)].set_index("bin").loc[labels]
                y = rows["success_rate"].to_numpy(float)
                if searcher == policy:
                    err = np.vstack([y - rows["ci_low"].to_numpy(float), rows["ci_high"].to_numpy(float) - y])
                    pooled = height == ALL_HEIGHTS
                    handles.append(ax.errorbar(x + dx, y, yerr=np.nan_to_num(err), color=colour, linestyle=ls,
                                               linewidth=lw, marker=marker, markersize=3.5 if pooled else 2.5,
                                               label=label, zorder=3 if pooled else 2))
                else:
                    handles += ax.plot(x + dx, y, color=colour, linestyle=ls, linewidth=lw, marker=marker,
                                       markersize=2.5, label=label, zorder=1)
            pooled = part[(part["searcher"] == policy) & (part["height"] == ALL_HEIGHTS)].set_index("bin").loc[labels]
            ax.set_xticks(x, [f"{lab}\nn={int(n)}" for lab, n in zip(labels, pooled["n_scenarios"])])
            ax.set_xlabel(BY_LABELS[by])
            ax.set_ylim(0, 1.02)
        axes[0].set_ylabel("Success rate")
        # the policy's lines first, in the order drawn (matplotlib lists error bars after lines)
        fig.legend(handles, [h.get_label() for h in handles], loc="upper center", bbox_to_anchor=(0.5, 1.0),
                   ncol=min(len(handles), 4))
        fig.subplots_adjust(top=0.78 if len(handles) > 4 else 0.86, wspace=0.08)
        return save_figure(fig, base)


def pathlength_report(eval_files: Iterable[PathLike], scenario_files: Iterable[PathLike], success_radius: float,
                      out_prefix: PathLike, out_csv: PathLike | None = None, bound_files: Iterable[PathLike] = (),
                      confidence: float = 0.95, n_resamples: int = 10_000, seed: int = 0) -> list[Path]:
    """Write ``{prefix}.md``, ``.png``, ``.pdf`` (a directory prefix gets ``pathlength.*``) and the numbers
    to ``out_csv`` (default ``{prefix}.csv``); return the paths. See :func:`pathlength_frame`."""
    eval_files = list(eval_files)
    df = pathlength_frame(eval_files, scenario_files, success_radius, bound_files, confidence, n_resamples, seed)
    policy = parse_eval_path(eval_files[0])["variant"]
    base = output_base(out_prefix, "pathlength")
    csv = Path(out_csv) if out_csv is not None else suffixed(base, ".csv")
    csv.parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(csv, index=False, float_format="%.6g")
    md = suffixed(base, ".md")
    md.write_text(_markdown(df, policy, success_radius, f"{confidence * 100:g}%", csv.name), encoding="utf-8")
    return [csv, md, *_figure(df, policy, base)]


# --------------------------------------------------------------------------------------------- compare
def _pooled(files: Mapping | Iterable[PathLike]) -> pd.DataFrame:
    paths = [p for v in files.values() for p in ([v] if isinstance(v, (str, os.PathLike)) else v)] \
        if isinstance(files, Mapping) else list(files)
    return read_episodes(paths)


def compare_by_length(reference_files: Mapping | Iterable[PathLike], candidate_files: Mapping | Iterable[PathLike],
                      out_csv: PathLike | None = None, metrics: Iterable[str] = METRICS, n_resamples: int = 10_000,
                      seed: int = 0, spreads=None) -> pd.DataFrame:
    """Candidate − reference per ℓ bin (:data:`LENGTH_BINS`) and metric, every evaluated cell pooled.

    Each side: ``{cell: [paths]}`` (as ``compare_report`` takes) or a flat list of one variant's evaluation
    CSVs. A scenario is ``(scenario set, id)``, so cells and homes stay apart inside a bin. Per bin
    :func:`~egosearch.report.stats.compare_cells` on the bin's scenarios: seed-averaged difference, paired
    two-level bootstrap interval (the bin's scenarios, then each side's seeds) and the p-value read from
    the same draws; Holm over this table's rows. Bins without scenarios are left out. Columns :data:`BY_LENGTH_COLUMNS`;
    written to ``out_csv`` when given. ``spreads``: the seeds whose spread a screen counts, of every cell
    (:func:`~egosearch.report.spread_sides.comparison_spreads`), which a screen's bins count as its
    cells do. ValueError when the two sides disagree on a scenario's ℓ."""
    ref, cand = _pooled(reference_files), _pooled(candidate_files)
    keys = ["scenario_set", "scenario_id"]
    lengths = ref.groupby(keys)["shortest_path"].first().rename("ref_l").reset_index()
    both = cand.merge(lengths, on=keys, how="left")
    off = (both["shortest_path"] - both["ref_l"]).abs() > L_TOLERANCE
    if off.any():
        r = both[off].iloc[0]
        raise ValueError(f"compare: scenario {r.scenario_id} of {r.scenario_set} has ℓ {r.ref_l:g} in the reference "
                         f"and {r.shortest_path:g} in the candidate: not the same scenarios")
    ref_bin, cand_bin = bin_of(ref["shortest_path"], LENGTH_BINS), bin_of(cand["shortest_path"], LENGTH_BINS)
    rows = []
    for i, label in enumerate(bin_labels(LENGTH_BINS)):
        r, c = ref[ref_bin == i], cand[cand_bin == i]
        if r.empty and c.empty:
            continue
        for metric in metrics:
            try:
                res = compare_cells(r, c, metric, n_resamples=n_resamples, seed=seed,
                                    spreads=spreads)
            except ValueError as e:
                raise ValueError(f"compare: ℓ bin {label} m: {e}") from None
            rows.append({"length_bin": label, "length_low": LENGTH_BINS[i], "length_high": LENGTH_BINS[i + 1],
                         "metric": metric, **res})
    df = pd.DataFrame(rows)
    if df.empty:
        raise ValueError("compare: no episodes in any ℓ bin")
    return holm_and_write(df, BY_LENGTH_COLUMNS, out_csv)


def by_length_path(out_csv: PathLike) -> Path:
    """Where ``egosearch report compare --out X.csv`` writes the ℓ split: ``X_by_length.csv``."""
    out = Path(out_csv)
    return out.with_name(out.stem + "_by_length" + (out.suffix or ".csv"))


def format_by_length(df: pd.DataFrame) -> str:
    """Fixed-width text of a :func:`compare_by_length` frame; ``*`` marks Holm-adjusted p < 0.05."""
    head = f"{'ℓ (m)':>7}  {'metric':<7} {'ref':>6} {'cand':>6} {'diff':>7}  {'95% CI':<17} {'p_holm':>7}  {'scen':>4}"
    lines = [head, "-" * len(head)]
    for r in df.itertuples(index=False):
        star = "*" if r.significant_holm else " "
        lines.append(f"{r.length_bin:>7}  {r.metric:<7} {r.reference:>6.3f} {r.candidate:>6.3f} {r.difference:>+7.3f}  "
                     f"{f'[{r.ci_low:+.3f}, {r.ci_high:+.3f}]':<17} {r.p_holm:>7.4f}{star} {r.n_scenarios:>4d}")
    lines.append("By shortest path ℓ, every cell pooled; * Holm-adjusted p < 0.05 over these rows.")
    return "\n".join(lines)

"""Table 1 (success rate by head height × object placement), Table 2 (hyper-parameters) and the
variant-vs-variant comparison report. CSV in, files out (``.csv``, ``.md``, ``.tex``)."""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from egosearch.report.data import output_base, read_episodes, sorted_cells, suffixed
from egosearch.report.failures import STUCK_COLLISIONS, stuck_share
from egosearch.report.spread_sides import comparison_spreads
from egosearch.report.stats import (
    METRICS,
    bootstrap_ci,
    compare_cells,
    holm,
    paired_scenarios,
    scenario_seed_matrix,
    two_level_ci,
    wilson_ci,
)
from egosearch.searchers import searcher_registry as searchers

PAPER_TABLE1: dict[tuple[float, str], float] = {
    (0.45, "no_low_cabinets"): 0.50, (1.05, "no_low_cabinets"): 0.92, (1.65, "no_low_cabinets"): 0.90,
    (0.45, "everywhere"): 0.58, (1.05, "everywhere"): 0.75, (1.65, "everywhere"): 0.76,
}
"""Paper, Table 1: success rate of the search policy (100 scenarios per cell)."""

PLACEMENT_LABELS = {"no_low_cabinets": "Excluding cabinets", "everywhere": "Everywhere"}

TABLE1_COLUMNS = ("home", "height", "placement", "n_episodes", "n_scenarios", "n_seeds", "success_rate", "ci_low",
                  "ci_high", "seed_boot_low", "seed_boot_high", "spl", "spl_low", "spl_high", "stuck_share",
                  "paper_success_rate")
"""``ci_*``: the two-level bootstrap (scenarios, then seeds) of :func:`~egosearch.report.stats.two_level_ci`."""
BOTH_HOMES = "both"
"""The ``home`` of Table 1's rows pooled over every home evaluated: the rows set beside the paper's column,
because the paper tests in both of its homes (Section 6) and gives one number per cell."""

BOUND_STATS = ("n_episodes", "success_rate", "wilson_low", "wilson_high", "spl", "stuck_share")
"""Table 1's columns of each bound: ``{bound}_{stat}``."""


def bound_names() -> tuple[str, ...]:
    """The searchers Table 1 sets beside each policy, on the same scenario sets, in its order (the registered
    bounds, :func:`egosearch.searchers.searcher_registry.bounds`): the random searcher (uniform random actions), the
    classical frontier searcher from the actor's observation and its own pose (head moving, then held fixed:
    ``egosearch.searchers.frontier``), and the privileged oracle (knows the target and walks the shortest path to
    it)."""
    return searchers.bounds()


def searcher_label(name: str) -> str:
    """A searcher's short label in the tables (its name when it is no registered searcher, or has no label)."""
    searcher = searchers.SEARCHERS.get(name)
    return searcher.label if searcher is not None and searcher.label else name


def bound_columns(bounds: Iterable[str] | None = None) -> tuple[str, ...]:
    """Table 1's columns of the bounds (every registered bound by default)."""
    return tuple(f"{b}_{c}" for b in (bound_names() if bounds is None else bounds) for c in BOUND_STATS)


def _always_shown(name: str) -> bool:
    """The floor and the ceiling stand in Table 1 (as "not run") even without files."""
    return searchers.get(name).table_row != searchers.BESIDE


NOT_RUN = "not run"

TABLE2_CAPTION = "A complete set of CURL hyperparameters used to conduct all of the training experiments."

PathLike = str | os.PathLike


def _fmt(x: float, nd: int = 2) -> str:
    return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.{nd}f}"


def _height_label(h: float) -> str:
    return f"{h:.2f}m"


def _tex_escape(s: str) -> str:
    for a, b in (("\\", r"\textbackslash{}"), ("&", r"\&"), ("%", r"\%"), ("$", r"\$"), ("#", r"\#"),
                 ("_", r"\_"), ("{", r"\{"), ("}", r"\}"), ("~", r"\textasciitilde{}"), ("^", r"\^{}")):
        if a == "\\":
            s = s.replace(a, "\0")
        else:
            s = s.replace(a, b)
    s = s.replace("\0", r"\textbackslash{}")
    for a, b in (("γ", r"$\gamma$"), ("β1", r"$\beta_1$"), ("β2", r"$\beta_2$"), ("β", r"$\beta$"),
                 ("τ", r"$\tau$"), ("α", r"$\alpha$"), ("×", r"$\times$"), ("–", "--"), ("·", r"$\cdot$")):
        s = s.replace(a, b)
    return s


def _md_escape(s: str) -> str:
    return str(s).replace("|", r"\|")


# --------------------------------------------------------------------------------------------- Table 1
def _home_of(scenario_set: str) -> str:
    """The home of an episode: the first directory of its scenario set (``kitchen_living/everywhere/h1.05.csv``)."""
    parts = str(scenario_set).split("/")
    return parts[0] if len(parts) >= 3 else "home"


def _read_cells(episode_files: Mapping, what: str) -> dict[tuple, pd.DataFrame]:
    """``{(seed, height, placement): paths}`` -> ``{(home, height, placement): episodes pooled over seeds}``,
    and ``(BOTH_HOMES, height, placement)`` pooling the homes when there are several."""
    cells: dict[tuple, list[pd.DataFrame]] = {}
    for key, paths in episode_files.items():
        if not (isinstance(key, tuple) and len(key) == 3):
            raise ValueError(f"{what}: key {key!r} is not (seed, height, placement)")
        s, h, pl = key
        df = read_episodes(paths, seed=int(s))
        df = df.assign(home=df["scenario_set"].map(_home_of))
        for home, part in df.groupby("home", sort=True):
            cells.setdefault((str(home), round(float(h), 4), str(pl)), []).append(part)
    out = {cell: pd.concat(frames, ignore_index=True) for cell, frames in cells.items()}
    homes = sorted({c[0] for c in out})
    if len(homes) > 1:
        for h, pl in {c[1:] for c in out}:
            parts = [out[(home, h, pl)] for home in homes if (home, h, pl) in out]
            out[(BOTH_HOMES, h, pl)] = pd.concat(parts, ignore_index=True)
    return out


def _sorted_home_cells(cells) -> list[tuple]:
    homes = sorted({c[0] for c in cells}, key=lambda h: (h == BOTH_HOMES, h))
    return [(home, h, pl) for home in homes for h, pl in sorted_cells({c[1:] for c in cells if c[0] == home})]


def _bound_row(df: pd.DataFrame | None, bound: str, confidence: float) -> dict:
    if df is None:
        return {f"{bound}_n_episodes": 0, f"{bound}_success_rate": math.nan, f"{bound}_wilson_low": math.nan,
                f"{bound}_wilson_high": math.nan, f"{bound}_spl": math.nan, f"{bound}_stuck_share": math.nan}
    n, k = len(df), int(df["success"].astype(int).sum())
    lo, hi = wilson_ci(k, n, confidence)
    return {f"{bound}_n_episodes": n, f"{bound}_success_rate": k / n, f"{bound}_wilson_low": lo,
            f"{bound}_wilson_high": hi, f"{bound}_spl": float(df["spl"].mean()),
            f"{bound}_stuck_share": stuck_share(df)}


def table1_frame(episode_files: Mapping, confidence: float = 0.95, n_resamples: int = 10_000,
                 seed: int = 0, bounds: Mapping[str, Mapping] | None = None) -> pd.DataFrame:
    """The numbers of Table 1, one row per (home, height, placement) with :data:`TABLE1_COLUMNS`.

    ``episode_files``: ``{(seed, height, placement): path or [paths]}``; several paths per key are
    the homes (``.../seed{N}/{home}/{placement}/h{height}.csv``). Each home gets its rows and, when
    there are several, :data:`BOTH_HOMES` pools them. Per cell: ``success_rate`` and ``spl`` are
    means over all episodes; ``ci_*`` / ``spl_low``, ``spl_high`` their two-level bootstrap interval
    (scenarios, then seeds: every seed ran the same scenarios, so the scenario is the unit that
    repeats, not the episode); ``seed_boot_*`` a percentile bootstrap over the per-seed success
    rates (NaN with one seed); ``paper_success_rate`` the paper's value (NaN where it has none).

    ``bounds`` (``{"random" | "oracle": {(seed, height, placement): paths}}``, either side possibly
    empty) adds :func:`bound_columns`: the bound searchers' pooled success rate, Wilson interval and
    SPL on each cell (NaN and 0 episodes where a bound was not run; a bound beside the policy with no files
    at all has no columns, so registering one leaves a stored table as it is until it runs). A bound runs one seed, each
    scenario once, so its episodes are independent and the Wilson interval is right for it. They
    must have run on the policy's scenario sets: a cell the policy lacks is an error.
    """
    if not episode_files:
        raise ValueError("table1: no evaluation files given")
    cells = _read_cells(episode_files, "table1")
    bound_cells = {}
    all_bounds = bound_names()
    for bound, files in (bounds or {}).items():
        if bound not in all_bounds:
            raise ValueError(f"table1: bound {bound!r}; allowed: {', '.join(all_bounds)}")
        bound_cells[bound] = _read_cells(files, f"table1 {bound}")
        extra = set(bound_cells[bound]) - set(cells)
        if extra:
            raise ValueError(f"table1: the {bound} files have cells the policy has not: {sorted(extra)}")
    shown = [b for b in all_bounds if _always_shown(b) or len(bound_cells.get(b, {})) > 0]
    rows = []
    for home, h, pl in _sorted_home_cells(cells):
        df = cells[(home, h, pl)]
        success, scenarios = scenario_seed_matrix(df, "success")
        rate, lo, hi = two_level_ci(success, confidence, n_resamples, seed)
        spl_mean, spl_lo, spl_hi = two_level_ci(scenario_seed_matrix(df, "spl")[0], confidence, n_resamples, seed)
        per_seed = df.groupby("seed")["success"].mean().to_numpy(dtype=float)
        blo, bhi = bootstrap_ci(per_seed, np.mean, confidence, n_resamples, seed)
        rows.append({"home": home, "height": h, "placement": pl, "n_episodes": len(df), "n_scenarios": len(scenarios),
                     "n_seeds": int(df["seed"].nunique()), "success_rate": rate, "ci_low": lo, "ci_high": hi,
                     "seed_boot_low": blo, "seed_boot_high": bhi, "spl": spl_mean, "spl_low": spl_lo,
                     "spl_high": spl_hi, "stuck_share": stuck_share(df),
                     "paper_success_rate": PAPER_TABLE1.get((round(h, 2), pl), math.nan)})
        if bounds is not None:
            for bound in shown:
                rows[-1].update(_bound_row(bound_cells.get(bound, {}).get((home, h, pl)), bound, confidence))
    columns = list(TABLE1_COLUMNS) + (list(bound_columns(shown)) if bounds is not None else [])
    return pd.DataFrame(rows, columns=columns)


def _table1_grid(df: pd.DataFrame) -> tuple[list[float], list[str]]:
    heights = sorted(set(df["height"]))
    order = {"no_low_cabinets": 0, "everywhere": 1}
    placements = sorted(set(df["placement"]), key=lambda p: (order.get(p, 2), p))
    return heights, placements


def _searcher_cell(df: pd.DataFrame, h: float, pl: str, who: str) -> str:
    """One searcher on one cell: ``0.83 [0.76, 0.88]`` (ours: two-level bootstrap; bounds: Wilson), the
    paper's value, or "not run"."""
    row = df[(df["height"] == h) & (df["placement"] == pl)]
    if who == "paper":
        return _fmt(PAPER_TABLE1.get((round(h, 2), pl), math.nan))
    if row.empty:
        return "–"
    r = row.iloc[0]
    if who == "ours":
        return f"{r.success_rate:.2f} [{r.ci_low:.2f}, {r.ci_high:.2f}]"
    if not r[f"{who}_n_episodes"]:
        return NOT_RUN
    return f"{r[who + '_success_rate']:.2f} [{r[who + '_wilson_low']:.2f}, {r[who + '_wilson_high']:.2f}]"


def _home_label(home: str, homes: list[str]) -> str:
    if home == BOTH_HOMES:
        return "both homes pooled (" + " and ".join(h for h in homes if h != BOTH_HOMES) + ")"
    return home


def _table1_section(df: pd.DataFrame, title: str, variant: str | None, with_bounds: bool,
                    label: str) -> tuple[list[str], list[str]]:
    """One home's Table 1 as Markdown and LaTeX lines: per height the policy (and, with bounds, the random
    searcher and the privileged oracle around it) and the paper."""
    heights, placements = _table1_grid(df)
    heads = [PLACEMENT_LABELS.get(p, p) for p in placements]
    ours = f"ours ({variant})" if variant else "ours"
    present = [b for b in bound_names() if with_bounds and f"{b}_n_episodes" in df
               and (_always_shown(b) or df[f"{b}_n_episodes"].any())]
    place = {b: searchers.get(b).table_row for b in present}
    rows = ([(b, searcher_label(b)) for b in present if place[b] == searchers.FLOOR] + [("ours", ours)]
            + [(b, searcher_label(b)) for b in present if place[b] == searchers.BESIDE]
            + [(b, searcher_label(b)) for b in present if place[b] == searchers.CEILING] + [("paper", "paper")])
    md = [title, "", "| Head height | Searcher | " + " | ".join(heads) + " |", "|---|---|" + "---|" * len(heads)]
    tex = [r"\begin{table}[t]", r"\centering", r"\small", r"\begin{tabular}{ll" + "c" * len(heads) + "}",
           r"\toprule", "Head height & Searcher & " + " & ".join(_tex_escape(x) for x in heads) + r" \\",
           r"\midrule"]
    for i, h in enumerate(heights):
        if i:
            tex.append(r"\midrule")
        for j, (who, name) in enumerate(rows):
            cells = [_searcher_cell(df, h, p, who) for p in placements]
            md.append(f"| {_height_label(h)} | {name} | " + " | ".join(cells) + " |")
            tex.append(f"{_height_label(h) if j == 0 else ''} & {_tex_escape(name)} & "
                       + " & ".join(_tex_escape(c) for c in cells) + r" \\")
    tex += [r"\bottomrule", r"\end{tabular}", r"\caption{" + _tex_escape(title) + "}", r"\label{" + label + "}",
            r"\end{table}", ""]
    return md, tex


def learning_adds_note(compare_csv: PathLike, variant: str | None = None) -> str:
    """One sentence of Table 1's notes from a stored comparison of the policy against its own start
    (``compare/{variant}_vs_its_start.csv``, rule ``learning_adds``): the success difference, final minus
    step 0, with its interval, per height and placement."""
    df = pd.read_csv(compare_csv)
    df = df[df["metric"] == "success"]
    if df.empty:
        raise ValueError(f"{compare_csv}: no success rows (not a comparison written by `egosearch report compare`)")
    name = f"ours ({variant})" if variant else "ours"
    parts = []
    for h in sorted(set(df["height"])):
        cells = []
        for placement, label in (("no_low_cabinets", "excluding cabinets"), ("everywhere", "everywhere")):
            row = df[(df["height"] == h) & (df["placement"] == placement)]
            if len(row):
                r = row.iloc[0]
                cells.append(f"{r['difference']:+.2f} [{r['ci_low']:+.2f}, {r['ci_high']:+.2f}] {label}")
        parts.append(f"{_height_label(h)} " + ", ".join(cells))
    seeds = int(df["n_seeds_cand"].iloc[0])
    return (f"What learning adds: {name} against its own start (each seed's policy at step 0, before any RL "
            f"update: the clone after imitation, else the untrained net) on the same scenarios and {seeds} "
            f"seed(s), success difference, final minus start [95% interval, same bootstrap]: {'; '.join(parts)} "
            f"({Path(compare_csv).name}).")


def table1(episode_files: Mapping, out_prefix: PathLike, confidence: float = 0.95, n_resamples: int = 10_000,
           seed: int = 0, bounds: Mapping[str, Mapping] | None = None, variant: str | None = None,
           learning_adds: PathLike | None = None) -> pd.DataFrame:
    """Write ``{prefix}.csv``, ``.md`` and ``.tex`` (see :func:`output_base`; a directory gets ``table1.*``); return
    the frame.

    See :func:`table1_frame` for ``episode_files`` and the numbers. The Markdown/LaTeX tables are laid
    out like the paper (rows: head height; columns: Excluding cabinets / Everywhere), each cell
    ``0.83 [0.76, 0.88]``. The first table is the one set beside the paper's column: every home pooled
    (the paper tests in both of its homes and gives one number per cell), or the one home evaluated;
    a table per home follows when there are several.

    With ``bounds`` (see :func:`table1_frame`; ``{}`` when none is stored) each height also gets the
    random searcher and the privileged oracle, a bound that was not run saying so. ``learning_adds``: the
    stored comparison of the policy against its own start, said in the notes (:func:`learning_adds_note`).
    """
    adds = learning_adds_note(learning_adds, variant) + " " if learning_adds is not None else ""
    df = table1_frame(episode_files, confidence, n_resamples, seed, bounds=bounds)
    base = output_base(out_prefix, "table1")
    out_csv = suffixed(base, ".csv")
    df.to_csv(out_csv, index=False, float_format="%.6g")
    homes = sorted(set(df["home"]), key=lambda h: (h != BOTH_HOMES, h))
    pct = f"{confidence * 100:g}%"
    seeds_s = "/".join(str(s) for s in sorted(set(df["n_seeds"])))
    with_bounds = bounds is not None
    md_all, tex_all = [], []
    for i, home in enumerate(homes):
        part = df[df["home"] == home]
        scen = "/".join(str(s) for s in sorted(set(part["n_scenarios"])))
        where = _home_label(home, homes)
        title = (f"Table 1: Success rate by head height and object placement, {where}"
                 + (": the search policy between the random searcher and the privileged oracle, and the paper's policy."
                    if with_bounds else " (ours vs. paper)."))
        if i:
            title = f"Table 1 in {where} alone."
        md, tex = _table1_section(part, title, variant, with_bounds, "tab:table1" + ("" if not i else f"_{home}"))
        md_all += md + [""]
        tex_all += tex
        if not i:
            if with_bounds:
                bound_eps = {b: "/".join(str(int(n)) for n in sorted(set(part[f"{b}_n_episodes"])) if n) or "0"
                             for b in bound_names() if f"{b}_n_episodes" in part}
                shown = [b for b in bound_eps if _always_shown(b) or bound_eps[b] != "0"]
                notes = " ".join(
                    f"{searcher_label(b)[0].upper() + searcher_label(b)[1:]}: {searchers.get(b).what}, "
                    + (f"{bound_eps[b]} episodes per cell on the same scenarios, one seed (independent episodes: "
                       f"{pct} Wilson interval)." if bound_eps[b] != "0"
                       else f"{NOT_RUN} (no stored per-episode CSVs; rule `bound`).") for b in shown)
            else:
                notes = ""
            md_all += [f"Ours: {scen} scenarios per cell, each run by {seeds_s} seed(s); brackets: {pct} two-level "
                       "bootstrap interval (scenarios resampled, then seeds: the seeds ran the same scenarios, so "
                       f"the scenario is the unit that repeats). {adds}{notes} "
                       + ("The paper's column is set beside both homes pooled: the paper tests its policy in both "
                          "homes (Section 6) and gives one number per cell. " if BOTH_HOMES in homes else "")
                       + f"SPL and its interval, the {pct} bootstrap over per-seed success rates and every searcher's "
                       f"stuck share (episodes failed with {STUCK_COLLISIONS} or more collisions) are in "
                       f"{out_csv.name}; how each fails is in failures.md (`snakemake failures`); how much memory the "
                       "search asks for (the tuned searcher held to its last K steps, beside the policy's 5 frames) is "
                       "in memory_window.md (`snakemake memory_window`). Paper: Table 1 of Sorokin et al. 2021.", ""]
    suffixed(base, ".md").write_text("\n".join(md_all).rstrip("\n") + "\n", encoding="utf-8")
    suffixed(base, ".tex").write_text("\n".join(tex_all), encoding="utf-8")
    return df


# --------------------------------------------------------------------------------------------- Table 2
def table2(rows: Iterable[tuple[str, str]], out_prefix: PathLike, caption: str = TABLE2_CAPTION,
           departures: Iterable[tuple[str, str, str, str]] = ()) -> None:
    """Write ``{prefix}.md`` and ``{prefix}.tex`` (a directory gets ``table2.*``): Parameter | Setting, rows in the
    order given.

    ``rows`` are (parameter, setting) pairs, e.g. ``egosearch.rl.config.table2_rows(cfg)`` (the caller
    passes them: the report layer does not import the config). ``departures`` (field, this preset,
    paper, field documentation), e.g. ``egosearch.rl.config.departure_rows(cfg)``, add a second
    table: every learner setting of this preset that is not the paper's.
    """
    departures = [tuple(str(x) for x in d) for d in departures]
    rows = [(str(a), str(b)) for a, b in rows]
    if not rows:
        raise ValueError("table2: no rows")
    base = output_base(out_prefix, "table2")
    md = [f"Table 2: {caption}", "", "| Parameter | Setting |", "|---|---|"]
    md += [f"| {_md_escape(a)} | {_md_escape(b)} |" for a, b in rows]
    if departures:
        md += ["", f"Where this preset departs from the paper ({len(departures)} learner settings; the paper "
               "preset is Table 2 exactly):", "",
               "| Field | This preset | Paper | Source and meaning (the field's docstring) |", "|---|---|---|---|"]
        md += [f"| `{f}` | {_md_escape(mine)} | {_md_escape(paper)} | {_md_escape(doc)} |"
               for f, mine, paper, doc in departures]
    suffixed(base, ".md").write_text("\n".join(md) + "\n", encoding="utf-8")
    tex = [r"\begin{table}[t]", r"\centering", r"\small", r"\begin{tabular}{ll}", r"\toprule",
           r"Parameter & Setting \\", r"\midrule"]
    tex += [f"{_tex_escape(a)} & {_tex_escape(b)} " + r"\\" for a, b in rows]
    if departures:
        tex += [r"\midrule", r"\multicolumn{2}{l}{\emph{Departures from the paper (this preset / paper)}} \\"]
        tex += [f"{_tex_escape(f)} & {_tex_escape(mine)} / {_tex_escape(paper)} " + r"\\"
                for f, mine, paper, _ in departures]
    tex += [r"\bottomrule", r"\end{tabular}", r"\caption{" + _tex_escape(caption) + "}", r"\label{tab:table2}",
            r"\end{table}", ""]
    suffixed(base, ".tex").write_text("\n".join(tex), encoding="utf-8")


# --------------------------------------------------------------------------------------------- compare
COMPARE_COLUMNS = ("height", "placement", "metric", "reference", "candidate", "difference", "ci_low", "ci_high",
                   "p_uncorrected", "p_holm", "significant_holm", "n_scenarios", "n_seeds_ref", "n_seeds_cand",
                   "detectable_80", "method", "seed_sd", "verdict", "homes")
"""``p_uncorrected`` is one cell's test alone, read from the same two-level bootstrap draws as ``ci_low`` /
``ci_high`` (below 0.05 exactly when that interval excludes 0); ``significant_holm`` is ``p_holm < 0.05``,
Holm's adjustment over every row of the file: the only column that says whether a difference is
significant (never true while the interval holds 0, since Holm only raises p). ``detectable_80``: the
true difference the cell's test would detect with 80% power (uncorrected), seeds counted; ``homes``:
the homes whose scenarios the cell pools. ``method``: ``seed spread`` (a screen, or a side with too few seeds
to show its own spread: the t-test on the seeds' cell means of :mod:`egosearch.report.seed_spread`, its
interval, p and ``detectable_80`` that test's) or ``bootstrap`` (not a screen, every trained side with 3 seeds
or more: the two-level bootstrap); ``seed_sd``: the standard deviation of one training seed's cell mean that
the seed-spread test counted (blank for the bootstrap); ``verdict``: ``higher`` or ``lower`` when
significant after Holm, else ``within the reference's seed spread`` (seed spread) or ``no difference
detected`` (bootstrap)."""

WITHIN_SEED_SPREAD = "within the reference's seed spread"


def verdicts(df: pd.DataFrame) -> pd.Series:
    """``verdict`` of a comparison frame with ``significant_holm``, ``difference`` and ``method`` (COMPARE_COLUMNS)."""
    def one(row) -> str:
        if row["significant_holm"]:
            side = "higher" if row["difference"] > 0 else "lower"
            return f"{side} than the scenarios explain (seed spread unknown)" if row["method"] == "scenarios only" \
                else side
        if row["method"] == "scenarios only":  # no seed spread to count: the old reading, said so
            return "no difference the scenarios show (seed spread unknown)"
        return WITHIN_SEED_SPREAD if row["method"] == "seed spread" else "no difference detected"
    return df.apply(one, axis=1) if len(df) else pd.Series([], dtype=str)


def _cell_name(cell) -> str:
    if isinstance(cell, tuple) and len(cell) == 2:
        return f"(height={cell[0]}, placement={cell[1]})"
    return repr(cell)


def compare_report(reference_files: Mapping, candidate_files: Mapping, out_csv: PathLike | None = None,
                   metrics: Iterable[str] = METRICS, n_resamples: int = 10_000, seed: int = 0,
                   spread_files: Mapping | None = None, count_seed_spread: bool = True) -> pd.DataFrame:
    """Candidate vs reference per cell and metric (:func:`~egosearch.report.stats.compare_cells`), as a frame.

    ``reference_files`` / ``candidate_files``: ``{(height, placement): [per-episode CSV paths]}``, the
    paths over seeds (and layouts) of one variant; the seed and the scenario file are read from each
    path (``.../seed{N}/{layout}/{placement}/h{height}.csv``). Columns :data:`COMPARE_COLUMNS`;
    ``p_holm`` are Holm-adjusted over all rows. Written to ``out_csv`` when given.

    ``spread_files``: every stored seed's files of the reference variant, ``{cell: [paths]}``: a screen, whose
    test counts the spread between those seeds (:func:`~egosearch.report.spread_sides.comparison_spreads`).
    ``count_seed_spread=False``: the comparison as it was read before that (each side's own seeds only, a
    one-seed side's scenarios only): the null screen's "before".

    ValueError (one line, naming the cell) if a cell is on one side only or the two sides were
    evaluated on different scenarios; SeedSpreadUnknown (a ValueError) when a side must borrow the seed
    spread and the reference has one seed.
    """
    ref_cells, cand_cells = set(reference_files), set(candidate_files)
    for cell in sorted(ref_cells ^ cand_cells, key=str):
        side = "reference" if cell in ref_cells else "candidate"
        raise ValueError(f"compare: cell {_cell_name(cell)} is only in the {side} files")
    if not ref_cells:
        raise ValueError("compare: no cells given")
    metrics = list(metrics)
    for cell in sorted_cells(ref_cells):  # the scenarios first: a mismatch is named before any seed is read
        try:
            paired_scenarios(read_episodes(reference_files[cell]), read_episodes(candidate_files[cell]))
        except ValueError as e:
            raise ValueError(f"compare: cell {_cell_name(cell)}: {e}") from None
    spreads = comparison_spreads(reference_files, candidate_files, spread_files) if count_seed_spread else None
    rows = []
    for cell in sorted_cells(ref_cells):
        ref = read_episodes(reference_files[cell])
        cand = read_episodes(candidate_files[cell])
        for metric in metrics:
            try:
                res = compare_cells(ref, cand, metric, n_resamples=n_resamples, seed=seed, spreads=spreads)
            except ValueError as e:
                raise type(e)(f"compare: cell {_cell_name(cell)}: {e}") from None
            homes = "+".join(sorted({_home_of(x) for x in ref["scenario_set"]}))
            rows.append({"height": cell[0], "placement": cell[1], "metric": metric, **res, "homes": homes})
    return holm_and_write(pd.DataFrame(rows), COMPARE_COLUMNS, out_csv)


def holm_and_write(df: pd.DataFrame, columns: Iterable[str], out_csv: PathLike | None = None) -> pd.DataFrame:
    """A comparison frame with ``p_holm`` (Holm over all its rows) and ``significant_holm``, cut to ``columns``,
    written to ``out_csv`` when given."""
    df["p_holm"] = holm(df["p_uncorrected"].to_numpy())
    df["significant_holm"] = df["p_holm"] < 0.05
    if "verdict" in columns:
        df["verdict"] = verdicts(df)
    df = df[list(columns)]
    if out_csv is not None:
        out_csv = Path(out_csv)
        out_csv.parent.mkdir(parents=True, exist_ok=True)
        df.to_csv(out_csv, index=False, float_format="%.6g")
    return df


def stuck_path(out_csv: PathLike) -> Path:
    """Where ``egosearch report compare --out X.csv`` writes the stuck shares: ``X_stuck.csv``."""
    out = Path(out_csv)
    return out.with_name(out.stem + "_stuck" + (out.suffix or ".csv"))


def format_stuck(df: pd.DataFrame) -> str:
    """One line: the stuck share of each side per cell (episodes failed with 50 or more collisions), the
    cells where it differs after Holm (over these rows alone)."""
    cells = "; ".join(f"{r.height:g} m {'excl.' if r.placement == 'no_low_cabinets' else 'every'} "
                      f"{r.reference * 100:.1f}% -> {r.candidate * 100:.1f}%{' *' if r.significant_holm else ''}"
                      for r in df.itertuples(index=False))
    return (f"stuck (failed with {STUCK_COLLISIONS} or more collisions), reference -> candidate: {cells} "
            "(* different after Holm over these rows)")


def format_compare(df: pd.DataFrame, reference_name: str = "reference", candidate_name: str = "candidate") -> str:
    """Fixed-width text of a :func:`compare_report` frame; ``*`` marks Holm-adjusted p < 0.05."""
    head = (f"{'height':>6}  {'placement':<16} {'metric':<7} {reference_name[:10]:>10} {candidate_name[:10]:>10} "
            f"{'diff':>7}  {'95% CI':<17} {'p_unc':>7} {'p_holm':>7}  {'scen':>4} {'seeds':>5}")
    lines = [head, "-" * len(head)]
    for r in df.itertuples(index=False):
        ci = f"[{r.ci_low:+.3f}, {r.ci_high:+.3f}]"
        star = "*" if r.significant_holm else " "
        lines.append(f"{float(r.height):>6.2f}  {str(r.placement):<16} {r.metric:<7} {r.reference:>10.3f} "
                     f"{r.candidate:>10.3f} {r.difference:>+7.3f}  {ci:<17} {r.p_uncorrected:>7.4f} "
                     f"{r.p_holm:>7.4f}{star} "
                     f"{r.n_scenarios:>4d} {r.n_seeds_ref:>2d}/{r.n_seeds_cand:<2d}")
    lines.append("* Holm-adjusted p < 0.05 over all rows (p_unc: one cell's test alone). diff = candidate - "
                 "reference; p < 0.05 exactly when the 95% CI excludes 0.")
    if (df["method"] == "seed spread").any():
        sd = float(df.loc[df["method"] == "seed spread", "seed_sd"].max())
        lines.append(f"A side has too few seeds to show its own spread: CI and p add the reference's seed variance "
                     f"(sd {sd:.3f} between training seeds) to the scenarios'; a row without * is within the "
                     "reference's seed spread, not lower or higher (docs/statistics.md).")
    elif (df["method"] == "scenarios only").any():
        lines.append("A side has one seed and the reference has no other to show how much training seeds differ: "
                     "CI and p count the scenarios only, so a difference may be a seed's luck (give the reference's "
                     "seeds with --spread; docs/statistics.md).")
    else:
        lines.append("CI: paired two-level bootstrap (scenarios, then each side's seeds); p: the same draws read as "
                     "a two-sided test.")
    return "\n".join(lines)

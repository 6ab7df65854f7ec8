"""Table 1 (success rate by head height × object placement), Table 2 (hyper-parameters) and the
variant-vs-variant comparison report. CSV in, files out (``.csv``, ``.md``, ``.tex``)."""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from egosearch.report.data import _sorted_cells, _with, output_base, read_episodes
from egosearch.report.stats import METRICS, bootstrap_ci, compare_cells, holm, wilson_ci

PAPER_TABLE1: dict[tuple[float, str], float] = {
    (0.45, "no_low_cabinets"): 0.50, (1.05, "no_low_cabinets"): 0.92, (1.65, "no_low_cabinets"): 0.90,
    (0.45, "everywhere"): 0.58, (1.05, "everywhere"): 0.75, (1.65, "everywhere"): 0.76,
}
"""Paper, Table 1: success rate of the search policy (100 scenarios per cell)."""

PLACEMENT_LABELS = {"no_low_cabinets": "Excluding cabinets", "everywhere": "Everywhere"}

TABLE1_COLUMNS = ("height", "placement", "n_episodes", "n_seeds", "success_rate", "wilson_low", "wilson_high",
                  "seed_boot_low", "seed_boot_high", "spl", "paper_success_rate")

BOUNDS = ("random", "oracle")
"""The searchers Table 1 puts each policy between, on the same scenario sets: uniform random actions,
and the privileged oracle (knows the target and walks the shortest path to it)."""
BOUND_LABELS = {"random": "random searcher", "oracle": "privileged oracle"}
BOUND_COLUMNS = tuple(f"{b}_{c}" for b in BOUNDS for c in ("n_episodes", "success_rate", "wilson_low",
                                                            "wilson_high", "spl"))
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
def _read_cells(episode_files: Mapping, what: str) -> dict[tuple, pd.DataFrame]:
    """``{(seed, height, placement): paths}`` -> ``{(height, placement): episodes pooled over seeds}``."""
    cells: dict[tuple, list[pd.DataFrame]] = {}
    for key, paths in episode_files.items():
        if not (isinstance(key, tuple) and len(key) == 3):
            raise ValueError(f"{what}: key {key!r} is not (seed, height, placement)")
        s, h, pl = key
        cells.setdefault((round(float(h), 4), str(pl)), []).append(read_episodes(paths, seed=int(s)))
    return {cell: pd.concat(frames, ignore_index=True) for cell, frames in cells.items()}


def _bound_row(df: pd.DataFrame | None, bound: str, confidence: float) -> dict:
    if df is None:
        return {f"{bound}_n_episodes": 0, f"{bound}_success_rate": math.nan, f"{bound}_wilson_low": math.nan,
                f"{bound}_wilson_high": math.nan, f"{bound}_spl": math.nan}
    n, k = len(df), int(df["success"].astype(int).sum())
    lo, hi = wilson_ci(k, n, confidence)
    return {f"{bound}_n_episodes": n, f"{bound}_success_rate": k / n, f"{bound}_wilson_low": lo,
            f"{bound}_wilson_high": hi, f"{bound}_spl": float(df["spl"].mean())}


def table1_frame(episode_files: Mapping, confidence: float = 0.95, n_resamples: int = 10_000,
                 seed: int = 0, bounds: Mapping[str, Mapping] | None = None) -> pd.DataFrame:
    """The numbers of Table 1, one row per (height, placement) with :data:`TABLE1_COLUMNS`.

    ``episode_files``: ``{(seed, height, placement): path or [paths]}``; several paths per key are
    pooled (e.g. the two layouts). Per cell: ``success_rate`` and ``spl`` are means over all
    episodes pooled over seeds; ``wilson_*`` the Wilson interval of the pooled successes;
    ``seed_boot_*`` a percentile bootstrap of the mean over the per-seed success rates (NaN with one
    seed); ``paper_success_rate`` the paper's value (NaN where the paper has none).

    ``bounds`` (``{"random" | "oracle": {(seed, height, placement): paths}}``, either side possibly
    empty) adds :data:`BOUND_COLUMNS`: the bound searchers' pooled success rate, Wilson interval and
    SPL on each cell (NaN and 0 episodes where a bound was not run). They must have run on the
    policy's scenario sets: a cell the policy lacks is an error.
    """
    if not episode_files:
        raise ValueError("table1: no evaluation files given")
    cells = _read_cells(episode_files, "table1")
    bound_cells = {}
    for bound, files in (bounds or {}).items():
        if bound not in BOUNDS:
            raise ValueError(f"table1: bound {bound!r}; allowed: {', '.join(BOUNDS)}")
        bound_cells[bound] = _read_cells(files, f"table1 {bound}")
        extra = set(bound_cells[bound]) - set(cells)
        if extra:
            raise ValueError(f"table1: the {bound} files have cells the policy has not: {sorted(extra)}")
    rows = []
    for h, pl in _sorted_cells(cells):
        df = cells[(h, pl)]
        n, k = len(df), int(df["success"].astype(int).sum())
        lo, hi = wilson_ci(k, n, confidence)
        per_seed = df.groupby("seed")["success"].mean().to_numpy(dtype=float)
        blo, bhi = bootstrap_ci(per_seed, np.mean, confidence, n_resamples, seed)
        rows.append({"height": h, "placement": pl, "n_episodes": n, "n_seeds": int(df["seed"].nunique()),
                     "success_rate": k / n, "wilson_low": lo, "wilson_high": hi,
                     "seed_boot_low": blo, "seed_boot_high": bhi, "spl": float(df["spl"].mean()),
                     "paper_success_rate": PAPER_TABLE1.get((round(h, 2), pl), math.nan)})
        if bounds is not None:
            for bound in BOUNDS:
                rows[-1].update(_bound_row(bound_cells.get(bound, {}).get((h, pl)), bound, confidence))
    columns = list(TABLE1_COLUMNS) + (list(BOUND_COLUMNS) if bounds is not None else [])
    return pd.DataFrame(rows, columns=columns)


def _table1_grid(df: pd.DataFrame) -> tuple[list[float], list[str]]:
    heights = sorted(set(df["height"]))
    order = {"no_low_cabinets": 0, "everywhere": 1}
    placements = sorted(set(df["placement"]), key=lambda p: (order.get(p, 2), p))
    return heights, placements


def _table1_cell(df: pd.DataFrame, h: float, pl: str, tex: bool = False) -> str:
    row = df[(df["height"] == h) & (df["placement"] == pl)]
    paper = PAPER_TABLE1.get((round(h, 2), pl), math.nan)
    paper_s = _fmt(paper)
    sep = r" $\cdot$ " if tex else " · "
    if row.empty:
        ours = "–"
    else:
        r = row.iloc[0]
        ours = f"{r.success_rate:.2f} [{r.wilson_low:.2f}, {r.wilson_high:.2f}]"
    return f"ours {ours}{sep}paper {paper_s}"


def _searcher_cell(df: pd.DataFrame, h: float, pl: str, who: str) -> str:
    """One searcher on one cell: ``0.83 [0.76, 0.88]`` (Wilson), the paper's value, or "not run"."""
    row = df[(df["height"] == h) & (df["placement"] == pl)]
    if who == "paper":
        return _fmt(PAPER_TABLE1.get((round(h, 2), pl), math.nan))
    if row.empty:
        return "–"
    r = row.iloc[0]
    prefix = "" if who == "ours" else f"{who}_"
    if who != "ours" and not r[f"{prefix}n_episodes"]:
        return NOT_RUN
    return f"{r[prefix + 'success_rate']:.2f} [{r[prefix + 'wilson_low']:.2f}, {r[prefix + 'wilson_high']:.2f}]"


def _table1_with_bounds(df: pd.DataFrame, base: Path, out_csv: Path, variant: str | None, seeds_s: str, eps_s: str,
                        pct: str) -> None:
    """Table 1 with, per height, four rows: random searcher, the policy, privileged oracle, paper."""
    heights, placements = _table1_grid(df)
    heads = [PLACEMENT_LABELS.get(p, p) for p in placements]
    ours = f"ours ({variant})" if variant else "ours"
    searchers = [("random", "random searcher"), ("ours", ours), ("oracle", "privileged oracle"), ("paper", "paper")]
    bound_eps = {b: "/".join(str(int(n)) for n in sorted(set(df[f"{b}_n_episodes"])) if n) or "0" for b in BOUNDS}
    what = {"random": "uniform random actions", "oracle": "knows the target and walks the shortest path to it"}
    notes = "; ".join(
        f"{BOUND_LABELS[b]}: {what[b]}, "
        + (f"{bound_eps[b]} episodes per cell on the same scenario sets" if bound_eps[b] != "0"
           else f"{NOT_RUN} (no stored per-episode CSVs; rule `bound`)") for b in BOUNDS)
    notes = notes[0].upper() + notes[1:]
    pct_tex = pct.replace("%", r"\%")

    md = ["Table 1: Success rate by head height and object placement: the search policy between the random "
          "searcher and the privileged oracle, and the paper's policy.", "",
          "| Head height | Searcher | " + " | ".join(heads) + " |", "|---|---|" + "---|" * len(heads)]
    for h in heights:
        for who, label in searchers:
            md.append(f"| {_height_label(h)} | {label} | "
                      + " | ".join(_searcher_cell(df, h, p, who) for p in placements) + " |")
    md += ["", f"Success rate over all episodes of a cell (ours: pooled over {seeds_s} seed(s), {eps_s} episodes per "
               f"cell); brackets: {pct} Wilson score interval. {notes}. The {pct} percentile bootstrap over ours' "
               f"per-seed success rates and every SPL are in {out_csv.name}. Paper: Table 1 of Sorokin et al. 2021.",
           ""]
    _with(base, ".md").write_text("\n".join(md), encoding="utf-8")

    cap = (f"Success rate by head height and object placement: the search policy between the random searcher and "
           f"the privileged oracle, and the paper's Table 1. Ours: pooled over {seeds_s} seed(s) ({eps_s} episodes "
           f"per cell); brackets: {pct_tex} Wilson score interval. {_tex_escape(notes)}.")
    tex = [r"\begin{table}[t]", r"\centering", r"\small", r"\begin{tabular}{ll" + "c" * len(heads) + "}",
           r"\toprule", "Head height & Searcher & " + " & ".join(_tex_escape(x) for x in heads) + r" \\",
           r"\midrule"]
    for i, h in enumerate(heights):
        if i:
            tex.append(r"\midrule")
        for j, (who, label) in enumerate(searchers):
            tex.append(f"{_height_label(h) if j == 0 else ''} & {_tex_escape(label)} & "
                       + " & ".join(_tex_escape(_searcher_cell(df, h, p, who)) for p in placements) + r" \\")
    tex += [r"\bottomrule", r"\end{tabular}", r"\caption{" + cap + "}", r"\label{tab:table1}", r"\end{table}",
            ""]
    _with(base, ".tex").write_text("\n".join(tex), encoding="utf-8")


def table1(episode_files: Mapping, out_prefix: PathLike, confidence: float = 0.95, n_resamples: int = 10_000,
           seed: int = 0, bounds: Mapping[str, Mapping] | None = None, variant: str | None = None) -> pd.DataFrame:
    """Write ``{prefix}.csv``, ``.md`` and ``.tex`` (see :func:`output_base`; a directory gets ``table1.*``); return
    the frame.

    See :func:`table1_frame` for ``episode_files`` and the numbers. The Markdown/LaTeX tables are
    laid out like the paper (rows: head height; columns: Excluding cabinets / Everywhere), each
    cell ``ours 0.83 [0.76, 0.88] · paper 0.92`` with the Wilson interval in brackets.

    With ``bounds`` (see :func:`table1_frame`; ``{}`` when none is stored) each height gets four
    rows instead: random searcher, ours (``variant``), privileged oracle and paper, a bound that was
    not run saying so.
    """
    df = table1_frame(episode_files, confidence, n_resamples, seed, bounds=bounds)
    base = output_base(out_prefix, "table1")
    out_csv = _with(base, ".csv")
    df.to_csv(out_csv, index=False, float_format="%.6g")
    heights, placements = _table1_grid(df)
    heads = [PLACEMENT_LABELS.get(p, p) for p in placements]
    n_seeds = sorted(set(df["n_seeds"]))
    n_eps = sorted(set(df["n_episodes"]))
    seeds_s = "/".join(str(s) for s in n_seeds)
    eps_s = "/".join(str(s) for s in n_eps)
    pct = f"{confidence * 100:g}%"
    pct_tex = pct.replace("%", r"\%")
    if bounds is not None:
        _table1_with_bounds(df, base, out_csv, variant, seeds_s, eps_s, pct)
        return df

    md = ["Table 1: Success rate of the search policy by head height and object placement (ours vs. paper).", "",
          "| Head height | " + " | ".join(heads) + " |", "|---|" + "---|" * len(heads)]
    for h in heights:
        md.append(f"| {_height_label(h)} | " + " | ".join(_table1_cell(df, h, p) for p in placements) + " |")
    md += ["", f"Ours: success rate over all episodes pooled over {seeds_s} seed(s) ({eps_s} episodes per cell); "
               f"brackets: {pct} Wilson score interval over the pooled episodes. The {pct} percentile bootstrap over "
               f"per-seed success rates is in {out_csv.name} (seed_boot_low/high). "
               "Paper: Table 1 of Sorokin et al. 2021.", ""]
    _with(base, ".md").write_text("\n".join(md), encoding="utf-8")

    cap = (f"Success rate of the search policy by head height and object placement, ours vs.\\ the paper's Table 1. "
           f"Ours: all episodes pooled over {seeds_s} seed(s) ({eps_s} episodes per cell); brackets: "
           f"{pct_tex} Wilson score interval over the pooled episodes; the "
           f"{pct_tex} percentile bootstrap interval over per-seed success rates is given "
           f"in {_tex_escape(out_csv.name)}.")
    tex = [r"\begin{table}[t]", r"\centering", r"\small", r"\begin{tabular}{l" + "c" * len(heads) + "}", r"\toprule",
           "Head height & " + " & ".join(_tex_escape(x) for x in heads) + r" \\", r"\midrule"]
    for h in heights:
        tex.append(f"{_height_label(h)} & " + " & ".join(_table1_cell(df, h, p, tex=True) for p in placements)
                   + r" \\")
    tex += [r"\bottomrule", r"\end{tabular}", r"\caption{" + cap + "}", r"\label{tab:table1}", r"\end{table}", ""]
    _with(base, ".tex").write_text("\n".join(tex), encoding="utf-8")
    return df


# --------------------------------------------------------------------------------------------- Table 2
def table2(rows: Iterable[tuple[str, str]], out_prefix: PathLike, caption: str = TABLE2_CAPTION,
           departures: Iterable[tuple[str, str, str, str]] = ()) -> None:
    """Write ``{prefix}.md`` and ``{prefix}.tex`` (a directory gets ``table2.*``): Parameter | Setting, rows in the
    order given.

    ``rows`` are (parameter, setting) pairs, e.g. ``egosearch.rl.config.table2_rows(cfg)`` (the caller
    passes them: the report layer does not import the config). ``departures`` (field, this profile,
    paper, field documentation), e.g. ``egosearch.rl.config.departure_rows(cfg)``, add a second
    table: every learner setting of this profile that is not the paper's.
    """
    departures = [tuple(str(x) for x in d) for d in departures]
    rows = [(str(a), str(b)) for a, b in rows]
    if not rows:
        raise ValueError("table2: no rows")
    base = output_base(out_prefix, "table2")
    md = [f"Table 2: {caption}", "", "| Parameter | Setting |", "|---|---|"]
    md += [f"| {_md_escape(a)} | {_md_escape(b)} |" for a, b in rows]
    if departures:
        md += ["", f"Where this profile departs from the paper ({len(departures)} learner settings; the paper "
               "profile is Table 2 exactly):", "",
               "| Field | This profile | Paper | Source and meaning (the field's docstring) |", "|---|---|---|---|"]
        md += [f"| `{f}` | {_md_escape(mine)} | {_md_escape(paper)} | {_md_escape(doc)} |"
               for f, mine, paper, doc in departures]
    _with(base, ".md").write_text("\n".join(md) + "\n", encoding="utf-8")
    tex = [r"\begin{table}[t]", r"\centering", r"\small", r"\begin{tabular}{ll}", r"\toprule",
           r"Parameter & Setting \\", r"\midrule"]
    tex += [f"{_tex_escape(a)} & {_tex_escape(b)} " + r"\\" for a, b in rows]
    if departures:
        tex += [r"\midrule", r"\multicolumn{2}{l}{\emph{Departures from the paper (this profile / paper)}} \\"]
        tex += [f"{_tex_escape(f)} & {_tex_escape(mine)} / {_tex_escape(paper)} " + r"\\"
                for f, mine, paper, _ in departures]
    tex += [r"\bottomrule", r"\end{tabular}", r"\caption{" + _tex_escape(caption) + "}", r"\label{tab:table2}",
            r"\end{table}", ""]
    _with(base, ".tex").write_text("\n".join(tex), encoding="utf-8")


# --------------------------------------------------------------------------------------------- compare
COMPARE_COLUMNS = ("height", "placement", "metric", "reference", "candidate", "difference", "ci_low", "ci_high",
                   "p_value", "p_holm", "significant", "n_scenarios", "n_seeds_ref", "n_seeds_cand")


def _cell_name(cell) -> str:
    if isinstance(cell, tuple) and len(cell) == 2:
        return f"(height={cell[0]}, placement={cell[1]})"
    return repr(cell)


def compare_report(reference_files: Mapping, candidate_files: Mapping, out_csv: PathLike | None = None,
                   metrics: Iterable[str] = METRICS, n_resamples: int = 10_000, seed: int = 0) -> pd.DataFrame:
    """Candidate vs reference per cell and metric (:func:`~egosearch.report.stats.compare_cells`), as a frame.

    ``reference_files`` / ``candidate_files``: ``{(height, placement): [per-episode CSV paths]}``, the
    paths over seeds (and layouts) of one variant; the seed and the scenario file are read from each
    path (``.../seed{N}/{layout}/{placement}/h{height}.csv``). Columns :data:`COMPARE_COLUMNS`;
    ``p_holm`` are Holm-adjusted over all rows. Written to ``out_csv`` when given.

    ValueError (one line, naming the cell) if a cell is on one side only or the two sides were
    evaluated on different scenarios.
    """
    ref_cells, cand_cells = set(reference_files), set(candidate_files)
    for cell in sorted(ref_cells ^ cand_cells, key=str):
        side = "reference" if cell in ref_cells else "candidate"
        raise ValueError(f"compare: cell {_cell_name(cell)} is only in the {side} files")
    if not ref_cells:
        raise ValueError("compare: no cells given")
    rows = []
    for cell in _sorted_cells(ref_cells):
        ref = read_episodes(reference_files[cell])
        cand = read_episodes(candidate_files[cell])
        for metric in metrics:
            try:
                res = compare_cells(ref, cand, metric, n_resamples=n_resamples, seed=seed)
            except ValueError as e:
                raise ValueError(f"compare: cell {_cell_name(cell)}: {e}") from None
            rows.append({"height": cell[0], "placement": cell[1], "metric": metric, **res})
    df = pd.DataFrame(rows)
    df["p_holm"] = holm(df["p_value"].to_numpy())
    df = df[list(COMPARE_COLUMNS)]
    if out_csv is not None:
        out_csv = Path(out_csv)
        out_csv.parent.mkdir(parents=True, exist_ok=True)
        df.to_csv(out_csv, index=False, float_format="%.6g")
    return df


def format_compare(df: pd.DataFrame, reference_name: str = "reference", candidate_name: str = "candidate") -> str:
    """Fixed-width text of a :func:`compare_report` frame; ``*`` marks p < 0.05 (uncorrected)."""
    head = (f"{'height':>6}  {'placement':<16} {'metric':<7} {reference_name[:10]:>10} {candidate_name[:10]:>10} "
            f"{'diff':>7}  {'95% CI':<17} {'p':>7} {'p_holm':>7}  {'scen':>4} {'seeds':>5}")
    lines = [head, "-" * len(head)]
    for r in df.itertuples(index=False):
        ci = f"[{r.ci_low:+.3f}, {r.ci_high:+.3f}]"
        star = "*" if r.significant else " "
        lines.append(f"{float(r.height):>6.2f}  {str(r.placement):<16} {r.metric:<7} {r.reference:>10.3f} "
                     f"{r.candidate:>10.3f} {r.difference:>+7.3f}  {ci:<17} {r.p_value:>7.4f} {r.p_holm:>7.4f}{star} "
                     f"{r.n_scenarios:>4d} {r.n_seeds_ref:>2d}/{r.n_seeds_cand:<2d}")
    lines.append("* p < 0.05 (per-cell, uncorrected; p_holm: Holm-adjusted over all rows). diff = candidate - "
                 "reference; CI: paired bootstrap over scenarios; p: paired sign-flip permutation test.")
    return "\n".join(lines)

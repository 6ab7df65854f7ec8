"""The fresh-set check: the reference's actors on scenario sets the project never stored.

Table 1's scenario sets are fixed and stored, so a preset chosen by reading them could fit them.
``snakemake --cores 2 fresh`` draws new sets (another scenario seed, the same homes and cells)
and evaluates the same actors there. Per cell, and pooled over the homes, this reports success
on the stored sets, on the fresh sets, and fresh minus stored with an interval.

The two sides hold different scenarios run by the same policies (one per seed), so a resample
draws each side's scenarios on its own and the seeds once for both: a seed that searches well
counts on both sides, and the interval is about the scenarios.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from os import PathLike
from pathlib import Path

import numpy as np
import pandas as pd

from egosearch.report.data import output_base, parse_eval_path, read_episodes, sorted_cells
from egosearch.report.stats import scenario_seed_matrix, shared_seed_difference_ci, two_level_ci

FRESH_COLUMNS = ("home", "height", "placement", "stored", "stored_low", "stored_high", "fresh", "fresh_low",
                 "fresh_high", "difference", "ci_low", "ci_high", "n_stored", "n_fresh", "n_seeds")
POOLED = "both homes"


def _cells(paths: Iterable[PathLike]) -> dict[tuple[str, float, str], list[Path]]:
    cells: dict[tuple[str, float, str], list[Path]] = {}
    for path in paths:
        p = parse_eval_path(path)
        cells.setdefault((p["layout"], p["height"], p["placement"]), []).append(Path(path))
    return cells


def _matrix(paths: list[Path], value: str = "success") -> tuple[np.ndarray, list[int]]:
    df = read_episodes(paths)
    m, _ = scenario_seed_matrix(df, value)
    return m, sorted(df["seed"].unique().tolist())


def fresh_frame(stored_files: Iterable[PathLike], fresh_files: Iterable[PathLike]) -> pd.DataFrame:
    """One row per home and cell, and per cell over the homes pooled (:data:`FRESH_COLUMNS`)."""
    stored, fresh = _cells(stored_files), _cells(fresh_files)
    if not stored or not fresh:
        raise ValueError("the fresh-set check needs evaluations on the stored sets and on the fresh sets")
    if set(stored) != set(fresh):
        only = sorted(set(stored) ^ set(fresh))
        raise ValueError(f"the stored and fresh evaluations cover different cells: {only}")
    rows = []
    homes = sorted({home for home, _, _ in stored})
    for height, placement in sorted_cells({(h, p) for _, h, p in stored}):
        for home in [*homes, POOLED]:
            pick = homes if home == POOLED else [home]
            if home == POOLED and len(homes) < 2:
                continue
            a, seeds_a = _matrix([f for h in pick for f in stored[(h, height, placement)]])
            b, seeds_b = _matrix([f for h in pick for f in fresh[(h, height, placement)]])
            if seeds_a != seeds_b:
                raise ValueError(f"{home} {height:g} m {placement}: stored sets run by seeds {seeds_a}, fresh "
                                 f"by {seeds_b}; the check needs the same actors on both")
            s, s_lo, s_hi = two_level_ci(a)
            f, f_lo, f_hi = two_level_ci(b)
            lo, hi = shared_seed_difference_ci(a, b)
            rows.append(dict(home=home, height=height, placement=placement, stored=s, stored_low=s_lo,
                             stored_high=s_hi, fresh=f, fresh_low=f_lo, fresh_high=f_hi, difference=f - s,
                             ci_low=lo, ci_high=hi, n_stored=a.shape[0], n_fresh=b.shape[0], n_seeds=a.shape[1]))
    return pd.DataFrame(rows, columns=list(FRESH_COLUMNS))


def _ci(x: float, lo: float, hi: float, signed: bool = False) -> str:
    if math.isnan(x):
        return "–"
    f = "{:+.2f}" if signed else "{:.2f}"
    return f"{f.format(x)} [{f.format(lo)}, {f.format(hi)}]"


def fresh_report(stored_files: Iterable[PathLike], fresh_files: Iterable[PathLike], out_prefix: PathLike,
                 variant: str, fresh_seed: int | None = None) -> list[Path]:
    """``<prefix>.csv`` and ``<prefix>.md``: success on the stored and the fresh sets per cell."""
    df = fresh_frame(stored_files, fresh_files)
    base = output_base(out_prefix, "fresh")
    base.parent.mkdir(parents=True, exist_ok=True)
    csv_path, md_path = base.with_suffix(".csv"), base.with_suffix(".md")
    df.to_csv(csv_path, index=False, float_format="%.4f")
    drawn = f" (scenario seed {fresh_seed})" if fresh_seed is not None else ""
    lines = [f"`{variant}` on the stored scenario sets and on fresh sets{drawn} of the same homes and cells, "
             "success with 95% two-level intervals (scenarios, then seeds); fresh − stored with an interval "
             "that draws each side's scenarios apart and the seeds once for both (the same actors ran both).", "",
             "| home | height | placement | stored sets | fresh sets | fresh − stored | scenarios (stored / fresh) | "
             "seeds |", "|---|---|---|---|---|---|---|---|"]
    for r in df.itertuples(index=False):
        lines.append(f"| {r.home} | {r.height:g} | {r.placement} | {_ci(r.stored, r.stored_low, r.stored_high)} | "
                     f"{_ci(r.fresh, r.fresh_low, r.fresh_high)} | {_ci(r.difference, r.ci_low, r.ci_high, True)} | "
                     f"{r.n_stored} / {r.n_fresh} | {r.n_seeds} |")
    apart = df[(df["ci_low"] > 0) | (df["ci_high"] < 0)]
    lines += ["", f"Rows whose interval of fresh − stored excludes 0: {len(apart)} of {len(df)} (each row's interval "
                  "alone, not corrected for the number of rows)."]
    md_path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return [csv_path, md_path]

"""One number over seeds and cells beside a comparison's per-cell rows, as rliable reads runs and tasks
(Agarwal et al. 2021, "Deep reinforcement learning at the edge of the statistical precipice"): the
interquartile mean (IQM) of every (seed, cell) success rate, and the probability of improvement, the
chance that a candidate seed beats a reference seed in a cell, averaged over cells. Their intervals are
rliable's stratified bootstrap: each side's seeds resampled within each cell.

rliable itself is not a dependency (it does not install beside pandas 3); these are its definitions.
A bootstrap over seeds cannot see a seed spread that one seed does not show: with fewer than 3 seeds on
a side its interval is labelled so, and the per-cell rows (which count the reference's spread) decide.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from egosearch.report.data import read_episodes, sorted_cells
from egosearch.report.seed_spread import MIN_SEEDS_OWN_SPREAD

AGGREGATE_COLUMNS = ("statistic", "reference", "candidate", "difference", "ci_low", "ci_high", "n_seeds_ref",
                     "n_seeds_cand", "n_cells", "note")


def seed_cell_scores(files: Mapping, metric: str = "success") -> np.ndarray:
    """(seeds x cells) mean of ``metric`` per seed and cell, cells in Table 1's order; ValueError if the cells
    do not hold the same seeds."""
    columns, seeds = [], None
    for cell in sorted_cells(files):
        per_seed = read_episodes(files[cell]).groupby("seed")[metric].mean()
        if seeds is not None and list(per_seed.index) != seeds:
            raise ValueError(f"cell {cell} holds seeds {list(per_seed.index)}, another {seeds}")
        seeds = list(per_seed.index)
        columns.append(per_seed.to_numpy(dtype=float))
    return np.column_stack(columns)


def interquartile_mean(scores: np.ndarray) -> float:
    """Mean of the middle 50% of the scores (rliable's IQM: scipy's trim_mean at 25%)."""
    x = np.sort(np.asarray(scores, float).ravel())
    n = x.size
    lo = int(np.floor(0.25 * n))
    return float(x[lo:n - lo].mean()) if n - 2 * lo > 0 else float(x.mean())


def probability_of_improvement(cand: np.ndarray, ref: np.ndarray) -> float:
    """P(a candidate seed scores above a reference seed in a cell), ties counted half, averaged over cells
    (rliable's: the Mann-Whitney U statistic per task, normalised)."""
    per_cell = []
    for c in range(cand.shape[1]):
        x, y = cand[:, c][:, None], ref[:, c][None, :]
        per_cell.append(float(((x > y) + 0.5 * (x == y)).mean()))
    return float(np.mean(per_cell))


def _stratified(scores: np.ndarray, rng, b: int) -> np.ndarray:
    """``b`` resamples of a (seeds x cells) matrix, seeds drawn with replacement within each cell."""
    k, c = scores.shape
    idx = rng.integers(0, k, size=(b, k, c))
    return np.take_along_axis(np.broadcast_to(scores, (b, k, c)), idx, axis=1)


def aggregate_report(reference_files: Mapping, candidate_files: Mapping, out_csv=None, n_resamples: int = 2000,
                     seed: int = 0, confidence: float = 0.95) -> pd.DataFrame:
    """IQM of each side and their difference, and the probability of improvement, each with its stratified
    bootstrap interval (:data:`AGGREGATE_COLUMNS`)."""
    ref, cand = seed_cell_scores(reference_files), seed_cell_scores(candidate_files)
    rng = np.random.default_rng(seed)
    ref_b, cand_b = _stratified(ref, rng, n_resamples), _stratified(cand, rng, n_resamples)
    iqm_r = np.array([interquartile_mean(m) for m in ref_b])
    iqm_c = np.array([interquartile_mean(m) for m in cand_b])
    poi = np.array([probability_of_improvement(c, r) for c, r in zip(cand_b, ref_b)])
    q = [(1 - confidence) / 2, (1 + confidence) / 2]
    few = min(ref.shape[0], cand.shape[0]) < MIN_SEEDS_OWN_SPREAD
    note = ("a side has fewer than 3 seeds: this interval resamples seeds and cannot see their spread; the "
            "per-cell rows decide" if few else "stratified bootstrap over each side's seeds")
    diff = interquartile_mean(cand) - interquartile_mean(ref)
    poi_point = probability_of_improvement(cand, ref)
    rows = [{"statistic": "iqm", "reference": interquartile_mean(ref), "candidate": interquartile_mean(cand),
             "difference": diff, "ci_low": float(np.quantile(iqm_c - iqm_r, q[0])),
             "ci_high": float(np.quantile(iqm_c - iqm_r, q[1]))},
            {"statistic": "probability_of_improvement", "reference": 0.5, "candidate": poi_point,
             "difference": poi_point - 0.5, "ci_low": float(np.quantile(poi, q[0])) - 0.5,
             "ci_high": float(np.quantile(poi, q[1])) - 0.5}]
    df = pd.DataFrame(rows).assign(n_seeds_ref=ref.shape[0], n_seeds_cand=cand.shape[0], n_cells=ref.shape[1],
                                   note=note)[list(AGGREGATE_COLUMNS)]
    if out_csv is not None:
        Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
        df.to_csv(out_csv, index=False, float_format="%.6g")
    return df


def aggregate_path(out_csv) -> Path:
    """Where ``egosearch report compare --out X.csv`` writes the aggregate: ``X_aggregate.csv``."""
    out = Path(out_csv)
    return out.with_name(out.stem + "_aggregate" + (out.suffix or ".csv"))


def format_aggregate(df: pd.DataFrame) -> str:
    lines = []
    for r in df.itertuples(index=False):
        name = "IQM over seeds and cells" if r.statistic == "iqm" else "probability of improvement"
        if r.statistic == "iqm":
            lines.append(f"{name}: reference {r.reference:.3f}, candidate {r.candidate:.3f}, difference "
                         f"{r.difference:+.3f} [{r.ci_low:+.3f}, {r.ci_high:+.3f}]")
        else:
            lines.append(f"{name}: {r.candidate:.2f} [{r.ci_low + 0.5:.2f}, {r.ci_high + 0.5:.2f}]")
    lines.append(f"({df['note'].iloc[0]})")
    return "\n".join(lines)

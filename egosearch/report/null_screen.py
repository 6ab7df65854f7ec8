"""The reference screened against itself: does a screen's verdict tell a lever from a luckier seed?

Every seed of one variant is one config trained again, so no screen between them may find a difference.
:func:`null_screen` screens each stored seed as a candidate would be screened, against each other seed
(the one-seed screen's form) and against the others together, with the verdict before the seed spread
counted (the scenarios only) and after (:mod:`egosearch.report.seed_spread`), the spread held out: estimated
from the seeds that are on neither side. With five seeds a pair leaves three, and the screens share their
seeds, so this is a consistency check of the stored seeds, not a calibration; the calibration is the
simulation (:mod:`egosearch.report.calibration`). :func:`power_table` gives the smallest difference a screen of
N seeds detects, and :func:`recommended_screen_seeds` the seeds a screen should train.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from egosearch.report.calibration import LEVEL_CLAIM, SIMULATIONS, false_positive_rates, level_holds, worst_setting
from egosearch.report.data import parse_eval_path, read_episodes, sorted_cells
from egosearch.report.seed_spread import power_multiplier, seed_spread, tail_factor
from egosearch.report.stats import scenario_seed_matrix
from egosearch.report.tables import compare_report

NULL_SCREEN_COLUMNS = ("screen", "candidate_seed", "reference_seeds", "spread_seeds", "height", "placement", "metric",
                       "reference", "candidate", "difference", "scenarios_ci_low", "scenarios_ci_high",
                       "scenarios_p_holm", "scenarios_verdict", "ci_low", "ci_high", "p_holm", "seed_sd", "verdict")
"""One row per screen, cell and metric. ``scenarios_*``: the screen as it was read before the seed spread
counted (the scenarios resampled only, as ``screen`` did); ``ci_*``, ``p_holm``, ``verdict``: as a screen
reads it now, the spread estimated from ``spread_seeds`` alone (neither side's). Holm runs over each screen's
rows, as in a screen's own CSV."""

MIN_NULL_SCREEN_SEEDS = 4
"""A pair of seeds must leave two others to estimate the spread without either."""


def files_by_seed(files: Mapping) -> dict[int, dict]:
    """``{cell: [paths]}`` of one variant -> ``{seed: {cell: [paths]}}``."""
    out: dict[int, dict] = {}
    for cell, paths in files.items():
        for path in ([paths] if isinstance(paths, (str, Path)) else paths):
            out.setdefault(parse_eval_path(path)["seed"], {}).setdefault(cell, []).append(path)
    return dict(sorted(out.items()))


def _merge(by_seed: dict[int, dict], seeds) -> dict:
    out: dict = {}
    for s in seeds:
        for cell, paths in by_seed[s].items():
            out.setdefault(cell, []).extend(paths)
    return out


def null_screen(files: Mapping, out_csv=None, n_resamples: int = 10_000) -> pd.DataFrame:
    """Each seed of one variant screened against each other seed, and against all the others, as a candidate
    would be (:data:`NULL_SCREEN_COLUMNS`). The spread is held out: for seed a against seed b it is estimated
    from the seeds other than a and b; for seed a against the rest, from the rest (a's own never counts).
    ValueError with fewer than :data:`MIN_NULL_SCREEN_SEEDS` seeds."""
    by_seed = files_by_seed(files)
    seeds = list(by_seed)
    if len(seeds) < MIN_NULL_SCREEN_SEEDS:
        raise ValueError(f"null screen: {len(seeds)} seed(s); it needs {MIN_NULL_SCREEN_SEEDS} or more (a pair of "
                         "seeds must leave two others to show the spread without either)")
    screens = [(cand, (ref,)) for ref, cand in itertools.combinations(seeds, 2)]
    screens += [(cand, tuple(s for s in seeds if s != cand)) for cand in seeds]
    frames = []
    for cand, refs in screens:
        held_out = [s for s in seeds if s != cand and (len(refs) > 1 or s not in refs)]
        reference, candidate = _merge(by_seed, refs), by_seed[cand]
        before = compare_report(reference, candidate, n_resamples=n_resamples, count_seed_spread=False)
        after = compare_report(reference, candidate, n_resamples=n_resamples, spread_files=_merge(by_seed, held_out))
        name = f"seed{cand}_vs_seed{refs[0]}" if len(refs) == 1 else f"seed{cand}_vs_the_others"
        frames.append(pd.DataFrame({
            "screen": name, "candidate_seed": cand, "reference_seeds": "+".join(map(str, refs)),
            "spread_seeds": "+".join(map(str, held_out)),
            "height": after["height"], "placement": after["placement"], "metric": after["metric"],
            "reference": after["reference"], "candidate": after["candidate"], "difference": after["difference"],
            "scenarios_ci_low": before["ci_low"], "scenarios_ci_high": before["ci_high"],
            "scenarios_p_holm": before["p_holm"], "scenarios_verdict": before["verdict"],
            "ci_low": after["ci_low"], "ci_high": after["ci_high"], "p_holm": after["p_holm"],
            "seed_sd": after["seed_sd"], "verdict": after["verdict"]}))
    df = pd.concat(frames, ignore_index=True)[list(NULL_SCREEN_COLUMNS)]
    if out_csv is not None:
        Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
        df.to_csv(out_csv, index=False, float_format="%.6g")
    return df


# --------------------------------------------------------------------------------------------- the model
def cell_matrices(files: Mapping, metric: str = "success") -> dict:
    """``{cell: (scenarios x seeds) matrix}`` of one variant's files, cells in Table 1's order."""
    return {cell: scenario_seed_matrix(read_episodes(files[cell]), metric)[0] for cell in sorted_cells(files)}


def seed_mean_sd(matrix: np.ndarray) -> float:
    """The spread of one training seed's mean over a cell's scenarios, from a (scenarios x seeds) matrix: the
    standard deviation of the seed means (``K - 1`` df), the ``sqrt(s2)`` a screen's test counts."""
    return float(np.asarray(matrix, float).mean(axis=0).std(ddof=1))


def detectable_difference(seed_sd: float, n_candidate: int, n_reference: int, alpha: float = 0.05,
                          power: float = 0.8) -> float:
    """The smallest true difference that a screen of ``n_candidate`` seeds against ``n_reference`` spread seeds
    detects with ``power`` (two-sided, level ``alpha``, before Holm) where one seed's cell mean spreads by
    ``seed_sd``: the test's ``(1/N_c + 1/N_r)`` standard error times the noncentral t's multiplier
    (:func:`~egosearch.report.seed_spread.power_multiplier`) at its ``N_r - 1 + N_c - 1`` degrees of freedom
    and its level (``alpha`` over :func:`~egosearch.report.seed_spread.tail_factor`: a one-seed candidate's p is
    taken 1.5 times), the formula of a screen's ``detectable_80`` column."""
    if n_candidate < 1 or n_reference < 2:
        raise ValueError("a screen needs 1 candidate seed or more and 2 reference seeds or more")
    df = n_reference - 1 + n_candidate - 1
    level = alpha / tail_factor(n_candidate)
    return power_multiplier(df, level, power) * seed_sd * math.sqrt(1 / n_candidate + 1 / n_reference)


def power_table(matrices: Mapping, seed_counts=(1, 2, 3, 6)) -> pd.DataFrame:
    """Per cell and candidate seed count, the difference a screen detects with 80% power against the variant's
    stored seeds, at the cell's stored seed-mean spread: columns ``height, placement, n_candidate, n_reference,
    seed_mean_sd, detectable_80``."""
    rows = []
    for cell, m in matrices.items():
        sd = seed_mean_sd(m)
        for n in seed_counts:
            rows.append({"height": cell[0], "placement": cell[1], "n_candidate": n, "n_reference": m.shape[1],
                         "seed_mean_sd": sd, "detectable_80": detectable_difference(sd, n, m.shape[1])})
    return pd.DataFrame(rows)


KNEE = 0.10
"""Where a target is out of a day's reach: the seeds whose detectable difference is within this fraction of
the day's best, past which more seeds barely help."""


def recommended_screen_seeds(matrices: Mapping, cell, target: float, max_seeds: int) -> int:
    """The fewest candidate seeds whose screen detects ``target`` in ``cell`` with 80% power against the stored
    seeds. When no count up to ``max_seeds`` (what a day affords) does, the fewest whose detectable difference
    is within :data:`KNEE` of the best affordable one: past it, more seeds barely help."""
    sd, k = seed_mean_sd(matrices[cell]), matrices[cell].shape[1]
    detectable = [detectable_difference(sd, seeds, k) for seeds in range(1, max_seeds + 1)]
    for seeds, d in enumerate(detectable, start=1):
        if d <= target:
            return seeds
    best = min(detectable)
    return next(seeds for seeds, d in enumerate(detectable, start=1) if d <= best * (1 + KNEE))


def cell_spreads(matrices: Mapping) -> pd.DataFrame:
    """Per cell, the spread of one seed's mean that a screen's test counts (``seed_mean_sd``) and its split
    (:func:`~egosearch.report.seed_spread.seed_spread`): columns ``height, placement, n_seeds, seed_mean_sd,
    seed_sd`` (the seeds' own part), ``raw_variance`` (its estimate before clipping at 0) and
    ``scenario_part_sd`` (``sqrt(MS_e / n)``: the part the scenarios' draw alone explains)."""
    rows = []
    for cell, m in matrices.items():
        s = seed_spread(m)
        rows.append({"height": cell[0], "placement": cell[1], "n_seeds": s.n_seeds, "seed_mean_sd": seed_mean_sd(m),
                     "seed_sd": s.sd, "raw_variance": s.raw, "scenario_part_sd": s.scenario_part_sd})
    return pd.DataFrame(rows)


def cell_correlation(matrices: Mapping) -> float:
    """How closely the seeds' means move together between cells: the mean correlation over pairs of cells of
    the seed means (a seed lucky in one cell tends to be lucky in another)."""
    means = np.column_stack([np.asarray(m, float).mean(axis=0) for m in matrices.values()])
    corr = np.corrcoef(means, rowvar=False)
    return float(corr[np.triu_indices_from(corr, k=1)].mean())


__all__ = ["NULL_SCREEN_COLUMNS", "cell_correlation", "cell_matrices", "cell_spreads", "detectable_difference",
           "files_by_seed", "null_screen", "power_table", "recommended_screen_seeds", "seed_mean_sd"]


# --------------------------------------------------------------------------------------------- the summary
POWER_CELL = (1.05, "no_low_cabinets")
"""The cell the recommended seed count is sized on (the issue's: a difference of 0.05 at 1.05 m)."""
POWER_TARGET = 0.05
USER_DAY_HOURS = 8.0
"""A user's day: the wall time a screen may take on the user's cores."""


def seeds_per_day(record: dict, reference: str, cores: int = 2, day_hours: float = USER_DAY_HOURS,
                  cells: int = 12) -> tuple[int, float]:
    """How many screen seeds fit in a user's day on ``cores`` cores, each seed one training at the slowest
    recorded wall time of the reference's trainings (``run_wall_s`` where a resumed job recorded it) and
    ``cells`` evaluations at the median recorded one: ``(seeds, hours per seed)``. ValueError when the
    provenance ``record`` holds no training of ``reference``."""
    trainings = [j.get("run_wall_s") or j["wall_s"] for j in record.get("jobs", [])
                 if j.get("rule") == "train" and str(j.get("job", "")).startswith(f"{reference}/")]
    if not trainings:
        raise ValueError(f"the provenance records no training of {reference}: no cost to size a day on")
    evals = sorted(j["wall_s"] for j in record.get("jobs", []) if j.get("rule") == "eval")
    per_eval = evals[len(evals) // 2] if evals else 0.0
    per_seed_h = (max(trainings) + cells * per_eval) / 3600
    return max(1, int(day_hours * cores // per_seed_h)), per_seed_h


def seed_spread_summary(files: Mapping, record: dict, reference: str, n_sims: int = SIMULATIONS) -> dict:
    """What `snakemake seed_spread` stores beside the null screen: per cell the seed spread; how the cells' seed
    means correlate; the screen's test's simulated false-positive rate in every setting
    (:func:`~egosearch.report.calibration.false_positive_rates`, ``n_sims`` screens each) with its worst
    setting and whether every setting stays at or below :data:`~egosearch.report.calibration.LEVEL_CLAIM`;
    the detectable difference for 1, 2, 3 and 6 candidate seeds; and the recommended ``screen_seeds``
    (:func:`recommended_screen_seeds` for :data:`POWER_TARGET` at :data:`POWER_CELL`, within
    :func:`seeds_per_day`), with the difference the day's most seeds would detect."""
    matrices = cell_matrices(files)
    k = next(iter(matrices.values())).shape[1]
    per_day, per_seed_h = seeds_per_day(record, reference)
    rates = false_positive_rates(matrices, n_sims=n_sims)
    worst = worst_setting(rates)
    recommended = recommended_screen_seeds(matrices, POWER_CELL, POWER_TARGET, per_day)
    power_sd = seed_mean_sd(matrices[POWER_CELL])
    return {
        "reference": reference, "n_seeds": k, "seeds": sorted(files_by_seed(files)),
        "n_scenarios": min(m.shape[0] for m in matrices.values()),
        "test": "seed-spread t-test on the seeds' cell means, per cell (docs/statistics.md)",
        "cells": cell_spreads(matrices).to_dict(orient="records"),
        "cell_correlation": cell_correlation(matrices),
        "false_positive_rate": rates.to_dict(orient="records"), "alpha": 0.05, "simulations": n_sims,
        "level_claim": LEVEL_CLAIM, "worst_setting": worst, "level_holds": level_holds(rates),
        "detectable_80": power_table(matrices).to_dict(orient="records"),
        "power_cell": list(POWER_CELL), "power_target": POWER_TARGET, "power_cell_seed_mean_sd": power_sd,
        "seeds_per_day": per_day, "hours_per_seed": per_seed_h, "day_hours": USER_DAY_HOURS, "day_cores": 2,
        "recommended_screen_seeds": recommended,
        "detectable_at_a_days_seeds": detectable_difference(power_sd, per_day, k),
        "knee": KNEE,
        "detectable_at_recommended": detectable_difference(power_sd, recommended, k),
    }


def detectable_from_summary(summary: dict, n_seeds: int) -> float:
    """:func:`detectable_difference` at :data:`POWER_CELL` for a screen of ``n_seeds`` seeds, from a stored
    :func:`seed_spread_summary` (no evaluation file read)."""
    return detectable_difference(summary["power_cell_seed_mean_sd"], n_seeds, summary["n_seeds"])

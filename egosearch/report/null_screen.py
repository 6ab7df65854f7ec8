"""The reference screened against itself: does a screen's verdict tell a lever from a luckier seed?

Every seed of one variant is one config trained again, so no screen between them may find a difference.
:func:`null_screen` screens each stored seed as a candidate would be screened, against each other seed
(the one-seed screen's form) and against the others together, with the verdict before the seed spread
counted (the scenarios only) and after (:mod:`egosearch.report.seed_spread`). :func:`false_positive_rate`
simulates how often each verdict calls a difference where there is none, on seeds drawn from a model
fitted to the stored episodes; :func:`power_table` gives the smallest difference a screen of N seeds
detects, and :func:`recommended_screen_seeds` the seeds a screen should train.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from egosearch.report.data import parse_eval_path, read_episodes, sorted_cells
from egosearch.report.seed_spread import (
    MIN_SEEDS_OWN_SPREAD,
    SeedSpread,
    compare_with_seed_spread,
    pooled_seed_spread,
    seed_spread,
)
from egosearch.report.stats import scenario_seed_matrix
from egosearch.report.tables import compare_report

NULL_SCREEN_COLUMNS = ("screen", "candidate_seed", "reference_seeds", "height", "placement", "metric", "reference",
                       "candidate", "difference", "scenarios_ci_low", "scenarios_ci_high", "scenarios_p_holm",
                       "scenarios_verdict", "ci_low", "ci_high", "p_holm", "seed_sd", "verdict")
"""One row per screen, cell and metric. ``scenarios_*``: the screen as it was read before the seed spread
counted (the scenarios resampled only, as ``screen`` did); ``ci_*``, ``p_holm``, ``verdict``: as a screen
reads it now. Holm runs over each screen's rows, as in a screen's own CSV."""


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
    would be (:data:`NULL_SCREEN_COLUMNS`). The seed spread a screen counts is the one a real screen of this
    seed would see: estimated from the variant's other seeds (the candidate's own is never the reference's).
    ValueError with fewer than 3 seeds (the others must show a spread)."""
    by_seed = files_by_seed(files)
    seeds = list(by_seed)
    if len(seeds) < 3:
        raise ValueError(f"null screen: {len(seeds)} seed(s); it needs 3 or more (the others must show a spread)")
    screens = [(cand, (ref,)) for ref, cand in itertools.combinations(seeds, 2)]
    screens += [(cand, tuple(s for s in seeds if s != cand)) for cand in seeds]
    frames = []
    for cand, refs in screens:
        others = _merge(by_seed, [s for s in seeds if s != cand])
        reference, candidate = _merge(by_seed, refs), by_seed[cand]
        before = compare_report(reference, candidate, n_resamples=n_resamples, count_seed_spread=False)
        after = compare_report(reference, candidate, n_resamples=n_resamples, spread_files=others)
        name = f"seed{cand}_vs_seed{refs[0]}" if len(refs) == 1 else f"seed{cand}_vs_the_others"
        frames.append(pd.DataFrame({
            "screen": name, "candidate_seed": cand, "reference_seeds": "+".join(map(str, refs)),
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


def one_seed_scenario_se(matrices: Mapping) -> dict:
    """Per cell, the scenario part of a one-seed-against-one-seed screen's standard error,
    ``sqrt(var(d_i) / n)``, averaged over the variant's pairs of seeds."""
    out = {}
    for cell, m in matrices.items():
        pairs = itertools.combinations(range(m.shape[1]), 2)
        out[cell] = float(np.mean([np.sqrt((m[:, a] - m[:, b]).var(ddof=1) / m.shape[0]) for a, b in pairs]))
    return out


def false_positive_rate(matrices: Mapping, n_reference: int, rho: float, n_sims: int = 400, alpha: float = 0.05,
                        seed: int = 0) -> dict:
    """How often a one-seed screen against ``n_reference`` seeds of the same config calls a cell different
    (uncorrected, per cell), before and after the seed spread counts, on simulated seeds.

    The model is fitted to the stored episodes (``matrices``: ``{cell: scenarios x seeds}``): a scenario's
    success probability is its stored seeds' mean, pulled half an episode towards 1/2 (``(sum + 0.5) /
    (K + 1)``: no scenario is certain); a seed shifts every scenario of a cell by ``u_c``, drawn normal with
    the stored pooled seed variance (:func:`~egosearch.report.seed_spread.pooled_seed_spread`) and
    correlation ``rho`` between cells (the cells share the seed's policy); an episode succeeds with the
    shifted probability, clipped to [0, 1]. Each simulation draws ``n_reference + 1`` seeds, screens the
    first against the rest both ways and counts the cells called different. Returns ``{scenarios_only,
    seed_spread, cells_tested, rho, n_reference}``."""
    cells = list(matrices)
    probs = [(m.sum(axis=1) + 0.5) / (m.shape[1] + 1) for m in matrices.values()]
    sigma2 = pooled_seed_spread(list(matrices.values())).variance
    cov = sigma2 * ((1 - rho) * np.eye(len(cells)) + rho * np.ones((len(cells), len(cells))))
    rng = np.random.default_rng(seed)
    z = stats.norm.ppf(1 - alpha / 2)
    called = {"scenarios_only": 0, "seed_spread": 0}
    tested = 0
    for _ in range(n_sims):
        shifts = rng.multivariate_normal(np.zeros(len(cells)), cov, size=n_reference + 1)
        sims = [(rng.random((p.size, n_reference + 1)) < np.clip(p[:, None] + shifts[None, :, c], 0, 1)).astype(float)
                for c, p in enumerate(probs)]
        spread = pooled_seed_spread([y[:, 1:] for y in sims])
        for y in sims:
            ref, cand = y[:, 1:], y[:, :1]
            d = cand[:, 0] - ref.mean(axis=1)
            se = d.std(ddof=1) / math.sqrt(d.size)
            called["scenarios_only"] += bool(se > 0 and abs(d.mean()) / se > z)
            # one estimate, from the reference's seeds, for both sides: the candidate borrows it, and the
            # reference's own is the same
            res = compare_with_seed_spread(ref, cand, spread, spread)
            called["seed_spread"] += res["p_uncorrected"] < alpha
            tested += 1
    return {"scenarios_only": called["scenarios_only"] / tested, "seed_spread": called["seed_spread"] / tested,
            "cells_tested": tested, "rho": rho, "n_reference": n_reference}


# --------------------------------------------------------------------------------------------- power
def detectable_difference(spread: SeedSpread, se_one_seed: float, n_candidate: int, n_reference: int,
                          n_scenarios: int, alpha: float = 0.05, power: float = 0.8) -> float:
    """The smallest true difference that a screen of ``n_candidate`` seeds against ``n_reference`` stored
    seeds detects with ``power`` (two-sided, level ``alpha``, before Holm), at this seed spread.
    ``se_one_seed``: a one-seed pair's scenario standard error (:func:`one_seed_scenario_se`); averaging more
    seeds on a side shrinks the seed-by-scenario noise in it, taken here as ``(1/N_c + 1/N_r) / 2`` of the
    one-seed pair's variance. A candidate side of 3 seeds or more counts its own spread (here assumed equal
    to the reference's, with its own degrees of freedom), a smaller one borrows the reference's."""
    if n_candidate < 1 or n_reference < 2:
        raise ValueError("a screen needs 1 candidate seed or more and 2 reference seeds or more")
    v_scen = se_one_seed ** 2 * (1 / n_candidate + 1 / n_reference) / 2
    if n_candidate >= MIN_SEEDS_OWN_SPREAD:
        terms = [(spread.variance / n_candidate, n_candidate - 1), (spread.variance / n_reference, n_reference - 1)]
    else:
        terms = [(spread.variance * (1 / n_candidate + 1 / n_reference), n_reference - 1)]
    v = v_scen + sum(t for t, _ in terms)
    df = v ** 2 / (v_scen ** 2 / (n_scenarios - 1) + sum(t ** 2 / d for t, d in terms))
    return float((stats.t.ppf(1 - alpha / 2, df) + stats.t.ppf(power, df)) * math.sqrt(v))


def power_table(matrices: Mapping, seed_counts=(1, 3, 5), n_reference: int | None = None) -> pd.DataFrame:
    """Per cell and candidate seed count, the difference a screen detects with 80% power against the
    variant's stored seeds (``n_reference``: how many; all of them by default), at the stored pooled seed
    spread: columns ``height, placement, n_candidate, n_reference, seed_sd, detectable_80``."""
    spread = pooled_seed_spread(list(matrices.values()))
    se = one_seed_scenario_se(matrices)
    k = n_reference or next(iter(matrices.values())).shape[1]
    rows = []
    for cell, m in matrices.items():
        for n in seed_counts:
            rows.append({"height": cell[0], "placement": cell[1], "n_candidate": n, "n_reference": k,
                         "seed_sd": spread.sd,
                         "detectable_80": detectable_difference(spread, se[cell], n, k, m.shape[0])})
    return pd.DataFrame(rows)


KNEE = 0.10
"""Where a target is out of a day's reach: the seeds whose detectable difference is within this fraction of
the day's best, past which more seeds barely help."""


def recommended_screen_seeds(matrices: Mapping, cell, target: float, max_seeds: int) -> int:
    """The fewest candidate seeds whose screen detects ``target`` in ``cell`` with 80% power against the stored
    seeds. When no count up to ``max_seeds`` (what a day affords) does, the fewest whose detectable difference
    is within :data:`KNEE` of the best affordable one: past it, more seeds barely help."""
    spread = pooled_seed_spread(list(matrices.values()))
    se = one_seed_scenario_se(matrices)[cell]
    k, n = matrices[cell].shape[1], matrices[cell].shape[0]
    detectable = [detectable_difference(spread, se, seeds, k, n) for seeds in range(1, max_seeds + 1)]
    for seeds, d in enumerate(detectable, start=1):
        if d <= target:
            return seeds
    best = min(detectable)
    return next(seeds for seeds, d in enumerate(detectable, start=1) if d <= best * (1 + KNEE))


def cell_spreads(matrices: Mapping) -> pd.DataFrame:
    """Per cell, the seed variance estimate (:func:`~egosearch.report.seed_spread.seed_spread`): columns
    ``height, placement, n_seeds, seed_sd, raw_variance, scenario_part_sd`` (``sqrt(MS_e / n)``: the spread of
    a seed's mean that the scenarios' draw alone explains)."""
    rows = []
    for cell, m in matrices.items():
        s = seed_spread(m)
        rows.append({"height": cell[0], "placement": cell[1], "n_seeds": s.n_seeds, "seed_sd": s.sd,
                     "raw_variance": s.raw, "scenario_part_sd": math.sqrt(s.residual / s.n_scenarios)})
    return pd.DataFrame(rows)


__all__ = ["NULL_SCREEN_COLUMNS", "cell_matrices", "cell_spreads", "detectable_difference", "false_positive_rate",
           "files_by_seed", "null_screen", "one_seed_scenario_se", "power_table", "recommended_screen_seeds"]


# --------------------------------------------------------------------------------------------- the summary
RHOS = (0.0, 0.5, 0.9)
"""Correlations between cells of a seed's shift that the false-positive simulation tries: the cells share
the seed's policy, and three seeds cannot say how closely (the excl. and everywhere cells of one height
move together, the heights less)."""
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


def seed_spread_summary(files: Mapping, record: dict, reference: str, n_sims: int = 400) -> dict:
    """What `snakemake seed_spread` stores beside the null screen: per cell the seed spread; the pooled
    spread; the simulated false-positive rates (:func:`false_positive_rate`, at each of :data:`RHOS`, for a
    screen against the other seeds of the null screen and against all of them); the detectable difference
    for 1, 3 and 5 candidate seeds; and the recommended ``screen_seeds`` (:func:`recommended_screen_seeds`
    for :data:`POWER_TARGET` at :data:`POWER_CELL`, within :func:`seeds_per_day`), with the difference the
    day's most seeds would detect."""
    matrices = cell_matrices(files)
    k = next(iter(matrices.values())).shape[1]
    pooled = pooled_seed_spread(list(matrices.values()))
    per_day, per_seed_h = seeds_per_day(record, reference)
    fpr = [false_positive_rate(matrices, n_ref, rho, n_sims=n_sims, seed=i)
           for i, (n_ref, rho) in enumerate(itertools.product(sorted({k - 1, k}), RHOS))]
    power = power_table(matrices)
    return {
        "reference": reference, "n_seeds": k, "seeds": sorted(files_by_seed(files)),
        "pooled_seed_sd": pooled.sd, "pooled_df": pooled.df,
        "cells": cell_spreads(matrices).to_dict(orient="records"),
        "one_seed_scenario_se": [{"height": c[0], "placement": c[1], "se": v, "n_scenarios": matrices[c].shape[0]}
                                 for c, v in one_seed_scenario_se(matrices).items()],
        "false_positive_rate": fpr, "alpha": 0.05, "simulations": n_sims,
        "detectable_80": power.to_dict(orient="records"),
        "power_cell": list(POWER_CELL), "power_target": POWER_TARGET,
        "seeds_per_day": per_day, "hours_per_seed": per_seed_h, "day_hours": USER_DAY_HOURS, "day_cores": 2,
        "recommended_screen_seeds": recommended_screen_seeds(matrices, POWER_CELL, POWER_TARGET, per_day),
        "detectable_at_a_days_seeds": detectable_difference(
            pooled, one_seed_scenario_se(matrices)[POWER_CELL], per_day, k, matrices[POWER_CELL].shape[0]),
        "knee": KNEE,
        "detectable_at_recommended": detectable_difference(
            pooled, one_seed_scenario_se(matrices)[POWER_CELL],
            recommended_screen_seeds(matrices, POWER_CELL, POWER_TARGET, per_day), k,
            matrices[POWER_CELL].shape[0]),
    }


def detectable_from_summary(summary: dict, n_seeds: int) -> float:
    """:func:`detectable_difference` at :data:`POWER_CELL` for a screen of ``n_seeds`` seeds, from a stored
    :func:`seed_spread_summary` (no evaluation file read)."""
    cell = next(c for c in summary["one_seed_scenario_se"]
                if (c["height"], c["placement"]) == tuple(summary["power_cell"]))
    variance = summary["pooled_seed_sd"] ** 2
    spread = SeedSpread(variance=variance, raw=variance, residual=0.0, n_scenarios=cell["n_scenarios"],
                        n_seeds=summary["n_seeds"])
    return detectable_difference(spread, cell["se"], n_seeds, summary["n_seeds"], cell["n_scenarios"])

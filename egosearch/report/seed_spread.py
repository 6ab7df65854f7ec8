"""How much a training seed moves a cell's success rate, and the test every screen runs on it.

A screen pairs a candidate's training runs with the reference's on the same scenarios. Resampling those
scenarios measures how much a *different draw of scenarios* would change the difference; it does not
measure how much a *different training seed* would. On the stored reference that second part is as big as
the levers it judges (docs/statistics.md, "Seed spread"), so a screen reads each side's seeds as what they
are: draws of one training run's cell mean.

**The test** (one cell; the same scenarios for every seed, so a scenario's difficulty is the same in every
seed's mean and cancels in their differences). ``m_k`` is seed ``k``'s mean over the cell's scenarios. The
spread seeds (the reference variant's stored seeds, ``K_s``) show how far one seed's mean strays; the
candidate's own seeds add theirs, and so does a reference seed that is not a spread seed. Each seed is counted
once, in one group, whatever object holds it::

    s2 = sum over groups g of sum_k (m_gk - mbar_g)^2  /  df,     df = sum_g (K_g - 1)
    D  = mean of the candidate's K_c seed means - mean of the reference's K_r seed means
    V  = s2 (1/K_c + 1/K_r)          (a side that is not trained, a searcher, adds no term)
    f  = 1.5 for a one-seed candidate, 1 otherwise
    p  = min(1, f * 2 P(T_df > |D| / sqrt(V)));   interval: D -/+ t(df, 1 - 0.05 / (2 f)) sqrt(V)

With two candidate seeds or more it is Student's pooled two-sample t-test on the seed means, exact when they
are normal with one variance in the cell, whatever the seed means of *other* cells do: each cell has its own
``s2``, so cells whose seeds spread differently (0.45 m against 1.65 m) are not read with one pooled number.
With one candidate seed it is the prediction interval of one new seed's mean, its p taken 1.5 times
(:data:`ONE_SEED_TAIL`): a prediction for ONE draw rests on the seed law's tail, not on a mean that thins it
(Hahn & Meeker 1991, *Statistical Intervals*, on prediction intervals' sensitivity to the normal shape). With
seed effects as heavy-tailed as a t with 3 degrees of freedom the plain prediction interval calls more than
the level claims in the cells whose seeds spread most (:mod:`egosearch.report.calibration`; the stored record
shows both); 1.5 holds the claim even for a seed mean that is all t(3) seed effect, with 3 to 10 spread seeds
(tests/test_seed_spread.py), and is conservative with normal seeds. p < 0.05 exactly when the 95% interval
excludes 0. ``detectable_80`` is the true difference the test finds with 80% power at the uncorrected 5%
level, from the noncentral t (:func:`power_multiplier`).

:func:`seed_spread` splits one cell's spread into the seeds' own part and the part the scenarios' draw alone
explains (a two-way random-effects model, method of moments); it describes the reference and sets the truth
of the simulated false-positive rate (:mod:`egosearch.report.calibration`), but the test above does not need
it: ``s2`` holds both parts, as a new seed's mean would.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import optimize, stats

SCENARIOS_ONLY = "scenarios only"
"""What a comparison counts when a side lacks the seeds to show a spread and none can be borrowed (the
reference has one seed): the bootstrap as it is, which resamples that side's scenarios only, marked so."""

MIN_SEEDS_OWN_SPREAD = 3
"""A comparison without spread files (not a screen) whose trained sides all have this many seeds or more
reads them with the two-level bootstrap; with a side of fewer it runs the seed-spread test on the
reference's own seeds."""


class SeedSpreadUnknown(ValueError):
    """The seed spread cannot be estimated: no group of seeds with 2 seeds or more."""


@dataclass(frozen=True)
class SeedSpread:
    """One cell's seed variance of one variant, split (module docstring, :func:`seed_spread`).

    ``variance``: ``sigma2_seed`` clipped at 0; ``raw``: before clipping; ``residual``: ``MS_e``;
    ``n_scenarios``; ``n_seeds``."""

    variance: float
    raw: float
    residual: float
    n_scenarios: int
    n_seeds: int

    @property
    def sd(self) -> float:
        return math.sqrt(self.variance)

    @property
    def scenario_part_sd(self) -> float:
        """``sqrt(MS_e / n)``: the spread of one seed's mean that the scenarios' draw alone explains."""
        return math.sqrt(self.residual / self.n_scenarios)


def seed_spread(matrix: np.ndarray) -> SeedSpread:
    """The seeds' own variance in a (scenarios x seeds) matrix of one cell: the two-way random-effects model
    without replication, ``y_ik = mu + a_i + u_k + e_ik``, by the method of moments (Searle, Casella &
    McCulloch 1992, *Variance Components*, ch. 4)::

        MS_seed = n * sum_k (ybar_.k - ybar_..)^2 / (K - 1)
        MS_e    = sum_ik (y_ik - ybar_i. - ybar_.k + ybar_..)^2 / ((n - 1)(K - 1))
        sigma2_seed = max(0, (MS_seed - MS_e) / n)

    ``MS_seed / n`` is the variance of the seed means (the test's ``s2`` with one group); ``MS_e / n`` the part
    of it the scenarios' draw alone explains. SeedSpreadUnknown with one seed; ValueError with one scenario."""
    m = np.asarray(matrix, dtype=float)
    if m.ndim != 2:
        raise ValueError(f"seed_spread needs a (scenarios x seeds) matrix, got shape {m.shape}")
    n, k = m.shape
    if k < 2:
        raise SeedSpreadUnknown(f"{k} seed: the seed variance cannot be estimated (it needs 2 seeds or more)")
    if n < 2:
        raise ValueError(f"{n} scenario: the seed variance needs 2 scenarios or more")
    grand = m.mean()
    row = m.mean(axis=1, keepdims=True)
    col = m.mean(axis=0, keepdims=True)
    ms_seed = n * float(((col - grand) ** 2).sum()) / (k - 1)
    ms_e = float(((m - row - col + grand) ** 2).sum()) / ((n - 1) * (k - 1))
    raw = (ms_seed - ms_e) / n
    return SeedSpread(variance=max(0.0, raw), raw=raw, residual=ms_e, n_scenarios=n, n_seeds=k)


@functools.lru_cache(maxsize=256)
def power_multiplier(df: float, alpha: float = 0.05, power: float = 0.8) -> float:
    """The true difference, in standard errors, that a two-sided t-test with ``df`` degrees of freedom at
    level ``alpha`` finds with probability ``power``: the noncentrality ``delta`` with
    ``P(|T'_{df, delta}| > t_{df, 1 - alpha/2}) = power``. 3.76 at 4 df, 2.80 as df grows."""
    crit = float(stats.t.ppf(1 - alpha / 2, df))

    def short(delta: float) -> float:
        # far in the lower tail scipy's noncentral t returns nan for what is 0
        return float(stats.nct.sf(crit, df, delta) + np.nan_to_num(stats.nct.cdf(-crit, df, delta))) - power

    high = 1.0
    while short(high) < 0:
        high *= 2
    return float(optimize.brentq(short, 0.0, high, xtol=1e-9))


def pooled_seed_variance(groups: Sequence[np.ndarray]) -> tuple[np.ndarray, int]:
    """``(s2, df)`` of the seed means in ``groups`` (each ``(..., K_g)``), every group around its own mean:
    ``sum_g sum_k (m_gk - mbar_g)^2 / sum_g (K_g - 1)``. SeedSpreadUnknown when that leaves no degree of
    freedom (no group of 2 seeds or more)."""
    groups = [np.asarray(g, float) for g in groups if np.shape(g)[-1] > 0]
    df = sum(g.shape[-1] - 1 for g in groups)
    if df < 1:
        raise SeedSpreadUnknown("no group of 2 seeds or more: the variance between training seeds cannot be "
                                "estimated")
    squares = sum(((g - g.mean(axis=-1, keepdims=True)) ** 2).sum(axis=-1) for g in groups)
    return squares / df, df


ONE_SEED_TAIL = 1.5
"""How much more a one-seed candidate's p is taken (module docstring): the prediction of one seed's mean rests
on the seed law's own tail."""


def tail_factor(n_candidate: int, one_seed_tail: bool = True) -> float:
    """The factor a candidate of ``n_candidate`` trained seeds' p is taken (0 for a searcher, no seed draw):
    :data:`ONE_SEED_TAIL` for one seed, 1 otherwise."""
    return ONE_SEED_TAIL if one_seed_tail and n_candidate == 1 else 1.0


def seed_spread_test(candidate, reference, spread, *, candidate_in_spread=None, reference_in_spread=None,
                     candidate_trained: bool = True, reference_trained: bool = True,
                     confidence: float = 0.95, one_seed_tail: bool = True) -> dict:
    """Candidate minus reference on one cell, read against the spread between training seeds (module
    docstring). Every argument may carry leading batch axes (a simulation's screens, all at once).

    ``candidate`` (``..., K_c``), ``reference`` (``..., K_r``): each side's seed means over the cell's
    scenarios; ``spread`` (``..., K_s``): the spread seeds' means over the same scenarios.
    ``candidate_in_spread`` / ``reference_in_spread``: length-``K`` masks of a side's seeds that ARE spread
    seeds (the same training run; counted in the spread's group, not again in the side's), none by default.
    A side that is not ``trained`` (a searcher: its seed is not a training run) adds neither a group nor a
    variance term. ``one_seed_tail``: a one-seed candidate's p is taken :data:`ONE_SEED_TAIL` times (module
    docstring); False only to show, in the calibration, what the plain prediction interval would call.

    Returns ``{difference, ci_low, ci_high, p_uncorrected, df, se, seed_sd, detectable_80}`` (arrays of the
    batch shape; ``seed_sd`` is ``sqrt(s2)``, the spread of one seed's mean). Where every group's seed means are
    equal (``s2`` 0) there is no spread to read: p 1, interval and ``se`` nan."""
    cand, ref, spread = (np.asarray(x, float) for x in (candidate, reference, spread))
    k_c, k_r = cand.shape[-1], ref.shape[-1]
    cand_in = np.zeros(k_c, bool) if candidate_in_spread is None else np.asarray(candidate_in_spread, bool)
    ref_in = np.zeros(k_r, bool) if reference_in_spread is None else np.asarray(reference_in_spread, bool)
    groups = [spread]
    if candidate_trained:
        groups.append(cand[..., ~cand_in])
    if reference_trained:
        groups.append(ref[..., ~ref_in])
    s2, df = pooled_seed_variance(groups)
    factor = tail_factor(k_c if candidate_trained else 0, one_seed_tail)
    difference = cand.mean(axis=-1) - ref.mean(axis=-1)
    weight = (1 / k_c if candidate_trained else 0.0) + (1 / k_r if reference_trained else 0.0)
    # every seed mean of a group equal (a coincidence of few seeds): no spread to read, no verdict
    se = np.where(s2 > 0, np.sqrt(s2 * weight), np.nan)
    crit = float(stats.t.ppf(1 - (1 - confidence) / (2 * factor), df))
    with np.errstate(invalid="ignore"):
        p = np.where(s2 > 0, np.minimum(1.0, factor * 2 * stats.t.sf(np.abs(difference) / se, df)), 1.0)
    return {"difference": difference, "ci_low": difference - crit * se, "ci_high": difference + crit * se,
            "p_uncorrected": p, "df": df, "se": se, "seed_sd": np.sqrt(s2),
            "detectable_80": power_multiplier(df, 0.05 / factor) * se}


@dataclass(frozen=True)
class SpreadSeeds:
    """What a screen reads its seed spread from (built by
    :func:`~egosearch.report.spread_sides.comparison_spreads`): ``episodes``, the spread seeds' per-episode rows
    of every compared cell (``scenario_set``, ``scenario_id``, ``seed`` and the metrics); ``variant``, whose
    seeds they are; whether each side is a trained policy; and which of each side's seeds are spread seeds
    (the same variant and seed: one training run, counted once)."""

    episodes: pd.DataFrame
    variant: str
    reference_trained: bool
    candidate_trained: bool
    reference_in_spread: frozenset = frozenset()
    candidate_in_spread: frozenset = frozenset()

    @property
    def seeds(self) -> list[int]:
        return sorted(int(s) for s in self.episodes["seed"].unique())


def seed_means(episodes: pd.DataFrame, metric: str, scenarios: pd.MultiIndex, side: str) -> tuple[list, np.ndarray]:
    """``(seeds, their means of metric over scenarios)``; ValueError (one line) when a seed lacks one of the
    ``scenarios`` (``(scenario_set, scenario_id)``): a seed's mean over other scenarios is not comparable."""
    keys = ["scenario_set", "scenario_id"]
    rows = episodes[pd.MultiIndex.from_frame(episodes[keys]).isin(scenarios)]
    wide = rows.pivot_table(index=keys, columns="seed", values=metric, aggfunc="first").reindex(scenarios)
    holes = int(wide.isna().to_numpy().sum())
    if holes or wide.shape[1] == 0:
        raise ValueError(f"the {side} seeds were not all evaluated on these scenarios ({holes} (scenario, seed) "
                         f"pair(s) missing of {len(scenarios)} scenarios x {wide.shape[1]} seeds): a seed's mean "
                         "over other scenarios is not comparable")
    return [int(s) for s in wide.columns], wide.to_numpy(dtype=float).mean(axis=0)


def compare_on_seed_spread(reference: pd.DataFrame, candidate: pd.DataFrame, metric: str, spread: SpreadSeeds,
                           confidence: float = 0.95) -> dict:
    """:func:`seed_spread_test` on one cell (or ℓ bin) of per-episode rows: each side's and the spread's seed
    means over the reference's scenarios, the seeds each side shares with the spread marked so."""
    scenarios = pd.MultiIndex.from_frame(reference[["scenario_set", "scenario_id"]].drop_duplicates()
                                         .sort_values(["scenario_set", "scenario_id"]))
    ref_seeds, ref_means = seed_means(reference, metric, scenarios, "reference")
    cand_seeds, cand_means = seed_means(candidate, metric, scenarios, "candidate")
    _, spread_means = seed_means(spread.episodes, metric, scenarios, f"spread ({spread.variant})")
    res = seed_spread_test(cand_means, ref_means, spread_means,
                           candidate_in_spread=[s in spread.candidate_in_spread for s in cand_seeds],
                           reference_in_spread=[s in spread.reference_in_spread for s in ref_seeds],
                           candidate_trained=spread.candidate_trained, reference_trained=spread.reference_trained,
                           confidence=confidence)
    return {k: float(v) for k, v in res.items()}

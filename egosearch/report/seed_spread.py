"""How much a training seed moves a cell's success rate, and the verdict of a comparison that counts it.

A one-seed screen pairs a candidate's training run with the reference's on the same scenarios. Resampling
those scenarios measures how much a *different draw of scenarios* would change the difference; it does
not measure how much a *different training seed* would. On the stored reference that second part is as
big as the levers it judges (docs/statistics.md, "Seed spread"), so a comparison in which a side has too
few seeds to show its own spread borrows the reference's.

The model of one cell (scenarios ``i = 1..n``, training seeds ``k = 1..K`` of one variant, every seed on
every scenario) is the two-way random-effects model without replication::

    y_ik = mu + a_i + u_k + e_ik,   u_k ~ (0, sigma2_seed),   e_ik ~ (0, sigma2_e)

``a_i`` is the scenario's difficulty (shared by the seeds: it cancels in a paired difference), ``u_k``
the training seed's shift, ``e_ik`` everything else (the seed-by-scenario interaction, which also holds
the episode's own luck). Method of moments (Searle, Casella & McCulloch 1992, *Variance Components*,
ch. 4)::

    MS_seed = n * sum_k (ybar_.k - ybar_..)^2 / (K - 1)
    MS_e    = sum_ik (y_ik - ybar_i. - ybar_.k + ybar_..)^2 / ((n - 1)(K - 1))
    sigma2_seed = max(0, (MS_seed - MS_e) / n)            df = K - 1

``MS_e / n`` is the part of the seeds' spread that the scenarios' draw alone explains; it is removed.

A comparison of a candidate's ``K_c`` seeds with a reference's ``K_r`` seeds on the same ``n`` scenarios
(``d_i`` = the candidate's seed mean minus the reference's on scenario ``i``)::

    D = mean_i d_i
    V = var(d_i) / n  +  s2_c / K_c  +  s2_r / K_r
    df = V^2 / ( (var(d_i)/n)^2 / (n-1) + (s2_c/K_c)^2 / df_c + (s2_r/K_r)^2 / df_r )   (Welch-Satterthwaite)
    interval: D -/+ t_{df, 0.975} sqrt(V);   p = 2 P(T_df > |D| / sqrt(V))

``var(d_i)/n`` holds the scenarios and the seed-by-scenario noise of the seeds used; ``s2`` is a side's
seed variance: its own estimate when it has :data:`MIN_SEEDS_OWN_SPREAD` seeds or more, the reference
variant's (from every seed it has stored) otherwise, with that estimate's degrees of freedom.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

SCENARIOS_ONLY = "scenarios only"
"""What a comparison counts when a side lacks the seeds to show a spread and none can be borrowed (the
reference has one seed): the bootstrap as it is, which resamples that side's scenarios only, marked so."""

MIN_SEEDS_OWN_SPREAD = 3
"""A side with this many seeds or more estimates its own seed variance (2 degrees of freedom or more);
with fewer, a comparison borrows the reference variant's."""


@dataclass(frozen=True)
class SeedSpread:
    """One cell's seed variance of one variant (module docstring).

    ``variance``: ``sigma2_seed``, clipped at 0; ``raw``: ``(MS_seed - MS_e) / n`` before clipping (an
    average over cells averages these); ``residual``: ``MS_e``; ``n_scenarios``; ``n_seeds``; ``df``:
    ``n_seeds - 1``."""

    variance: float
    raw: float
    residual: float
    n_scenarios: int
    n_seeds: int

    @property
    def df(self) -> int:
        return self.n_seeds - 1

    @property
    def sd(self) -> float:
        return math.sqrt(self.variance)


class SeedSpreadUnknown(ValueError):
    """The seed variance cannot be estimated: fewer than 2 seeds."""


def seed_spread(matrix: np.ndarray) -> SeedSpread:
    """The seed variance of a (scenarios x seeds) matrix of one cell (module docstring). SeedSpreadUnknown
    with one seed; ValueError with one scenario."""
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


def pooled_seed_spread(matrices) -> SeedSpread:
    """One seed variance for several cells of the same seeds: the mean of the cells' unclipped estimates,
    clipped at 0, with ``K - 1`` degrees of freedom. The cells share their seeds, so pooling them steadies
    the estimate but does not add independent seeds; counting ``K - 1`` and not ``cells x (K - 1)`` keeps
    the test near its level when the cells' seed shifts are correlated (docs/statistics.md, the
    simulated false-positive rate). SeedSpreadUnknown with one seed; ValueError if the cells' seed counts
    differ."""
    spreads = [seed_spread(m) for m in matrices]
    if not spreads:
        raise ValueError("pooled_seed_spread: no cells")
    ks = {s.n_seeds for s in spreads}
    if len(ks) != 1:
        raise ValueError(f"pooled_seed_spread: the cells have different seed counts {sorted(ks)}")
    raw = float(np.mean([s.raw for s in spreads]))
    return SeedSpread(variance=max(0.0, raw), raw=raw, residual=float(np.mean([s.residual for s in spreads])),
                      n_scenarios=min(s.n_scenarios for s in spreads), n_seeds=spreads[0].n_seeds)


NO_SEEDS = SeedSpread(variance=0.0, raw=0.0, residual=0.0, n_scenarios=0, n_seeds=0)
"""The spread of a searcher that is not trained (the frontier searcher, the oracle...): its seed is not a
training run, so it adds no variance."""


def compare_with_seed_spread(ref: np.ndarray, cand: np.ndarray, spread_ref: SeedSpread, spread_cand: SeedSpread,
                             confidence: float = 0.95) -> dict:
    """Candidate minus reference on one cell, counting the seeds' spread (module docstring).

    ``ref`` / ``cand``: (scenarios x seeds) matrices on the same scenarios (rows in the same order);
    ``spread_ref`` / ``spread_cand``: the seed variance each side's seed mean carries (``variance / K``,
    with its ``df``); :data:`NO_SEEDS` for a searcher that is not trained.

    Returns ``{difference, ci_low, ci_high, p_uncorrected, df, se, se_scenarios, detectable_80}``;
    ``detectable_80`` is the true difference this test finds with 80% power at the uncorrected 5% level,
    ``(t_{df,0.975} + t_{df,0.80}) * se``."""
    ref, cand = np.asarray(ref, float), np.asarray(cand, float)
    if ref.ndim != 2 or cand.ndim != 2 or ref.shape[0] != cand.shape[0]:
        raise ValueError(f"two (scenarios x seeds) matrices on the same scenarios needed, got {ref.shape} "
                         f"and {cand.shape}")
    n = ref.shape[0]
    if n < 2:
        raise ValueError(f"{n} scenario: nothing to resample")
    d = cand.mean(axis=1) - ref.mean(axis=1)
    diff = float(d.mean())
    v_scen = float(d.var(ddof=1)) / n
    # Both sides may count the same estimate (a screen borrows the reference's for its one-seed sides): one
    # estimate is one term of the Welch-Satterthwaite sum, with its own degrees of freedom.
    terms = [(spread_cand.variance / cand.shape[1], spread_cand.df)]
    if spread_ref is spread_cand:
        terms = [(spread_cand.variance * (1 / cand.shape[1] + 1 / ref.shape[1]), spread_cand.df)]
    else:
        terms.append((spread_ref.variance / ref.shape[1], spread_ref.df))
    terms = [(t, df) for t, df in terms if t > 0]
    v = v_scen + sum(t for t, _ in terms)
    if v <= 0:  # identical sides, nothing varies
        return {"difference": diff, "ci_low": diff, "ci_high": diff, "p_uncorrected": 1.0 if diff == 0 else 0.0,
                "df": math.inf, "se": 0.0, "se_scenarios": 0.0, "detectable_80": 0.0}
    denominator = v_scen ** 2 / (n - 1) + sum(t ** 2 / df for t, df in terms)
    df = v ** 2 / denominator
    se = math.sqrt(v)
    t_crit = float(stats.t.ppf(0.5 + confidence / 2, df))
    p = float(2 * stats.t.sf(abs(diff) / se, df))
    return {"difference": diff, "ci_low": diff - t_crit * se, "ci_high": diff + t_crit * se, "p_uncorrected": p,
            "df": float(df), "se": se, "se_scenarios": math.sqrt(v_scen),
            "detectable_80": float((stats.t.ppf(0.975, df) + stats.t.ppf(0.8, df)) * se)}

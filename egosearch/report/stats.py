"""Confidence intervals and paired comparisons for the report (scipy.stats only).

- :func:`wilson_ci`: Wilson score interval of a success rate from pooled episodes.
- :func:`bootstrap_ci`: bootstrap interval of a statistic over a few per-seed values.
- :func:`compare_cells`: candidate vs reference on one evaluation cell (same scenarios), paired
  by scenario with seeds pooled: difference, bootstrap CI and sign-flip permutation p-value.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pandas as pd
from scipy import stats

METRICS = ("success", "spl")


def wilson_ci(successes: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval (no continuity correction) of ``successes`` out of ``n`` trials.

    With ``p = k/n`` and ``z`` the two-sided normal quantile,
    ``(p + z^2/2n ± z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n)``; computed by
    ``scipy.stats.binomtest(k, n).proportion_ci(method="wilson")``.
    """
    successes, n = int(successes), int(n)
    if n <= 0:
        raise ValueError(f"Wilson interval of {successes} successes in n={n} trials: n must be positive")
    if not 0 <= successes <= n:
        raise ValueError(f"Wilson interval: successes={successes} outside [0, n={n}]")
    ci = stats.binomtest(successes, n).proportion_ci(confidence_level=confidence, method="wilson")
    return float(ci.low), float(ci.high)


def bootstrap_ci(values_per_seed, statistic: Callable = np.mean, confidence: float = 0.95,
                 n_resamples: int = 10_000, seed: int = 0, method: str = "percentile") -> tuple[float, float]:
    """Bootstrap interval of ``statistic`` over per-seed values (``scipy.stats.bootstrap``, percentile by default).

    - fewer than 2 finite values: ``(nan, nan)`` (no interval from one seed);
    - all values equal: ``(v, v)`` exactly (the bootstrap distribution is a point);
    - NaN values are dropped first.

    With few seeds a percentile bootstrap is narrow (with 2 seeds it spans at most their range):
    read it as "spread over seeds", not as a calibrated 95% interval.
    """
    x = np.asarray(values_per_seed, dtype=float).ravel()
    x = x[np.isfinite(x)]
    if x.size < 2:
        return math.nan, math.nan
    if np.all(x == x[0]):
        v = float(statistic(x))
        if math.isclose(v, x[0], rel_tol=1e-12, abs_tol=1e-15):
            v = float(x[0])  # the mean of n copies of v may round to v - ulp
        return v, v
    res = stats.bootstrap((x,), statistic, n_resamples=n_resamples, confidence_level=confidence,
                          method=method, rng=np.random.default_rng(seed))
    return float(res.confidence_interval.low), float(res.confidence_interval.high)


def _per_scenario(df: pd.DataFrame, metric: str, side: str) -> tuple[pd.Series, int]:
    missing = [c for c in ("scenario_id", "seed", metric) if c not in df.columns]
    if missing:
        raise ValueError(f"{side} episodes lack columns {missing}")
    if df.empty:
        raise ValueError(f"{side}: no episodes")
    keys = ["scenario_set", "scenario_id"] if "scenario_set" in df.columns else ["scenario_id"]
    if df.duplicated([*keys, "seed"]).any():
        raise ValueError(f"{side}: a scenario appears twice for the same seed")
    per = df.groupby(keys, sort=True)[metric].mean().astype(float)
    return per, int(df["seed"].nunique())


def compare_cells(reference: pd.DataFrame, candidate: pd.DataFrame, metric: str = "success",
                  confidence: float = 0.95, n_resamples: int = 10_000, seed: int = 0) -> dict:
    """Candidate − reference in the mean of ``metric`` (``success`` or ``spl``) on one evaluation cell.

    Both frames hold per-episode rows with ``scenario_id``, ``seed`` and the metric (and optionally
    ``scenario_set``, which file the scenario came from; see ``data.read_episodes``). Both sides
    must cover exactly the same scenarios (ValueError otherwise).

    Method (scenarios are the unit; seeds are pooled within a scenario):

    1. per side and scenario ``s``, average the metric over the seeds that side has for ``s``:
       ``r_s``, ``c_s``; ``reference = mean_s r_s``, ``candidate = mean_s c_s`` (equal to the pooled
       episode mean when every seed covers every scenario); ``difference = mean_s (c_s - r_s)``.
    2. CI: paired bootstrap over scenarios, i.e. resample scenario ids with replacement (each
       resampled scenario brings both of its seed-averaged values) and take the mean paired
       difference; ``n_resamples`` resamples, percentile interval, ``rng=default_rng(seed)``.
       All-equal differences give the point interval ``(d, d)``.
    3. p-value: two-sided paired permutation (sign-flip) test over scenarios: under H0 the labels
       reference/candidate are exchangeable within a scenario, so each ``d_s`` keeps or flips its
       sign at random; statistic = mean ``d_s``; ``scipy.stats.permutation_test`` with
       ``permutation_type="samples"``, ``n_resamples`` random flips (exact enumeration when
       ``2**n_scenarios <= n_resamples``), ``rng=default_rng(seed)``. Identical sides give p = 1.

    Returns ``{reference, candidate, difference, ci_low, ci_high, p_value, n_scenarios, n_seeds_ref,
    n_seeds_cand, significant}`` with ``significant = p_value < 0.05`` (not corrected for the number of
    cells compared; ``compare_report`` adds Holm-adjusted p-values).
    """
    if metric not in METRICS:
        raise ValueError(f"metric={metric!r}; allowed: {', '.join(METRICS)}")
    ref, n_ref = _per_scenario(reference, metric, "reference")
    cand, n_cand = _per_scenario(candidate, metric, "candidate")
    if not ref.index.equals(cand.index):
        only_ref = ref.index.difference(cand.index)
        only_cand = cand.index.difference(ref.index)
        raise ValueError(f"reference and candidate were evaluated on different scenarios "
                         f"({len(only_ref)} only in reference, {len(only_cand)} only in candidate, "
                         f"e.g. {list(only_ref[:2]) + list(only_cand[:2])})")
    r, c = ref.to_numpy(), cand.to_numpy()
    d = c - r
    diff = float(d.mean())
    if d.size < 2 or np.all(d == d[0]):
        lo = hi = diff
    else:
        res = stats.bootstrap((d,), np.mean, n_resamples=n_resamples, confidence_level=confidence,
                              method="percentile", rng=np.random.default_rng(seed))
        lo, hi = float(res.confidence_interval.low), float(res.confidence_interval.high)
    if np.all(d == 0):
        p = 1.0
    else:
        perm = stats.permutation_test((c, r), lambda x, y, axis: np.mean(x - y, axis=axis),
                                      permutation_type="samples", vectorized=True, n_resamples=n_resamples,
                                      alternative="two-sided", rng=np.random.default_rng(seed))
        p = float(min(1.0, perm.pvalue))
    return {"reference": float(r.mean()), "candidate": float(c.mean()), "difference": diff,
            "ci_low": lo, "ci_high": hi, "p_value": p, "n_scenarios": int(d.size),
            "n_seeds_ref": n_ref, "n_seeds_cand": n_cand, "significant": bool(p < 0.05)}


def holm(p_values) -> np.ndarray:
    """Holm-Bonferroni adjusted p-values (same order as given)."""
    p = np.asarray(p_values, dtype=float)
    m = p.size
    if m == 0:
        return p
    order = np.argsort(p)
    adj = np.minimum(1.0, np.maximum.accumulate((m - np.arange(m)) * p[order]))
    out = np.empty(m)
    out[order] = adj
    return out


def cluster_bootstrap_mean(df: pd.DataFrame, value: str, cluster: str | list[str] = "scenario_id",
                           confidence: float = 0.95, n_resamples: int = 10_000,
                           seed: int = 0) -> tuple[float, float, float]:
    """Mean of ``value`` with a bootstrap CI that resamples clusters (scenarios), seeds pooled.

    Per cluster the rows (one per seed) are averaged first; the estimate is the mean of the cluster
    means (= pooled mean when every seed covers every scenario) and the CI a percentile bootstrap of
    it over clusters. One cluster: ``(m, nan, nan)``.
    """
    per = df.groupby(cluster, sort=True)[value].mean().astype(float).to_numpy()
    per = per[np.isfinite(per)]
    if per.size == 0:
        return math.nan, math.nan, math.nan
    m = float(per.mean())
    if per.size < 2:
        return m, math.nan, math.nan
    lo, hi = bootstrap_ci(per, np.mean, confidence=confidence, n_resamples=n_resamples, seed=seed)
    return m, lo, hi

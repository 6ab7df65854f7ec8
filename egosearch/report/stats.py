"""Confidence intervals and paired comparisons for the report (scipy.stats only).

- :func:`wilson_ci`: Wilson score interval of a success rate from independent episodes (one seed,
  each scenario once: the bounds' rows);
- :func:`two_level_ci`: the interval of a policy's mean when several seeds ran the SAME scenarios:
  a bootstrap that resamples scenarios, then seeds, so that the scenario is the unit that repeats;
- :func:`bootstrap_ci`: bootstrap interval of a statistic over a few per-seed values.
- :func:`compare_cells`: candidate vs reference on one evaluation cell (same scenarios), paired
  by scenario: difference, and the two-level paired bootstrap's interval and p-value, both read
  from one set of resampled differences (:func:`percentile_p_value`), so that p < 0.05 exactly
  when the 95% interval excludes 0.

Why not a Wilson interval over every episode of a cell: 3 seeds x 100 scenarios are not 300
independent trials. A scenario that is hard for one seed is hard for the others, so the pooled
interval is too narrow by up to sqrt(seeds) (tests/test_report.py builds such a case by hand).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pandas as pd
from scipy import stats

from egosearch.report.seed_spread import SCENARIOS_ONLY, SpreadSeeds, compare_on_seed_spread

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


def scenario_seed_matrix(df: pd.DataFrame, value: str) -> tuple[np.ndarray, list]:
    """Per-episode rows -> (scenarios x seeds) matrix of ``value`` and the scenario keys.

    A scenario is ``(scenario_set, scenario_id)`` when the frame says which file it came from (ids
    restart in every file). Every seed must cover every scenario (ValueError otherwise): the design
    is crossed, and a hole would silently reweight the scenarios."""
    missing = [c for c in ("scenario_id", "seed", value) if c not in df.columns]
    if missing:
        raise ValueError(f"episodes lack columns {missing}")
    if df.empty:
        raise ValueError("no episodes")
    keys = ["scenario_set", "scenario_id"] if "scenario_set" in df.columns else ["scenario_id"]
    if df.duplicated([*keys, "seed"]).any():
        raise ValueError("a scenario appears twice for the same seed")
    wide = df.pivot_table(index=keys, columns="seed", values=value, aggfunc="first", sort=True)
    if wide.isna().to_numpy().any():
        holes = int(wide.isna().to_numpy().sum())
        raise ValueError(f"{holes} (scenario, seed) pair(s) missing: every seed must run every scenario")
    return wide.to_numpy(dtype=float), list(wide.index)


def _two_level_means(m: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Mean of ``m[rows_b][:, cols_b]`` for every resample b (rows (B, S), cols (B, K))."""
    col_sums = m[rows].sum(axis=1)  # (B, K): the resampled scenarios' sum, per seed
    return np.take_along_axis(col_sums, cols, axis=1).mean(axis=1) / m.shape[0]


def quantile_interval(draws: np.ndarray, confidence: float) -> tuple[float, float]:
    """The central ``confidence`` percentile interval of the finite ``draws``; ``(nan, nan)`` when none is finite."""
    draws = draws[np.isfinite(draws)]
    if draws.size == 0:
        return math.nan, math.nan
    alpha = (1 - confidence) / 2
    lo, hi = np.quantile(draws, [alpha, 1 - alpha])
    return float(lo), float(hi)


def two_level_ci(m: np.ndarray, confidence: float = 0.95, n_resamples: int = 10_000,
                 seed: int = 0) -> tuple[float, float, float]:
    """Mean of a (scenarios x seeds) matrix and its two-level bootstrap interval.

    Each resample draws the scenarios with replacement, then, independently, the seeds with
    replacement (seeds and scenarios are crossed: every seed ran every scenario), and takes the
    mean of the resampled matrix; the interval is the percentile interval of those means. With one
    seed it is the ordinary bootstrap over scenarios; with one scenario the seeds alone.
    ``(mean, nan, nan)`` for a 1 x 1 matrix."""
    m = np.asarray(m, dtype=float)
    if m.ndim != 2 or m.size == 0:
        raise ValueError(f"two_level_ci needs a non-empty (scenarios x seeds) matrix, got shape {m.shape}")
    mean = float(m.mean())
    if m.size == 1:
        return mean, math.nan, math.nan
    if np.all(m == m.flat[0]):
        return mean, mean, mean
    rng = np.random.default_rng(seed)
    n_s, n_k = m.shape
    means = np.empty(n_resamples)
    chunk = max(1, 4_000_000 // max(1, n_s * n_k))
    for start in range(0, n_resamples, chunk):
        b = min(chunk, n_resamples - start)
        means[start:start + b] = _two_level_means(m, rng.integers(0, n_s, (b, n_s)), rng.integers(0, n_k, (b, n_k)))
    alpha = (1 - confidence) / 2
    lo, hi = np.quantile(means, [alpha, 1 - alpha])
    return mean, float(lo), float(hi)


def paired_two_level_draws(ref: np.ndarray, cand: np.ndarray, n_resamples: int = 10_000,
                           seed: int = 0) -> np.ndarray:
    """``n_resamples`` bootstrap draws of mean(cand) - mean(ref) over the same scenarios (rows), each side
    with its own seeds (columns): one draw of scenarios serves both sides (the pairing), the seeds are
    drawn per side (they are different training runs). A side with one seed has no seed level: its
    draws resample the scenarios only."""
    ref, cand = np.asarray(ref, float), np.asarray(cand, float)
    if ref.shape[0] != cand.shape[0]:
        raise ValueError("paired_two_level_ci: the two sides have different numbers of scenarios")
    n_s = ref.shape[0]
    rng = np.random.default_rng(seed)
    diffs = np.empty(n_resamples)
    chunk = max(1, 4_000_000 // max(1, n_s * max(ref.shape[1], cand.shape[1])))
    for start in range(0, n_resamples, chunk):
        b = min(chunk, n_resamples - start)
        rows = rng.integers(0, n_s, (b, n_s))
        diffs[start:start + b] = (_two_level_means(cand, rows, rng.integers(0, cand.shape[1], (b, cand.shape[1])))
                                  - _two_level_means(ref, rows, rng.integers(0, ref.shape[1], (b, ref.shape[1]))))
    return diffs


def paired_two_level_ci(ref: np.ndarray, cand: np.ndarray, confidence: float = 0.95, n_resamples: int = 10_000,
                        seed: int = 0) -> tuple[float, float]:
    """Percentile interval of :func:`paired_two_level_draws`."""
    return quantile_interval(paired_two_level_draws(ref, cand, n_resamples, seed), confidence)


def _zero_crossing(x: np.ndarray) -> float:
    """For sorted ``x``: the largest ``a`` in [0, 1] with ``np.quantile(x, a) <= 0`` (linear interpolation,
    numpy's default); 0 when even the smallest draw is above 0."""
    n = x.size
    k = int(np.searchsorted(x, 0.0, side="right"))  # draws <= 0
    if k == 0:
        return 0.0
    if k == n or n == 1:
        return 1.0
    t = (k - 1) + (-x[k - 1]) / (x[k] - x[k - 1])  # where the interpolated quantile crosses 0
    return min(1.0, t / (n - 1))


def percentile_p_value(draws: np.ndarray) -> float:
    """Two-sided bootstrap p-value of "the difference is 0" read from the same draws as the percentile
    interval: the smallest ``alpha`` at which the central ``1 - alpha`` percentile interval of
    :func:`quantile_interval` excludes 0.

    So p < 0.05 exactly when the 95% interval excludes 0, and p is about twice the share of draws on
    the far side of 0 (``2 * min(share <= 0, share >= 0)``, capped at 1). This is the test that a
    percentile interval implies (Efron & Tibshirani 1993, *An Introduction to the Bootstrap*, §15.4
    on the relation of tests to confidence intervals, and ch. 16 on bootstrap tests). It is floored at
    one draw's share, ``1 / len(draws)``: fewer draws than that on the far side are not resolved
    (with 20 draws or fewer the floor is 0.05 or more and the equivalence at 0.05 fails). ``nan`` without a
    finite draw."""
    x = np.sort(np.asarray(draws, float)[np.isfinite(draws)])
    if x.size == 0:
        return math.nan
    p = min(1.0, 2 * _zero_crossing(x), 2 * _zero_crossing(-x[::-1]))
    return float(max(p, 1.0 / x.size))


def shared_seed_difference_ci(stored: np.ndarray, fresh: np.ndarray, confidence: float = 0.95,
                              n_resamples: int = 10_000, seed: int = 0) -> tuple[float, float]:
    """Interval of mean(fresh) - mean(stored) for two (scenarios x seeds) matrices whose columns are
    the same seeds and whose rows are different scenarios: each resample draws each side's rows on
    their own and one draw of seed columns for both sides."""
    stored, fresh = np.asarray(stored, float), np.asarray(fresh, float)
    if stored.ndim != 2 or fresh.ndim != 2 or stored.shape[1] != fresh.shape[1] or not stored.size or not fresh.size:
        raise ValueError(f"two non-empty matrices with the same seed columns needed, got {stored.shape} and "
                         f"{fresh.shape}")
    rng = np.random.default_rng(seed)
    n_k = stored.shape[1]
    diffs = np.empty(n_resamples)
    chunk = max(1, 2_000_000 // max(1, max(stored.shape[0], fresh.shape[0]) * n_k))
    for start in range(0, n_resamples, chunk):
        b = min(chunk, n_resamples - start)
        cols = rng.integers(0, n_k, (b, n_k))
        diffs[start:start + b] = (_two_level_means(fresh, rng.integers(0, fresh.shape[0], (b, fresh.shape[0])), cols)
                                  - _two_level_means(stored, rng.integers(0, stored.shape[0], (b, stored.shape[0])),
                                                     cols))
    alpha = (1 - confidence) / 2
    lo, hi = np.quantile(diffs, [alpha, 1 - alpha])
    return float(lo), float(hi)


def detectable_difference(sd_paired: float, n_scenarios: int, alpha: float = 0.05, power: float = 0.8) -> float:
    """Smallest true mean difference a paired two-sided test at level ``alpha`` detects with probability
    ``power`` over ``n_scenarios`` scenarios whose seed-averaged paired differences have standard
    deviation ``sd_paired``: ``(z_{1-alpha/2} + z_power) * sd / sqrt(n)`` (normal approximation).
    It counts the scenarios' spread only; :func:`detectable_from_se` takes a standard error that
    counts the seeds too."""
    if n_scenarios < 1:
        raise ValueError(f"n_scenarios={n_scenarios}: must be >= 1")
    return detectable_from_se(sd_paired / math.sqrt(n_scenarios), alpha, power)


def detectable_from_se(standard_error: float, alpha: float = 0.05, power: float = 0.8) -> float:
    """Smallest true difference a two-sided test at level ``alpha`` whose estimate has this standard
    error detects with probability ``power``: ``(z_{1-alpha/2} + z_power) * se`` (normal approximation)."""
    z = stats.norm.ppf(1 - alpha / 2) + stats.norm.ppf(power)
    return float(z * standard_error)


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


def paired_scenarios(reference: pd.DataFrame, candidate: pd.DataFrame, metric: str = "success"):
    """``((reference's per-scenario seed mean, its seeds), (candidate's, its seeds))``; ValueError (one line)
    when the two sides were not evaluated on the same scenarios."""
    ref, n_ref = _per_scenario(reference, metric, "reference")
    cand, n_cand = _per_scenario(candidate, metric, "candidate")
    if not ref.index.equals(cand.index):
        only_ref = ref.index.difference(cand.index)
        only_cand = cand.index.difference(ref.index)
        raise ValueError(f"reference and candidate were evaluated on different scenarios "
                         f"({len(only_ref)} only in reference, {len(only_cand)} only in candidate, "
                         f"e.g. {list(only_ref[:2]) + list(only_cand[:2])})")
    return (ref, n_ref), (cand, n_cand)


def compare_cells(reference: pd.DataFrame, candidate: pd.DataFrame, metric: str = "success",
                  confidence: float = 0.95, n_resamples: int = 10_000, seed: int = 0,
                  spreads: SpreadSeeds | str | None = None) -> dict:
    """Candidate − reference in the mean of ``metric`` (``success`` or ``spl``) on one evaluation cell.

    Both frames hold per-episode rows with ``scenario_id``, ``seed`` and the metric (and optionally
    ``scenario_set``, which file the scenario came from; see ``data.read_episodes``). Both sides
    must cover exactly the same scenarios (ValueError otherwise).

    Method (the scenario is the unit that repeats, and each side's seeds are its training runs):

    1. per side and scenario ``s``, average the metric over the seeds that side has for ``s``:
       ``r_s``, ``c_s``; ``reference = mean_s r_s``, ``candidate = mean_s c_s`` (equal to the pooled
       episode mean when every seed covers every scenario); ``difference = mean_s (c_s - r_s)``.
    2. Draws: a two-level paired bootstrap (:func:`paired_two_level_draws`, ``n_resamples`` draws,
       ``rng=default_rng(seed)``): resample the scenarios with replacement (one draw for both sides:
       the pairing), then each side's seeds with replacement (different training runs), and take the
       difference of the means (Davison & Hinkley 1997, *Bootstrap Methods and their Application*,
       §3.8 on resampling hierarchical data; Agarwal et al. 2021, "Deep reinforcement learning at the
       edge of the statistical precipice", on resampling runs and tasks). A side with ONE seed has no
       seed level: a one-seed-against-one-seed screen resamples the scenarios only, and its interval
       and p do not count how much another training seed would differ. Where a side's seeds do not all
       cover every scenario, the seeds are averaged per scenario first and only the scenarios are
       resampled.
    3. CI: the percentile interval of the draws (:func:`quantile_interval`).
    4. p-value: :func:`percentile_p_value` of the SAME draws: the smallest level at which their
       percentile interval excludes 0 (two-sided; about twice the share of draws on the far side of
       0). So p < 0.05 exactly when the 95% interval excludes 0, and a difference that the seeds do
       not agree on is not called significant because the scenarios do (the sign-flip test over
       seed-averaged scenarios that this replaces did). It is per cell and UNCORRECTED;
       ``compare_report`` adds Holm's adjustment over every row, and only that decides significance
       (Holm only raises p, so a Holm-significant row's interval always excludes 0).

       Draws that are all equal (no variation at either level, e.g. identical sides with one seed)
       give the point interval ``(d, d)`` and p = 1 when d = 0. With fewer than 2 scenarios there is
       nothing to resample at the scenario level: interval ``(nan, nan)``, p = 1.
    5. ``detectable_80``: the difference this cell's test detects with 80% power at p < 0.05
       uncorrected, from the draws' standard deviation (:func:`detectable_from_se`; normal
       approximation), so that it counts the seeds' spread as the test does.

    ``spreads``: the seeds whose spread a screen counts
    (:class:`~egosearch.report.seed_spread.SpreadSeeds`, from
    :func:`~egosearch.report.spread_sides.comparison_spreads`): then steps 2-5 are
    :func:`~egosearch.report.seed_spread.seed_spread_test`'s instead, a t interval and p on the seeds' cell
    means, each side's and the spread seeds' (docs/statistics.md, "Seed spread"), and ``method`` says
    ``seed spread``; :data:`~egosearch.report.seed_spread.SCENARIOS_ONLY`: the bootstrap, marked so; otherwise
    ``method`` says ``bootstrap``.

    Returns ``{reference, candidate, difference, ci_low, ci_high, p_uncorrected, n_scenarios,
    n_seeds_ref, n_seeds_cand, detectable_80, seed_sd, method}`` (``seed_sd``: the spread of one seed's cell
    mean that the seed-spread test counted; nan otherwise).
    """
    if metric not in (*METRICS, "stuck"):
        raise ValueError(f"metric={metric!r}; allowed: {', '.join((*METRICS, 'stuck'))}")
    (ref, n_ref), (cand, n_cand) = paired_scenarios(reference, candidate, metric)
    r, c = ref.to_numpy(), cand.to_numpy()
    d = c - r
    diff = float(d.mean())
    common = {"reference": float(r.mean()), "candidate": float(c.mean()), "n_scenarios": int(d.size),
              "n_seeds_ref": n_ref, "n_seeds_cand": n_cand}
    if isinstance(spreads, str) and spreads == SCENARIOS_ONLY:
        spreads = None
        method = "scenarios only"
    else:
        method = "bootstrap"
    if isinstance(spreads, SpreadSeeds) and d.size >= 2:
        res = compare_on_seed_spread(reference, candidate, metric, spreads, confidence)
        return {**common, **{k: res[k] for k in ("difference", "ci_low", "ci_high", "p_uncorrected",
                                                   "detectable_80", "seed_sd")}, "method": "seed spread"}
    if d.size < 2:
        lo = hi = detectable = math.nan
        p = 1.0
    else:
        try:
            ref_m, _ = scenario_seed_matrix(reference, metric)
            cand_m, _ = scenario_seed_matrix(candidate, metric)
        except ValueError:  # a seed lacks a scenario: resample the seed-averaged scenarios only
            ref_m, cand_m = r[:, None], c[:, None]
        draws = paired_two_level_draws(ref_m, cand_m, n_resamples, seed)
        # Means of equal values can differ from the value by an ulp; such draws carry no spread.
        if np.ptp(draws) <= 1e-12 * max(1.0, abs(diff)):
            lo = hi = diff
            p = 1.0 if diff == 0 else percentile_p_value(np.full(draws.size, diff))
            detectable = 0.0
        else:
            lo, hi = quantile_interval(draws, confidence)
            p = percentile_p_value(draws)
            detectable = detectable_from_se(float(draws.std(ddof=1)))
    return {**common, "difference": diff, "ci_low": lo, "ci_high": hi, "p_uncorrected": p,
            "detectable_80": detectable, "seed_sd": math.nan, "method": method}


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


DRAW_COLUMNS = ("layout", "start_x", "start_y", "start_theta", "target_object", "target_x", "target_y", "target_z")
"""What makes two scenarios of different cells the same draw: the home, the start and the target.
Table 1's cells are drawn from one stream per home, so a height or placement contrast shares many
draws (about three quarters between heights of one placement in the stored sets)."""


def cell_contrast(a: pd.DataFrame, b: pd.DataFrame, value: str = "success", confidence: float = 0.95,
                  n_resamples: int = 10_000, seed: int = 0) -> dict:
    """mean(a) − mean(b) for two cells evaluated by the same seeds (one policy per seed), with a
    bootstrap interval that resamples the draws and the seeds.

    Each frame holds per-episode rows with ``seed``, ``value`` and the :data:`DRAW_COLUMNS`. A draw
    run in both cells is one unit on both sides (the pairing: its difficulty cancels); draws run in
    one cell only are units of that side alone. Each resample draws units from the union of draws
    with replacement, then the seeds with replacement, and takes the difference of the two cells'
    means over the drawn units each side has; percentile interval. Returns ``{difference, ci_low,
    ci_high, n_shared, n_a, n_b, n_seeds}``."""
    keys = list(DRAW_COLUMNS)
    for side, df in (("a", a), ("b", b)):
        missing = [c for c in (*keys, "seed", value) if c not in df.columns]
        if missing:
            raise ValueError(f"cell {side} lacks columns {missing}")
    seeds = sorted(set(a["seed"]) | set(b["seed"]))
    if set(a["seed"]) != set(b["seed"]):
        raise ValueError(f"the two cells were run by different seeds ({sorted(set(a['seed']))} vs "
                         f"{sorted(set(b['seed']))}): a contrast needs the same policies on both sides")
    wide = {}
    for side, df in (("a", a), ("b", b)):
        wide[side] = df.pivot_table(index=keys, columns="seed", values=value, aggfunc="mean")
    draws = wide["a"].index.union(wide["b"].index)
    ma = wide["a"].reindex(index=draws, columns=seeds).to_numpy(float)  # NaN: the draw is not in that cell
    mb = wide["b"].reindex(index=draws, columns=seeds).to_numpy(float)
    in_a, in_b = ~np.isnan(ma[:, 0]), ~np.isnan(mb[:, 0])
    if np.isnan(ma[in_a]).any() or np.isnan(mb[in_b]).any():
        raise ValueError("every seed must run every scenario of a cell")
    diff = float(np.nanmean(ma) - np.nanmean(mb))
    rng = np.random.default_rng(seed)
    n_u, n_k = ma.shape
    za, zb = np.nan_to_num(ma), np.nan_to_num(mb)
    out = np.empty(n_resamples)
    chunk = max(1, 2_000_000 // max(1, n_u * n_k))
    for start in range(0, n_resamples, chunk):
        m = min(chunk, n_resamples - start)
        rows = rng.integers(0, n_u, (m, n_u))
        cols = rng.integers(0, n_k, (m, n_k))
        count_a, count_b = in_a[rows].sum(axis=1), in_b[rows].sum(axis=1)
        sum_a = np.take_along_axis(za[rows].sum(axis=1), cols, axis=1).mean(axis=1)
        sum_b = np.take_along_axis(zb[rows].sum(axis=1), cols, axis=1).mean(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            out[start:start + m] = sum_a / count_a - sum_b / count_b
    out = out[np.isfinite(out)]
    alpha = (1 - confidence) / 2
    lo, hi = np.quantile(out, [alpha, 1 - alpha]) if out.size else (math.nan, math.nan)
    return {"difference": diff, "ci_low": float(lo), "ci_high": float(hi), "n_shared": int((in_a & in_b).sum()),
            "n_a": int(in_a.sum()), "n_b": int(in_b.sum()), "n_seeds": n_k}

"""Does the screen's test keep its level? Its false-positive rate, simulated on the test as a screen runs it.

A screen reads each cell with :func:`~egosearch.report.seed_spread.seed_spread_test`, the reference's spread
seeds being the reference's seeds (the `screen` rule's form). :func:`false_positive_rates` draws screens in
which the candidate is the reference's own config, so that every difference it calls is a false positive,
and hands their seed means to that same function, with the arguments a screen gives it
(:func:`~egosearch.report.seed_spread.compare_on_seed_spread`), all simulated screens at once.

The truth is fitted to the stored episodes (``matrices``: ``{cell: scenarios x seeds}`` of the reference):

- a scenario's success probability is its stored seeds' mean, pulled half an episode towards 1/2
  (``(sum + 0.5) / (K + 1)``: no scenario is certain);
- a training seed shifts every scenario of a cell by ``u_c``; its standard deviation is the cell's stored seed
  spread (``per cell``: :func:`~egosearch.report.seed_spread.seed_spread`, 0.45 m and 1.65 m apart) or one
  number for every cell (``pooled``: the mean of the cells' variances, the truth the test before this one
  was simulated on);
- the shifts of one seed are correlated ``rho`` between cells (the cells share the seed's policy) and drawn
  normal or from a t with 3 degrees of freedom scaled to the same variance (a seed now and then far off, in
  every cell at once: a multivariate t);
- an episode succeeds with the shifted probability, clipped to [0, 1].

Each setting draws ``n_sims`` screens of ``n_candidate`` seeds against the stored seed count of the reference,
and counts the success cells called different at ``p < alpha`` before Holm (the test's own level), over all
cells and in the cell where it is highest, and the screens in which any cell is different after Holm over
their cells (:data:`CALIBRATION_COLUMNS`). The stored record claims every setting's rate, and its highest
cell's, at or below :data:`LEVEL_CLAIM` (:func:`level_holds`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping

import numpy as np
import pandas as pd

from egosearch.report.seed_spread import seed_spread, seed_spread_test

CANDIDATE_SEEDS = (1, 2, 3, 6)
"""The screens simulated: one, two and three seeds (the stored lever screens) and six. The workflow's default
screen_seeds (the power analysis's recommendation, which follows the reference's spread) is not itself simulated."""
RHOS = (0.0, 0.5, 0.7, 0.9)
"""How closely one seed's shifts move together between cells: the stored record says how closely the stored seed
means correlate (:func:`~egosearch.report.null_screen.cell_correlation`), and five seeds cannot say it precisely."""
LAWS = ("normal", "t3")
TRUTHS = ("per cell", "pooled")
LEVEL_CLAIM = 0.06
"""What the stored record claims of every setting at alpha 0.05: the simulated rate stays at or below it."""
SIMULATIONS = 20_000
"""Simulated screens per setting in the stored record: 120,000 cell tests, a rate's standard error about 0.001."""

CALIBRATION_COLUMNS = ("law", "truth", "rho", "n_candidate", "n_reference", "rate", "highest_cell_rate",
                       "screens_any_after_holm", "rate_without_one_seed_factor",
                       "highest_cell_rate_without_one_seed_factor", "cell_tests")
"""``rate``: the share of success cells called different at p < alpha (the test's level; every cell tested);
``highest_cell_rate``: the same in the cell where it is highest; ``screens_any_after_holm``: the share of screens
with any cell different after Holm over their cells; ``rate_without_one_seed_factor`` and its highest cell: for
one-seed screens, those of the plain prediction interval (its p not taken 1.5 times: why it is)."""


def scenario_probabilities(matrix: np.ndarray) -> np.ndarray:
    """Each scenario's success probability in the simulation: its stored seeds' mean pulled half an episode
    towards 1/2."""
    m = np.asarray(matrix, float)
    return (m.sum(axis=1) + 0.5) / (m.shape[1] + 1)


def seed_shifts(rng: np.random.Generator, n_sims: int, n_seeds: int, sds: np.ndarray, rho: float,
                law: str) -> np.ndarray:
    """``(n_sims, n_seeds, cells)`` shifts of a cell's success probability per training seed: correlation
    ``rho`` between cells, standard deviation ``sds[c]`` in cell ``c``, normal or a multivariate t with 3 df."""
    cells = len(sds)
    common = rng.standard_normal((n_sims, n_seeds, 1))
    own = rng.standard_normal((n_sims, n_seeds, cells))
    z = np.sqrt(rho) * common + np.sqrt(1 - rho) * own
    if law == "t3":
        # one chi-square per seed: a far-off seed is far off in every cell; sqrt(1/3) gives variance 1
        z = z / np.sqrt(rng.chisquare(3, (n_sims, n_seeds, 1)) / 3) * np.sqrt(1 / 3)
    elif law != "normal":
        raise ValueError(f"law={law!r}; allowed: {', '.join(LAWS)}")
    return z * np.asarray(sds, float)


def simulated_seed_means(rng: np.random.Generator, probabilities: list[np.ndarray], shifts: np.ndarray) -> np.ndarray:
    """``(n_sims, n_seeds, cells)`` seed means over each cell's scenarios, every episode a Bernoulli draw at its
    scenario's probability plus the seed's shift. Scenarios of one probability are drawn together as one
    binomial (the same draws as one Bernoulli each, far fewer calls)."""
    out = np.empty(shifts.shape)
    for c, p in enumerate(probabilities):
        values, counts = np.unique(p, return_counts=True)
        q = np.clip(values[None, None, :] + shifts[:, :, c, None], 0.0, 1.0)
        out[:, :, c] = rng.binomial(counts, q).sum(axis=-1) / p.size
    return out


def false_positive_rates(matrices: Mapping, n_sims: int = SIMULATIONS, seed: int = 0, alpha: float = 0.05,
                         candidate_seeds=CANDIDATE_SEEDS, rhos=RHOS, laws=LAWS, truths=TRUTHS,
                         sd_scale: float = 1.0) -> pd.DataFrame:
    """The simulated false-positive rate of the screen's test in every setting (module docstring), columns
    :data:`CALIBRATION_COLUMNS`. ``sd_scale`` multiplies the candidate's seed spread (1: the same config on
    both sides, the null the claim is about; a check that the simulation can fail uses more)."""
    cells = list(matrices)
    k_ref = next(iter(matrices.values())).shape[1]
    probabilities = [scenario_probabilities(matrices[c]) for c in cells]
    spreads = [seed_spread(matrices[c]) for c in cells]
    per_cell = np.array([s.sd for s in spreads])
    pooled = np.full(len(cells), np.sqrt(max(0.0, float(np.mean([s.raw for s in spreads])))))
    rng = np.random.default_rng(seed)
    rows = []
    for law, truth, rho in itertools.product(laws, truths, rhos):
        sds = per_cell if truth == "per cell" else pooled
        n_seeds = k_ref + max(candidate_seeds)
        shifts = seed_shifts(rng, n_sims, n_seeds, sds, rho, law)
        shifts[:, k_ref:, :] *= sd_scale
        means = np.moveaxis(simulated_seed_means(rng, probabilities, shifts), 1, -1)  # (sims, cells, seeds)
        reference = means[..., :k_ref]
        in_spread = np.ones(k_ref, bool)
        for k_cand in candidate_seeds:
            # a screen's call: the reference's seeds are the spread seeds, the candidate's its own group
            candidate = means[..., k_ref:k_ref + k_cand]
            p = seed_spread_test(candidate, reference, reference, reference_in_spread=in_spread)["p_uncorrected"]
            called = p < alpha
            plain = plain_highest = math.nan
            if k_cand == 1:
                plain_called = seed_spread_test(candidate, reference, reference, reference_in_spread=in_spread,
                                                one_seed_tail=False)["p_uncorrected"] < alpha
                plain, plain_highest = float(plain_called.mean()), float(plain_called.mean(axis=0).max())
            rows.append({"law": law, "truth": truth, "rho": rho, "n_candidate": k_cand, "n_reference": k_ref,
                         "rate": float(called.mean()), "highest_cell_rate": float(called.mean(axis=0).max()),
                         # Holm calls a cell only if its smallest p is below alpha / cells (its first step)
                         "screens_any_after_holm": float((p.min(axis=1) < alpha / len(cells)).mean()),
                         "rate_without_one_seed_factor": plain,
                         "highest_cell_rate_without_one_seed_factor": plain_highest, "cell_tests": int(called.size)})
    return pd.DataFrame(rows, columns=list(CALIBRATION_COLUMNS))


def worst_setting(table: pd.DataFrame) -> dict:
    """The setting of the highest simulated rate, as a record."""
    return table.loc[table["rate"].idxmax()].to_dict()


def level_holds(table: pd.DataFrame, claim: float = LEVEL_CLAIM) -> bool:
    """Every setting's rate, and its highest cell's, at or below ``claim``."""
    return bool(table["rate"].max() <= claim and table["highest_cell_rate"].max() <= claim)

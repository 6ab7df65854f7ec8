"""Which seed spread each side of a comparison counts (:mod:`egosearch.report.seed_spread`), read from its
evaluation files: a trained side with 3 seeds or more its own, one with fewer the reference variant's, a
searcher that is not trained none."""

from __future__ import annotations

import os
from collections.abc import Mapping

import numpy as np

from egosearch.report.data import parse_eval_path, read_episodes
from egosearch.report.seed_spread import (
    MIN_SEEDS_OWN_SPREAD,
    NO_SEEDS,
    SCENARIOS_ONLY,
    SeedSpread,
    SeedSpreadUnknown,
    pooled_seed_spread,
)
from egosearch.report.stats import scenario_seed_matrix
from egosearch.searchers.registry import names


def _variants_of(files: Mapping) -> set[str]:
    return {parse_eval_path(p)["variant"] for paths in files.values() for p in _listed(paths)}


def _listed(paths) -> list:
    return [paths] if isinstance(paths, (str, os.PathLike)) else list(paths)


def is_trained(variants: set[str]) -> bool:
    """A side is a trained policy unless every file is a registered searcher's (no training seed)."""
    return not variants <= set(names())


def _matrix(paths, metric: str) -> np.ndarray:
    return scenario_seed_matrix(read_episodes(_listed(paths)), metric)[0]


def _seed_count(files: Mapping) -> int:
    return min(len({parse_eval_path(p)["seed"] for p in _listed(paths)}) for paths in files.values())


def comparison_spreads(reference_files: Mapping, candidate_files: Mapping, spread_files: Mapping | None,
                       metric: str = "success") -> tuple[SeedSpread, SeedSpread] | str | None:
    """The ``(reference's, candidate's)`` seed spreads a comparison counts, or None when each side shows its
    own (every trained side has :data:`MIN_SEEDS_OWN_SPREAD` seeds or more: the two-level bootstrap).

    Each side's: a searcher that is not trained, :data:`NO_SEEDS`; a trained side with enough seeds, its own
    (:func:`pooled_seed_spread` over the compared cells); one with fewer, the reference variant's, from
    ``spread_files`` (``{cell: [every stored seed's paths]}``; the reference's files when None). SeedSpreadUnknown,
    one line, when a side must borrow and there is no trained reference to borrow from, or ``spread_files``
    holds one seed. Without ``spread_files`` and with a one-seed reference, the comparison cannot count a
    seed spread: :data:`~egosearch.report.seed_spread.SCENARIOS_ONLY` (its table's footnote says so)."""
    sides = []
    for files in (reference_files, candidate_files):
        sides.append((is_trained(_variants_of(files)), _seed_count(files), files))
    if not any(trained and k < MIN_SEEDS_OWN_SPREAD for trained, k, _ in sides):
        return None
    cells = sorted(reference_files, key=str)
    if spread_files is None:
        if not sides[0][0]:
            raise SeedSpreadUnknown("the candidate has fewer than 3 seeds and the reference is not trained: give the "
                                    "stored seeds of a trained variant whose seed spread it borrows (--spread)")
        if _seed_count(reference_files) < 2:
            return SCENARIOS_ONLY
        spread_files = reference_files  # the reference's seeds given are all it has
    missing = [c for c in cells if c not in spread_files]
    if missing:
        raise ValueError(f"the reference's seed files lack cell {missing[0]}")
    spread_names = ", ".join(sorted(_variants_of(spread_files)))
    if _seed_count({c: spread_files[c] for c in cells}) < 2:
        raise SeedSpreadUnknown(f"the reference {spread_names} has 1 stored seed: the variance between training "
                                "seeds cannot be estimated, so a screen against it cannot count it (train 2 or more "
                                "of its seeds)")
    borrowed = pooled_seed_spread([_matrix(spread_files[c], metric) for c in cells])
    out = []
    for trained, k, files in sides:
        if not trained:
            out.append(NO_SEEDS)
        elif k >= MIN_SEEDS_OWN_SPREAD:
            out.append(pooled_seed_spread([_matrix(files[c], metric) for c in cells]))
        else:
            out.append(borrowed)
    return out[0], out[1]

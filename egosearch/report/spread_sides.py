"""Which seeds show the spread a comparison's test counts (:mod:`egosearch.report.seed_spread`), read from its
evaluation files, and the one-line refusals of a screen's inputs that cannot be read together."""

from __future__ import annotations

import os
from collections.abc import Mapping

from egosearch.report.data import parse_eval_path, read_episodes
from egosearch.report.seed_spread import MIN_SEEDS_OWN_SPREAD, SCENARIOS_ONLY, SeedSpreadUnknown, SpreadSeeds
from egosearch.searchers.searcher_registry import names


def _listed(paths) -> list:
    return [paths] if isinstance(paths, (str, os.PathLike)) else list(paths)


def _runs(files: Mapping, cells=None) -> set[tuple[str, int]]:
    """The (variant, seed) training runs whose files ``files`` holds (in ``cells`` when given)."""
    return {(parse_eval_path(p)["variant"], parse_eval_path(p)["seed"])
            for cell, paths in files.items() if cells is None or cell in cells for p in _listed(paths)}


def _variants_of(files: Mapping) -> set[str]:
    return {variant for variant, _ in _runs(files)}


def is_trained(variants: set[str]) -> bool:
    """A side is a trained policy unless every file is a registered searcher's (no training seed)."""
    return not variants <= set(names())


def _seed_count(files: Mapping) -> int:
    return min(len({parse_eval_path(p)["seed"] for p in _listed(paths)}) for paths in files.values())


def _seeds_text(seeds) -> str:
    return ", ".join(str(s) for s in sorted(seeds))


def check_screen_inputs(reference_files: Mapping, candidate_files: Mapping, spread_files: Mapping) -> None:
    """A screen's inputs that cannot be read together, one line each (ValueError), before anything is read:

    - spread files of another variant than a trained reference (the spread counted would be another
      policy's), or of several variants;
    - a trained reference with seeds that are not among the spread seeds (its files are not the spread's);
    - a seed-matched screen (the reference given as some of its spread seeds, seed N against seed N) whose
      candidate has a seed the reference lacks, or the reverse. When the reference is every spread seed,
      the seeds are not matched and the candidate's may be any."""
    spread_variants = _variants_of(spread_files)
    ref_variants = _variants_of(reference_files)
    if len(spread_variants) != 1:
        raise ValueError(f"--spread holds {len(spread_variants)} variants ({', '.join(sorted(spread_variants))}); "
                         "give the stored seeds of one: the reference's")
    spread_variant = next(iter(spread_variants))
    if not is_trained(ref_variants):
        return  # a searcher's seed is not a training run: the spread is borrowed from a trained variant
    if ref_variants != spread_variants:
        raise ValueError(f"--spread holds {spread_variant}'s seeds, but the reference is "
                         f"{', '.join(sorted(ref_variants))}: a screen counts its reference's own seed spread")
    cells = set(reference_files)
    ref_seeds = {s for _, s in _runs(reference_files)}
    spread_seeds = {s for _, s in _runs(spread_files, cells)}
    outside = ref_seeds - spread_seeds
    if outside:
        raise ValueError(f"the reference's seed(s) {_seeds_text(outside)} are not among the spread seeds "
                         f"({_seeds_text(spread_seeds)}) of {spread_variant}: give every seed the reference uses "
                         "with --spread")
    if ref_seeds == spread_seeds:
        return
    cand_seeds = {s for _, s in _runs(candidate_files)}
    if cand_seeds != ref_seeds:
        lacks, extra = cand_seeds - ref_seeds, ref_seeds - cand_seeds
        which = (f"the candidate has seed(s) {_seeds_text(lacks)} the reference lacks" if lacks else
                 f"the reference has seed(s) {_seeds_text(extra)} the candidate lacks")
        raise ValueError(f"a seed-matched screen (the reference's seeds {_seeds_text(ref_seeds)} of its spread seeds "
                         f"{_seeds_text(spread_seeds)}) reads seed against seed, and {which}: give the same seeds "
                         "on both sides, or every spread seed as the reference")


def comparison_spreads(reference_files: Mapping, candidate_files: Mapping,
                       spread_files: Mapping | None) -> SpreadSeeds | str | None:
    """The seeds whose spread a comparison's test counts (:class:`~egosearch.report.seed_spread.SpreadSeeds`),
    or None when the comparison is not a screen and each trained side shows its own (every one has
    :data:`MIN_SEEDS_OWN_SPREAD` seeds or more: the two-level bootstrap).

    ``spread_files`` (``{cell: [every stored seed's paths]}`` of the reference variant) make it a screen,
    whatever the seed counts. Without them, a trained side with fewer than 3 seeds makes it one too, on the
    reference's own seeds. SeedSpreadUnknown, one line, when a side must borrow and there is no trained
    reference to borrow from, or the spread holds one seed. Without ``spread_files`` and with a one-seed
    reference, no seed spread can be counted: :data:`~egosearch.report.seed_spread.SCENARIOS_ONLY` (its
    table's footnote says so)."""
    trained = (is_trained(_variants_of(reference_files)), is_trained(_variants_of(candidate_files)))
    if spread_files is None:
        few = any(t and _seed_count(files) < MIN_SEEDS_OWN_SPREAD
                  for t, files in zip(trained, (reference_files, candidate_files)))
        if not few:
            return None
        if not trained[0]:
            raise SeedSpreadUnknown("the candidate has fewer than 3 seeds and the reference is not trained: give the "
                                    "stored seeds of a trained variant whose seed spread it borrows (--spread)")
        if _seed_count(reference_files) < 2:
            return SCENARIOS_ONLY
        spread_files = reference_files  # the reference's seeds given are all it has
    cells = sorted(reference_files, key=str)
    missing = [c for c in cells if c not in spread_files]
    if missing:
        raise ValueError(f"the spread seeds' files lack cell {missing[0]}")
    spread_files = {c: spread_files[c] for c in cells}
    spread_names = ", ".join(sorted(_variants_of(spread_files)))
    if _seed_count(spread_files) < 2:
        raise SeedSpreadUnknown(f"the reference {spread_names} has 1 stored seed: the variance between training "
                                "seeds cannot be estimated, so a screen against it cannot count it (train 2 or more "
                                "of its seeds)")
    spread_runs = _runs(spread_files)
    return SpreadSeeds(
        episodes=read_episodes([p for c in cells for p in _listed(spread_files[c])]), variant=spread_names,
        reference_trained=trained[0], candidate_trained=trained[1],
        reference_in_spread=frozenset(s for v, s in _runs(reference_files) if (v, s) in spread_runs),
        candidate_in_spread=frozenset(s for v, s in _runs(candidate_files) if (v, s) in spread_runs))

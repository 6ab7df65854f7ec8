"""The stored screens read again with the test every screen runs now (docs/ablations/reread.md).

A stored screen (``results/<preset>/compare/screen_<candidate>_seed<N>_vs_<reference>[_seed<N>][_in_<home>].csv``
or ``screen_<candidate>_seeds<A>-<B>_vs_<reference>.csv``) was read with the test of its day: a one-seed screen's
interval resampled the scenarios only, a two-seed screen's counted one seed spread twice, a screen of three
seeds or more ran the two-level bootstrap. :func:`reread_screens` recomputes each from the same evaluation files
with the seed-spread test (:mod:`egosearch.report.seed_spread`), the spread being the reference variant's stored
seeds (the candidate variant's other seeds where the reference is a searcher, which has no training seed), and
sets the stored verdict beside the new one. The stored screen files are left as they were: this is a second
reading.
"""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd

from egosearch.report.data import cells_from_paths
from egosearch.report.seed_spread import SeedSpreadUnknown
from egosearch.report.spread_sides import check_screen_inputs, is_trained
from egosearch.report.tables import compare_report

SCREEN_NAME = re.compile(r"^screen_(?P<cand>.+?)_(?:seed(?P<seed>\d+)|seeds(?P<first>\d+)-(?P<last>\d+))"
                         r"_vs_(?P<ref>.+?)(?:_seed(?P<ref_seed>\d+))?(?:_in_(?P<home>[a-z_]+))?$")
REREAD_COLUMNS = ("screen", "candidate", "reference", "candidate_seeds", "reference_seeds", "spread_from",
                  "spread_seeds", "old_method", "height", "placement", "metric", "difference", "old_ci_low",
                  "old_ci_high", "old_p_holm", "old_verdict", "ci_low", "ci_high", "p_holm", "detectable_80",
                  "verdict", "changed")
"""``old_*``: the stored screen's row (``old_method``: the test it was read with); ``ci_*``, ``p_holm``,
``detectable_80``, ``verdict``: the seed-spread test's; ``changed``: whether the verdict (different or not, and
which way) differs."""

NOT_STORED = "not re-read: its evaluation files are not stored"


def _old_verdict(row) -> str:
    if not row["significant_holm"]:
        return "no difference detected"
    return "higher" if row["difference"] > 0 else "lower"


def _files(eval_dir: Path, variant: str, seeds, homes) -> list[str]:
    return sorted(str(p) for s in seeds for home in homes
                  for p in (eval_dir / variant / f"seed{s}" / home).glob("*/h*.csv"))


def _stored_seeds(eval_dir: Path, variant: str, homes) -> list[int]:
    return sorted(int(p.name[4:]) for p in (eval_dir / variant).glob("seed*")
                  if all((p / home).is_dir() for home in homes))


def _read(eval_dir: Path, variant: str, seeds, homes, cells) -> dict:
    """The stored screen's cells only (some screens read one height)."""
    return {c: v for c, v in cells_from_paths(_files(eval_dir, variant, seeds, homes)).items() if c in cells}


def _seeds_text(seeds) -> str:
    return "+".join(str(s) for s in seeds)


def screen_seeds(name: str) -> tuple[re.Match, list[int]]:
    """The name's parts and the candidate's seeds it names; ValueError when it is not a screen's name."""
    m = SCREEN_NAME.match(name)
    if m is None:
        raise ValueError(f"{name}: not a screen's name (screen_<candidate>_seed<N>_vs_<reference>... or "
                         "screen_<candidate>_seeds<A>-<B>_vs_<reference>)")
    if m["seed"] is not None:
        return m, [int(m["seed"])]
    first, last = int(m["first"]), int(m["last"])
    if last < first:
        raise ValueError(f"{name}: seeds {first}-{last} run backwards")
    return m, list(range(first, last + 1))


def reread_screens(compare_dir: Path, eval_dir: Path, out_csv=None, n_resamples: int = 10_000) -> pd.DataFrame:
    """Every stored screen (:data:`SCREEN_NAME`; ℓ, aggregate and stuck files left out) read again
    (:data:`REREAD_COLUMNS`). A screen whose evaluation files are not stored, or whose spread has too few seeds
    for the test, gets one row saying so. ValueError, one line naming the screen, when its name asks for
    candidate seeds that are not stored, or its inputs cannot be read together
    (:func:`~egosearch.report.spread_sides.check_screen_inputs`)."""
    frames = []
    for path in sorted(Path(compare_dir).glob("screen_*.csv")):
        if path.stem.endswith(("_by_length", "_aggregate", "_stuck")):
            continue
        m, seeds = screen_seeds(path.stem)
        old = pd.read_csv(path)  # a screen stored before the seed spread has no method: the bootstrap
        homes = sorted({h for value in old["homes"] for h in str(value).split("+")})
        stored = _stored_seeds(eval_dir, m["cand"], homes)
        missing = [s for s in seeds if s not in stored]
        if missing and stored:
            raise ValueError(f"{path.name}: names {m['cand']}'s seed(s) {_seeds_text(seeds)}, but only "
                             f"{_seeds_text(stored)} are stored in {eval_dir / m['cand']} (a screen_seeds above the "
                             "stored seeds)")
        ref_seeds = [int(m["ref_seed"])] if m["ref_seed"] else _stored_seeds(eval_dir, m["ref"], homes)
        spread_variant = m["ref"] if is_trained({m["ref"]}) else m["cand"]
        spread_seeds = [s for s in _stored_seeds(eval_dir, spread_variant, homes)
                        if spread_variant != m["cand"] or s not in seeds]
        cells = {(float(h), p) for h, p in zip(old["height"], old["placement"])}

        reference, candidate = (_read(eval_dir, m["ref"], ref_seeds, homes, cells),
                                _read(eval_dir, m["cand"], seeds, homes, cells))
        spread = _read(eval_dir, spread_variant, spread_seeds, homes, cells)
        # a screen whose candidate was later evaluated in fewer cells (a budget study's) is read where it still is
        common = set(reference) & set(candidate) & set(spread)
        if not common:
            frames.append(pd.DataFrame([{"screen": path.stem, "candidate": m["cand"], "reference": m["ref"],
                                         "verdict": NOT_STORED}]))
            continue
        reference, candidate, spread = ({c: v for c, v in side.items() if c in common}
                                        for side in (reference, candidate, spread))
        old = old[[(float(h), p) in common for h, p in zip(old["height"], old["placement"])]].reset_index(drop=True)
        try:
            check_screen_inputs(reference, candidate, spread)
            new = compare_report(reference, candidate, n_resamples=n_resamples, spread_files=spread)
        except SeedSpreadUnknown as err:  # too few spread seeds for this screen: said in its row, the rest read
            frames.append(pd.DataFrame([{"screen": path.stem, "candidate": m["cand"], "reference": m["ref"],
                                         "candidate_seeds": _seeds_text(seeds), "spread_from": spread_variant,
                                         "spread_seeds": _seeds_text(spread_seeds),
                                         "verdict": f"not re-read: {str(err).split(': ')[-1]}"}]))
            continue
        except ValueError as err:
            raise ValueError(f"{path.name}: {err}") from None
        frame = pd.DataFrame({
            "screen": path.stem, "candidate": m["cand"], "reference": m["ref"], "candidate_seeds": _seeds_text(seeds),
            "reference_seeds": _seeds_text(ref_seeds), "spread_from": spread_variant,
            "spread_seeds": _seeds_text(spread_seeds), "old_method": old["method"] if "method" in old else "bootstrap",
            "height": new["height"], "placement": new["placement"], "metric": new["metric"],
            "difference": new["difference"], "old_ci_low": old["ci_low"], "old_ci_high": old["ci_high"],
            "old_p_holm": old["p_holm"], "old_verdict": old.apply(_old_verdict, axis=1), "ci_low": new["ci_low"],
            "ci_high": new["ci_high"], "p_holm": new["p_holm"], "detectable_80": new["detectable_80"],
            "verdict": new["verdict"]})
        frame["changed"] = frame["old_verdict"] != frame["verdict"].where(frame["verdict"].isin(["higher", "lower"]),
                                                                          "no difference detected")
        frames.append(frame)
    df = pd.concat(frames, ignore_index=True)[list(REREAD_COLUMNS)] if frames else pd.DataFrame(columns=REREAD_COLUMNS)
    if out_csv is not None:
        Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
        df.to_csv(out_csv, index=False, float_format="%.6g")
    return df

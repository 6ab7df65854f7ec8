"""The stored screens read again with the verdict that counts the seed spread (docs/ablations.md).

A stored screen (``results/<profile>/compare/screen_<candidate>_seed<N>_vs_<reference>[_seed<N>][_in_<home>].csv``)
compared one training seed of a lever with the reference's same seed (or its mean), its interval resampling
the scenarios only. :func:`reread_screens` recomputes each from the same evaluation files, with the spread
of the reference variant's stored seeds counted (:mod:`egosearch.report.seed_spread`), and sets the old
verdict beside the new one. The stored screen files are left as they were: this is a second reading.
"""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd

from egosearch.report.data import cells_from_paths
from egosearch.report.spread_sides import is_trained
from egosearch.report.tables import compare_report

SCREEN_NAME = re.compile(r"^screen_(?P<cand>.+?)_seed(?P<seed>\d+)_vs_(?P<ref>.+?)(?:_seed(?P<ref_seed>\d+))?"
                         r"(?:_in_(?P<home>[a-z_]+))?$")
REREAD_COLUMNS = ("screen", "candidate", "reference", "spread_from", "spread_seeds", "height", "placement", "metric",
                  "difference", "old_ci_low", "old_ci_high", "old_p_holm", "old_verdict", "ci_low", "ci_high",
                  "p_holm", "verdict", "changed")


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


def reread_screens(compare_dir: Path, eval_dir: Path, out_csv=None, n_resamples: int = 10_000) -> pd.DataFrame:
    """Every stored screen (:data:`SCREEN_NAME`, aggregate and ℓ files left out) read again (:data:`REREAD_COLUMNS`).
    The spread counted is the reference variant's over its stored seeds, or the candidate variant's when the
    reference is a searcher that is not trained."""
    frames = []
    for path in sorted(Path(compare_dir).glob("screen_*.csv")):
        if path.stem.endswith(("_by_length", "_aggregate", "_stuck")):
            continue
        m = SCREEN_NAME.match(path.stem)
        if m is None or "seeds" in path.stem.split("_vs_")[0].rsplit("_", 1)[-1]:
            continue  # a screen of several seeds counts the spread already
        old = pd.read_csv(path)
        homes = sorted({h for value in old["homes"] for h in str(value).split("+")})
        seed = int(m["seed"])
        ref_seeds = [int(m["ref_seed"])] if m["ref_seed"] else _stored_seeds(eval_dir, m["ref"], homes)
        spread_variant = m["ref"] if is_trained({m["ref"]}) else m["cand"]
        spread_seeds = _stored_seeds(eval_dir, spread_variant, homes)
        cells = {(float(h), p) for h, p in zip(old["height"], old["placement"])}

        reference, candidate = (_read(eval_dir, m["ref"], ref_seeds, homes, cells),
                                _read(eval_dir, m["cand"], [seed], homes, cells))
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
        if spread_variant == m["cand"]:
            spread = {cell: [p for p in paths if f"/seed{seed}/" not in str(p)] for cell, paths in spread.items()}
        try:
            new = compare_report(reference, candidate, n_resamples=n_resamples, spread_files=spread)
        except ValueError as err:
            raise ValueError(f"{path.name}: {err}") from None
        old_verdict = old.apply(_old_verdict, axis=1)
        frame = pd.DataFrame({
            "screen": path.stem, "candidate": m["cand"], "reference": m["ref"], "spread_from": spread_variant,
            "spread_seeds": "+".join(str(s) for s in spread_seeds if spread_variant != m["cand"] or s != seed),
            "height": new["height"], "placement": new["placement"], "metric": new["metric"],
            "difference": new["difference"], "old_ci_low": old["ci_low"], "old_ci_high": old["ci_high"],
            "old_p_holm": old["p_holm"], "old_verdict": old_verdict, "ci_low": new["ci_low"],
            "ci_high": new["ci_high"], "p_holm": new["p_holm"], "verdict": new["verdict"]})
        frame["changed"] = frame["old_verdict"] != frame["verdict"].where(frame["verdict"].isin(["higher", "lower"]),
                                                                          "no difference detected")
        frames.append(frame)
    df = pd.concat(frames, ignore_index=True)[list(REREAD_COLUMNS)] if frames else pd.DataFrame(columns=REREAD_COLUMNS)
    if out_csv is not None:
        Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
        df.to_csv(out_csv, index=False, float_format="%.6g")
    return df

"""Report entry points for the main CLI (``egosearch.cli``), which wires argparse and passes plain paths.

Each ``cmd_*`` takes explicit file lists or dicts, writes its outputs, prints one line per file
(or the comparison table) and returns what it wrote. Flat lists of evaluation CSVs are grouped by
their paths (``.../{variant}/seed{seed}/{layout}/{placement}/h{height}.csv``).
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from pathlib import Path

import pandas as pd

from egosearch.report.data import cells_from_paths, group_eval_paths, output_base, parse_eval_path, suffixed
from egosearch.report.figures import PLANNER_TITLES, figure6, figure7
from egosearch.report.pathlength import by_length_path, compare_by_length, format_by_length, pathlength_report
from egosearch.report.provenance import check_stored
from egosearch.report.spread_sides import check_screen_inputs, comparison_spreads
from egosearch.report.tables import (
    bound_names,
    compare_report,
    format_compare,
    format_stuck,
    stuck_path,
    table1,
    table2,
)

PathLike = str | os.PathLike


def _flat(groups: Iterable) -> list:
    return [p for g in groups for p in ([g] if isinstance(g, (str, os.PathLike)) else g)]


def _say(paths: Iterable[Path]) -> None:
    for p in paths:
        print(f"wrote {p}")


def group_bounds(paths: Iterable[PathLike]) -> dict[str, dict]:
    """Evaluation CSVs of the reference searchers (``.../eval/{random|frontier|...|oracle}/seed{N}/...``) ->
    ``{bound: {(seed, height, placement): [paths]}}``, every bound present (empty when not run)."""
    out: dict[str, list] = {bound: [] for bound in bound_names()}
    for path in paths:
        bound = parse_eval_path(path)["variant"]
        if bound not in out:
            names = "|".join(out)
            raise ValueError(f"{path}: not a reference searcher's evaluation (expected .../eval/{{{names}}}/...)")
        out[bound].append(path)
    return {bound: group_eval_paths(files) for bound, files in out.items()}


def cmd_table1(episode_files: Mapping | Iterable[PathLike], out_prefix: PathLike, variant: str | None = None,
               bounds: Iterable[PathLike] | None = None, learning_adds: PathLike | None = None) -> pd.DataFrame:
    """Table 1 from ``{(seed, height, placement): path(s)}`` or a flat list of one variant's evaluation CSVs;
    ``bounds`` (a list, possibly empty) of the random searcher's and the oracle's evaluation CSVs puts the
    policy between them; ``learning_adds`` (the policy against its own start, a comparison CSV) adds what
    its learning adds to the notes."""
    if not isinstance(episode_files, Mapping):
        episode_files = group_eval_paths(episode_files, variant=variant)
    df = table1(episode_files, out_prefix, bounds=None if bounds is None else group_bounds(bounds), variant=variant,
                learning_adds=learning_adds)
    base = output_base(out_prefix, "table1")
    _say(suffixed(base, e) for e in (".csv", ".md", ".tex"))
    return df


def cmd_table2(rows: Iterable[tuple[str, str]], out_prefix: PathLike,
               departures: Iterable[tuple[str, str, str, str]] = ()) -> None:
    """Table 2 from (parameter, setting) rows, e.g. ``egosearch.rl.config.table2_rows(cfg)``, and the
    preset's departures from the paper (``egosearch.rl.config.departure_rows(cfg)``)."""
    table2(rows, out_prefix, departures=departures)
    base = output_base(out_prefix, "table2")
    _say(suffixed(base, e) for e in (".md", ".tex"))


def cmd_fig6(curves: Mapping[str, Iterable[PathLike]], out_prefix: PathLike,
             labels: Mapping[str, str] | None = None, level_files: Iterable[PathLike] | None = None) -> list[Path]:
    """Figure 6 from ``{variant: [curve.csv per seed]}``; ``level_files``: the random and classical searchers'
    evaluations on the training home's cells (a horizontal line each)."""
    outs = figure6(curves, out_prefix, labels=labels, level_files=level_files)
    _say(outs)
    return outs


def cmd_fig7(fullbody_files: Iterable[PathLike], out_prefix: PathLike, planner: str = "actor") -> list[Path]:
    """Figure 7 from a list of full-body CSVs (all settings and seeds) planned by ``planner``."""
    outs = figure7(fullbody_files, out_prefix, title=PLANNER_TITLES[planner])
    _say(outs)
    return outs


def cmd_compare(reference_files: Mapping | Iterable[PathLike], candidate_files: Mapping | Iterable[PathLike],
                out_csv: PathLike | None = None, reference_name: str = "reference",
                candidate_name: str = "candidate",
                spread_files: Mapping | Iterable[PathLike] | None = None) -> pd.DataFrame:
    """Candidate vs reference per (height, placement) cell; each side a ``{cell: [paths]}`` dict or a flat
    list of one variant's evaluation CSVs. Prints the table; writes ``out_csv`` when given.

    Refuses (:class:`~egosearch.report.provenance.StoredFileError`) a stored file that differs from
    the sha256 its results folder's provenance recorded; files the record does not list (a new
    candidate's) are used as they are. ``spread_files``: every stored seed's files of the reference
    variant, whose spread a screen's test counts (docs/statistics.md); inputs that cannot be read together
    are refused first, one line each (:func:`~egosearch.report.spread_sides.check_screen_inputs`)."""
    reference_list, candidate_list = (_flat(side.values()) if isinstance(side, Mapping) else list(side)
                                      for side in (reference_files, candidate_files))
    # A file on both sides (a variant compared with itself) gives differences of 0 that read as a result.
    candidates = {Path(p).resolve() for p in candidate_list}
    both = [p for p in reference_list if Path(p).resolve() in candidates]
    if both:
        more = f" ({len(both) - 1} more file(s) too)" if len(both) > 1 else ""
        raise ValueError(f"{os.fspath(both[0])} is both a reference and a candidate file{more}: compare two "
                         "different variants (is the candidate the reference itself?)")
    spread_list = [] if spread_files is None else (
        _flat(spread_files.values()) if isinstance(spread_files, Mapping) else list(spread_files))
    if not isinstance(reference_files, Mapping):
        reference_files = cells_from_paths(reference_files)
    if not isinstance(candidate_files, Mapping):
        candidate_files = cells_from_paths(candidate_files)
    if spread_files is not None and not isinstance(spread_files, Mapping):
        spread_files = cells_from_paths(spread_files)
    if spread_files is not None:  # from the paths alone, before a file is read
        check_screen_inputs(reference_files, candidate_files, spread_files)
    check_stored([*reference_list, *candidate_list, *spread_list], require_record=False)
    # the seed spreads first: a screen against a one-seed reference is refused before any table is drawn
    spreads = comparison_spreads(reference_files, candidate_files, spread_files)
    df = compare_report(reference_files, candidate_files, out_csv, spread_files=spread_files)
    print(format_compare(df, reference_name, candidate_name))
    if out_csv is not None:
        print(f"wrote {out_csv}")
    by_csv = None if out_csv is None else by_length_path(out_csv)
    print(format_by_length(compare_by_length(reference_files, candidate_files, by_csv, spreads=spreads)))
    if by_csv is not None:
        print(f"wrote {by_csv}")
    stuck_csv = None if out_csv is None else stuck_path(out_csv)
    stuck_df = compare_report(reference_files, candidate_files, stuck_csv, metrics=("stuck",),
                              spread_files=spread_files)
    print(format_stuck(stuck_df))
    if stuck_csv is not None:
        print(f"wrote {stuck_csv}")
    return df


def cmd_pathlength(episode_files: Iterable[PathLike], scenario_files: Iterable[PathLike], success_radius: float,
                   out_prefix: PathLike, out_csv: PathLike | None = None,
                   bounds: Iterable[PathLike] = ()) -> list[Path]:
    """Success by shortest path ℓ and by detour for one variant's evaluation CSVs (and the reference
    searchers' ``bounds``), joined to the ``scenario_files`` they ran; ``success_radius`` (m) from the
    target's centre to the body's axis (the caller knows the env's)."""
    outs = pathlength_report(episode_files, scenario_files, success_radius, out_prefix, out_csv=out_csv,
                             bound_files=bounds)
    _say(outs)
    return outs

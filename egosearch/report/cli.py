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

from egosearch.report.data import _with, cells_from_paths, group_eval_paths, output_base
from egosearch.report.figures import PLANNER_TITLES, figure6, figure7
from egosearch.report.tables import compare_report, format_compare, table1, table2

PathLike = str | os.PathLike


def _say(paths: Iterable[Path]) -> None:
    for p in paths:
        print(f"wrote {p}")


def cmd_table1(episode_files: Mapping | Iterable[PathLike], out_prefix: PathLike,
               variant: str | None = None) -> pd.DataFrame:
    """Table 1 from ``{(seed, height, placement): path(s)}`` or a flat list of one variant's evaluation CSVs."""
    if not isinstance(episode_files, Mapping):
        episode_files = group_eval_paths(episode_files, variant=variant)
    df = table1(episode_files, out_prefix)
    base = output_base(out_prefix, "table1")
    _say(_with(base, e) for e in (".csv", ".md", ".tex"))
    return df


def cmd_table2(rows: Iterable[tuple[str, str]], out_prefix: PathLike) -> None:
    """Table 2 from (parameter, setting) rows, e.g. ``egosearch.rl.config.table2_rows(cfg)``."""
    table2(rows, out_prefix)
    base = output_base(out_prefix, "table2")
    _say(_with(base, e) for e in (".md", ".tex"))


def cmd_fig6(curves: Mapping[str, Iterable[PathLike]], out_prefix: PathLike,
             labels: Mapping[str, str] | None = None) -> list[Path]:
    """Figure 6 from ``{variant: [curve.csv per seed]}``."""
    outs = figure6(curves, out_prefix, labels=labels)
    _say(outs)
    return outs


def cmd_fig7(fullbody_files: Iterable[PathLike], out_prefix: PathLike, planner: str = "actor") -> list[Path]:
    """Figure 7 from a list of full-body CSVs (all settings and seeds) planned by ``planner``."""
    outs = figure7(fullbody_files, out_prefix, title=PLANNER_TITLES[planner])
    _say(outs)
    return outs


def cmd_compare(reference_files: Mapping | Iterable[PathLike], candidate_files: Mapping | Iterable[PathLike],
                out_csv: PathLike | None = None, reference_name: str = "reference",
                candidate_name: str = "candidate") -> pd.DataFrame:
    """Candidate vs reference per (height, placement) cell; each side a ``{cell: [paths]}`` dict or a flat
    list of one variant's evaluation CSVs. Prints the table; writes ``out_csv`` when given."""
    if not isinstance(reference_files, Mapping):
        reference_files = cells_from_paths(reference_files)
    if not isinstance(candidate_files, Mapping):
        candidate_files = cells_from_paths(candidate_files)
    df = compare_report(reference_files, candidate_files, out_csv)
    print(format_compare(df, reference_name, candidate_name))
    if out_csv is not None:
        print(f"wrote {out_csv}")
    return df

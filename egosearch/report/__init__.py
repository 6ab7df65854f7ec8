"""The report layer: stored CSVs and JSON in; tables, figures, studies and the docs' generated blocks out.
Imports: core, scene, searchers.
Imported by: cli, cost, workflow, Snakefile.
Packages: matplotlib, numpy, pandas, scipy, yaml.
Never torch, the simulator or gymnasium: scene only where ``searches`` draws a home, searchers only its registry
(the names, labels and bound rows of the searchers). The CLI passes Table 2's rows in; the Snakefile's rules and
the workflow read ``workflow_jobs`` (the bound files in the DAG's order), the cost model its config readers and
job costs and ``data``'s reading of a stored training.
"""

from egosearch.report.data import (
    cells_from_paths,
    group_eval_paths,
    parse_eval_path,
    read_curves,
    read_episodes,
    read_fullbody,
)
from egosearch.report.figures import fig6, fig7, figure6, figure6_frame, figure7, figure7_frame
from egosearch.report.stats import bootstrap_ci, compare_cells, holm, wilson_ci
from egosearch.report.tables import PAPER_TABLE1, compare_report, format_compare, table1, table1_frame, table2

__all__ = [
    "PAPER_TABLE1", "bootstrap_ci", "fig6", "fig7", "cells_from_paths", "compare_cells", "compare_report", "figure6",
    "figure6_frame", "figure7", "figure7_frame", "format_compare", "group_eval_paths", "holm", "parse_eval_path",
    "read_curves", "read_episodes", "read_fullbody", "table1", "table1_frame", "table2", "wilson_ci",
]

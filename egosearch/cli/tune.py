"""``egosearch tune``: the tuned frontier searcher's tuning, run again (egosearch.runs.teacher_tuning)."""

from __future__ import annotations

from egosearch.cli.checks import at_least
from egosearch.core.outputs import check_outputs, check_overwrites
from egosearch.runs.teacher_tuning import summary_line, tune


def run(args) -> None:
    check_outputs(dirs={"--out": args.out})
    check_overwrites(dirs={"--out": args.out}, force=args.force)
    at_least("--limit", args.limit, 0, "scenarios of each cell (0: all)")
    record = tune(args.out, limit=args.limit or None)
    print(summary_line(record))
    print(f"wrote {args.out}/record.json")

"""``egosearch <command>``: the entry points users and the Snakefile call.
Imports every stage, each only when its command runs; nothing in the package imports it.

One module per command (``egosearch/cli/<command>.py``, with ``run(args)``) and its parser in
:mod:`egosearch.cli.parsers`; ``main`` imports only the command that runs.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from pathlib import Path

from egosearch.cli import parsers
from egosearch.sim import rasterbuild

COMMANDS = ("scenarios", "evaluate", "train", "demos", "variant", "fullbody", "bench", "estimate", "video", "report",
            "pictures")
"""In the order ``egosearch --help`` lists them; each has ``parsers.add_<command>`` and a module."""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="egosearch", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    for command in COMMANDS:
        getattr(parsers, f"add_{command}")(sub)
    return parser


NOTICE_MARKER = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "egosearch" / "raster-noted"
"""Remembers that this machine was told its install has no C rasteriser (said once, by the first command)."""


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    notice = rasterbuild.notice_once(NOTICE_MARKER)
    if notice:
        print(notice, file=sys.stderr)
    try:
        # local: a command's module loads what it runs (torch, the simulator), so `--help` and the
        # report commands start in a fraction of a second
        importlib.import_module(f"egosearch.cli.{args.command}").run(args)
    except (ValueError, FileNotFoundError) as err:
        # Bad input gets one line, not a traceback.
        print(f"egosearch {args.command}: error: {err}", file=sys.stderr)
        return 2
    return 0



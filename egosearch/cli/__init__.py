"""``egosearch <command>``: the entry points users and the Snakefile call.
Imports: core, cost, envs, motion, report, rl, runs, scene, searchers, sim, variants, workflow.
Imported by: nothing.
Packages: pandas, torch.
Each stage is imported only when its command runs.

One module per command (``egosearch/cli/<command>.py``, with ``run(args)``) and its parser in
:mod:`egosearch.cli.parsers`; ``main`` imports only the command that runs.
"""

from __future__ import annotations

import argparse
import difflib
import importlib
import os
import sys
from pathlib import Path

from egosearch.cli import parsers
from egosearch.sim import rasterbuild

COMMANDS = ("scenarios", "evaluate", "train", "demos", "tune", "variant", "config", "fullbody", "bench", "estimate",
            "video", "report", "pictures")
"""In the order ``egosearch --help`` lists them; each has ``parsers.add_<command>`` and a module, named as the
command unless :data:`COMMAND_MODULES` names another."""
COMMAND_MODULES = {"report": "report_commands"}
"""A command's module whose name would be a package's of the suite: ``egosearch.cli.report`` read as
``egosearch.report``, the package that writes the tables, which these commands call."""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="egosearch", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    for command in COMMANDS:
        getattr(parsers, f"add_{command}")(sub)
    return parser


NOTICE_MARKER = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "egosearch" / "raster-noted"
"""Remembers that this machine was told its install has no C rasteriser (said once, by the first command)."""


TRACES = ("`egosearch evaluate --traces FILE.npz` writes a search's every step; `egosearch report behaviour` and "
          "`egosearch report searches` read them (the workflow's targets: `snakemake --cores 2 behaviour searches`)")
"""Where the per-step traces are, for a user who types ``egosearch traces``: no command or rule has that name."""


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    return next((a.choices for a in parser._actions if isinstance(a, argparse._SubParsersAction)), {})


def misplaced_command(argv: list[str]) -> str | None:
    """One line for a command word that is no command where it stands but is one elsewhere: a report typed
    as a command (``egosearch generalise``: ``egosearch report generalise``), a command typed as a report,
    a workflow target, or a near miss; None when the word is a command, or nothing is near it (argparse's
    own line lists the choices)."""
    commands = _subcommands(build_parser())
    reports = _subcommands(commands["report"])
    if not argv or argv[0].startswith("-"):
        return None
    if argv[0] in commands:
        if argv[0] != "report" or len(argv) < 2 or argv[1].startswith("-") or argv[1] in reports:
            return None
        word, where, here, elsewhere = argv[1], "a report", reports, {w: f"egosearch {w}" for w in commands}
    else:
        word, where, here, elsewhere = argv[0], "a command", commands, {w: f"egosearch report {w}" for w in reports}
    # local: the workflow's rule names are read from its files, only for a word that is no command
    from egosearch.workflow.dag import rule_names

    if word in ("trace", "traces"):
        return f"{word!r} is not {where}: {TRACES}"
    spelled = {w: f"egosearch {'report ' if here is reports else ''}{w}" for w in here}
    targets = {w: f"snakemake --cores 2 {w}" for w in rule_names()}
    if word in elsewhere or word in targets:
        hints = ([f"it is `{elsewhere[word]}`"] if word in elsewhere else []) + (
            [f"the workflow's target `{targets[word]}`"] if word in targets else [])
        return f"{word!r} is not {where}; {', or '.join(hints)}"
    close = difflib.get_close_matches(word, [*spelled, *elsewhere, *targets], n=1)
    if not close:
        return None
    return f"{word!r} is not {where}; did you mean `{({**targets, **elsewhere, **spelled})[close[0]]}`?"


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    hint = misplaced_command(argv)
    if hint:
        print(f"egosearch: error: {hint}", file=sys.stderr)
        return 2
    args = build_parser().parse_args(argv)
    if parsers.uses_old_preset_flag(argv):
        print(parsers.OLD_PRESET_NOTE, file=sys.stderr)
    notice = rasterbuild.notice_once(NOTICE_MARKER)
    if notice:
        print(notice, file=sys.stderr)
    try:
        # local: a command's module loads what it runs (torch, the simulator), so `--help` and the
        # report commands start in a fraction of a second
        importlib.import_module(f"egosearch.cli.{COMMAND_MODULES.get(args.command, args.command)}").run(args)
    except (ValueError, FileNotFoundError) as err:
        # Bad input gets one line, not a traceback.
        print(f"egosearch {args.command}: error: {err}", file=sys.stderr)
        return 2
    return 0



"""Output paths are checked before any work: an evaluation that runs every episode and then cannot
write its CSV has wasted the run, so each command checks every path it will write first.

The check creates nothing: it finds the nearest folder that exists on the way to each path and
writes (then removes) a probe file there, which is the only test that also holds for root, for
read-only file systems and for pseudo file systems such as /proc.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Mapping
from pathlib import Path

PathLike = str | os.PathLike


class OutputPathError(ValueError):
    """An output path that cannot be written: the message names the option and the path."""


def _named(option: str, shown: str) -> str:
    """``--out=x.csv`` for an option, ``the figures folder paper_figs/cpu`` for a fixed output."""
    return f"{option}={shown}" if option.startswith("-") else f"{option} {shown}"


def _nearest_existing(path: Path) -> Path:
    for candidate in (path, *path.parents):
        if candidate.exists():
            return candidate
    return Path(".")


def _check_folder_can_hold(option: str, shown: str, folder: Path) -> None:
    """``folder`` is, or can be created as, a folder this process may write into."""
    existing = _nearest_existing(folder)
    if not existing.is_dir():
        raise OutputPathError(f"{_named(option, shown)}: {existing} is a file, so no folder can be created under it")
    try:
        fd, probe = tempfile.mkstemp(prefix=".egosearch-write-probe-", dir=existing)
    except OSError as err:
        reason = err.strerror or type(err).__name__
        raise OutputPathError(f"{_named(option, shown)}: cannot write in {existing} ({reason})") from None
    os.close(fd)
    os.unlink(probe)


def check_outputs(files: Mapping[str, PathLike | None] | None = None,
                  dirs: Mapping[str, PathLike | None] | None = None,
                  prefixes: Mapping[str, PathLike | None] | None = None) -> None:
    """Raise :class:`OutputPathError` (one line) unless every output can be written. Each mapping
    is ``{option name: path}`` (a None path is an option not given; a name without a leading dash
    describes a fixed output, e.g. ``"the figures folder"``): ``files`` are written as files,
    ``dirs`` are folders a command writes into, ``prefixes`` are report prefixes (a folder when it
    exists as one or ends in a separator, else the stem of the files written beside it)."""
    for option, raw in (files or {}).items():
        if raw is None:
            continue
        path, shown = Path(raw), os.fspath(raw)
        if os.fspath(raw).endswith(("/", os.sep)) or path.is_dir():
            raise OutputPathError(f"{_named(option, shown)} is a folder; a file path is expected here")
        _check_folder_can_hold(option, shown, path.parent)
    for option, raw in (dirs or {}).items():
        if raw is None:
            continue
        path, shown = Path(raw), os.fspath(raw)
        if path.exists() and not path.is_dir():
            raise OutputPathError(f"{_named(option, shown)} is a file; a folder is expected here")
        _check_folder_can_hold(option, shown, path)
    for option, raw in (prefixes or {}).items():
        if raw is None:
            continue
        path, shown = Path(raw), os.fspath(raw)
        folder = path if (shown.endswith(("/", os.sep)) or path.is_dir()) else path.parent
        _check_folder_can_hold(option, shown, folder)

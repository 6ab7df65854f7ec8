"""Output paths are checked before any work: an evaluation that runs every episode and then cannot
write its CSV has wasted the run, so each command checks every path it will write first.

The check creates nothing: it finds the nearest folder that exists on the way to each path and
writes (then removes) a probe file there, which is the only test that also holds for root, for
read-only file systems and for pseudo file systems such as /proc.

It also refuses to overwrite what is kept (:func:`check_overwrites`): an output that is one of the
command's own inputs, and, unless ``--force``, a stored result. A stored result is a file under
``results/`` or ``paper_figs/`` that git tracks, or, where there is no git checkout to ask (an
unpacked archive, git not installed), one that ``results/<preset>/provenance.json`` lists (and, in
``paper_figs/``, any file beside a results folder that holds such a record). A file that does not
exist yet is never a stored result.
"""

from __future__ import annotations

import json
import os
import subprocess
import tempfile
from collections.abc import Iterable, Mapping
from pathlib import Path

PathLike = str | os.PathLike

STORED_ROOTS = ("results", "paper_figs")
"""The folders of a checkout whose tracked files are the stored results."""


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


# --------------------------------------------------------------------------- what must not be overwritten
def _as_list(value) -> list[PathLike]:
    if value is None:
        return []
    if isinstance(value, (str, os.PathLike)):
        return [value]
    return [v for v in value if v is not None]


def _same_file(a: Path, b: Path) -> bool:
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)  # hard links too
    except OSError:
        return False


def _split_stored_root(path: Path) -> tuple[Path, str] | None:
    """(the checkout holding it, its path from there) for a path inside a ``results/`` or
    ``paper_figs/`` folder; None for any other path. The last such folder on the way counts, so that a
    checkout kept under someone's ``results/`` folder still finds its own."""
    parts = path.parts
    for i in range(len(parts) - 2, 0, -1):
        if parts[i] in STORED_ROOTS:
            return Path(*parts[:i]), Path(*parts[i:]).as_posix()
    return None


def _git_tracked(root: Path, rels: list[str]) -> set[str] | None:
    """The files git tracks among ``rels`` (files, or folders: every tracked file under them), paths
    from ``root``; None when ``root`` is not in a git checkout or git cannot be run."""
    try:
        out = subprocess.run(["git", "--literal-pathspecs", "-C", str(root), "ls-files", "-z", "--", *rels],
                             capture_output=True, timeout=60)
    except (OSError, subprocess.SubprocessError):
        return None
    if out.returncode != 0:
        return None
    return {name for name in out.stdout.decode("utf-8", "surrogateescape").split("\0") if name}


def _provenance_listed(root: Path, rels: list[str]) -> set[str]:
    """Without git: the files among ``rels`` that a ``results/<preset>/provenance.json`` vouches
    for, and every existing file under ``paper_figs/`` when some results folder holds such a record."""
    recorded: dict[str, set[str]] = {}
    for record in sorted((root / "results").glob("*/provenance.json")):
        try:
            files = json.loads(record.read_text(encoding="utf-8")).get("files")
        except (OSError, ValueError, AttributeError):
            continue
        if isinstance(files, dict):
            recorded[record.parent.name] = set(files)
    out = set()
    for rel in rels:
        parts = Path(rel).parts
        under = [rel] if (root / rel).is_file() else [p.relative_to(root).as_posix()
                                                      for p in sorted((root / rel).rglob("*")) if p.is_file()]
        for name in under:
            names = Path(name).parts
            if parts[0] == "results" and len(names) > 2 and Path(*names[2:]).as_posix() in recorded.get(names[1], ()):
                out.add(name)
            elif parts[0] == "paper_figs" and recorded:
                out.add(name)
    return out


def stored_results(paths: Iterable[PathLike]) -> dict[Path, tuple[Path, str]]:
    """``{path: (a stored file it is or holds, how that is known)}`` for each of ``paths`` (files or
    folders) that is, or holds, a stored result (see the module docstring)."""
    by_root: dict[Path, list[tuple[Path, str]]] = {}
    for path in map(Path, paths):
        if not path.exists():
            continue
        for form in dict.fromkeys((Path(os.path.abspath(path)), Path(os.path.realpath(path)))):
            split = _split_stored_root(form)
            if split is not None:
                by_root.setdefault(split[0], []).append((path, split[1]))
    found: dict[Path, tuple[Path, str]] = {}
    for root, items in by_root.items():
        rels = list(dict.fromkeys(rel for _, rel in items))
        tracked = _git_tracked(root, rels)
        how = "tracked by git"
        if tracked is None:
            tracked = _provenance_listed(root, rels)
            how = "listed in the results' provenance.json"
        for path, rel in items:
            hits = sorted(t for t in tracked if t == rel or t.startswith(rel.rstrip("/") + "/"))
            if hits and path not in found:
                found[path] = (root / hits[0], how + (f"; {len(hits) - 1} more there" if len(hits) > 1 else ""))
    return found


def check_overwrites(files: Mapping[str, PathLike | Iterable[PathLike] | None] | None = None,
                     dirs: Mapping[str, PathLike | None] | None = None,
                     inputs: Mapping[str, PathLike | Iterable[PathLike] | None] | None = None,
                     prefixes: Mapping[str, tuple[PathLike | None, Iterable[PathLike]]] | None = None,
                     force: bool = False) -> None:
    """Raise :class:`OutputPathError` (one line) when a command would overwrite what it must not.

    ``files``: ``{option: the file(s) it writes}``; ``prefixes``: ``{option: (its value, the files
    it writes)}``; ``dirs``: ``{option: a folder it writes into}``; ``inputs``: ``{option or what
    they are: the file(s) it reads}``. An output that is an input, or that another option writes
    too, is refused whatever ``force`` says: the command would read or write a file it is
    rewriting. A file that exists and is a stored result, or a folder that holds one, is refused
    unless ``force`` (the DAG's own jobs pass ``--force``)."""
    outputs: list[tuple[str, str, Path]] = []  # (option, how the output is named in a message, a file)
    for option, value in (files or {}).items():
        outputs += [(option, _named(option, os.fspath(p)), Path(p)) for p in _as_list(value)]
    for option, (prefix, written) in (prefixes or {}).items():
        if prefix is not None:
            outputs += [(option, f"{_named(option, os.fspath(prefix))} writes {os.fspath(p)}, which", Path(p))
                        for p in written]
    reads = [(source, Path(p)) for source, value in (inputs or {}).items() for p in _as_list(value)]
    for _, named, out in outputs:
        for source, path in reads:
            if _same_file(out, path):
                raise OutputPathError(f"{named} is also an input ({source}): a command never writes over its own "
                                      "input; choose another output path")
    for i, (option, named, out) in enumerate(outputs):
        for other, _, path in outputs[:i]:
            if other != option and _same_file(out, path):
                raise OutputPathError(f"{named} is also written by {other}: give each output its own path")
    if force:
        return
    folders = [(option, Path(p)) for option, p in (dirs or {}).items() if p is not None]
    stored = stored_results([out for _, _, out in outputs] + [p for _, p in folders])
    for _, named, out in outputs:
        if out in stored:
            raise OutputPathError(f"{named} is a stored result ({stored[out][1]}); pass --force to overwrite it, "
                                  "or write elsewhere")
    for option, folder in folders:
        if folder in stored:
            hit, how = stored[folder]
            raise OutputPathError(f"{_named(option, os.fspath(folder))} holds stored results ({_shown(hit)}, {how}), "
                                  "which this command may overwrite; pass --force to overwrite them, or write "
                                  "elsewhere")


def _shown(path: Path) -> str:
    try:
        return Path(os.path.abspath(path)).relative_to(Path.cwd()).as_posix()
    except ValueError:
        return os.fspath(path)

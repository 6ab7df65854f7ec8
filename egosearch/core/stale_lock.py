"""Snakemake's lock of a run that was killed: removed when no snakemake process runs here any more.

A run killed by SIGKILL (or a power loss) leaves ``.snakemake/locks/`` behind, and the next run of
the same command stops with "Directory cannot be locked" until ``snakemake --unlock``. The
Snakefile calls :func:`clear_stale_locks` in the main process so that rerunning the command is
enough. A lock stays whenever another snakemake process, of this user or not, has this folder as
its working directory; a run on another machine sharing the folder is not seen (run one at a time
there, or keep ``--unlock`` for it).
"""

from __future__ import annotations

import os
from pathlib import Path


def _ancestors(pid: int) -> set[int]:
    out = set()
    while pid > 1 and pid not in out:
        out.add(pid)
        try:
            stat = Path(f"/proc/{pid}/stat").read_text()
        except OSError:
            break
        pid = int(stat.rsplit(")", 1)[1].split()[1])  # the field after the state: the parent's pid
    return out


def snakemake_running_in(workdir: str | os.PathLike, ignore: set[int] = frozenset()) -> bool:
    """Whether a snakemake process other than ``ignore`` has ``workdir`` as working directory."""
    cwd = Path(workdir).resolve()
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit() or int(entry.name) in ignore:
            continue
        try:
            argv = (entry / "cmdline").read_bytes().split(b"\0")[:3]
            if any(b"snakemake" in arg for arg in argv) and Path(os.readlink(entry / "cwd")).resolve() == cwd:
                return True
        except OSError:  # gone meanwhile, or not ours to read
            continue
    return False


def clear_stale_locks(workdir: str | os.PathLike = ".") -> list[Path]:
    """Remove Snakemake's lock files under ``workdir`` if no other snakemake process runs there;
    return the removed files (none without /proc: then nothing can be told, and nothing is removed)."""
    locks = Path(workdir) / ".snakemake" / "locks"
    files = sorted(locks.glob("*.lock")) if locks.is_dir() else []
    if not files or not Path("/proc/self").exists():
        return []
    if snakemake_running_in(workdir, ignore=_ancestors(os.getpid())):
        return []
    for path in files:
        path.unlink(missing_ok=True)
    return files

"""Two runs in one clone never race: the suite's own record of the runs in progress.

Snakemake locks the outputs of a run in ``.snakemake/locks``, but a run that ends removes that whole folder, the
lock of a run still going included (seen with Snakemake 9.27: a second, non-overlapping run ended, and a third,
identical to the first, then ran the same jobs beside it). So each real run of the suite also records itself here,
in its own folder, one file per run: its process id, its command and the files its plan writes. Before its first
job a run reads the others' records; one whose process still lives and whose plan writes a file this plan writes
too is a race: the run refuses in one line naming that command. A record is removed when its run ends, and a
record whose process is gone (a run killed by SIGKILL) is ignored and removed. The check and the write happen
under an exclusive file lock, so two runs started together cannot both pass.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import shlex
from collections.abc import Iterable
from pathlib import Path

RUNS_DIR = Path(".snakemake") / "egosearch_runs"
"""Where the records lie, relative to the clone (``.snakemake/`` is git-ignored; Snakemake's own lock folder is
``.snakemake/locks``, which this is not)."""


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process: alive
        return True
    return True


@contextlib.contextmanager
def _exclusive(folder: Path):
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / ".lock", "a+") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def live_runs(root: str | os.PathLike = ".") -> list[dict]:
    """The records of runs whose processes still live; the records of dead ones are removed."""
    folder = Path(root) / RUNS_DIR
    runs = []
    for path in sorted(folder.glob("*.json")):
        try:
            record = json.loads(path.read_text(encoding="utf-8"))
            pid = int(record["pid"])
        except (OSError, ValueError, KeyError, TypeError):
            continue
        if _alive(pid):
            runs.append(record)
        else:
            path.unlink(missing_ok=True)
    return runs


def claim(outputs: Iterable[str], command: Iterable[str], root: str | os.PathLike = ".",
          pid: int | None = None) -> str | None:
    """Record this run (its ``outputs``, the files its plan writes, and its ``command``) unless a live run's plan
    writes one of them too; then return the one-line refusal instead and record nothing."""
    folder = Path(root) / RUNS_DIR
    pid = os.getpid() if pid is None else int(pid)
    mine = sorted({os.path.normpath(str(f)) for f in outputs})
    with _exclusive(folder):
        for other in live_runs(root):
            if int(other["pid"]) == pid:
                continue
            shared = sorted(set(mine) & set(other.get("outputs", [])))
            if shared:
                more = f" and {len(shared) - 1} more" if len(shared) > 1 else ""
                return (f"refusing to start: another snakemake in this clone (pid {other['pid']}: "
                        f"`{other.get('command', '?')}`) is making {shared[0]}{more}; wait for it to end, or stop it "
                        "and rerun this command")
        record = {"pid": pid, "command": shlex.join(list(command)), "outputs": mine}
        (folder / f"{pid}.json").write_text(json.dumps(record), encoding="utf-8")
    return None


def release(root: str | os.PathLike = ".", pid: int | None = None) -> None:
    """Remove this run's record (its run ends)."""
    pid = os.getpid() if pid is None else int(pid)
    (Path(root) / RUNS_DIR / f"{pid}.json").unlink(missing_ok=True)

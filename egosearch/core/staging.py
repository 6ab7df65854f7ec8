"""A finished run's files appear in their final folder only once the run is complete.

Snakemake takes a declared output that exists as done unless it marked the job incomplete, and it
deletes the outputs of an incomplete job before rerunning it. A training that writes curve.csv as it
goes therefore loses, when it is killed, the rows its checkpoint expects, and cannot resume. So the
DAG trains in a work folder that Snakemake does not know about (the checkpoint and the partial CSVs
survive a kill there) and publishes the files when the run is done.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

LAST = "done.json"
"""Published last: its presence in the final folder means every other file is there."""
CHECKPOINT_NAME = Path("ckpt") / "train_state.ckpt"
"""The resumable state inside a run's folder (``*.ckpt`` is git-ignored: it holds the replay)."""
START_ACTOR_NAME = "actor_start.pt"
"""The run's policy at step 0, beside ``actor.pt`` (:meth:`egosearch.rl.train.LiveRun.write_start_actor`)."""


def _copy_atomic(src: Path, dest: Path) -> None:
    tmp = dest.with_name(f".tmp{os.getpid()}.{dest.name}")
    shutil.copyfile(src, tmp)
    with open(tmp, "rb") as f:
        os.fsync(f.fileno())
    os.replace(tmp, dest)


def publish_run(work_dir: str | os.PathLike, out_dir: str | os.PathLike) -> list[Path]:
    """Copy the finished run's files (the top level of ``work_dir``) into ``out_dir``, each by an
    atomic rename and ``done.json`` last, then remove ``work_dir``. Killed half-way, it leaves the
    work folder whole, so running it again completes the copy."""
    work, out = Path(work_dir), Path(out_dir)
    if not (work / LAST).is_file():
        raise ValueError(f"{work} holds no finished run ({LAST} is missing): nothing to publish")
    out.mkdir(parents=True, exist_ok=True)
    files = sorted((p for p in work.iterdir() if p.is_file() and not p.name.startswith(".")),
                   key=lambda p: (p.name == LAST, p.name))
    for src in files:
        _copy_atomic(src, out / src.name)
    shutil.rmtree(work)
    return [out / p.name for p in files]

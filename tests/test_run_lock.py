"""Two runs in one clone never race: the suite's own record of the runs in progress (egosearch.workflow.run_lock)."""

from __future__ import annotations

import subprocess
import sys

from egosearch.workflow.run_lock import RUNS_DIR, claim, live_runs, release


def test_a_run_whose_plan_overlaps_a_live_one_is_refused_and_a_disjoint_or_dead_one_is_not(tmp_path):
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        assert claim(["results/a.csv", "results/b.csv"], ["snakemake", "table1"], tmp_path, pid=sleeper.pid) is None
        line = claim(["results/b.csv", "results/c.csv"], ["snakemake", "-R", "table1"], tmp_path, pid=12345678)
        assert line == (f"refusing to start: another snakemake in this clone (pid {sleeper.pid}: `snakemake table1`) "
                        "is making results/b.csv; wait for it to end, or stop it and rerun this command")
        assert not (tmp_path / RUNS_DIR / "12345678.json").exists()  # a refused run records nothing
        # a run making other files goes ahead beside it, and is recorded
        assert claim(["results/d.csv"], ["snakemake", "fig6"], tmp_path, pid=os_pid()) is None
        assert {r["pid"] for r in live_runs(tmp_path)} == {sleeper.pid, os_pid()}
        release(tmp_path, pid=os_pid())
        # Snakemake's own lock folder removed by another run's end changes nothing here
        (tmp_path / ".snakemake" / "locks").mkdir(parents=True, exist_ok=True)
        subprocess.run(["rm", "-rf", str(tmp_path / ".snakemake" / "locks")], check=True)
        assert claim(["results/a.csv"], ["snakemake", "all"], tmp_path, pid=12345678) is not None
    finally:
        sleeper.kill()
        sleeper.wait()
    # its process gone (killed with SIGKILL: no release), its record no longer holds anyone back
    assert claim(["results/a.csv"], ["snakemake", "all"], tmp_path, pid=12345678) is None
    assert live_runs(tmp_path) == []  # both processes gone: their records removed
    assert not list((tmp_path / RUNS_DIR).glob("*.json"))


def os_pid() -> int:
    import os

    return os.getpid()

"""Nothing stored is lost by a failed or forced job: a redo that fails leaves every stored file as it was, and the
console says why in one line (issue: a newcomer's fourth round, item 1)."""

from __future__ import annotations

import hashlib
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from egosearch.workflow.failures import failed_job_lines, failed_jobs

REPO = Path(__file__).resolve().parent.parent


def test_a_failed_jobs_reason_is_read_from_its_own_log(tmp_path):
    """The Snakemake log names the failed rule and its log; the line printed is that log's last line."""
    job_log = tmp_path / "table1.log"
    job_log.write_text("progress 10%\rprogress 100%\negosearch report: error: 151 (scenario, seed) pair(s) missing\n")
    main_log = tmp_path / "run.log"
    main_log.write_text("Error in rule table1:\n    message: None\n    jobid: 0\n    output: a.csv\n"
                        f"    log: {job_log} (check log file(s) for error details)\n    shell:\n        egosearch ...\n"
                        "Error in rule compare:\n    jobid: 3\n")
    assert failed_jobs(main_log.read_text()) == [("table1", [str(job_log)]), ("compare", [])]
    assert failed_job_lines(str(main_log)) == [
        f"rule table1 failed: egosearch report: error: 151 (scenario, seed) pair(s) missing (log: {job_log})",
        "rule compare failed"]


def _copy(dest: Path, record: bool) -> Path:
    """The workflow, the variants and the stored files table1 and compare read: a clone's, without the rest;
    ``record``: with the results' provenance record too."""
    shutil.copy2(REPO / "Snakefile", dest / "Snakefile")
    for name in ("egosearch/workflow", "ablations", "profiles", "paper_figs/cpu", "results/cpu/scenarios",
                 "results/cpu/compare", "results/cpu/bench"):
        if (REPO / name).is_dir():
            shutil.copytree(REPO / name, dest / name)
    for name in ("head_on", "head_off", "random", "oracle", "frontier", "frontier_head_off", "frontier_tuned",
                 "frontier_tuned_head_off"):
        shutil.copytree(REPO / "results/cpu/eval" / name, dest / "results/cpu/eval" / name,
                        ignore=shutil.ignore_patterns("generated_*"))
    if record:
        shutil.copy2(REPO / "results/cpu/provenance.json", dest / "results/cpu/provenance.json")
    return dest


def _digests(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for folder in ("paper_figs", "results/cpu/compare") for p in sorted((root / folder).rglob("*"))
            if p.is_file()}


@pytest.mark.slow
@pytest.mark.parametrize("target, record", [(["table1", "-R", "table1"], False),
                                            (["compare", "--config", "variant=head_off", "-R", "compare"], True)],
                         ids=["table1-job-fails", "compare-refused-at-start"])
def test_a_forced_redo_of_damaged_inputs_keeps_every_stored_file_and_says_why(tmp_path, target, record):
    """A stored evaluation truncated, then the redo the suite's own hints suggest (`-R`). Where the results have
    their provenance record, the run refuses before its first job, in one line naming the file and
    `git checkout -- FILE`; without it the job runs and fails, and every file it would have replaced is restored
    (its outputs are update(): Snakemake removed them before), its own reason the console's line. Either way every
    stored table, figure and comparison is byte for byte what it was."""
    suite = _copy(tmp_path, record)
    before = _digests(suite)
    damaged = suite / "results/cpu/eval/head_on/seed1/kitchen_living/everywhere/h1.05.csv"
    damaged.write_text("\n".join(damaged.read_text().splitlines()[:50]) + "\n")
    out = subprocess.run(["nice", "-n", "19", sys.executable, "-m", "snakemake", "--cores", "1", *target],
                         cwd=suite, capture_output=True, text=True, timeout=900)
    said = out.stdout + out.stderr
    assert out.returncode != 0, said[-3000:]
    assert _digests(suite) == before
    if record:
        refusals = [line for line in said.splitlines() if line.startswith("refusing to start: ")]
        assert len(refusals) == 1 and "was truncated" in refusals[0], said[-3000:]
        assert "git checkout -- results/cpu/eval/head_on/seed1/kitchen_living/everywhere/h1.05.csv" in refusals[0]
        assert f"rule {target[0]}:" not in said  # refused before any job
    else:
        reasons = [line for line in said.splitlines() if line.startswith(f"rule {target[0]} failed: ")]
        assert reasons and "missing" in reasons[0], said[-3000:]

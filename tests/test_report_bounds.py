"""Table 1 and Figure 6 read against the random searcher and the privileged oracle; Figure 7 says
when every bar is 0."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from egosearch.report.data import FULLBODY_COLUMNS
from egosearch.report.figures import ALL_ZERO_NOTE, figure7, figure7_figure, figure7_frame
from egosearch.report.stats import two_level_ci


def _fullbody(root: Path, spl_of) -> list[Path]:
    """One seed of 4 scenarios per setting; ``spl_of(method, M)`` is every episode's SPL."""
    paths = []
    for method, M in [("one_step_short", 1), ("noisy_search", 1), ("ours", 5), ("ours", 20)]:
        spl = spl_of(method, M)
        rows = [dict(zip(FULLBODY_COLUMNS, (i, method, "humanoid_phase", M, 20, int(spl > 0), 100, 5.0, 4.0, spl,
                                            100 // M, 0, 0.1, 3))) for i in range(4)]
        path = root / f"{method}-M{M}" / "seed0.csv"
        path.parent.mkdir(parents=True)
        pd.DataFrame(rows).to_csv(path, index=False)
        paths.append(path)
    return paths


def _texts(fig) -> list[str]:
    return [t.get_text() for ax in fig.axes for t in ax.texts]


def test_figure7_says_so_when_every_bar_is_zero(tmp_path):
    zero = _fullbody(tmp_path / "zero", lambda method, M: 0.0)
    assert ALL_ZERO_NOTE in _texts(figure7_figure(figure7_frame(zero, n_resamples=50)))
    png, _pdf, _csv = figure7(zero, tmp_path / "fig7", n_resamples=50)
    assert png.stat().st_size > 10_000
    # One bar above 0 is a plot to read, not an empty one.
    some = _fullbody(tmp_path / "some", lambda method, M: 0.5 if M == 20 else 0.0)
    assert ALL_ZERO_NOTE not in _texts(figure7_figure(figure7_frame(some, n_resamples=50)))


EPISODE_COLUMNS = ("scenario_id", "success", "steps", "path_length", "shortest_path", "spl", "collisions",
                   "episode_return")


def _eval_csv(root: Path, who: str, placement: str, height: float, successes: list[int], seed: int = 0) -> Path:
    path = root / "eval" / who / f"seed{seed}" / "home" / placement / f"h{height:g}.csv"
    path.parent.mkdir(parents=True, exist_ok=True)
    pd.DataFrame([dict(zip(EPISODE_COLUMNS, (i, s, 10, 4.0, 2.0, 0.5 * s, 0, -1.0)))
                  for i, s in enumerate(successes)]).to_csv(path, index=False)
    return path


def test_table1_puts_the_policy_between_the_random_searcher_and_the_oracle(tmp_path):
    from egosearch.report.commands import cmd_table1

    cells = [("everywhere", 1.05), ("no_low_cabinets", 1.05)]
    ours = [_eval_csv(tmp_path, "head_on", pl, h, [1, 0, 0, 0], seed) for pl, h in cells for seed in (0, 1)]
    rand = [_eval_csv(tmp_path, "random", pl, h, [0, 0, 0, 1, 0]) for pl, h in cells]
    oracle = [_eval_csv(tmp_path, "oracle", "everywhere", 1.05, [1, 1, 1, 1, 0])]   # one cell only
    df = cmd_table1(ours, tmp_path / "out" / "table1", variant="head_on", bounds=rand + oracle).set_index("placement")
    # 2 of 8 pooled episodes for ours, 1 of 5 for random, 4 of 5 for the oracle
    assert df.loc["everywhere", "success_rate"] == 0.25
    assert df.loc["everywhere", "random_success_rate"] == 0.2 and df.loc["everywhere", "random_n_episodes"] == 5
    assert df.loc["everywhere", "oracle_success_rate"] == 0.8 and df.loc["everywhere", "oracle_spl"] == 0.4
    assert df.loc["no_low_cabinets", "oracle_n_episodes"] == 0 and pd.isna(df.loc["no_low_cabinets",
                                                                                  "oracle_success_rate"])
    md = (tmp_path / "out" / "table1.md").read_text()
    assert "| Head height | Searcher | Excluding cabinets | Everywhere |" in md
    assert "| 1.05m | random searcher | 0.20 [0.04, 0.62] | 0.20 [0.04, 0.62] |" in md
    # ours: both seeds solve scenario 0 of 4, so the interval is the two-level bootstrap of that matrix
    lo, hi = two_level_ci(np.array([[1, 1], [0, 0], [0, 0], [0, 0]], float))[1:]
    assert f"| 1.05m | ours (head_on) | 0.25 [{lo:.2f}, {hi:.2f}] | 0.25 [{lo:.2f}, {hi:.2f}] |" in md
    assert "frontier" not in md  # a reference searcher without files is left out, not "not run"
    assert "| 1.05m | privileged oracle | not run | 0.80 [0.38, 0.96] |" in md
    assert "| 1.05m | paper | 0.92 | 0.75 |" in md
    assert "privileged oracle" in (tmp_path / "out" / "table1.tex").read_text()
    # The classical searcher, when stored, sits between the policy and the oracle.
    frontier = [_eval_csv(tmp_path, "frontier", pl, h, [1, 1, 0, 1]) for pl, h in cells]
    cmd_table1(ours, tmp_path / "out3" / "table1", variant="head_on", bounds=rand + oracle + frontier)
    lines = (tmp_path / "out3" / "table1.md").read_text().splitlines()
    row = "| 1.05m | frontier searcher (classical) | 0.75 [0.30, 0.95] | 0.75 [0.30, 0.95] |"
    assert row in lines and lines.index(row) == lines.index(
        "| 1.05m | ours (head_on) | " + f"0.25 [{lo:.2f}, {hi:.2f}] | 0.25 [{lo:.2f}, {hi:.2f}] |") + 1
    # Bounds of a cell the policy was not evaluated on were not run on its scenarios.
    stray = [_eval_csv(tmp_path, "random", "everywhere", 0.45, [0])]
    with pytest.raises(ValueError, match="cells the policy has not"):
        cmd_table1(ours, tmp_path / "out2", variant="head_on", bounds=stray)


CURVE_SCENARIOS = [("kitchen_living", 0.45, 0, 4.5), ("kitchen_living", 1.05, 0, 6.0),
                   ("bedroom_bath", 0.45, 0, 3.0), ("bedroom_bath", 1.65, 1, 5.5)]
"""A curve's held-out scenarios: (home, height, scenario_id, shortest path); ids restart in each group."""


def _curve_level_csv(root: Path, searcher: str, successes: list[int], scenarios=CURVE_SCENARIOS) -> Path:
    from egosearch.report.data import CURVE_LEVEL_COLUMNS

    rows = [dict(zip(CURVE_LEVEL_COLUMNS, (home, h, i, ok, 50, 6.0, ell, 0.5 * ok, 0, -10.0)))
            for (home, h, i, ell), ok in zip(scenarios, successes, strict=True)]
    path = root / "eval_curve" / searcher / "head_on.csv"
    path.parent.mkdir(parents=True, exist_ok=True)
    pd.DataFrame(rows, columns=list(CURVE_LEVEL_COLUMNS)).to_csv(path, index=False)
    return path


def test_figure6_draws_the_random_and_classical_searchers_and_each_start_as_levels(tmp_path):
    from matplotlib.figure import Figure

    from egosearch.report import figures
    from egosearch.report.figures import RANDOM, START_LABEL, figure6, figure6_frame

    curve = tmp_path / "train" / "head_on" / "seed0" / "curve.csv"
    curve.parent.mkdir(parents=True)
    pd.DataFrame({"env_steps": [0, 100, 200], "success_rate": [0.25, 0.5, 0.75]}).to_csv(curve, index=False)
    # the episodes behind the curve: the same four scenarios at every step
    pd.DataFrame([{"env_steps": step, "home": home, "height": h, "scenario_id": i, "success": int(k <= step // 100),
                   "shortest_path": ell, "path_length": 7.0}
                  for step in (0, 100, 200) for k, (home, h, i, ell) in enumerate(CURVE_SCENARIOS)]
                 ).to_csv(curve.with_name("curve_episodes.csv"), index=False)
    rand = [_curve_level_csv(tmp_path, "random", [1, 0, 0, 0])]
    classical = [_curve_level_csv(tmp_path, "frontier", [1, 1, 1, 0])]
    df = figure6_frame({"head_on": [curve]}, level_files=rand + classical, n_resamples=50)
    level = df[df["variant"] == RANDOM]
    assert list(level["env_steps"]) == [0, 100, 200] and (level["success_rate"] == 1 / 4).all()
    assert (level["n_scenarios"] == 4).all()
    assert (df[df["variant"] == "frontier"]["success_rate"] == 3 / 4).all()
    assert set(df[df["variant"] == "frontier"]["label"]) == {"classical searcher, head moving"}

    drawn = []  # every horizontal line the figure draws: (label, height)
    add_subplot = Figure.add_subplot

    def recording_subplot(fig, *args, **kwargs):
        ax = add_subplot(fig, *args, **kwargs)
        plain = ax.axhline
        ax.axhline = lambda y, **kw: (drawn.append((kw.get("label"), y)), plain(y, **kw))[1]
        return ax

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(figures.Figure, "add_subplot", recording_subplot)
        png, _pdf, _csv = figure6({"head_on": [curve]}, tmp_path / "fig6", level_files=rand + classical,
                                  n_resamples=50)
    assert png.stat().st_size > 10_000
    assert sorted(drawn) == sorted([("random searcher", 1 / 4), ("classical searcher, head moving", 3 / 4),
                                    (START_LABEL, 0.25)])
    with pytest.raises(ValueError, match="may not be called 'random'"):
        figure6_frame({"random": [curve]}, level_files=rand)
    # a level read on other episodes than the curve's (Table 1's sets, or another curve's scenarios) is refused
    with pytest.raises(ValueError, match="no level's episodes on a curve's scenarios"):
        figure6_frame({"head_on": [curve]}, level_files=[_eval_csv(tmp_path, "frontier", "everywhere", 1.05, [1])])
    moved = [(home, h, i, ell + 1.0) for home, h, i, ell in CURVE_SCENARIOS]
    other = _curve_level_csv(tmp_path / "other", "frontier", [1, 1, 1, 0], scenarios=moved)
    with pytest.raises(ValueError, match="ran other scenarios than head_on's curve"):
        figure6_frame({"head_on": [curve]}, level_files=[other])


# --------------------------------------------------------------------------------------------- provenance
def _stored_run(root: Path) -> tuple[Path, list[Path]]:
    from egosearch.report.provenance import write_provenance

    results = root / "results" / "p"
    files = [_eval_csv(results, "head_on", "everywhere", 1.05, [1, 0, 1, 0], seed) for seed in (0, 1)]
    files += [_eval_csv(results, "head_off", "everywhere", 1.05, [0, 0, 1, 0], seed) for seed in (0, 1)]
    (results / "train" / "head_on" / "seed0" / "ckpt").mkdir(parents=True)
    (results / "train" / "head_on" / "seed0" / "ckpt" / "train_state.ckpt").write_bytes(b"in progress")
    (results / "logs").mkdir()
    (results / "logs" / "x.log").write_text("log")
    write_provenance("p", results, results / "provenance.json")
    return results, files


def test_provenance_records_the_sha256_of_every_stored_file(tmp_path):
    import hashlib
    import json

    results, files = _stored_run(tmp_path)
    record = json.loads((results / "provenance.json").read_text())["files"]
    # Results only: not the logs, not a checkpoint of a run in progress, not the record itself.
    assert sorted(record) == sorted(p.relative_to(results).as_posix() for p in files)
    first = files[0].relative_to(results).as_posix()
    assert record[first] == {"sha256": hashlib.sha256(files[0].read_bytes()).hexdigest(),
                             "bytes": files[0].stat().st_size}


def test_provenance_is_rewritten_only_when_a_stored_file_changes(tmp_path, monkeypatch):
    """`report regenerate` then `snakemake all` rewrote the committed record with a new commit and date
    although every file was byte-identical: the record must stay byte for byte unless the results change."""
    import json

    from egosearch.report import provenance

    results, files = _stored_run(tmp_path)
    record = results / "provenance.json"
    first = record.read_bytes()
    monkeypatch.setattr(provenance, "_git", lambda *args: "a later commit")  # another commit, another date
    files[0].write_bytes(files[0].read_bytes())  # rewritten, identical
    provenance.write_provenance("p", results, record)
    assert record.read_bytes() == first
    files[0].write_text(files[0].read_text() + files[0].read_text().splitlines()[-1] + "\n")
    provenance.write_provenance("p", results, record)
    rewritten = json.loads(record.read_text())
    assert rewritten["commit"] == "a later commit"
    assert rewritten["files"] == provenance.record_files(results) != json.loads(first)["files"]
    # a new note is a change of the record too; the old note survives a rerun without one
    provenance.write_provenance("p", results, record, note="resumed by hand")
    noted = record.read_bytes()
    provenance.write_provenance("p", results, record)
    assert record.read_bytes() == noted and json.loads(noted)["note"] == "resumed by hand"


def test_the_provenance_log_line_is_the_same_whether_the_record_was_rewritten_or_kept(tmp_path, capsys):
    """The workflow commits the command's output as its log: a rerun that keeps the record must not change it."""
    from egosearch.cli import main

    results, files = _stored_run(tmp_path)
    record = results / "provenance.json"
    argv = ["report", "provenance", "--preset", "p", "--results", str(results), "--out", str(record)]
    files[0].write_text(files[0].read_text() + "0,0,100,1.0,1.0,0.0,0,0.0\n")
    capsys.readouterr()
    assert main(argv) == 0  # rewritten: a stored file changed
    rewritten = capsys.readouterr().out
    assert main(argv) == 0  # kept
    assert capsys.readouterr().out == rewritten == f"{record}: sha256 of 4 stored files, 0 jobs, 0 s summed\n"


def test_verify_and_compare_refuse_a_truncated_or_edited_csv(tmp_path, capsys):
    from egosearch.cli import main
    from egosearch.report.commands import cmd_compare
    from egosearch.report.provenance import StoredFileError, verify

    results, files = _stored_run(tmp_path)
    ref, cand = files[:2], files[2:]
    assert verify(results) == (4, [])
    cmd_compare(ref, cand)                                          # intact: used
    text = files[0].read_text()
    files[0].write_text(text[: len(text) // 2])                     # truncated by hand
    with pytest.raises(StoredFileError, match=r"h1.05.csv was truncated: \d+ bytes, \d+ recorded"):
        cmd_compare(ref, cand)
    files[0].write_text(text)
    assert verify(results) == (4, [])
    files[3].write_text(files[3].read_text().replace("\n0,0,", "\n0,1,", 1))   # a failure made a success
    with pytest.raises(StoredFileError, match="h1.05.csv was edited: its sha256 differs"):
        cmd_compare(ref, cand)
    ok, problems = verify(results)
    assert ok == 3 and len(problems) == 1 and "seed1" in problems[0] and "head_off" in problems[0]
    # The CLI: one line on stderr, exit 2, no traceback.
    capsys.readouterr()
    assert main(["report", "compare", "--reference", *map(str, ref), "--candidate", *map(str, cand)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "was edited" in err and "Traceback" not in err
    # A new candidate that the record does not list is a comparison's normal input.
    new = [_eval_csv(results, "new", "everywhere", 1.05, [1, 1, 1, 1], seed) for seed in (0, 1)]
    cmd_compare(ref, new)
    assert any("new/seed0" in p and "not in the sha256 list" in p for p in verify(results)[1])


def test_a_jobs_cpu_time_is_recorded_beside_its_wall_time(tmp_path):
    from egosearch.report.provenance import rule_times

    header = "s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\tcpu_time\n"
    (tmp_path / "train" / "v").mkdir(parents=True)
    # a training that shared its core with another job: half of its wall time on the CPU
    row = "7200.5\t2:00:00\t1500\t2300\t1400\t1450\t0\t10\t50.0\t3600.04\n"
    (tmp_path / "train" / "v" / "seed0.tsv").write_text(header + row)
    (tmp_path / "report").mkdir()
    (tmp_path / "report" / "table1.tsv").write_text("s\th:m:s\n12.0\t0:00:12\n")  # no CPU time recorded
    assert rule_times(tmp_path) == [
        {"rule": "report", "job": "table1", "wall_s": 12.0, "max_rss_mb": ""},
        {"rule": "train", "job": "v/seed0", "wall_s": 7200.5, "max_rss_mb": "1500", "cpu_s": 3600.0}]


def test_a_resumed_training_costs_its_whole_run_in_the_estimate(tmp_path):
    from egosearch.report.provenance import rule_times
    from egosearch.report.workflow_jobs import job_cost_s

    benchmarks = tmp_path / "benchmarks"
    header = "s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\tcpu_time\n"
    for run, bench_row, curve_wall in (("resumed", "2000.0\t0:33:20\t1\t1\t1\t1\t0\t0\t90\t1800.0\n", 5000.0),
                                       ("whole", "5000.0\t1:23:20\t1\t1\t1\t1\t0\t0\t90\t4500.0\n", 4990.0)):
        (benchmarks / "train" / "v").mkdir(parents=True, exist_ok=True)
        (benchmarks / "train" / "v" / f"{run}.tsv").write_text(header + bench_row)
        (tmp_path / "train" / "v" / run).mkdir(parents=True)
        # the curve counts wall time from the run's start, across its resume
        (tmp_path / "train" / "v" / run / "curve.csv").write_text(
            f"env_steps,success_rate,wall_s\n100000,0.3,{curve_wall / 2}\n200000,0.5,{curve_wall}\n")
    resumed, whole = rule_times(benchmarks)
    assert resumed["run_wall_s"] == 5000.0 and "run_wall_s" not in whole
    # its benchmark timed the last 2,000 s at 0.9 CPU-s per second: the whole run is 5,000 s of that
    assert job_cost_s(resumed) == 4500.0
    assert job_cost_s(whole) == 4500.0

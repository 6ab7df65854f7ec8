"""The memory-window report: success against memory per cell, from per-episode CSVs, against hand-worked cases."""

from __future__ import annotations

import math

import pandas as pd
import pytest

from egosearch.report.memory_window import memory_window_inputs, memory_window_markdown, memory_window_report
from egosearch.report.stats import wilson_ci
from egosearch.runs.evaluate import EPISODE_COLUMNS

CELLS = [(home, placement, height) for home in ("kitchen_living", "bedroom_bath")
         for placement in ("no_low_cabinets", "everywhere") for height in (0.45, 1.05)]


def _write(root, who, seed, successes_of):
    paths = []
    for home, placement, height in CELLS:
        path = root / "eval" / who / f"seed{seed}" / home / placement / f"h{height:g}.csv"
        path.parent.mkdir(parents=True, exist_ok=True)
        wins = successes_of(home, placement, height)
        rows = [{"scenario_id": i, "success": int(w), "steps": 50, "path_length": 3.0, "shortest_path": 2.0,
                 "spl": 0.6 * w, "collisions": 60 if i == len(wins) - 1 and not w else 1, "episode_return": 0.0}
                for i, w in enumerate(wins)]
        pd.DataFrame(rows, columns=list(EPISODE_COLUMNS)).to_csv(path, index=False)
        paths.append(str(path))
    return paths


def test_success_by_memory_pools_both_homes_and_reads_the_students_seeds(tmp_path):
    """Ten scenarios a home: the 5-step searcher finds 6 in each home (12 of 20: 0.60, Wilson's interval), the
    whole-episode one 9 (0.90); the student's two seeds find 5 and 7 of 10 in each home (0.60); the last scenario
    fails stuck (60 collisions) where it fails."""
    five = _write(tmp_path, "frontier_tuned_window5", 0, lambda *_: [1] * 6 + [0] * 4)
    whole = _write(tmp_path, "frontier_tuned", 0, lambda *_: [1] * 9 + [0])
    student = (_write(tmp_path, "head_on", 0, lambda *_: [1] * 5 + [0] * 5)
               + _write(tmp_path, "head_on", 1, lambda *_: [1] * 7 + [0] * 3))
    searchers, students = memory_window_inputs(five + whole, student)
    assert set(searchers["head moving"]) == {5, None} and students["head moving"][0] == "head_on"
    out = memory_window_report(searchers, students, tmp_path / "figs" / "memory_window")
    assert [p.suffix for p in out] == [".csv", ".md", ".png", ".pdf"]
    df = pd.read_csv(out[0])
    cell = df[(df["placement"] == "everywhere") & (df["height"] == 1.05)]
    k5 = cell[cell["memory_steps"] == 5].iloc[0]
    lo, hi = wilson_ci(12, 20)
    assert (k5["success"], k5["n_episodes"], k5["n_seeds"]) == (0.6, 20, 1)
    assert math.isclose(k5["ci_low"], round(lo, 4)) and math.isclose(k5["ci_high"], round(hi, 4))
    assert math.isclose(k5["stuck_share"], 2 / 20)
    assert cell[cell["memory_steps"].isna() & (cell["who"] == "frontier_tuned")].iloc[0]["success"] == 0.9
    stud = cell[cell["who"] == "head_on"].iloc[0]
    assert (stud["success"], stud["n_episodes"], stud["n_seeds"]) == (0.6, 40, 2)
    assert stud["ci_low"] < 0.6 < stud["ci_high"]
    text = memory_window_markdown(df)
    assert "| head moving | last 5 steps | 0.60 [" in text and "| head moving | whole episode | 0.90 [" in text


def test_a_file_of_another_searcher_or_a_second_student_is_one_line(tmp_path):
    other = _write(tmp_path, "frontier", 0, lambda *_: [1, 0])
    with pytest.raises(ValueError, match="is not the tuned searcher or one of its memory windows"):
        memory_window_inputs(other, [])
    a = _write(tmp_path, "head_on", 0, lambda *_: [1, 0])
    b = _write(tmp_path, "head_on_map_image", 0, lambda *_: [1, 0])
    with pytest.raises(ValueError, match="a second head moving student"):
        memory_window_inputs([], a + b)

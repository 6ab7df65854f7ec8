"""The budget study's numbers from known CSVs (no torch, no simulator)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from egosearch.report.budget import BUDGET_COLUMNS, budget_figure, budget_frame, log_ticks
from egosearch.report.stats import two_level_ci, wilson_ci

CURVE = ["env_steps", "success_rate", "spl", "episode_return", "critic_loss", "actor_loss", "curl_loss",
         "alpha", "entropy", "steps_per_s", "updates_per_s", "wall_s"]
EPISODES = ["scenario_id", "success", "steps", "path_length", "shortest_path", "spl", "collisions", "episode_return"]


def _run(root, setting, seed, steps, wall_s, successes):
    d = root / setting / f"seed{seed}"
    d.mkdir(parents=True)
    curve = pd.DataFrame([[0, 0.0] + [0.0] * 9 + [10.0], [steps, 0.5] + [0.0] * 9 + [wall_s]], columns=CURVE)
    curve.to_csv(d / "curve.csv", index=False)
    cell = d / "kitchen_living" / "no_low_cabinets"
    cell.mkdir(parents=True)
    pd.DataFrame([[i, s, 10, 1.0, 1.0, float(s), 0, 0.0] for i, s in enumerate(successes)],
                 columns=EPISODES).to_csv(cell / "h1.05.csv", index=False)
    return d / "curve.csv", cell / "h1.05.csv"


def test_budget_pools_seeds_and_counts_core_hours(tmp_path):
    runs = {"small": [_run(tmp_path, "small", 0, 24_000, 1800.0, [1, 0, 0, 0])],
            "chosen": [_run(tmp_path, "chosen", s, 150_000, 900.0 * (s + 1), [1, 1, 0, 1]) for s in range(3)]}
    df = budget_frame(runs).set_index("setting")
    assert list(df.reset_index().columns) == list(BUDGET_COLUMNS)
    small, chosen = df.loc["small"], df.loc["chosen"]
    assert small.core_hours == pytest.approx(0.5) and small.env_steps_per_core_s == pytest.approx(24_000 / 1800)
    # 3 seeds: 900 + 1800 + 2700 s of training; 9 of 12 episodes succeed
    assert chosen.core_hours == pytest.approx(1.5) and chosen.core_hours_per_seed == pytest.approx(0.5)
    assert chosen.env_steps_per_core_s == pytest.approx(3 * 150_000 / 5400)
    assert chosen.success_rate == pytest.approx(0.75) and chosen.episodes == 12
    # the seeds ran the same 4 scenarios and agree on each: the interval is the two-level bootstrap of
    # that (scenarios x seeds) matrix, not Wilson over 12 independent episodes; one seed is Wilson
    same = np.array([[1, 1, 1], [1, 1, 1], [0, 0, 0], [1, 1, 1]], float)
    assert (chosen.low, chosen.high) == pytest.approx(two_level_ci(same)[1:])
    assert chosen.high - chosen.low > (lambda lo, hi: hi - lo)(*wilson_ci(9, 12))
    assert (small.low, small.high) == pytest.approx(wilson_ci(1, 4))
    outs = budget_figure(df.reset_index(), tmp_path / "out" / "budget", chosen="chosen")
    assert [p.suffix for p in outs] == [".csv", ".png", ".pdf"] and all(p.stat().st_size > 0 for p in outs)


def test_budget_names_where_each_setting_trained(tmp_path):
    here = _run(tmp_path, "here", 0, 1000, 5.0, [1])
    (here[0].parent / "done.json").write_text(
        '{"env_kwargs": "[(\'layout\', \'kitchen_living\'), (\'placement\', \'everywhere\')]", '
        '"machine": {"cpu": "X"}}')
    both = [_run(tmp_path, "both", s, 1000, 5.0, [0]) for s in range(2)]
    for curve, _ in both:
        (curve.parent / "done.json").write_text('{"env_kwargs": "[(\'layout\', \'paper_homes\')]"}')
    unknown = _run(tmp_path, "unknown", 0, 1000, 5.0, [1])
    df = budget_frame({"here": [here], "both": both, "unknown": [unknown]}).set_index("setting")
    assert df.loc["here", "trained_in"] == "kitchen_living" and df.loc["here", "machine"] == "X"
    assert df.loc["both", "trained_in"] == "paper_homes" and df.loc["both", "machine"] == "not recorded"
    assert df.loc["unknown", "trained_in"] == "not recorded"


def test_budget_refuses_runs_of_one_setting_that_end_at_different_steps(tmp_path):
    runs = {"mixed": [_run(tmp_path, "mixed", 0, 1000, 5.0, [1]), _run(tmp_path, "mixed", 1, 2000, 5.0, [0])]}
    with pytest.raises(ValueError, match="different env steps"):
        budget_frame(runs)


def test_log_ticks_label_a_span_narrower_than_a_decade():
    # The stored study's core-hours (0.36-0.80 per run, padded by 1.4x): no power of ten inside
    # but 1, so a plain log axis labels one tick at most.
    assert log_ticks(0.255, 1.116) == [0.3, 0.5, 1.0]
    assert log_ticks(17_000, 420_000) == [20_000, 30_000, 50_000, 100_000, 200_000, 300_000]
    # Too many at 1-2-3-5: 1-2-5, then 1-3, then one per decade.
    assert log_ticks(1, 50) == [1, 2, 5, 10, 20, 50]
    assert log_ticks(1, 100) == [1, 3, 10, 30, 100]
    assert log_ticks(1, 1000) == [1, 10, 100, 1000]


def test_budget_names_the_machine_each_setting_trained_on(tmp_path):
    import json

    old = _run(tmp_path, "old", 0, 1000, 100.0, [1, 0])
    new = [_run(tmp_path, "new", s, 1000, 100.0, [1, 1]) for s in range(2)]
    for (curve, _), cpu in zip(new, ("CPU B", "CPU A")):
        (curve.parent / "done.json").write_text(json.dumps({"machine": {"cpu": cpu, "cores": 2}}))
    df = budget_frame({"old": [old], "new": new}).set_index("setting")
    # A run finished before training recorded its machine says so; seeds split over machines name both.
    assert df.loc["old", "machine"] == "not recorded"
    assert df.loc["new", "machine"] == "CPU A + CPU B"

"""The budget study's numbers from known CSVs (no torch, no simulator)."""

from __future__ import annotations

import pandas as pd
import pytest

from egosearch.report.budget import BUDGET_COLUMNS, budget_figure, budget_frame
from egosearch.report.stats import wilson_ci

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
    assert (chosen.low, chosen.high) == pytest.approx(wilson_ci(9, 12))
    outs = budget_figure(df.reset_index(), tmp_path / "out" / "budget", chosen="chosen")
    assert [p.suffix for p in outs] == [".csv", ".png", ".pdf"] and all(p.stat().st_size > 0 for p in outs)


def test_budget_refuses_runs_of_one_setting_that_end_at_different_steps(tmp_path):
    runs = {"mixed": [_run(tmp_path, "mixed", 0, 1000, 5.0, [1]), _run(tmp_path, "mixed", 1, 2000, 5.0, [0])]}
    with pytest.raises(ValueError, match="different env steps"):
        budget_frame(runs)

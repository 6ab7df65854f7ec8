"""The fresh-set check's numbers from hand-built evaluation CSVs (no simulator)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from egosearch.report.fresh import POOLED, fresh_frame, fresh_report, shared_seed_difference_ci
from tests.test_report import write_eval


def test_a_seed_that_always_succeeds_and_one_that_never_does_cancel_between_the_sets():
    # Seed 0 finds every target and seed 1 none, on both sets: each resample draws the same seeds
    # for both sides, so fresh - stored is 0 in every resample (drawn apart, it would span ±0.5).
    stored = np.column_stack([np.ones(30), np.zeros(30)])
    fresh = np.column_stack([np.ones(50), np.zeros(50)])
    assert shared_seed_difference_ci(stored, fresh) == (0.0, 0.0)


def test_scenarios_drawn_apart_give_the_interval_of_two_independent_samples():
    rng = np.random.default_rng(1)
    stored = (rng.random((400, 1)) < 0.5).astype(float)
    fresh = (rng.random((400, 1)) < 0.7).astype(float)
    lo, hi = shared_seed_difference_ci(stored, fresh)
    d = fresh.mean() - stored.mean()
    # One seed: the bootstrap of a difference of two independent proportions, half-width ~1.96 sd.
    sd = np.sqrt(stored.mean() * (1 - stored.mean()) / 400 + fresh.mean() * (1 - fresh.mean()) / 400)
    assert lo < d < hi
    assert (hi - lo) / 2 == pytest.approx(1.96 * sd, rel=0.1)


def test_fresh_frame_by_hand(tmp_path):
    files = {"stored": [], "fresh": []}
    for side, root in (("stored", tmp_path / "a"), ("fresh", tmp_path / "b")):
        for seed in (0, 1):
            for home in ("kitchen", "bedroom"):
                success = [1, 1, 0, 0] if side == "stored" else [1, 1, 1, 0]
                files[side].append(write_eval(root, "head_on", seed, home, "everywhere", 1.05, success))
    df = fresh_frame(files["stored"], files["fresh"]).set_index("home")
    assert list(df.index) == ["bedroom", "kitchen", POOLED]
    for home in df.index:
        assert df.loc[home, "stored"] == pytest.approx(0.5)
        assert df.loc[home, "fresh"] == pytest.approx(0.75)
        assert df.loc[home, "difference"] == pytest.approx(0.25)
        assert df.loc[home, "ci_low"] <= 0.25 <= df.loc[home, "ci_high"]
    assert df.loc[POOLED, "n_stored"] == 8 and df.loc["kitchen", "n_fresh"] == 4
    assert (df["n_seeds"] == 2).all()
    csv, md = fresh_report(files["stored"], files["fresh"], tmp_path / "out" / "fresh", "head_on", fresh_seed=7)
    assert pd.read_csv(csv).shape[0] == 3
    assert "scenario seed 7" in md.read_text()


def test_fresh_frame_refuses_different_cells_or_seeds(tmp_path):
    a = write_eval(tmp_path / "a", "head_on", 0, "kitchen", "everywhere", 1.05, [1, 0])
    b = write_eval(tmp_path / "b", "head_on", 0, "kitchen", "everywhere", 1.65, [1, 0])
    with pytest.raises(ValueError, match="different cells"):
        fresh_frame([a], [b])
    c = write_eval(tmp_path / "c", "head_on", 1, "kitchen", "everywhere", 1.05, [1, 0])
    with pytest.raises(ValueError, match="same actors"):
        fresh_frame([a], [c])

"""How a searcher fails: the stuck definition and the failure kinds, on hand-made traces and evaluation rows."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from egosearch.report.failures import (
    KINDS,
    NEAR_M,
    STUCK_COLLISIONS,
    episode_kinds,
    failure_table,
    stuck,
    stuck_share,
)


def _episode(sid, visible, collisions, geodesic, success=False):
    n = len(visible)
    return {"scenario_id": np.full(n, sid), "step": np.arange(n), "visible": np.asarray(visible, bool),
            "collisions": np.asarray(collisions), "geodesic": np.asarray(geodesic, float),
            "success": np.r_[np.zeros(n - 1, bool), [success]]}


def _trace(*episodes):
    return {k: np.concatenate([e[k] for e in episodes]) for k in episodes[0]}


# one episode of each kind, by hand (4 steps each; the collision count is the env's running count)
EPISODES = [
    _episode(0, [0, 0, 0, 0], [0, 10, 40, 60], [5, 5, 5, 5]),                  # never saw it (stuck, unseen)
    _episode(1, [0, 1, 1, 0], [0, 1, 2, 3], [5, 4, 3, 3]),                     # saw it and lost it
    _episode(2, [0, 1, 1, 1], [0, 20, 45, STUCK_COLLISIONS], [5, 3, 3, 3]),   # saw it and was stuck
    _episode(3, [1, 1, 1, 0], [0, 0, 0, 0], [3, 2, 1.5, NEAR_M]),              # timed out near it
    _episode(4, [0, 0, 1, 1], [0, 0, 0, 0], [6, 5, 4, 3]),                     # in view at the end, not near
    _episode(5, [0, 1, 1, 1], [0, 0, 0, 0], [3, 2, 1, 0], success=True),       # found it
]


def test_episode_kinds_by_hand():
    kinds = episode_kinds(_trace(*EPISODES)).set_index("scenario_id")["kind"]
    assert list(kinds) == ["never_saw", "saw_lost", "saw_stuck", "timed_out_near", "saw_other", "success"]


def test_stuck_is_a_failure_with_at_least_50_collisions():
    df = pd.DataFrame({"success": [0, 0, 1, 0], "collisions": [STUCK_COLLISIONS, STUCK_COLLISIONS - 1, 80, 99]})
    assert list(stuck(df)) == [1, 0, 0, 1]
    assert stuck_share(df) == pytest.approx(0.5)


def test_failure_table_shares_sum_to_one(tmp_path):
    path = tmp_path / "traces" / "mine" / "seed0" / "kitchen_living" / "no_low_cabinets" / "h1.05.npz"
    path.parent.mkdir(parents=True)
    np.savez_compressed(path, **_trace(*EPISODES))
    df = failure_table({"mine": [path]}, tmp_path / "f.csv")
    row = df.iloc[0]
    assert row["episodes"] == 6 and row["success"] == pytest.approx(1 / 6)
    assert row[list(KINDS)].sum() + row["success"] == pytest.approx(1.0)
    assert row["stuck"] == pytest.approx(2 / 6)  # the unseen stuck episode counts as stuck too
    assert pd.read_csv(tmp_path / "f.csv").shape == df.shape

import math

import pytest

from egosearch.runs.metrics import episode_spl, spl
from egosearch.sim.env import reward_terms


def test_spl_hand_worked():
    # Three episodes: an optimal success, a success at twice the shortest path, a failure.
    assert spl([1, 1, 0], [4.0, 3.0, 5.0], [4.0, 6.0, 1.0]) == pytest.approx((1.0 + 0.5 + 0.0) / 3)


def test_spl_path_shorter_than_geodesic_counts_as_optimal():
    # Grid geodesics overestimate slightly: a real path may come out shorter than l.
    assert episode_spl(True, 2.0, 1.9) == 1.0
    assert episode_spl(True, 0.0, 0.3) == 1.0
    assert episode_spl(False, 2.0, 2.0) == 0.0


def test_spl_rejects_empty_and_mismatched():
    with pytest.raises(ValueError):
        spl([], [], [])
    with pytest.raises(ValueError):
        spl([1], [1.0, 2.0], [1.0])


def test_reward_terms_hand_worked():
    # Success while seen at 0.3 m, 2 collisions so far: 10 - 0.3 - 0.1 + 0.1 * (-0.2).
    t = reward_terms(success=True, visible=True, distance=0.3, n_collisions=2)
    assert (t["r_s"], t["r_d"], t["r_l"], t["r_c"]) == (10.0, -0.3, -0.1, pytest.approx(-0.2))
    assert t["reward"] == pytest.approx(10 - 0.3 - 0.1 - 0.02)


def test_reward_distance_only_while_visible_and_collision_floor():
    t = reward_terms(success=False, visible=False, distance=4.0, n_collisions=100)
    assert t["r_d"] == 0.0
    assert t["r_c"] == -3.0  # clip(-0.1 * 100, -3, 0)
    assert t["reward"] == pytest.approx(-0.1 + 0.1 * -3.0)
    seen = reward_terms(success=False, visible=True, distance=2.5, n_collisions=0)
    assert seen["reward"] == pytest.approx(-2.5 - 0.1)
    assert math.isclose(seen["r_c"], 0.0)


def test_progress_reward_ablation_hand_worked():
    # Seen at 2.0 m, now seen at 1.5 m: r_d = +0.5 (Savva et al.'s progress form).
    t = reward_terms(success=False, visible=True, distance=1.5, n_collisions=0, previous_distance=2.0,
                     distance_reward="progress")
    assert t["r_d"] == pytest.approx(0.5) and t["reward"] == pytest.approx(0.5 - 0.1)
    # First sight (nothing to compare with) and not seen: 0.
    assert reward_terms(False, True, 1.5, 0, None, "progress")["r_d"] == 0.0
    assert reward_terms(False, False, 1.5, 0, 2.0, "progress")["r_d"] == 0.0
    # The paper's form ignores the previous distance.
    assert reward_terms(False, True, 1.5, 0, 2.0)["r_d"] == -1.5


def test_geodesic_reward_ablation_hand_worked():
    # 0.2 m closer along the floor while the target is unseen, 100 collisions so far:
    # r_d = +0.2 and r_c = -10 (no floor at -3), so 0.2 - 0.1 + 0.1 * -10.
    t = reward_terms(success=False, visible=False, distance=4.0, n_collisions=100, distance_reward="geodesic",
                     geodesic_decrease=0.2)
    assert t["r_d"] == pytest.approx(0.2) and t["r_c"] == pytest.approx(-10.0)
    assert t["reward"] == pytest.approx(0.2 - 0.1 - 1.0)
    # Moving away costs what coming closer earns; the Euclidean distance plays no part.
    away = reward_terms(False, True, 0.5, 0, 2.0, "geodesic", geodesic_decrease=-0.15)
    assert away["r_d"] == pytest.approx(-0.15)

"""The generalisation benchmark: the held-out split is never drawn, the home pool swaps homes, and the
normalised score and its gap are what hand-worked inputs give."""

import math

import numpy as np
import pandas as pd
import pytest

from egosearch.report.generalise import generalise_frame, generalise_report
from egosearch.sim.home_pool import HELDOUT_HOME_SEEDS, HomePoolEnv, check_home_split, curve_homes

EPISODE = ["scenario_id", "success", "steps", "path_length", "shortest_path", "spl", "collisions", "episode_return"]


def test_split_refuses_the_heldout_homes():
    assert check_home_split([0, 10]) == range(0, 10)
    for bad in ([HELDOUT_HOME_SEEDS.start - 1, HELDOUT_HOME_SEEDS.start + 1], [HELDOUT_HOME_SEEDS.stop - 1, 10**7],
                [5, 5], [3, 1], "0:10"):
        with pytest.raises(ValueError):
            check_home_split(bad)
    assert len(HELDOUT_HOME_SEEDS) >= 20


@pytest.mark.slow
def test_home_pool_swaps_homes_and_is_seeded():
    def homes_of(seed):
        env = HomePoolEnv("EgoSearch-v0", home_seeds=[0, 50], pool_size=2, episodes_per_swap=2)
        try:
            env.reset(seed=seed)
            seen = [env.home]
            for _ in range(7):
                obs, info = env.reset()
                assert info["home"] == env.home and obs["depth"].shape == (5, 100, 100)
                seen.append(env.home)
            env.step(env.action_space.sample())
            return seen, env.homes_built
        finally:
            env.close()

    seen, built = homes_of(3)
    assert built == 2 + 3  # the first pool, then one swap after every 2nd episode (episodes 3, 5, 7)
    assert all(0 <= int(h[4:]) < 50 for h in seen) and len(set(seen)) >= 3
    assert homes_of(3) == (seen, built)  # same seed, same homes


def _write(path, success, spl=None):
    path.parent.mkdir(parents=True, exist_ok=True)
    success = np.asarray(success, int)
    spl = success * 0.5 if spl is None else np.asarray(spl, float)
    pd.DataFrame({"scenario_id": range(len(success)), "success": success, "steps": 10, "path_length": 1.0,
                  "shortest_path": 1.0, "spl": spl, "collisions": 0, "episode_return": 0.0},
                 columns=EPISODE).to_csv(path, index=False)
    return path


def test_normalised_score_and_gap_by_hand(tmp_path):
    # 10 scenarios per group. Random solves scenario 0 (0.1), the oracle all but scenario 9 (0.9).
    # Policy "gen" (2 seeds) solves 5 and 3 in its training split: mean 0.4, normalised (0.4 - 0.1) / 0.8 =
    # 0.375; in the held-out group 2 and 2: 0.2 -> 0.125; gap -0.25.
    root = tmp_path / "eval"
    random = [1] + [0] * 9
    oracle = [1] * 9 + [0]
    files, bounds = [], []
    for group, solved in (("generated_train", (5, 3)), ("generated_heldout", (2, 2))):
        for name, vals in (("random", random), ("oracle", oracle)):
            bounds.append(_write(root / name / "seed0" / group / "everywhere" / "h1.05.csv", vals))
        for seed, k in enumerate(solved):
            files.append(_write(root / "gen" / f"seed{seed}" / group / "everywhere" / "h1.05.csv",
                                [1] * k + [0] * (10 - k)))
    df = generalise_frame(files, bounds, {"gen": "home0-home9"}, generated="gen", n_resamples=2000)
    train = df[df.group == "generated_train"].iloc[0]
    held = df[df.group == "generated_heldout"].iloc[0]
    assert (train.n_scenarios, train.n_seeds) == (10, 2)
    assert train.success == pytest.approx(0.4) and train.normalised == pytest.approx(0.375)
    assert held.success == pytest.approx(0.2) and held.normalised == pytest.approx(0.125)
    assert (train.random_success, train.oracle_success) == (pytest.approx(0.1), pytest.approx(0.9))
    assert held.gap_to_train == pytest.approx(-0.25) and held.gap_low <= -0.25 <= held.gap_high
    assert math.isnan(train.gap_to_train)
    assert train.normalised_low <= train.normalised <= train.normalised_high
    outs = generalise_report(files, bounds, tmp_path / "out" / "generalise", {"gen": "home0-home9"}, "gen",
                             n_resamples=500)
    md = outs[1].read_text()
    assert "| gen (home0-home9) | 0.38 [" in md and "generated homes (held out): -0.25 [" in md
    assert outs[2].stat().st_size > 1000


def test_the_generated_variant_is_read_against_the_reference_in_a_paper_home(tmp_path):
    # bounds 0.1 / 0.9 as above; in kitchen_living the generated-homes variant solves 5 and 3 of 10
    # (0.4 -> 0.375), the reference 7 and 7 (0.7 -> 0.75): -0.375. No such line in a generated group.
    root = tmp_path / "eval"
    files, bounds = [], []
    for group in ("generated_train", "kitchen_living"):
        for name, vals in (("random", [1] + [0] * 9), ("oracle", [1] * 9 + [0])):
            bounds.append(_write(root / name / "seed0" / group / "everywhere" / "h1.05.csv", vals))
        for variant, solved in (("gen", (5, 3)), ("ref", (7, 7))):
            for seed, k in enumerate(solved):
                files.append(_write(root / variant / f"seed{seed}" / group / "everywhere" / "h1.05.csv",
                                    [1] * k + [0] * (10 - k)))
    df = generalise_frame(files, bounds, generated="gen", reference="ref", n_resamples=2000)
    row = df[(df.variant == "gen") & (df.group == "kitchen_living")].iloc[0]
    assert row.vs_reference == pytest.approx(-0.375)
    assert row.vs_reference_low <= -0.375 <= row.vs_reference_high <= 0
    others = df[(df.variant != "gen") | (df.group != "kitchen_living")]
    assert others["vs_reference"].isna().all()
    outs = generalise_report(files, bounds, tmp_path / "out" / "g", generated="gen", reference="ref", n_resamples=500)
    assert "against `ref`" in outs[1].read_text() and "- kitchen_living (paper): -0.37 [" in outs[1].read_text()


def test_a_bound_that_missed_scenarios_is_one_line(tmp_path):
    files = [_write(tmp_path / "eval/p/seed0/kitchen_living/everywhere/h1.05.csv", [1, 0, 1])]
    bounds = [_write(tmp_path / "eval/random/seed0/kitchen_living/everywhere/h1.05.csv", [0, 0]),
              _write(tmp_path / "eval/oracle/seed0/kitchen_living/everywhere/h1.05.csv", [1, 1, 1])]
    with pytest.raises(ValueError, match="random searcher did not run 1 of the policy's scenarios"):
        generalise_frame(files, bounds)


def test_the_training_curve_is_read_in_both_paper_homes_unless_trained_in_generated_ones():
    both = ["kitchen_living", "bedroom_bath"]
    assert sorted(curve_homes({"layout": "paper_homes"})) == sorted(both)
    assert sorted(curve_homes({"layout": "kitchen_living"})) == sorted(both)
    assert curve_homes({"layout": "generated", "home_seeds": [1000, 2000]}) == ["home1000"]
    assert curve_homes({"layout": "home5"}) == ["home5"]

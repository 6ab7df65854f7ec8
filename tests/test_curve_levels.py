"""Figure 6's levels run the curve's own episodes: ``egosearch evaluate --curve-of`` gives a searcher the
scenarios and episode seeds that the training curve's evaluator gives a policy, so a level and a curve are
read on the same episodes."""

from __future__ import annotations

import pandas as pd
import pytest

from egosearch.cli import main
from egosearch.report.data import CURVE_LEVEL_COLUMNS as REPORT_COLUMNS
from egosearch.runs.evaluate import CURVE_LEVEL_COLUMNS, curve_episodes, curve_scenarios, scenario_evaluator
from egosearch.searchers.policies import RandomPolicy
from egosearch.sim.home_pool import curve_homes
from egosearch.variants import resolve_variant

HOMES = ["kitchen_living", "bedroom_bath"]


def test_a_searcher_on_the_curves_scenarios_runs_the_curves_episodes():
    # the same policy (seeded per episode) through the curve's evaluator and through evaluate --curve-of's path
    scenarios = curve_scenarios(HOMES, "everywhere", 6)
    assert [(sc.layout, sc.height) for sc in scenarios] == [(h, z) for h in HOMES for z in (0.45, 1.05, 1.65)]
    evaluator = scenario_evaluator("EgoSearch-v0", HOMES, "everywhere", 6)
    try:
        curve = pd.DataFrame(evaluator(RandomPolicy(5, seed=0))["episodes"])
    finally:
        evaluator.close()
    level = pd.DataFrame(curve_episodes("EgoSearch-v0", lambda env: RandomPolicy(5, seed=0), scenarios))
    assert list(level.columns) == list(CURVE_LEVEL_COLUMNS) == list(REPORT_COLUMNS)
    key = ["home", "height", "scenario_id"]
    merged = curve.merge(level, on=key, suffixes=("_curve", "_level"), validate="one_to_one")
    assert len(merged) == 6
    for column in ("success", "shortest_path", "path_length"):
        assert (merged[f"{column}_curve"] == merged[f"{column}_level"]).all(), column
    assert merged["path_length_curve"].nunique() > 1  # the episodes differ from one another


def test_evaluate_curve_of_reads_the_variants_curve_scenarios_and_refuses_a_seed(tmp_path, capsys):
    resolved = resolve_variant("head_on", "smoke")
    expected = curve_scenarios(curve_homes(resolved.train_env), resolved.train_env["placement"],
                               resolved.config.eval_episodes)
    out = tmp_path / "random.csv"
    assert main(["evaluate", "--policy", "random", "--curve-of", "head_on", "--preset", "smoke", "--out",
                 str(out)]) == 0
    rows = pd.read_csv(out)
    assert sorted(zip(rows["home"], rows["height"], rows["scenario_id"])) == sorted(
        (sc.layout, sc.height, sc.scenario_id) for sc in expected)
    assert main(["evaluate", "--policy", "random", "--curve-of", "head_on", "--seed", "3", "--out",
                 str(tmp_path / "x.csv")]) == 2
    assert not (tmp_path / "x.csv").exists()
    assert "the curve's episodes have their own seeds" in capsys.readouterr().err


# -- the tuned teacher's tuning, as a command (egosearch.runs.teacher_tuning) --------------------------------
def test_the_tuning_candidates_are_the_shipped_parameters_and_one_weight_halved_or_doubled():
    from egosearch.runs import teacher_tuning
    from egosearch.searchers.frontier import FrontierPolicy
    from egosearch.searchers.frontier_tuned import FrontierTunedPolicy

    found = teacher_tuning.candidates()
    assert len(found) == 9 and found[teacher_tuning.SHIPPED] == {}
    for name, overrides in found.items():
        if name == teacher_tuning.SHIPPED:
            continue
        ((attribute, value),) = overrides.items()
        assert value / getattr(FrontierTunedPolicy, attribute) in (0.5, 2.0), name
        maker = teacher_tuning.policy_maker(name)
        assert issubclass(maker, FrontierTunedPolicy) and getattr(maker, attribute) == value
    assert teacher_tuning.policy_maker(teacher_tuning.UNTUNED) is FrontierPolicy
    assert teacher_tuning.policy_maker(teacher_tuning.SHIPPED) is FrontierTunedPolicy


def test_the_splits_share_no_scenario_seed_or_home_with_the_stored_sets():
    from egosearch.runs.teacher_tuning import SPLITS
    from egosearch.scene.layouts import HELDOUT_HOME_SEEDS

    fit, held = SPLITS["fit"], SPLITS["held_out"]
    assert {fit.paper_seed, held.paper_seed}.isdisjoint({2021, 7})  # Table 1's sets, the fresh-set check
    assert not set(fit.generated_homes) & set(held.generated_homes)
    for split in (fit, held):
        assert not set(split.generated_homes) & (set(range(20)) | set(HELDOUT_HOME_SEEDS))


@pytest.mark.slow
def test_a_quick_tuning_chooses_on_the_fit_split_and_checks_only_the_choice_held_out(tmp_path, monkeypatch):
    from egosearch.runs import teacher_tuning

    monkeypatch.setattr(teacher_tuning, "NEIGHBOURS", {"GAIN_WEIGHT": (2.0,)})
    monkeypatch.setattr(teacher_tuning, "HEAD_MODES", {"head_on": "EgoSearch-v0"})
    record = teacher_tuning.tune(tmp_path, limit=1, progress=False)
    fit = {name: c["fit_mean_over_head_modes"] for name, c in record["candidates"].items()}
    assert set(fit) == {"shipped", "gain_weight_x2"}
    assert fit[record["chosen"]] == max(fit.values())
    assert record["chosen_is_shipped"] == (record["chosen"] == "shipped")
    held = sorted(p.name for p in (tmp_path / "held_out" / "head_on").iterdir())
    assert held == sorted({"untuned.csv", f"{record['chosen']}.csv"})  # nothing else ran the held-out split
    assert record["held_out"]["head_on"]["scenarios"] == 6  # 1 a cell: 2 placements x 3 heights
    # a second run reads the finished episodes back instead of running them again
    stamps = {p: p.stat().st_mtime_ns for p in tmp_path.rglob("*.csv")}
    assert teacher_tuning.tune(tmp_path, limit=1, progress=False)["held_out"] == record["held_out"]
    assert {p: p.stat().st_mtime_ns for p in tmp_path.rglob("*.csv")} == stamps


def test_the_tuning_block_shows_the_records_candidates_choice_and_held_out_check(tmp_path):
    """docs/baselines.md's teacher_tuning block is the stored record, each number read from it (a hand-made
    record here: two candidates, one head mode), and says when the choice is not the shipped parameters."""
    import json

    from egosearch.report.readme import block_teacher_tuning

    def paired(ref, cand, low, high):
        return {"reference": ref, "candidate": cand, "difference": round(cand - ref, 4), "low": low, "high": high,
                "scenarios": 540}

    record = {"splits": {"fit": {"scenarios": 540}, "held_out": {"scenarios": 540}},
              "candidates": {"shipped": {"fit_mean_over_head_modes": 0.85,
                                         "fit_head_on": paired(0.78, 0.85, 0.04, 0.1)},
                             "gain_weight_x2": {"fit_mean_over_head_modes": 0.875,
                                                "fit_head_on": paired(0.78, 0.875, 0.06, 0.13)}},
              "chosen": "gain_weight_x2", "chosen_is_shipped": False,
              "held_out": {"head_on": paired(0.77, 0.86, 0.05, 0.12)}}
    missing = block_teacher_tuning(tmp_path, "cpu")
    assert missing.startswith("*Not run yet") and "teacher_tuning" in missing
    path = tmp_path / "results" / "cpu" / "teacher_tuning" / "record.json"
    path.parent.mkdir(parents=True)
    path.write_text(json.dumps(record))
    text = block_teacher_tuning(tmp_path, "cpu")
    assert "| `gain_weight_x2` **(chosen)** | 0.875 (+0.095 [+0.060, +0.130]) | 0.875 |" in text
    assert "| `shipped` | 0.850 (+0.070 [+0.040, +0.100]) | 0.850 |" in text
    assert "**not** the shipped parameters" in text
    assert "- held out, head_on: untuned 0.770 -> chosen 0.860, +0.090 [+0.050, +0.120] (540 scenarios)" in text

"""Behaviour statistics from hand-built traces: the per-episode formulas, the ratio-of-sums summary with
its intervals, the claims' verdicts and the README block (no simulator)."""

import math

import numpy as np
import pandas as pd
import pytest

from egosearch.report.behaviour import (
    behaviour_episodes,
    behaviour_report,
    block_claims,
    claims_frame,
    episode_behaviour,
    revisit_steps,
    summarise,
)


def _episode(**cols):
    n = len(cols["x"])
    base = {"scenario_id": [0] * n, "step": list(range(n)), "y": [0.0] * n, "theta": [0.0] * n,
            "head_yaw": [0.0] * n, "pitch": [0.0] * n, "visible": [False] * n, "success": [False] * n,
            "gaze_kind": ["none"] * n, "opening_distance": [5.0] * n}
    base.update(cols)
    return pd.DataFrame(base)


# Five steps of 0.5 s along +x (theta = 0): step 3 goes back 0.2 m; steps 1, 2 and 5 start within 1 m of
# an opening; the target is first seen after step 4 and gone again after step 5.
HAND = _episode(x=[0.0, 0.25, 0.5, 0.3, 0.3, 0.8],
                opening_distance=[0.5, 0.5, 1.5, 1.5, 0.8, 2.0],
                visible=[False, False, False, False, True, False],
                gaze_kind=["none", "shelf", "shelf", "surface", "low_cabinet_interior", "wall"],
                pitch=[0.0, -0.2, -0.4, 0.0, -0.6, 0.1],
                head_yaw=[0.0, 0.3, -0.1, -0.1, 0.2, 0.2])


def test_one_hand_built_episode():
    got = episode_behaviour(HAND, step_seconds=0.5)
    assert got["steps"] == 5 and got["success"] == 0
    # speeds 0.5, 0.5, 0.4, 0, 1.0 m/s; near at the starts of steps 1, 2, 5
    assert (got["steps_near"], got["speed_near_sum"]) == (3, pytest.approx(2.0))
    assert (got["steps_far"], got["speed_far_sum"]) == (2, pytest.approx(0.4))
    # step 3 is the only backward step; the window is steps 1..4 (first sight after step 4)
    assert (got["backward_steps"], got["window_steps"], got["backward_in_window"]) == (1, 4, 1)
    assert (got["other_steps"], got["backward_other"]) == (1, 0)
    # openings after steps 1, 2 and 4: two looks; one look at a table-like surface
    assert (got["steps_gaze_opening"], got["opening_looks"]) == (3, 2)
    assert (got["steps_gaze_surface"], got["surface_looks"]) == (1, 1)
    assert got["pitch_gaze_opening_sum"] == pytest.approx(-1.2) and got["pitch_gaze_else_sum"] == pytest.approx(0.1)
    assert got["head_yaw_sweep"] == pytest.approx(1.0) and got["body_turn"] == 0.0
    assert got["camera_sweep"] == pytest.approx(1.0) and got["turning"] == pytest.approx(1.0)
    assert (got["seen"], got["first_seen_steps"], got["lost_sight"], got["sight_to_success"]) == (1, 4, 1, 0)
    # floor squares 0, 0, 1, 0, 0, 1: back into square 0 at step 3, stays at 4, back into 1 at 5
    assert got["revisit_steps"] == 3


def test_a_turn_across_pi_is_its_short_way_and_a_success_counts_from_first_sight():
    ep = _episode(x=[0.0, 0.0, 0.0], theta=[3.1, -3.1, -3.0], head_yaw=[0.0, -0.1, -0.1],
                  visible=[True, True, True], success=[False, False, True])
    got = episode_behaviour(ep, step_seconds=0.15)
    assert got["body_turn"] == pytest.approx((2 * math.pi - 6.2) + 0.1)
    # camera heading 3.1 -> -3.2 -> -3.1: 2 pi - 6.3 the short way, then 0.1
    assert got["camera_sweep"] == pytest.approx(abs(2 * math.pi - 6.3) + 0.1)
    # seen at the reset: no window before it, nothing lost, success 2 steps after first sight
    assert (got["first_seen_steps"], got["window_steps"], got["lost_sight"], got["sight_to_success"]) == (0, 0, 0, 2)


def test_revisits_count_coming_back_not_staying():
    # squares A A B A A C
    assert revisit_steps([0.1, 0.2, 0.7, 0.2, 0.3, 1.2], [0.1] * 6) == 2
    assert revisit_steps([0.1, 0.2, 0.3], [0.1] * 3) == 0


def _episodes(variant, per_scenario, seeds=(0,), cell="kitchen_living/everywhere/h1.65"):
    """Rows of behaviour_episodes from {scenario_id: {column: value}} (the other columns 0)."""
    from egosearch.report.behaviour import STATISTICS

    cols = {c for s in STATISTICS for c in (s.num, s.den, *(s.minus or ()))}
    rows = []
    for seed in seeds:
        for sid, values in per_scenario.items():
            rows.append({"variant": variant, "seed": seed, "cell": cell, "scenario_id": sid, "head": True,
                         **{c: 0 for c in cols}, "episodes": 1, **values})
    return pd.DataFrame(rows)


def test_a_statistic_is_a_ratio_of_sums_and_a_contrast_pairs_the_scenarios():
    on = _episodes("head_on", {0: {"success": 1, "steps": 20, "backward_steps": 4},
                               1: {"success": 1, "steps": 80, "backward_steps": 4},
                               2: {"success": 0, "steps": 100, "backward_steps": 0}}, seeds=(0, 1))
    off = _episodes("head_off", {0: {"success": 1, "steps": 50}, 1: {"success": 0, "steps": 100},
                                 2: {"success": 0, "steps": 100}, 3: {"success": 1, "steps": 10}}, seeds=(0, 1))
    s = summarise(pd.concat([on, off]), n_resamples=2000).set_index(["variant", "statistic"])
    assert s.loc[("head_on", "success"), "value"] == pytest.approx(2 / 3)
    # 8 backward of 200 steps per seed: steps are pooled, not episode shares averaged (that gives 0.0667)
    assert s.loc[("head_on", "backward_share"), "value"] == pytest.approx(8 / 200)
    # paired on scenarios 0..2 only: 2/3 - 1/3
    pair = s.loc[("head_on - head_off", "success")]
    assert pair["value"] == pytest.approx(1 / 3) and pair["n_scenarios"] == 3
    for key in (("head_on", "success"), ("head_on", "backward_share"), ("head_on - head_off", "success")):
        assert s.loc[key, "ci_low"] <= s.loc[key, "value"] <= s.loc[key, "ci_high"]
    # no step near an opening anywhere: no number, not a zero
    assert math.isnan(s.loc[("head_on", "speed_near_opening"), "value"])


def test_a_scenario_that_repeats_over_seeds_is_one_unit():
    # the same two scenarios under 1 or 3 seeds with identical outcomes: the interval does not narrow
    per = {0: {"success": 1}, 1: {"success": 0}}
    one = summarise(_episodes("head_on", per, seeds=(0,)), n_resamples=4000).set_index("statistic")
    three = summarise(_episodes("head_on", per, seeds=(0, 1, 2)), n_resamples=4000).set_index("statistic")
    assert (three.loc["success", "ci_low"], three.loc["success", "ci_high"]) == (
        one.loc["success", "ci_low"], one.loc["success", "ci_high"]) == (0.0, 1.0)


def _summary(rows):
    return pd.DataFrame([{"variant": v, "statistic": s, "value": x, "ci_low": lo, "ci_high": hi, "n_scenarios": 100,
                          "n_seeds": 3} for v, s, x, lo, hi in rows])


def test_verdicts_follow_the_side_of_the_interval():
    summary = _summary([
        ("head_on", "speed_near_minus_elsewhere", -0.2, -0.3, -0.1),      # slower near cabinets: holds
        ("head_on", "dwell_opening_minus_surface", 0.4, -0.1, 0.9),       # straddles 0
        ("head_on", "backward_before_sight_minus_other", -0.05, -0.08, -0.02),  # the other side
        ("head_on", "success", 0.8, 0.7, 0.9),
    ])
    got = claims_frame(summary)
    assert list(got["sign"]) == ["holds", "not shown", "opposite", "not testable here", "not testable here"]
    # Section 6.3 states no number; Figure 6 does, but there is no head-off side to measure it on.
    assert list(got["size"]) == ["no size in the paper"] * 3 + ["not testable here", "no size in the paper"]
    assert list(got["verdict"]) == ["sign holds, no size in the paper", "sign not shown, no size in the paper",
                                    "sign opposite, no size in the paper", "not testable here", "not testable here"]
    details = list(got["detail"])
    assert "includes 0" in details[1] and "other side" in details[2] and "head_off" in details[3]
    summary = pd.concat([summary, _summary([("head_on - head_off", "success", 0.15, 0.05, 0.25),
                                            ("head_on - head_off", "body_turn_per_step", 0.01, -0.02, 0.04)])])
    got = claims_frame(summary)
    assert list(got["verdict"])[3:] == ["sign holds, size reproduced", "sign not shown, no size in the paper"]
    assert got["paper_size"][3] == pytest.approx(0.20) and math.isnan(got["paper_size"][4])
    assert "+0.20 is inside" in got["detail"][3]


def _success_claim(value, lo, hi, head_off_rate=0.5):
    summary = _summary([("head_on - head_off", "success", value, lo, hi),
                        ("head_off", "success", head_off_rate, head_off_rate - 0.03, head_off_rate + 0.03)])
    return claims_frame(summary).iloc[3]


def test_the_size_is_read_apart_from_the_sign():
    # Excludes 0 but not the paper's +0.20: the direction is reproduced, the amount is not.
    row = _success_claim(0.05, 0.02, 0.08)
    assert (row["sign"], row["size"]) == ("holds", "size not reproduced")
    assert row["verdict"] == "sign holds, size not reproduced" and "+0.20 is outside" in row["detail"]
    # The interval holds +0.20: both reproduced.
    row = _success_claim(0.18, 0.12, 0.24)
    assert row["verdict"] == "sign holds, size reproduced"
    # Straddles 0: the sign is not shown, whatever the size; +0.20 inside says only "not ruled out".
    row = _success_claim(0.10, -0.02, 0.22)
    assert (row["sign"], row["size"]) == ("not shown", "size reproduced") and "not ruled out" in row["detail"]
    assert _success_claim(0.02, -0.02, 0.06)["verdict"] == "sign not shown, size not reproduced"
    # Wholly below 0: opposite, and the paper's size cannot be inside.
    assert _success_claim(-0.06, -0.09, -0.03)["verdict"] == "sign opposite, size not reproduced"
    # "20% higher" read as a share of head off's own rate: 0.2 x 0.4 = +0.08, inside [0.02, 0.09].
    row = _success_claim(0.05, 0.02, 0.09, head_off_rate=0.4)
    assert row["size"] == "size not reproduced" and "+0.080: inside it" in row["detail"]


def test_sign_and_size_verdicts_by_hand():
    from egosearch.report.behaviour import sign_verdict, size_verdict
    assert sign_verdict(0.01, 0.2, +1) == "holds" and sign_verdict(-0.2, -0.01, -1) == "holds"
    assert sign_verdict(-0.01, 0.2, +1) == "not shown" and sign_verdict(0.0, 0.2, +1) == "not shown"
    assert sign_verdict(-0.2, -0.01, +1) == "opposite" and sign_verdict(0.01, 0.2, -1) == "opposite"
    assert size_verdict(0.1, 0.3, 0.2) == "size reproduced" and size_verdict(0.2, 0.3, 0.2) == "size reproduced"
    assert size_verdict(0.01, 0.19, 0.2) == "size not reproduced" and size_verdict(0.1, 0.3, None) == \
        "no size in the paper"


def test_an_empty_measure_is_not_testable():
    got = claims_frame(_summary([("head_on", "speed_near_minus_elsewhere", math.nan, math.nan, math.nan)]))
    assert got["verdict"][0] == "not testable here" and "no step" in got["detail"][0]
    assert got["sign"][0] == "not testable here"


def _write_trace(path, episodes, head=True, learns=None):
    cols = {k: [] for k in ("scenario_id", "step", "x", "y", "theta", "head_yaw", "pitch", "visible", "success",
                            "gaze_kind", "opening_distance")}
    for sid, ep in episodes.items():
        for k in cols:
            cols[k] += list(ep[k]) if k != "scenario_id" else [sid] * len(ep)
    path.parent.mkdir(parents=True, exist_ok=True)
    facts = {} if learns is None else {"learns": np.asarray(learns)}
    np.savez_compressed(path, **{k: np.asarray(v) for k, v in cols.items()}, step_seconds=np.asarray(0.5),
                        head=np.asarray(head), **facts)


def test_trace_files_to_claims_and_the_readme_block(tmp_path):
    root = tmp_path / "repo"
    assert "Not yet stored" in block_claims(root, "cpu")
    traces = root / "results" / "cpu" / "traces"
    for variant in ("head_on", "head_off"):
        for seed in (0, 1):
            _write_trace(traces / variant / f"seed{seed}" / "kitchen_living" / "everywhere" / "h1.65.npz",
                         {0: HAND, 3: HAND}, head=variant == "head_on")
    paths = sorted(traces.rglob("*.npz"))
    eps = behaviour_episodes(paths)
    assert len(eps) == 8 and set(eps["cell"]) == {"kitchen_living/everywhere/h1.65"}
    assert set(eps.loc[eps["variant"] == "head_off", "head"]) == {False}
    written = behaviour_report(paths, root / "paper_figs" / "cpu" / "behaviour", n_resamples=500)
    assert [p.name for p in written] == ["behaviour_episodes.csv", "behaviour.csv", "behaviour.md",
                                         "behaviour_claims.csv", "behaviour_claims.md"]
    block = block_claims(root, "cpu")
    assert "moves slower" not in block and "move slower around cabinets" in block
    # identical traces on both sides: the success gain is exactly 0, which is no gain
    assert "| **sign not shown, size not reproduced**" in block.split("20% higher")[1].split("\n")[0]
    assert "| +0.20 |" in block and "| none stated |" in block
    with pytest.raises(ValueError, match="a second trace"):
        behaviour_episodes(paths + paths[:1])


def test_the_readme_block_and_the_command(tmp_path, capsys):
    from egosearch.cli import main
    from egosearch.report.readme import render_readme

    root = tmp_path / "repo"
    text = "<!-- egosearch:begin claims -->\nold\n<!-- egosearch:end claims -->\n"
    assert "Not yet stored: `paper_figs/cpu/behaviour_claims.csv`" in render_readme(text, root, "cpu")
    paths = []
    for variant in ("head_on", "head_off"):
        paths.append(root / "results" / "cpu" / "traces" / variant / "seed0" / "kitchen_living" / "everywhere" /
                     "h1.65.npz")
        _write_trace(paths[-1], {0: HAND, 1: HAND})
    assert main(["report", "behaviour", *map(str, paths), "--out-prefix", f"{root}/paper_figs/cpu/"]) == 0
    assert "behaviour_claims.md" in capsys.readouterr().out
    rendered = render_readme(text, root, "cpu")
    assert "| paper (where) |" in rendered and "From `paper_figs/cpu/behaviour_claims.csv`" in rendered
    assert main(["report", "behaviour", str(tmp_path / "nothing" / "h1.65.npz"), "--out-prefix", str(tmp_path)]) == 2


def test_the_claims_are_read_on_each_pair_side_by_side(tmp_path):
    from egosearch.report.behaviour import claims_markdown

    # Two pairs: the learned one gains 0.15 in success with head movement, the classical one loses 0.05.
    summary = _summary([("head_on", "success", 0.8, 0.7, 0.9), ("head_off", "success", 0.65, 0.55, 0.75),
                        ("head_on - head_off", "success", 0.15, 0.05, 0.25),
                        ("frontier", "success", 0.7, 0.6, 0.8), ("frontier_head_off", "success", 0.75, 0.65, 0.85),
                        ("frontier - frontier_head_off", "success", -0.05, -0.09, -0.01)])
    got = claims_frame(summary, [("head_on", "head_off"), ("frontier", "frontier_head_off")])
    assert list(got["searchers"]) == ["head_on / head_off"] * 5 + ["frontier / frontier_head_off"] * 5
    success = got[got["claim"].str.contains("20% higher")].set_index("searchers")
    assert success.loc["head_on / head_off", "verdict"] == "sign holds, size reproduced"
    assert success.loc["frontier / frontier_head_off", "verdict"] == "sign opposite, size not reproduced"
    # each pair's "20% of the head-off rate" reading uses its own head-off searcher's rate
    assert "head_off's own rate 0.650" in success.loc["head_on / head_off", "detail"]
    assert "frontier_head_off's own rate 0.750" in success.loc["frontier / frontier_head_off", "detail"]
    md = claims_markdown(got)
    header, _, *rows = md.split("\n")[:7]
    assert header.endswith("| `head_on / head_off` | `frontier / frontier_head_off` |")
    assert len(rows) == 5 and all(r.count("**") == 4 for r in rows)
    line = next(r for r in rows if "20% higher" in r)
    assert "+0.150 [+0.050, +0.250], 100 × 3: **sign holds, size reproduced**" in line
    assert line.endswith("-0.050 [-0.090, -0.010], 100 × 3: **sign opposite, size not reproduced** |")
    assert "What each verdict rests on" in md and md.count("`frontier / frontier_head_off`: ") == 5
    # one pair: the single-pair table, as before
    assert "| verdict: sign, size |" in claims_markdown(claims_frame(summary))


def test_a_pair_without_traces_is_one_line_before_any_work(tmp_path):
    from egosearch.cli import main

    path = tmp_path / "traces" / "head_on" / "seed0" / "kitchen_living" / "everywhere" / "h1.65.npz"
    _write_trace(path, {0: HAND})
    with pytest.raises(ValueError, match=r"^no trace files of frontier, head_off \(the pairs' variants\)"):
        behaviour_report([path], tmp_path / "out" / "behaviour", pairs=[("head_on", "head_off"),
                                                                        ("frontier", "head_on")])
    assert not (tmp_path / "out").exists()
    assert main(["report", "behaviour", str(path), "--pairs", "head_on", "--out-prefix", str(tmp_path)]) == 2
    assert main(["report", "behaviour", str(path), "--pairs", "head_on:head_on", "--out-prefix", str(tmp_path)]) == 2


def test_the_body_claims_are_not_read_on_a_searcher_whose_body_steps_are_not_learned(tmp_path):
    """A modular searcher's traces say it learns decisions: its speed, backward steps and body turns are the
    frontier searcher's, so those claims are declared unread on its pair; success is read as on any pair."""
    from egosearch.report.behaviour import CLAIMS, NOT_LEARNED

    traces = tmp_path / "traces"
    paths = []
    for variant, learns in (("head_on", None), ("head_off", None), ("head_on_modular", "decisions"),
                            ("head_off_modular", "decisions")):
        paths.append(traces / variant / "seed0" / "kitchen_living" / "everywhere" / "h1.65.npz")
        _write_trace(paths[-1], {0: HAND, 3: HAND}, head="head_on" in variant, learns=learns)
    assert set(behaviour_episodes(paths).groupby("variant")["learns"].first().items()) == {
        ("head_on", "steps"), ("head_off", "steps"), ("head_on_modular", "decisions"),
        ("head_off_modular", "decisions")}
    written = behaviour_report(paths, tmp_path / "out" / "behaviour", n_resamples=200,
                               pairs=[("head_on", "head_off"), ("head_on_modular", "head_off_modular")])
    claims = pd.read_csv(written[3])
    modular = claims[claims["searchers"] == "head_on_modular / head_off_modular"].set_index("claim")
    learned = claims[claims["searchers"] == "head_on / head_off"].set_index("claim")
    body = [c.claim for c in CLAIMS if c.body]
    assert len(body) == 3 and (modular.loc[body, "detail"] == NOT_LEARNED).all()
    assert (modular.loc[body, "verdict"] == "not testable here").all()
    assert not (learned["detail"] == NOT_LEARNED).any()
    success = next(c.claim for c in CLAIMS if c.statistic == "success")
    assert modular.loc[success, "n_scenarios"] == 2 and modular.loc[success, "detail"] != NOT_LEARNED

"""Success by shortest path ℓ and by detour, and compare's split by ℓ: hand-worked synthetic CSVs."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from egosearch.cli import main
from egosearch.report.commands import cmd_compare
from egosearch.report.pathlength import (
    BY_LENGTH_COLUMNS,
    DETOUR_BINS,
    LENGTH_BINS,
    PATHLENGTH_COLUMNS,
    bin_labels,
    bin_of,
    compare_by_length,
    detour,
    pathlength_frame,
    pathlength_report,
)

RADIUS = 0.7


def write_scenarios(root: Path, home: str, placement: str, height: float, rows: list[tuple]) -> Path:
    """``rows``: (start_x, start_y, target_x, target_y, ℓ) per scenario, ids 0..n-1."""
    path = root / "scenarios" / home / placement / f"h{height:g}.csv"
    path.parent.mkdir(parents=True, exist_ok=True)
    pd.DataFrame([{"scenario_id": i, "layout": home, "placement": placement, "height": height, "start_x": sx,
                   "start_y": sy, "start_theta": 0.0, "target_object": "mug", "target_x": tx, "target_y": ty,
                   "target_z": 0.5, "target_yaw": 0.0, "shortest_path": ell}
                  for i, (sx, sy, tx, ty, ell) in enumerate(rows)]).to_csv(path, index=False)
    return path


def write_eval(root: Path, variant: str, seed: int, home: str, placement: str, height: float, lengths,
               success) -> Path:
    path = root / "eval" / variant / f"seed{seed}" / home / placement / f"h{height:g}.csv"
    path.parent.mkdir(parents=True, exist_ok=True)
    success = np.asarray(success, int)
    ell = np.asarray(lengths, float)
    pd.DataFrame({"scenario_id": np.arange(len(ell)), "success": success, "steps": 50, "path_length": ell,
                  "shortest_path": ell, "spl": success.astype(float), "collisions": 0,
                  "episode_return": 0.0}).to_csv(path, index=False)
    return path


# Two cells of one home. At 1.05 m: ℓ 1, 1.5, 3, 9 with targets 1.7, 1.0, 3.4 and 6.7 m from the start,
# so detours ℓ - max(0, d - 0.7) of 0.0, 1.2, 0.3 and 3.0 m; at 1.65 m: ℓ 2.5 and 5 at 3.0 and 5.7 m,
# detours 0.2 and 0.0 m.
CELL_105 = [(0, 0, 1.02, 1.36, 1.0), (0, 0, 0.6, 0.8, 1.5), (0, 0, 2.04, 2.72, 3.0), (0, 0, 4.02, 5.36, 9.0)]
CELL_165 = [(0, 0, 1.8, 2.4, 2.5), (0, 0, 3.42, 4.56, 5.0)]
SUCCESS = {(0, 1.05): [1, 1, 0, 0], (1, 1.05): [1, 0, 0, 0], (0, 1.65): [1, 1], (1, 1.65): [1, 1]}


def make_tree(root: Path, variant: str = "head_on") -> tuple[list[Path], list[Path]]:
    scenarios = [write_scenarios(root, "kitchen", "everywhere", 1.05, CELL_105),
                 write_scenarios(root, "kitchen", "everywhere", 1.65, CELL_165)]
    evals = [write_eval(root, variant, seed, "kitchen", "everywhere", h, [r[-1] for r in cell], SUCCESS[(seed, h)])
             for seed in (0, 1) for h, cell in ((1.05, CELL_105), (1.65, CELL_165))]
    return evals, scenarios


def row(df: pd.DataFrame, by: str, label: str, height: str = "all", searcher: str = "head_on") -> pd.Series:
    hit = df[(df["searcher"] == searcher) & (df["height"] == height) & (df["by"] == by) & (df["bin"] == label)]
    assert len(hit) == 1
    return hit.iloc[0]


def test_bins_are_half_open_and_labelled():
    assert bin_labels(LENGTH_BINS) == ["0-2", "2-4", "4-6", "6-8", "8+"]
    assert bin_labels(DETOUR_BINS) == ["<0.25", "0.25-1", "1-2.5", "2.5+"]
    assert bin_of([0.0, 1.99, 2.0, 7.99, 8.0, 30.0, math.nan], LENGTH_BINS).tolist() == [0, 0, 1, 3, 4, 4, -1]
    assert bin_of([-0.04, 0.25, 0.99, 2.5], DETOUR_BINS).tolist() == [0, 1, 1, 3]


def test_detour_hand_worked():
    # |(3, 4)| = 5: the ring of 0.7 m is 4.3 m away, so ℓ 5.3 is a 1.0 m detour; a start 0.5 m from the
    # target is inside the ring: its detour is ℓ itself.
    df = pd.DataFrame({"start_x": [0.0, 0.0], "start_y": [0.0, 0.0], "target_x": [3.0, 0.3], "target_y": [4.0, 0.4],
                       "shortest_path": [5.3, 0.2]})
    assert detour(df, RADIUS).tolist() == pytest.approx([1.0, 0.2])
    assert detour(df, 0.0).tolist() == pytest.approx([0.3, 0.2 - 0.5])


def test_success_by_length_and_detour_hand_worked(tmp_path):
    evals, scenarios = make_tree(tmp_path)
    df = pathlength_frame(evals, scenarios, RADIUS, n_resamples=2000)
    assert list(df.columns) == list(PATHLENGTH_COLUMNS)
    # ℓ 0-2: the 1.05 m scenarios 0 (success 1, 1) and 1 (1, 0): 3 of 4 episodes
    r = row(df, "length", "0-2")
    assert (r.n_scenarios, r.n_seeds, r.n_episodes, r.success_rate) == (2, 2, 4, 0.75)
    # matrix [[1, 1], [1, 0]]: all-zero resamples (scenario 1 twice, seed 1 twice) have probability
    # 1/16 and all-one ones 5/16, both above 2.5%: the interval is [0, 1]
    assert (r.ci_low, r.ci_high) == (0.0, 1.0)
    # ℓ 2-4 pools the cells: 1.05 m scenario 2 (0, 0) and 1.65 m scenario 0 (1, 1)
    r = row(df, "length", "2-4")
    assert (r.n_scenarios, r.success_rate, r.ci_low, r.ci_high) == (2, 0.5, 0.0, 1.0)
    r = row(df, "length", "4-6")
    assert (r.n_scenarios, r.success_rate, r.ci_low, r.ci_high) == (1, 1.0, 1.0, 1.0)
    r = row(df, "length", "6-8")
    assert r.n_scenarios == 0 and math.isnan(r.success_rate)
    assert row(df, "length", "8+").success_rate == 0.0
    # per height: 1.65 m has ℓ 2.5 and 5 only
    assert row(df, "length", "2-4", "1.65").success_rate == 1.0
    assert row(df, "length", "0-2", "1.65").n_scenarios == 0
    # detours 0.0, 1.2, 0.3, 3.0 (1.05 m) and 0.2, 0.0 (1.65 m)
    r = row(df, "detour", "<0.25")  # 1.05 #0, 1.65 #0 and #1: every episode a success
    assert (r.n_scenarios, r.success_rate) == (3, 1.0)
    assert row(df, "detour", "0.25-1").success_rate == 0.0  # 1.05 #2
    assert row(df, "detour", "1-2.5").success_rate == 0.5  # 1.05 #1: seed 0 only
    assert row(df, "detour", "2.5+").success_rate == 0.0  # 1.05 #3
    assert set(df["height"]) == {"all", "1.05", "1.65"}


def test_bounds_are_binned_on_the_same_scenarios(tmp_path):
    evals, scenarios = make_tree(tmp_path)
    bounds = [write_eval(tmp_path, "oracle", 0, "kitchen", "everywhere", h, [r[-1] for r in cell], [1] * len(cell))
              for h, cell in ((1.05, CELL_105), (1.65, CELL_165))]
    df = pathlength_frame(evals, scenarios, RADIUS, bound_files=bounds, n_resamples=500)
    r = row(df, "length", "0-2", searcher="oracle")
    assert (r.n_scenarios, r.n_seeds, r.success_rate) == (2, 1, 1.0)
    assert set(df.loc[df["searcher"] == "oracle", "height"]) == {"all"}  # the policy alone is split by height
    other = write_scenarios(tmp_path, "bedroom", "everywhere", 1.05, CELL_105)
    stray = write_eval(tmp_path, "random", 0, "bedroom", "everywhere", 1.05, [r[-1] for r in CELL_105], [0] * 4)
    with pytest.raises(ValueError, match="random ran scenario sets head_on did not"):
        pathlength_frame(evals, [*scenarios, other], RADIUS, bound_files=[stray], n_resamples=100)


def test_pathlength_refuses_unmatched_scenarios(tmp_path):
    evals, scenarios = make_tree(tmp_path)
    with pytest.raises(ValueError, match="no scenario file for the evaluated set kitchen/everywhere/h1.65.csv"):
        pathlength_frame(evals, scenarios[:1], RADIUS, n_resamples=100)
    wrong = write_scenarios(tmp_path / "other", "kitchen", "everywhere", 1.65, [(0, 0, 1, 1, 7.0), (0, 0, 1, 1, 5.0)])
    with pytest.raises(ValueError, match="not the scenario set evaluated in kitchen/everywhere/h1.65.csv"):
        pathlength_frame(evals, [scenarios[0], wrong], RADIUS, n_resamples=100)
    with pytest.raises(ValueError, match="2 variants"):
        pathlength_frame(evals + make_tree(tmp_path, "head_off")[0], scenarios, RADIUS, n_resamples=100)


def test_pathlength_files_and_the_cli_radius(tmp_path, capsys):
    evals, scenarios = make_tree(tmp_path)
    outs = pathlength_report(evals, scenarios, RADIUS, tmp_path / "figs" / "pathlength_head_on",
                             out_csv=tmp_path / "res" / "head_on.csv", n_resamples=500)
    assert [p.name for p in outs] == ["head_on.csv", "pathlength_head_on.md", "pathlength_head_on.png",
                                      "pathlength_head_on.pdf"]
    assert outs[2].stat().st_size > 20_000
    md = outs[1].read_text()
    assert "| 2-4 | 2 | 0.50 [0.00, 1.00] | 0.00 [0.00, 0.00] | 1.00 [1.00, 1.00] |" in md  # pooled, 1.05, 1.65 m
    assert "| 6-8 | 0 | – | – | – |" in md
    # The CLI's ring is the success distance plus the body's radius (0.7 m): a start 5 m from the target
    # with ℓ 4.6 is a 0.3 m detour (with 0.5 m it would be 0.1, in the first bin).
    scen = write_scenarios(tmp_path / "c", "kitchen", "everywhere", 1.05, [(0, 0, 3, 4, 4.6)])
    ev = write_eval(tmp_path / "c", "head_on", 0, "kitchen", "everywhere", 1.05, [4.6], [1])
    argv = ["report", "pathlength", str(ev), "--scenarios", str(scen), "--out-prefix", str(tmp_path / "c" / "pl")]
    assert main(argv) == 0
    df = pd.read_csv(tmp_path / "c" / "pl.csv")
    hit = df[(df["by"] == "detour") & (df["n_scenarios"] > 0) & (df["height"] == "all")]
    assert hit["bin"].tolist() == ["0.25-1"]
    assert "wrote" in capsys.readouterr().out


# --------------------------------------------------------------------------------------------- compare
def _side(root: Path, variant: str, success_short, success_long, seeds=(0, 1)) -> list[Path]:
    """Two cells (heights) of 3 scenarios each: ℓ 1.0 (bin 0-2) for ids 0-1 and ℓ 3.0 (bin 2-4) for id 2."""
    paths = []
    for seed in seeds:
        for h in (1.05, 1.65):
            paths.append(write_eval(root, variant, seed, "kitchen", "everywhere", h, [1.0, 1.0, 3.0],
                                    [success_short, success_short, success_long]))
    return paths


def test_compare_by_length_hand_worked(tmp_path):
    """The candidate finds every short target the reference misses and ties on the long ones: +1 on
    the 4 short scenarios (both cells), interval [1, 1]; 0 and p = 1 on the 2 long ones. The p-value is
    read off the interval's own draws: none reaches 0, so p is its floor, one draw's share (1/1000).
    Holm over the 4 rows: 4 x 0.001 for the first, 3 x 0.001 (raised to the running max) for the
    second: significant; the long rows stay at 1. (A bootstrap sees no spread the 4 scenarios do not
    show: the stored bins hold 29 or more.)"""
    ref = _side(tmp_path, "head_on", 0, 1)
    cand = _side(tmp_path, "head_off", 1, 1)
    df = compare_by_length(ref, cand, tmp_path / "cmp_by_length.csv", n_resamples=1000)
    assert list(df.columns) == list(BY_LENGTH_COLUMNS)
    assert df["length_bin"].tolist() == ["0-2", "0-2", "2-4", "2-4"]
    assert df["metric"].tolist() == ["success", "spl"] * 2
    short, long_ = df.iloc[0], df.iloc[2]
    assert (short.reference, short.candidate, short.difference) == (0.0, 1.0, 1.0)
    assert (short.ci_low, short.ci_high, short.n_scenarios) == (1.0, 1.0, 4)
    assert short.p_uncorrected == pytest.approx(1 / 1000)
    assert (long_.difference, long_.ci_low, long_.ci_high, long_.p_uncorrected, long_.n_scenarios) == (0, 0, 0, 1, 2)
    assert df["p_holm"].tolist() == pytest.approx([0.004, 0.004, 1.0, 1.0])
    assert df["significant_holm"].tolist() == [True, True, False, False]
    assert pd.read_csv(tmp_path / "cmp_by_length.csv").shape == df.shape


def test_compare_writes_the_split_beside_the_stable_cell_csv(tmp_path, capsys):
    ref = _side(tmp_path, "head_on", 0, 1)
    cand = _side(tmp_path, "head_off", 1, 1)
    cmd_compare(ref, cand, tmp_path / "o" / "head_off_vs_head_on.csv")
    cells = pd.read_csv(tmp_path / "o" / "head_off_vs_head_on.csv")
    assert list(cells.columns)[:4] == ["height", "placement", "metric", "reference"]  # unchanged
    by = pd.read_csv(tmp_path / "o" / "head_off_vs_head_on_by_length.csv")
    assert list(by.columns) == list(BY_LENGTH_COLUMNS) and len(by) == 4
    out = capsys.readouterr().out
    assert "By shortest path ℓ" in out and "head_off_vs_head_on_by_length.csv" in out


def test_compare_by_length_refuses_different_lengths(tmp_path):
    ref = _side(tmp_path, "head_on", 0, 1)
    cand = [write_eval(tmp_path, "head_off", s, "kitchen", "everywhere", h, [1.0, 1.0, 5.0], [1, 1, 1])
            for s in (0, 1) for h in (1.05, 1.65)]
    with pytest.raises(ValueError, match="has ℓ 3 in the reference and 5 in the candidate"):
        compare_by_length(ref, cand, n_resamples=100)

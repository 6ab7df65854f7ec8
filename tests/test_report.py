"""The report layer: statistics, tables, figures and comparisons from synthetic CSVs (fast, no torch/sim)."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from egosearch.report import (
    PAPER_TABLE1,
    bootstrap_ci,
    cells_from_paths,
    compare_cells,
    compare_report,
    figure6,
    figure7,
    format_compare,
    group_eval_paths,
    holm,
    parse_eval_path,
    table1,
    table2,
    wilson_ci,
)
from egosearch.report.commands import cmd_compare, cmd_fig6, cmd_fig7, cmd_table1, cmd_table2
from egosearch.report.stats import detectable_difference, scenario_seed_matrix, two_level_ci

EPISODE_COLUMNS = ["scenario_id", "success", "steps", "path_length", "shortest_path", "spl", "collisions",
                   "episode_return"]
CURVE_COLUMNS = ["env_steps", "success_rate", "spl", "episode_return", "critic_loss", "actor_loss", "curl_loss",
                 "alpha", "entropy", "steps_per_s", "updates_per_s", "wall_s"]
FULLBODY_COLUMNS = ["scenario_id", "method", "mg", "M", "T", "success", "steps", "path_length", "shortest_path",
                    "spl", "attempts", "penetrations", "penetration_rate", "collisions"]
N_RES = 999  # bootstrap resamples in the figure/table tests (speed)


# --------------------------------------------------------------------------------------------- synthetic data
def episodes_frame(success, rng=None) -> pd.DataFrame:
    """Per-episode rows with the evaluation CSV's columns; scenario ids 0..n-1."""
    rng = rng or np.random.default_rng(0)
    success = np.asarray(success, dtype=int)
    n = success.size
    shortest = np.round(rng.uniform(1.0, 6.0, n), 3)
    path = np.round(shortest * rng.uniform(1.0, 2.5, n), 3)
    spl = np.where(success == 1, shortest / np.maximum(path, shortest), 0.0)
    return pd.DataFrame({"scenario_id": np.arange(n), "success": success, "steps": rng.integers(5, 100, n),
                         "path_length": path, "shortest_path": shortest, "spl": np.round(spl, 5),
                         "collisions": rng.integers(0, 4, n), "episode_return": np.round(rng.normal(0, 3, n), 3)},
                        columns=EPISODE_COLUMNS)


def eval_path(root: Path, variant: str, seed: int, layout: str, placement: str, height: float) -> Path:
    return root / "eval" / variant / f"seed{seed}" / layout / placement / f"h{height:.2f}.csv"


def write_eval(root, variant, seed, layout, placement, height, success, rng=None) -> Path:
    p = eval_path(root, variant, seed, layout, placement, height)
    p.parent.mkdir(parents=True, exist_ok=True)
    episodes_frame(success, rng).to_csv(p, index=False)
    return p


def make_eval_tree(root: Path, variant: str = "head_on", seeds=(0, 1, 2), n: int = 50, shift: float = 0.0,
                   layouts=("kitchen", "bedroom")) -> list[Path]:
    """All 6 Table-1 cells x seeds x layouts, success probability near the paper's, plus ``shift``."""
    paths = []
    for (h, pl), p in PAPER_TABLE1.items():
        for s in seeds:
            for li, lay in enumerate(layouts):
                rng = np.random.default_rng(1000 * s + 17 * li + int(h * 100) + len(pl))
                succ = rng.random(n) < min(1.0, max(0.0, p + shift))
                paths.append(write_eval(root, variant, s, lay, pl, h, succ, rng))
    return paths


def write_curve(path: Path, steps, success) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    k = len(steps)
    df = pd.DataFrame({c: np.zeros(k) for c in CURVE_COLUMNS})
    df["env_steps"] = steps
    df["success_rate"] = success
    df.to_csv(path, index=False)
    return path


def make_curves(root: Path, seeds=(0, 1, 2)) -> dict[str, list[Path]]:
    steps = np.arange(0, 750_001, 25_000)
    out = {}
    for variant, top in (("head_on", 0.85), ("head_off", 0.65)):
        out[variant] = []
        for s in seeds:
            rng = np.random.default_rng(s + (0 if variant == "head_on" else 100))
            curve = top * (1 - np.exp(-steps / 150_000)) + rng.normal(0, 0.04, steps.size)
            out[variant].append(write_curve(root / "train" / variant / f"seed{s}" / "curve.csv", steps,
                                            np.clip(curve, 0, 1)))
    return out


def fullbody_frame(method, mg, M, n, spl_mean, attempts_mean, rng, T=20) -> pd.DataFrame:
    shortest = rng.uniform(1.0, 6.0, n)
    success = (rng.random(n) < min(1.0, spl_mean * 1.4)).astype(int)
    spl = np.where(success == 1, np.clip(rng.normal(spl_mean / max(success.mean(), 1e-3), 0.1, n), 0, 1), 0.0)
    path = np.where(spl > 0, shortest / np.maximum(spl, 1e-3), shortest * 3)
    return pd.DataFrame({"scenario_id": np.arange(n), "method": method, "mg": mg, "M": M, "T": T, "success": success,
                         "steps": rng.integers(10, 100, n), "path_length": path, "shortest_path": shortest,
                         "spl": spl, "attempts": rng.poisson(attempts_mean, n), "penetrations": rng.integers(0, 3, n),
                         "penetration_rate": rng.uniform(0, 0.1, n), "collisions": rng.integers(0, 3, n)},
                        columns=FULLBODY_COLUMNS)


FB_SETTINGS = [("one_step_short", 5, 0.25, 60), ("one_step_long", 20, 0.3, 15), ("noisy_search", 5, 0.28, 12),
               ("ours", 1, 0.72, 60), ("ours", 5, 0.68, 14), ("ours", 10, 0.6, 8), ("ours", 20, 0.5, 5)]


def make_fullbody(root: Path, mgs=("humanoid_phase",), seeds=(0, 1), n: int = 40) -> list[Path]:
    paths = []
    for mi, mg in enumerate(mgs):
        for method, M, spl, att in FB_SETTINGS:
            for s in seeds:
                rng = np.random.default_rng(hash((mg, method, M, s)) % 2**32)
                p = root / "fullbody" / f"{mg}_{method}_M{M}" / f"seed{s}.csv"
                p.parent.mkdir(parents=True, exist_ok=True)
                fullbody_frame(method, mg, M, n, max(0.05, spl - 0.08 * mi), att, rng).to_csv(p, index=False)
                paths.append(p)
    return paths


def cell_frame(success, seed=0) -> pd.DataFrame:
    return episodes_frame(success).assign(seed=seed)


# --------------------------------------------------------------------------------------------- stats
def _wilson_by_hand(k: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """Wilson score interval: (p + z²/2n ± z·sqrt(p(1-p)/n + z²/4n²)) / (1 + z²/n), p = k/n."""
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return centre - half, centre + half


def test_wilson_hand_worked():
    # (0, 10): centre = (0 + 0.19208)/1.38415 = 0.138766, half = 0.138766 -> [0, 0.277533]
    # (5, 10): centre = 0.5, half = 1.95996/1.38415 * sqrt(0.025 + 0.0096) = 0.263407 -> [0.236593, 0.763407]
    # (10, 10): mirror of (0, 10) -> [0.722467, 1]
    expected = {(0, 10): (0.0, 0.277533), (5, 10): (0.236593, 0.763407), (10, 10): (0.722467, 1.0)}
    for (k, n), (lo, hi) in expected.items():
        got = wilson_ci(k, n)
        assert got == pytest.approx((lo, hi), abs=1e-6)
        assert got == pytest.approx(_wilson_by_hand(k, n), abs=1e-9)
    lo90, hi90 = wilson_ci(5, 10, confidence=0.90)
    assert lo90 > 0.236593 and hi90 < 0.763407


def test_wilson_rejects_bad_input():
    with pytest.raises(ValueError, match="n must be positive"):
        wilson_ci(0, 0)
    with pytest.raises(ValueError):
        wilson_ci(11, 10)


def test_bootstrap_constant_and_degenerate():
    assert bootstrap_ci([0.7, 0.7, 0.7]) == (0.7, 0.7)
    lo, hi = bootstrap_ci([0.5])
    assert math.isnan(lo) and math.isnan(hi)
    lo, hi = bootstrap_ci([])
    assert math.isnan(lo) and math.isnan(hi)
    assert bootstrap_ci([0.2, 0.4, 0.6], n_resamples=500, seed=3) == bootstrap_ci([0.2, 0.4, 0.6], n_resamples=500,
                                                                                   seed=3)


def test_bootstrap_coverage_sanity():
    """Percentile bootstrap of the mean of n=30 normal values: brackets the true mean most of the time."""
    rng = np.random.default_rng(0)
    hits, widths = 0, []
    for i in range(100):
        x = rng.normal(1.0, 1.0, 30)
        lo, hi = bootstrap_ci(x, n_resamples=1000, seed=i)
        assert lo <= x.mean() <= hi
        hits += lo <= 1.0 <= hi
        widths.append(hi - lo)
    assert 85 <= hits <= 100
    # width close to the normal-theory 2 * 1.96 / sqrt(30) = 0.716
    assert np.mean(widths) == pytest.approx(2 * 1.96 / math.sqrt(30), rel=0.15)


def test_compare_planted_difference():
    ids = np.arange(100)
    ref = pd.concat([cell_frame(ids < 50, seed=s) for s in range(3)], ignore_index=True)
    cand = pd.concat([cell_frame(ids < 80, seed=s) for s in (0, 1)], ignore_index=True)
    res = compare_cells(ref, cand, "success")
    assert res["reference"] == pytest.approx(0.5) and res["candidate"] == pytest.approx(0.8)
    assert res["difference"] == pytest.approx(0.3)
    assert res["ci_low"] > 0 and res["ci_low"] < 0.3 < res["ci_high"]
    assert res["p_uncorrected"] < 0.001
    assert (res["n_scenarios"], res["n_seeds_ref"], res["n_seeds_cand"]) == (100, 3, 2)
    worse = compare_cells(cand, ref, "success")
    assert worse["difference"] == pytest.approx(-0.3) and worse["ci_high"] < 0 and worse["p_uncorrected"] < 0.001


def test_compare_identical_copy():
    rng = np.random.default_rng(5)
    one = cell_frame(rng.random(100) < 0.6)
    for metric in ("success", "spl"):
        res = compare_cells(one, one.copy(), metric)
        assert (res["difference"], res["ci_low"], res["ci_high"], res["p_uncorrected"]) == (0.0, 0.0, 0.0, 1.0)
    # Two seeds that disagree: the copy's seeds are other training runs to the bootstrap, so the
    # interval is as wide as the seeds' spread, around 0, and p is far from significant.
    ref = pd.concat([cell_frame(rng.random(100) < 0.6, seed=s) for s in range(2)], ignore_index=True)
    for metric in ("success", "spl"):
        res = compare_cells(ref, ref.copy(), metric)
        assert res["difference"] == 0.0 and res["ci_low"] < 0 < res["ci_high"]
        assert res["p_uncorrected"] > 0.5


def test_compare_noise_not_significant_and_seed_averaging():
    rng = np.random.default_rng(11)
    ref = cell_frame(rng.random(100) < 0.5)
    cand = cell_frame(rng.random(100) < 0.5)
    res = compare_cells(ref, cand, "success")
    assert res["ci_low"] <= res["difference"] <= res["ci_high"]
    assert res["p_uncorrected"] > 0.01
    # two candidate seeds disagreeing on scenario 0: that scenario counts 0.5
    ref2 = cell_frame([0, 0])
    cand2 = pd.concat([cell_frame([1, 0], seed=0), cell_frame([0, 0], seed=1)], ignore_index=True)
    assert compare_cells(ref2, cand2, "success")["candidate"] == pytest.approx(0.25)


def test_compare_rejects_bad_input():
    with pytest.raises(ValueError, match="different scenarios"):
        compare_cells(cell_frame(np.ones(10)), cell_frame(np.ones(11)), "success")
    with pytest.raises(ValueError, match="metric"):
        compare_cells(cell_frame(np.ones(10)), cell_frame(np.ones(10)), "steps")


def _paired(values, metric, seeds=(0,)):
    return pd.concat([pd.DataFrame({"scenario_id": range(len(values)), "seed": s, metric: values}) for s in seeds],
                     ignore_index=True)


def _old_sign_flip_p(reference: pd.DataFrame, candidate: pd.DataFrame, metric: str, n_resamples: int = 10_000) -> float:
    """The p-value compare_cells gave before it read p from its bootstrap: a two-sided sign-flip test over
    scenarios on the seed-averaged differences (the seeds' disagreement never enters it)."""
    from scipy import stats as sstats
    r = reference.groupby("scenario_id")[metric].mean().to_numpy()
    c = candidate.groupby("scenario_id")[metric].mean().to_numpy()
    res = sstats.permutation_test((c, r), lambda x, y, axis: np.mean(x - y, axis=axis), permutation_type="samples",
                                  vectorized=True, n_resamples=n_resamples, alternative="two-sided",
                                  rng=np.random.default_rng(0))
    return float(res.pvalue)


def test_compare_seeds_disagree_while_scenarios_agree_is_not_significant():
    """The candidate's seed 0 is far better than the reference on every scenario, its seed 1 far worse,
    so that every seed-averaged difference is a little above 0: the scenarios agree, the seeds do not.
    The old sign-flip test over scenarios saw only the seed averages and called it significant; the
    two-level bootstrap resamples the candidate's seeds too and does not."""
    n = 100
    rng = np.random.default_rng(3)
    ref = _paired(np.full(n, 0.5), "spl", seeds=(0, 1))
    up, down = 0.8 + rng.uniform(0, 0.02, n), 0.2 + rng.uniform(0, 0.02, n)
    cand = pd.concat([_paired(up, "spl", seeds=(0,)), _paired(down, "spl", seeds=(1,))], ignore_index=True)
    seed_averaged = (up + down) / 2 - 0.5
    assert (seed_averaged > 0).all()                      # every scenario agrees on the sign
    old_p = _old_sign_flip_p(ref, cand, "spl")
    assert old_p < 0.001                                  # 1/10001: the old test called it significant
    res = compare_cells(ref, cand, "spl")
    assert res["difference"] == pytest.approx(seed_averaged.mean())
    assert res["ci_low"] < 0 < res["ci_high"] and res["p_uncorrected"] > 0.3
    assert res["detectable_80"] > 0.5                     # the seeds' spread: no small difference is detectable
    # The same candidate with the seeds agreeing (each seed the average) is significant under both tests.
    agree = _paired((up + down) / 2, "spl", seeds=(0, 1))
    assert compare_cells(ref, agree, "spl")["p_uncorrected"] < 0.001 and _old_sign_flip_p(ref, agree, "spl") < 0.001


def test_percentile_p_value_by_hand():
    from egosearch.report.stats import percentile_p_value, quantile_interval
    # 100 draws -4.5, -3.5, ..., 94.5: 5 at or below 0; numpy's linear quantile crosses 0 at position
    # 4.5 of 99, so the interval excludes 0 for every alpha above 2 * 4.5 / 99.
    draws = np.arange(100) - 4.5
    assert percentile_p_value(draws) == pytest.approx(9 / 99)
    assert quantile_interval(draws, 1 - 9 / 99)[0] == pytest.approx(0.0, abs=1e-12)
    assert percentile_p_value(-draws) == pytest.approx(9 / 99)   # two-sided: the mirror gives the same p
    assert percentile_p_value(np.arange(1.0, 101.0)) == pytest.approx(1 / 100)   # none on the far side: the floor
    assert percentile_p_value(np.zeros(50)) == 1.0
    assert percentile_p_value(np.r_[-np.ones(50), np.ones(50)]) == 1.0
    assert math.isnan(percentile_p_value(np.array([np.nan])))


def test_p_below_005_exactly_when_the_95_interval_excludes_0():
    from egosearch.report.stats import percentile_p_value, quantile_interval
    rng = np.random.default_rng(7)
    for i in range(3000):
        n = int(rng.choice([21, 100, 999, 10_000]))
        centre = rng.normal(0, 0.04)
        draws = (rng.normal(centre, 0.02, n) if i % 3 == 0 else np.round(rng.normal(centre, 0.02, n), 2)
                 if i % 3 == 1 else rng.integers(-2, 6, n) / 8.0)  # ties and draws exactly at 0 too
        lo, hi = quantile_interval(draws, 0.95)
        assert (percentile_p_value(draws) < 0.05) == (lo > 0 or hi < 0), (i, lo, hi, percentile_p_value(draws))


def test_compare_p_and_interval_agree_on_cells():
    rng = np.random.default_rng(2)
    for i in range(30):
        ref = pd.concat([cell_frame(rng.random(60) < 0.5, seed=s) for s in range(3)], ignore_index=True)
        cand = pd.concat([cell_frame(rng.random(60) < 0.5 + 0.01 * i, seed=s) for s in range(2)],
                         ignore_index=True)
        res = compare_cells(ref, cand, "success", n_resamples=2000)
        assert (res["p_uncorrected"] < 0.05) == (res["ci_low"] > 0 or res["ci_high"] < 0)


def test_compare_one_seed_each_resamples_the_scenarios_only():
    # One seed a side: the draws are the ordinary paired bootstrap over scenarios (no seed level).
    from egosearch.report.stats import paired_two_level_draws
    rng = np.random.default_rng(4)
    r, c = rng.random(80), rng.random(80) + 0.1
    draws = paired_two_level_draws(r[:, None], c[:, None], n_resamples=500, seed=0)
    idx = np.random.default_rng(0).integers(0, 80, (500, 80))  # the scenario draws, first from the stream
    by_hand = c[idx].mean(axis=1) - r[idx].mean(axis=1)
    assert draws == pytest.approx(by_hand)
    res = compare_cells(_paired(r, "spl"), _paired(c, "spl"), "spl", n_resamples=500)
    assert (res["n_seeds_ref"], res["n_seeds_cand"]) == (1, 1)
    assert (res["ci_low"], res["ci_high"]) == pytest.approx(tuple(np.quantile(by_hand, [0.025, 0.975])))


def test_compare_one_scenario_gives_no_interval_and_no_test():
    res = compare_cells(_paired([0], "success"), _paired([1], "success"), "success")
    assert res["difference"] == 1.0 and math.isnan(res["ci_low"]) and math.isnan(res["ci_high"])
    assert res["p_uncorrected"] == 1.0


def test_holm():
    assert holm([0.01, 0.04, 0.03]) == pytest.approx([0.03, 0.06, 0.06])
    assert holm([]).size == 0


# --------------------------------------------------------------------------------------------- tables
def test_paths_parse_and_group(tmp_path):
    p = eval_path(tmp_path, "head_on", 3, "kitchen", "everywhere", 1.65)
    assert parse_eval_path(p) == {"variant": "head_on", "seed": 3, "layout": "kitchen", "placement": "everywhere",
                                  "height": 1.65}
    paths = make_eval_tree(tmp_path, seeds=(0, 1), n=5)
    groups = group_eval_paths(paths)
    assert len(groups) == 6 * 2 and all(len(v) == 2 for v in groups.values())
    cells = cells_from_paths(paths)
    assert set(cells) == set(PAPER_TABLE1) and all(len(v) == 4 for v in cells.values())
    with pytest.raises(ValueError, match="seed"):
        parse_eval_path(tmp_path / "x.csv")


def _cell_rows(k: int, n: int, spl_of_success: float) -> pd.DataFrame:
    """n episodes of one evaluation file: the first k succeed, each with SPL ``spl_of_success``."""
    success = np.arange(n) < k
    return pd.DataFrame({"scenario_id": np.arange(n), "success": success.astype(int), "steps": 50,
                         "path_length": 2.0, "shortest_path": 1.0, "spl": np.where(success, spl_of_success, 0.0),
                         "collisions": 0, "episode_return": 0.0}, columns=EPISODE_COLUMNS)


def test_table1(tmp_path):
    # Known inputs: per cell i (in Table 1 order), seed s and layout l, k = (3 * i + s + 4 * l) % 11 successes
    # of 10, each success with SPL (0.25, 0.5, 1.0)[s]; cell 2 has k = 6 everywhere (equal seeds).
    cells = sorted(PAPER_TABLE1, key=lambda hp: (hp[0], hp[1] != "no_low_cabinets"))
    layouts, n = ("kitchen", "bedroom"), 10
    paths, expected = [], {}
    for i, (h, pl) in enumerate(cells):
        ks = {(s, li): 6 if i == 2 else (3 * i + s + 4 * li) % 11 for s in range(3) for li in range(2)}
        for (s, li), k in ks.items():
            p = eval_path(tmp_path / "r", "head_on", s, layouts[li], pl, h)
            p.parent.mkdir(parents=True, exist_ok=True)
            _cell_rows(k, n, (0.25, 0.5, 1.0)[s]).to_csv(p, index=False)
            paths.append(p)
        total = sum(ks.values())
        expected[(h, pl)] = {"k": total, "spl": sum(k * (0.25, 0.5, 1.0)[s] for (s, _), k in ks.items()) / 60,
                             "per_seed": [(ks[(s, 0)] + ks[(s, 1)]) / 20 for s in range(3)]}
    df = table1(group_eval_paths(paths), tmp_path / "out" / "table1", n_resamples=N_RES)
    assert list(df.columns) == ["home", "height", "placement", "n_episodes", "n_scenarios", "n_seeds", "success_rate",
                                "ci_low", "ci_high", "seed_boot_low", "seed_boot_high", "spl", "spl_low", "spl_high",
                                "stuck_share", "paper_success_rate"]
    # the synthetic episodes have 0-3 collisions: none is stuck
    assert (df["stuck_share"] == 0).all()
    # each home alone, then both pooled (the rows set beside the paper)
    assert [r.home for r in df.itertuples()] == ["bedroom"] * 6 + ["kitchen"] * 6 + ["both"] * 6
    both = df[df["home"] == "both"]
    assert [(r.height, r.placement) for r in both.itertuples()] == cells
    for r in both.itertuples():
        e = expected[(r.height, r.placement)]
        assert (r.n_episodes, r.n_scenarios, r.n_seeds) == (60, 20, 3)
        assert r.success_rate == pytest.approx(e["k"] / 60, abs=1e-12)
        assert r.ci_low <= r.success_rate <= r.ci_high
        assert r.spl == pytest.approx(e["spl"], abs=1e-12)
        # A percentile bootstrap of the mean of the three per-seed rates stays within them.
        assert min(e["per_seed"]) - 1e-12 <= r.seed_boot_low <= r.seed_boot_high <= max(e["per_seed"]) + 1e-12
        assert r.paper_success_rate == PAPER_TABLE1[(r.height, r.placement)]
    kitchen = df[(df["home"] == "kitchen")].iloc[0]
    assert kitchen.success_rate == pytest.approx(sum((0 + s) % 11 for s in range(3)) / 30)
    equal = both.iloc[2]
    assert (equal.success_rate, equal.seed_boot_low, equal.seed_boot_high) == (0.6, 0.6, 0.6)
    out = tmp_path / "out"
    assert pd.read_csv(out / "table1.csv").shape == (18, 16)
    md = (out / "table1.md").read_text()
    assert md.index("both homes pooled (bedroom and kitchen)") < md.index("Table 1 in bedroom alone")
    assert "| Head height | Searcher | Excluding cabinets | Everywhere |" in md
    r2, r3 = both.iloc[2], both.iloc[3]
    row = (f"| 1.05m | ours | 0.60 [{r2.ci_low:.2f}, {r2.ci_high:.2f}] | {r3.success_rate:.2f} [{r3.ci_low:.2f}, "
           f"{r3.ci_high:.2f}] |")
    assert row in md.splitlines(), md
    assert f"| 1.05m | paper | {PAPER_TABLE1[cells[2]]:.2f} | {PAPER_TABLE1[cells[3]]:.2f} |" in md
    assert "20 scenarios per cell, each run by 3 seed(s)" in md and "two-level bootstrap" in md
    tex = (out / "table1.tex").read_text()
    assert r"\toprule" in tex and r"\bottomrule" in tex and r"\caption{" in tex
    assert f"1.05m & ours & 0.60 [{r2.ci_low:.2f}, " in tex


def test_two_level_interval_is_wider_than_pooled_wilson_when_seeds_share_scenarios():
    # By hand: 20 scenarios, 3 seeds. A scenario is solved by every seed or by none (10 of each), so the
    # seeds add no information: there are 20 independent draws, not 60. Wilson over the 60 pooled
    # episodes is as narrow as 60 trials allow; the two-level interval is as wide as 20 trials.
    success = np.repeat((np.arange(20) < 10)[:, None], 3, axis=1).astype(float)
    mean, lo, hi = two_level_ci(success, n_resamples=20_000, seed=1)
    assert mean == 0.5
    w_lo, w_hi = wilson_ci(30, 60)
    assert (hi - lo) > 1.5 * (w_hi - w_lo)
    # 20 independent scenarios: the normal-theory width is 2 * 1.96 * sqrt(0.25 / 20) = 0.438
    assert hi - lo == pytest.approx(0.438, abs=0.06)
    # Seeds that disagree independently inside each scenario: the seed level adds spread.
    rng = np.random.default_rng(0)
    noisy = (rng.random((20, 3)) < 0.5).astype(float)
    m2, lo2, hi2 = two_level_ci(noisy, n_resamples=20_000, seed=1)
    assert lo2 <= m2 <= hi2
    # one seed: the bootstrap over scenarios alone; a constant matrix: a point
    assert two_level_ci(np.ones((5, 1))) == (1.0, 1.0, 1.0)
    with pytest.raises(ValueError, match="missing"):
        scenario_seed_matrix(pd.DataFrame({"scenario_id": [0, 1, 0], "seed": [0, 0, 1], "success": [1, 0, 1]}),
                             "success")


def test_detectable_difference_by_hand():
    # (1.959964 + 0.841621) * 0.5 / sqrt(100) = 0.14008
    assert detectable_difference(0.5, 100) == pytest.approx(0.140079, abs=1e-5)
    assert detectable_difference(0.5, 400) == pytest.approx(0.140079 / 2, abs=1e-5)


def test_table1_one_seed_and_directory_prefix(tmp_path):
    paths = make_eval_tree(tmp_path / "r", seeds=(4,), n=10, layouts=("kitchen",))
    out = tmp_path / "out"
    out.mkdir()
    df = table1({k: v[0] for k, v in group_eval_paths(paths).items()}, out, n_resamples=N_RES)
    assert df["seed_boot_low"].isna().all() and (df["n_seeds"] == 1).all()
    assert (out / "table1.csv").exists() and (out / "table1.md").exists() and (out / "table1.tex").exists()
    with pytest.raises(ValueError, match="no evaluation files"):
        table1({}, out)
    # the key gives the seed: paths need not follow the results/ layout
    flat = tmp_path / "flat.csv"
    episodes_frame(np.ones(10)).to_csv(flat, index=False)
    df = table1({(7, 1.05, "everywhere"): flat}, tmp_path / "flat_table", n_resamples=N_RES)
    assert df["success_rate"].tolist() == [1.0] and (tmp_path / "flat_table.md").exists()


def test_table2(tmp_path):
    rows = [("Image Size", "100x100"), ("Discount rate γ", "0.99"), ("Alpha (SAC) : optimizer β1", "0.5"),
            ("Critic : τ (polyak averaging)", "0.01"), ("Batch-size", "32"), ("Number of training steps", "0.75M")]
    table2(rows, tmp_path / "table2")
    md = (tmp_path / "table2.md").read_text().splitlines()
    assert "CURL hyperparameters" in md[0]
    body = [ln for ln in md if ln.startswith("| ") and "Parameter" not in ln]
    assert body == [f"| {a} | {b} |" for a, b in rows]
    tex = (tmp_path / "table2.tex").read_text()
    assert r"Discount rate $\gamma$ & 0.99 \\" in tex and r"$\beta_1$" in tex and r"$\tau$" in tex
    assert tex.index("Image Size") < tex.index("Discount") < tex.index("Batch-size") < tex.index("0.75M")
    assert r"\toprule" in tex and "CURL hyperparameters" in tex


def test_compare_report(tmp_path):
    ref_paths = make_eval_tree(tmp_path / "r", "head_on", seeds=(0, 1), n=60)
    cand_paths = make_eval_tree(tmp_path / "r", "head_off", seeds=(0, 1, 2), n=60, shift=-0.35)
    ref, cand = cells_from_paths(ref_paths), cells_from_paths(cand_paths)
    df = compare_report(ref, cand, tmp_path / "cmp.csv", n_resamples=N_RES)
    assert len(df) == 12 and set(df["metric"]) == {"success", "spl"}
    assert (df["n_scenarios"] == 120).all()  # 60 scenarios x 2 layouts, layouts kept apart
    assert (df["n_seeds_ref"] == 2).all() and (df["n_seeds_cand"] == 3).all()
    succ = df[df.metric == "success"]
    assert (succ["difference"] < -0.15).all() and succ["significant_holm"].all()
    assert (df["p_holm"] >= df["p_uncorrected"]).all()
    assert (df["significant_holm"] == (df["p_holm"] < 0.05)).all() and "significant" not in df.columns
    holds_0 = (df["ci_low"] <= 0) & (df["ci_high"] >= 0)
    assert not (df["significant_holm"] & holds_0).any()
    assert pd.read_csv(tmp_path / "cmp.csv").shape == df.shape
    text = format_compare(df, "head_on", "head_off")
    # a header, a rule, 12 rows and two lines of footnote: the reference has 2 seeds, too few to show its own
    # spread, so the comparison counts the spread its 2 seeds show (method "seed spread")
    assert "*" in text and "everywhere" in text and len(text.splitlines()) == 12 + 4
    assert (df["method"] == "seed spread").all() and (df.loc[succ.index, "verdict"] == "lower").all()


def test_compare_report_errors(tmp_path):
    ref = cells_from_paths(make_eval_tree(tmp_path / "r", "a", seeds=(0,), n=8))
    cand = cells_from_paths(make_eval_tree(tmp_path / "r", "b", seeds=(0,), n=8))
    partial = {k: v for k, v in cand.items() if k != (1.65, "everywhere")}
    with pytest.raises(ValueError, match=r"height=1.65, placement=everywhere.*only in the reference"):
        compare_report(ref, partial, n_resamples=N_RES)
    other = cells_from_paths(make_eval_tree(tmp_path / "r", "c", seeds=(0,), n=9))
    with pytest.raises(ValueError, match=r"cell \(height=0.45, placement=no_low_cabinets\).*different scenarios"):
        compare_report(ref, other, n_resamples=N_RES)
    with pytest.raises(ValueError) as e:
        compare_report(ref, other, n_resamples=N_RES)
    assert "\n" not in str(e.value)


# --------------------------------------------------------------------------------------------- figures
def _png_ok(p: Path, min_bytes: int = 20_000):
    assert p.exists() and p.stat().st_size > min_bytes
    assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_figure6(tmp_path):
    curves = make_curves(tmp_path / "r", seeds=(0, 1, 2))
    outs = figure6(curves, tmp_path / "fig6", n_resamples=N_RES)
    png, pdf, csv = outs
    _png_ok(png)
    assert pdf.read_bytes()[:5] == b"%PDF-" and pdf.stat().st_size > 5_000
    df = pd.read_csv(csv)
    assert set(df["variant"]) == {"head_on", "head_off"} and (df["n_seeds"] == 3).all()
    assert (df["low"] <= df["success_rate"] + 1e-12).all() and (df["high"] >= df["success_rate"] - 1e-12).all()
    assert set(df["label"]) == {"with head movement", "without head movement"}


def test_figure6_one_seed_and_empty(tmp_path):
    curves = make_curves(tmp_path / "r", seeds=(0,))
    png, _, csv = figure6(curves, tmp_path / "one", n_resamples=N_RES)
    _png_ok(png)
    assert pd.read_csv(csv)["low"].isna().all()
    with pytest.raises(ValueError, match="no training curves"):
        figure6({}, tmp_path / "x")
    with pytest.raises(ValueError, match="no curve files"):
        figure6({"head_on": []}, tmp_path / "x")
    empty = write_curve(tmp_path / "e" / "seed0" / "curve.csv", [], [])
    with pytest.raises(ValueError, match="no evaluated rows"):
        figure6({"head_on": [empty]}, tmp_path / "x")


def _fullbody_rows(method, M, spl, attempts, success=None) -> pd.DataFrame:
    """One full-body CSV: one row per scenario, with the given per-scenario SPL and attempts."""
    n = len(spl)
    success = (np.asarray(spl) > 0).astype(int) if success is None else success
    return pd.DataFrame({"scenario_id": np.arange(n), "method": method, "mg": "humanoid_phase", "M": M, "T": 20,
                         "success": success, "steps": 60, "path_length": 3.0, "shortest_path": 1.5, "spl": spl,
                         "attempts": attempts, "penetrations": 1, "penetration_rate": 0.01 * M, "collisions": 2},
                        columns=FULLBODY_COLUMNS)


def test_figure7(tmp_path):
    # Known inputs, 4 scenarios x 2 seeds per setting. The attempts of ours do not fall with M here (M=10
    # plans more than M=5): the figure reports what the files say, in the order of M.
    settings = {("one_step_short", 5): ([0.0, 0.0, 0.5, 0.0], [1, 1, 1, 1]),
                ("one_step_long", 20): ([0.0, 0.0, 0.0, 0.0], [1, 1, 1, 1]),
                ("noisy_search", 5): ([0.2, 0.0, 0.0, 0.4], [20, 20, 18, 20]),
                ("ours", 1): ([0.9, 0.8, 0.0, 0.7], [100, 100, 100, 100]),
                ("ours", 5): ([0.6, 0.6, 0.6, 0.6], [20, 20, 20, 20]),
                ("ours", 10): ([0.5, 0.0, 0.5, 0.3], [30, 10, 20, 40]),
                ("ours", 20): ([0.4, 0.2, 0.0, 0.0], [5, 5, 5, 5])}
    files = []
    for (method, M), (spl, att) in settings.items():
        for seed in (0, 1):
            p = tmp_path / "r" / f"{method}-M{M}" / f"seed{seed}.csv"
            p.parent.mkdir(parents=True, exist_ok=True)
            # Seed 1 halves the SPL of seed 0 and plans the same: per-scenario means are 0.75 x seed 0.
            _fullbody_rows(method, M, np.asarray(spl) * (1.0 if seed == 0 else 0.5), att).to_csv(p, index=False)
            files.append(p)
    png, pdf, csv = figure7(files, tmp_path / "fig7", n_resamples=N_RES)
    _png_ok(png)
    assert pdf.read_bytes()[:5] == b"%PDF-"
    df = pd.read_csv(csv)
    assert list(zip(df["method"], df["M"])) == [("one_step_short", 5), ("one_step_long", 20), ("noisy_search", 5),
                                                ("ours", 1), ("ours", 5), ("ours", 10), ("ours", 20)]
    assert list(df["label"]) == ["1-step short", "1-step long", "Noisy search", "Ours M=1", "Ours M=5", "Ours M=10",
                                 "Ours M=20"]
    assert (df["n_seeds"] == 2).all() and (df["n_episodes"] == 8).all() and (df["n_scenarios"] == 4).all()
    assert (df["ci_unit"] == "scenario").all()
    for r in df.itertuples():
        spl, att = settings[(r.method, r.M)]
        assert r.spl == pytest.approx(0.75 * np.mean(spl), abs=1e-12)
        assert r.attempts == pytest.approx(np.mean(att), abs=1e-12)
        assert r.success_rate == pytest.approx(np.mean(np.asarray(spl) > 0), abs=1e-12)
        assert r.penetration_rate == pytest.approx(0.01 * r.M) and r.collisions == 2.0
        # Bootstrap over the 4 scenario means: within their range; a constant column is a point.
        means = 0.75 * np.asarray(spl)
        assert means.min() - 1e-12 <= r.spl_low <= r.spl <= r.spl_high <= means.max() + 1e-12
        if np.ptp(att) == 0:
            assert r.attempts_low == r.attempts_high == att[0]
        else:
            assert min(att) <= r.attempts_low < r.attempts_high <= max(att)
    ours = df[df.method == "ours"]
    assert list(ours["attempts"]) == [100.0, 20.0, 25.0, 5.0]
    assert (df.loc[df.method == "one_step_long", ["spl", "spl_low", "spl_high"]] == 0.0).all(axis=None)


def test_figure7_several_mgs_one_seed_and_empty(tmp_path):
    files = make_fullbody(tmp_path / "r", mgs=("humanoid_phase", "humanoid_matching", "fetch"), seeds=(0,))
    png, _, csv = figure7(files, tmp_path / "fig7mg", n_resamples=N_RES)
    _png_ok(png)
    df = pd.read_csv(csv)
    assert set(df["mg"]) == {"humanoid_phase", "humanoid_matching", "fetch"} and len(df) == 21
    baselines_only = [p for p in files if "ours" not in p.parent.name]
    png, _, csv = figure7(baselines_only, tmp_path / "fig7b", n_resamples=N_RES)
    _png_ok(png, 10_000)
    assert not pd.read_csv(csv)["method"].eq("ours").any()
    with pytest.raises(ValueError, match="no full-body CSVs"):
        figure7([], tmp_path / "x")
    empty = tmp_path / "empty" / "seed0.csv"
    empty.parent.mkdir()
    pd.DataFrame(columns=FULLBODY_COLUMNS).to_csv(empty, index=False)
    with pytest.raises(ValueError, match="no episodes"):
        figure7([empty], tmp_path / "x")


# --------------------------------------------------------------------------------------------- CLI helpers
def test_cli_helpers(tmp_path, capsys):
    ref = make_eval_tree(tmp_path / "r", "head_on", seeds=(0,), n=10, layouts=("kitchen",))
    cand = make_eval_tree(tmp_path / "r", "head_off", seeds=(0,), n=10, layouts=("kitchen",))
    cmd_table1(ref + cand, tmp_path / "o" / "table1", variant="head_on")
    cmd_table2([("Batch-size", "32")], tmp_path / "o" / "table2")
    df = cmd_compare(ref, cand, tmp_path / "o" / "compare.csv", "head_on", "head_off")
    assert len(df) == 12
    cmd_fig6(make_curves(tmp_path / "r", seeds=(0,)), tmp_path / "o" / "fig6")
    cmd_fig7(make_fullbody(tmp_path / "r", seeds=(0,), n=10), tmp_path / "o" / "fig7")
    out = capsys.readouterr().out
    for name in ("table1.csv", "table1.md", "table1.tex", "table2.md", "table2.tex", "compare.csv", "fig6.png",
                 "fig6.pdf", "fig7.png", "fig7.csv"):
        assert (tmp_path / "o" / name).exists() and name in out
    with pytest.raises(ValueError, match="several variants"):
        cmd_table1(ref + cand, tmp_path / "o" / "t")


# --------------------------------------------------------------------------------------------- isolation
def test_report_imports_no_torch_or_simulator():
    code = ("import sys, egosearch.report, egosearch.report.commands\n"
            "bad = sorted(m for m in sys.modules if m.split('.')[0] in "
            "('torch', 'pybullet', 'gymnasium', 'pyrender', 'trimesh', 'pybullet_data'))\n"
            "mods = sorted(m for m in sys.modules if m.startswith('egosearch.') "
            "and not m.startswith('egosearch.report') and m not in ('egosearch.core', 'egosearch.core.machine', "
            # the searchers' registry and the registry helper, plain data open to every stage (tests/test_layout.py)
            "'egosearch.searchers', 'egosearch.searchers.searcher_registry', 'egosearch.core.named_registry'))\n"
            "print(bad, mods)\n"
            "assert not bad and not mods, (bad, mods)\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stdout + r.stderr


# --------------------------------------------------------------------------------------------- properties
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 500).flatmap(lambda n: st.tuples(st.integers(0, n), st.just(n))))
def test_wilson_brackets_the_rate(kn):
    k, n = kn
    lo, hi = wilson_ci(k, n)
    assert 0.0 <= lo <= k / n <= hi <= 1.0
    assert (lo, hi) == pytest.approx(_wilson_by_hand(k, n), abs=1e-9)


def _draw_frame(draw_ids, success_by_draw, seeds=(0, 1, 2)):
    from egosearch.report.stats import DRAW_COLUMNS

    rows = []
    for d, v in zip(draw_ids, success_by_draw, strict=True):
        for s in seeds:
            row = dict.fromkeys(DRAW_COLUMNS, 0.0)
            row.update(layout="kitchen_living", target_object="mug", start_x=float(d), seed=s, success=float(v))
            rows.append(row)
    return pd.DataFrame(rows)


def test_cell_contrast_pairs_shared_draws_and_not_disjoint_ones():
    """Two cells on the same 60 draws, the first 0.2 easier on every draw: paired, the draws' spread
    of difficulty cancels and the interval is the point +0.2. The same numbers on disjoint draws
    keep that spread: the interval is wide, yet still centred on +0.2."""
    from egosearch.report.stats import cell_contrast

    difficulty = np.linspace(0.0, 0.8, 60)
    paired = cell_contrast(_draw_frame(range(60), difficulty + 0.2), _draw_frame(range(60), difficulty))
    assert paired["n_shared"] == 60
    assert paired["difference"] == pytest.approx(0.2)
    assert paired["ci_low"] == pytest.approx(0.2) and paired["ci_high"] == pytest.approx(0.2)
    apart = cell_contrast(_draw_frame(range(60), difficulty + 0.2), _draw_frame(range(100, 160), difficulty))
    assert apart["n_shared"] == 0
    assert apart["difference"] == pytest.approx(0.2)
    assert apart["ci_low"] < 0.12 and apart["ci_high"] > 0.28


def test_cell_contrast_refuses_cells_run_by_different_seeds():
    from egosearch.report.stats import cell_contrast

    with pytest.raises(ValueError, match="different seeds"):
        cell_contrast(_draw_frame(range(5), [1] * 5, seeds=(0, 1)), _draw_frame(range(5), [0] * 5, seeds=(0, 2)))


def test_figure6_band_resamples_the_curve_episodes_when_every_seed_kept_them(tmp_path):
    """Two seeds, 40 in-training scenarios, the same episodes at both evaluations: the band of the
    step whose episodes every seed kept is the two-level interval of the (scenarios x seeds) matrix;
    a step one seed lacks falls back to the seeds' bootstrap (and says so)."""
    from egosearch.report.figures import CI_SEEDS, CI_TWO_LEVEL, figure6_frame
    from egosearch.report.stats import two_level_ci

    rng = np.random.default_rng(3)
    success = rng.integers(0, 2, size=(40, 2))
    paths = []
    for s in (0, 1):
        run = tmp_path / "head_on" / f"seed{s}"
        run.mkdir(parents=True)
        rates = success[:, s].mean()
        pd.DataFrame({"env_steps": [0, 100], "success_rate": [rates, rates]}).to_csv(run / "curve.csv", index=False)
        steps = (0, 100) if s == 0 else (100,)  # seed 1 kept no episodes at step 0
        pd.DataFrame([{"env_steps": t, "home": "kitchen_living", "height": 1.05, "scenario_id": i,
                       "success": int(success[i, s]), "shortest_path": 2.0, "path_length": 3.0}
                      for t in steps for i in range(40)]).to_csv(run / "curve_episodes.csv", index=False)
        paths.append(run / "curve.csv")
    df = figure6_frame({"head_on": paths}, n_resamples=N_RES).set_index("env_steps")
    mean, lo, hi = two_level_ci(success.astype(float), n_resamples=N_RES)
    assert df.loc[100, "ci_unit"] == CI_TWO_LEVEL and df.loc[100, "n_scenarios"] == 40
    assert df.loc[100, "success_rate"] == pytest.approx(mean)
    assert (df.loc[100, "low"], df.loc[100, "high"]) == pytest.approx((lo, hi))
    assert df.loc[0, "ci_unit"] == CI_SEEDS


def test_gpu_projection_by_hand(tmp_path):
    """The paper preset's `all` from a GPU check: trainings one at a time at the measured rate with
    their curve evaluations, plus the cpu run's other jobs of `all` over the machine's cores, the
    full-body ones scaled by the paper preset's count of runs (3 motion generators x 3 seeds = 9)."""
    import json

    from egosearch.report.gpu import GPU_CHECK, block_gpu_projection, projection

    (tmp_path / GPU_CHECK).mkdir(parents=True)
    run = {"total_env_steps": 1000, "eval_every": 500, "env_steps_per_s_updating": 10.0,
           "curve_evaluation_s_mean": 20.0, "env_steps": 100}
    record = {"machine": {"cores": 4, "cpu": "x", "gpu": "G"}, "date_utc": "2026-01-01T00:00:00+00:00",
              "result": {"training": run}}
    (tmp_path / GPU_CHECK / "gpu_check.json").write_text(json.dumps(record))
    (tmp_path / "results" / "cpu").mkdir(parents=True)
    jobs = [{"rule": "train", "job": "head_on/seed0", "wall_s": 9e9},  # replaced by the GPU's rate
            {"rule": "eval", "job": "head_on/seed0/kitchen_living/everywhere/h1.05", "wall_s": 720.0, "cpu_s": 360.0},
            {"rule": "fullbody", "job": "ours-M5/seed0", "wall_s": 80.0},
            {"rule": "traces", "job": "head_on/seed0/x", "wall_s": 1e6}]  # not part of `all`
    (tmp_path / "results" / "cpu" / "provenance.json").write_text(json.dumps({"jobs": jobs}))
    p = projection(tmp_path)
    # a training: 1000 / 10 = 100 s of steps + 3 evaluations (0, 500, 1000) x 20 s = 160 s; 2 variants x 3 seeds
    assert p["evaluations"] == 3 and p["trainings"] == 6
    assert math.isclose(p["train_h"] * 3600, 160.0) and math.isclose(p["trainings_h"] * 3600, 960.0)
    # other jobs: 360 (CPU time) + 9 x 80 = 1080 core-seconds, over 4 cores = 270 s
    assert math.isclose(p["other_core_h"] * 3600, 1080.0) and math.isclose(p["other_h"] * 3600, 270.0)
    assert math.isclose(p["total_h"] * 3600, 1230.0)
    assert "6 trainings of 1,000 env steps" in block_gpu_projection(tmp_path, "cpu")
    assert "CUDA graphs" not in block_gpu_projection(tmp_path, "cpu")
    # a graphed training with its eager baseline on the same machine: the projection says which rate it used
    record["result"]["training"] = {**run, "overrides": {"cuda_graph": True}}
    (tmp_path / GPU_CHECK / "gpu_check.json").write_text(json.dumps(record))
    assert "(0.0 h each; the update recorded as CUDA graphs, as the preset does)" in block_gpu_projection(
        tmp_path, "cpu")
    from egosearch.report.gpu import _baseline_sentence

    base = {"wall_s": 60.4, "env_steps_per_s_updating": 4.0, "train_rows_used": 3}
    assert _baseline_sentence(base, record["result"]["training"]) == (
        " The same training with the update launched eagerly (`cuda_graph: false`), run next for 60 s on the same "
        "machine (`baseline/`): 4.0 env steps/s while updating (median of 3 rows), so 2.5x.")
    record["result"]["training"] = {**run, "cuda_graph": True}  # what a record says since the preset graphs
    (tmp_path / GPU_CHECK / "gpu_check.json").write_text(json.dumps(record))
    assert "as the preset does" in block_gpu_projection(tmp_path, "cpu")
    (tmp_path / GPU_CHECK / "gpu_check.json").unlink()
    assert projection(tmp_path) is None and "Not measured yet" in block_gpu_projection(tmp_path, "cpu")


def test_the_cuda_tests_of_a_later_tree_and_a_gpu_hosts_benchmark_are_read_from_their_files(tmp_path):
    """docs/gpu.md's last part: the summary line of a quiet pytest log, the report's figures, and only the
    benchmark records of machines with a GPU."""
    import json

    from egosearch.report.gpu import CPU_PRESET_GPU_CHECK, _cpu_profile_lines

    assert _cpu_profile_lines(tmp_path) == []                       # nothing stored: nothing said
    check = tmp_path / CPU_PRESET_GPU_CHECK
    check.mkdir(parents=True)
    (check / "cuda_tests.log").write_text("......                [100%]\n6 passed, 1 deselected in 53.59s\n")
    (check / "cuda_report.json").write_text(json.dumps({"modular_cpu_profile": {"env_steps": 64, "updates": 49}}))
    hosts = tmp_path / "results" / "cpu" / "bench" / "hosts"
    for name, gpu, rate in (("a", "Some GPU", 11.7), ("b", None, 14.8)):
        (hosts / name).mkdir(parents=True)
        machine = {"cpu": "X", "cores": 16, **({"gpu": gpu} if gpu else {})}
        (hosts / name / "learner.json").write_text(json.dumps({
            "date_utc": "2026-01-02T00:00:00", "machine": machine,
            "result": {"updates_per_s_cpu_profile": 58.2, "env_steps_per_core_s_cpu_profile": rate,
                       "cpu_profile_steps": "decisions"}}))
    lines = _cpu_profile_lines(tmp_path)
    assert lines[0].endswith("`results/cpu/gpu_check/cuda_tests.log`): 6 passed, 1 deselected.")
    assert "(64 decisions, 49 updates)" in lines[1]
    assert len(lines) == 3 and "(Some GPU, 16 cores, 2026-01-02;" in lines[2] and "**11.7 decisions per core-second**" \
        in lines[2]


def test_table1_notes_say_what_learning_adds_from_the_comparison_against_the_start(tmp_path):
    from egosearch.report.tables import learning_adds_note

    rows = ["height,placement,metric,reference,candidate,difference,ci_low,ci_high,p_uncorrected,p_holm,"
            "significant_holm,n_scenarios,n_seeds_ref,n_seeds_cand,detectable_80,homes"]
    for h, d in ((0.45, 0.02), (1.05, 0.125)):
        for placement in ("no_low_cabinets", "everywhere"):
            rows.append(f"{h},{placement},success,0.5,{0.5 + d},{d},{d - 0.05},{d + 0.05},0.01,0.02,True,400,3,3,"
                        "0.05,x")
            rows.append(f"{h},{placement},spl,0.3,0.9,0.6,0.5,0.7,0.01,0.02,True,400,3,3,0.05,x")
    path = tmp_path / "head_on_vs_its_start.csv"
    path.write_text("\n".join(rows) + "\n")
    note = learning_adds_note(path, "head_on")
    assert note.startswith("What learning adds: ours (head_on) against its own start")
    assert "3 seed(s)" in note and "(head_on_vs_its_start.csv)" in note
    # success rows only (the SPL rows' +0.60 never shows), per height, excluding cabinets first
    assert "0.45m +0.02 [-0.03, +0.07] excluding cabinets, +0.02 [-0.03, +0.07] everywhere" in note
    assert "1.05m +0.12 [+0.07, +0.17] excluding cabinets" in note and "+0.60" not in note
    (tmp_path / "bad.csv").write_text(rows[0] + "\n")
    with pytest.raises(ValueError, match="no success rows"):
        learning_adds_note(tmp_path / "bad.csv")

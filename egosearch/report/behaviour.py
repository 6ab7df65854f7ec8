"""How the searchers search, from their per-step traces (``egosearch evaluate --traces``), read
against the paper's sentences about behaviour (Section 6.3, Section 6.2 and Figure 6).

Three steps, each a function:

1. :func:`episode_behaviour`: one episode's trace -> sums and counts (the formulas below);
2. :func:`summarise`: per variant, every statistic of :data:`STATISTICS` as a ratio of sums over
   episodes, with a two-level bootstrap interval (scenarios, then seeds, as ``stats.two_level_ci``);
   and head-on minus head-off on the scenarios both ran (one draw of scenarios for both sides, the
   seeds per side, as ``stats.paired_two_level_ci``);
3. :func:`claims_frame`: one row per pair of searchers (head moving, head fixed) and paper sentence, with two
   verdicts, for its sign and for its size.

A statistic is ``sum(numerator) / sum(denominator)`` over the drawn episodes (a mean over steps
weighs every step alike, a share of episodes every episode alike), so an episode with nothing to
count (no step near a cabinet, no sight of the target) adds nothing rather than a hole. Per-episode
formulas, over the steps t = 1..T of an episode of T steps (row 0 is the state after the reset):

- speed: |p_t - p_{t-1}| / step duration; "near an opening" when the step STARTS within
  :data:`NEAR_OPENING` of a cabinet interior or shelf (the trace's ``opening_distance``);
- backward step: the body moves back along its heading at the step's start by more than
  :data:`BACKWARD_MIN`; "before sight": the :data:`SIGHT_WINDOW` steps up to and including the one
  after which the target is first seen;
- gaze: the kind of what the camera's centre ray meets after step t (``gaze_kind``); a look is a
  run of consecutive steps of one class (openings, or other support surfaces), its dwell the run's
  length;
- turning: sums of |change| of head yaw, body heading and camera heading (body + head), per episode;
- first sight: the first row whose mask is not empty (0: seen at the reset); lost sight: a later
  row with an empty mask; steps from first sight to success: T minus that row, successes only;
- revisit: step t ends in a :data:`REVISIT_CELL` floor square that the body had stood in and left
  before (staying where it is does not count, coming back does, and so does each step it then stays).

Numbers only: numpy, pandas and the report's own helpers, no simulator (the trace holds what the report needs).
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from egosearch.report.data import output_base
from egosearch.report.stats import quantile_interval

PathLike = str | os.PathLike

OPENING_KINDS = ("low_cabinet_interior", "wall_cabinet_interior", "shelf")
"""Gaze kinds inside furniture (``egosearch.runs.trace.OPENING_KINDS``; this layer may not import it)."""
NEAR_OPENING = 1.0
"""A step starting this close (m) to an opening is "around cabinets"."""
BACKWARD_MIN = 0.02
"""A backward step moves the body back by more than this (m): a tenth of the slowest deliberate
backward step (0.25 m max forward speed), above the centimetre a blocked or turning body drifts."""
SIGHT_WINDOW = 5
"""Steps (0.75 s) up to the first sight that count as "just before" it."""
REVISIT_CELL = 0.5
"""Side (m) of the floor squares of the revisit rate: the env's coverage cells (a body diameter and
a half)."""
PAPER_HEAD_GAIN = 0.20
"""Figure 6 and Section 6.2: "a 20% higher success rate" with head movement, read as 20 points of
success rate (the claims table also gives the reading as 20% of the head-off rate)."""

Pair = tuple[str, str]
"""(the searcher that moves its head, its counterpart that does not): the claims are read on each pair."""
DEFAULT_PAIRS: tuple[Pair, ...] = (("head_on", "head_off"),)

_TRACE = re.compile(r"^h(\d+(?:\.\d+)?)\.npz$")
_SEED = re.compile(r"^seed(\d+)$")


def parse_trace_path(path: PathLike) -> dict:
    """``{variant, seed, layout, placement, height}`` of a trace file's path,
    ``.../{variant}/seed{seed}/{layout}/{placement}/h{height}.npz``."""
    parts = Path(path).parts
    m = _TRACE.match(parts[-1])
    if m is None or len(parts) < 5 or not _SEED.match(parts[-4]):
        raise ValueError(f"{path}: expected .../{{variant}}/seed{{seed}}/{{layout}}/{{placement}}/h{{height}}.npz")
    return {"variant": parts[-5], "seed": int(_SEED.match(parts[-4]).group(1)), "layout": parts[-3],
            "placement": parts[-2], "height": float(m.group(1))}


def read_trace_file(path: PathLike) -> tuple[pd.DataFrame, dict]:
    """(one row per step, the file's facts) of a trace file written by ``egosearch evaluate --traces``."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"trace file not found: {path}")
    with np.load(path, allow_pickle=False) as data:
        cols = {k: data[k] for k in data.files if data[k].ndim == 1}
        facts = {k: data[k].item() for k in data.files if data[k].ndim == 0}
    missing = [c for c in ("scenario_id", "step", "x", "y", "theta", "head_yaw", "pitch", "visible", "success",
                           "gaze_kind", "opening_distance") if c not in cols]
    if missing or "step_seconds" not in facts:
        raise ValueError(f"{path}: not a trace file (missing {missing or ['step_seconds']})")
    return pd.DataFrame(cols), facts


def _runs(flags: np.ndarray) -> int:
    """Number of maximal runs of True."""
    flags = np.asarray(flags, bool)
    return int(flags[0] + np.count_nonzero(flags[1:] & ~flags[:-1])) if flags.size else 0


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi


def revisit_steps(x: np.ndarray, y: np.ndarray, cell: float = REVISIT_CELL) -> int:
    """Steps t >= 1 ending in a cell the body had left before (see the module docstring)."""
    cells = list(zip(np.floor(np.asarray(x) / cell).astype(int), np.floor(np.asarray(y) / cell).astype(int)))
    left, count = set(), 0
    for t in range(1, len(cells)):
        if cells[t] != cells[t - 1]:
            left.add(cells[t - 1])
        count += cells[t] in left
    return count


def episode_behaviour(ep: pd.DataFrame, step_seconds: float) -> dict:
    """Sums and counts of one episode's trace rows (row 0: the reset; sorted by ``step``)."""
    ep = ep.sort_values("step")
    if list(ep["step"]) != list(range(len(ep))):
        raise ValueError(f"scenario {ep['scenario_id'].iloc[0]}: trace steps are not 0..T")
    x, y, theta = (ep[c].to_numpy(float) for c in ("x", "y", "theta"))
    yaw, pitch = ep["head_yaw"].to_numpy(float), ep["pitch"].to_numpy(float)
    visible = ep["visible"].to_numpy(bool)
    kind = ep["gaze_kind"].to_numpy(str)[1:]
    steps = len(ep) - 1
    dx, dy = np.diff(x), np.diff(y)
    speed = np.hypot(dx, dy) / step_seconds
    near = ep["opening_distance"].to_numpy(float)[:-1] <= NEAR_OPENING
    backward = dx * np.cos(theta[:-1]) + dy * np.sin(theta[:-1]) < -BACKWARD_MIN
    seen_rows = np.flatnonzero(visible)
    first = int(seen_rows[0]) if seen_rows.size else None
    window = np.zeros(steps, bool)  # index t-1 holds step t
    if first:
        window[max(0, first - SIGHT_WINDOW):first] = True
    opening = np.isin(kind, OPENING_KINDS)
    surface = kind == "surface"
    success = bool(ep["success"].iloc[-1])
    head_turn = float(np.abs(np.diff(yaw)).sum())
    body_turn = float(np.abs(_wrap(np.diff(theta))).sum())
    return {
        "episodes": 1, "steps": steps, "success": int(success),
        "steps_near": int(near.sum()), "speed_near_sum": float(speed[near].sum()),
        "steps_far": int((~near).sum()), "speed_far_sum": float(speed[~near].sum()),
        "steps_gaze_opening": int(opening.sum()), "pitch_gaze_opening_sum": float(pitch[1:][opening].sum()),
        "steps_gaze_else": int((~opening).sum()), "pitch_gaze_else_sum": float(pitch[1:][~opening].sum()),
        "opening_looks": _runs(opening), "steps_gaze_surface": int(surface.sum()), "surface_looks": _runs(surface),
        "backward_steps": int(backward.sum()), "window_steps": int(window.sum()),
        "backward_in_window": int((backward & window).sum()), "other_steps": int((~window).sum()),
        "backward_other": int((backward & ~window).sum()),
        "head_yaw_sweep": head_turn, "body_turn": body_turn, "turning": head_turn + body_turn,
        "camera_sweep": float(np.abs(_wrap(np.diff(theta + yaw))).sum()),
        "seen": int(first is not None), "first_seen_steps": first or 0,
        "sight_to_success": steps - first if success and first is not None else 0,
        "lost_sight": int(first is not None and not visible[first:].all()),
        "revisit_steps": revisit_steps(x, y),
    }


def behaviour_episodes(paths: Iterable[PathLike]) -> pd.DataFrame:
    """One row per episode of every trace file: its coordinates (variant, seed, cell, scenario_id)
    and :func:`episode_behaviour`'s sums and counts."""
    rows, seen = [], set()
    for path in paths:
        where = parse_trace_path(path)
        cell = f"{where['layout']}/{where['placement']}/h{where['height']:g}"
        if (where["variant"], where["seed"], cell) in seen:
            raise ValueError(f"{path}: a second trace of {where['variant']} seed {where['seed']} on {cell}")
        seen.add((where["variant"], where["seed"], cell))
        steps, facts = read_trace_file(path)
        for scenario_id, ep in steps.groupby("scenario_id", sort=True):
            rows.append({"variant": where["variant"], "seed": where["seed"], "cell": cell,
                         "scenario_id": int(scenario_id), "head": bool(facts.get("head", True)),
                         "learns": str(facts.get("learns", "steps")),
                         **episode_behaviour(ep, float(facts["step_seconds"]))})
    if not rows:
        raise ValueError("no trace files given")
    return pd.DataFrame(rows)


@dataclass(frozen=True)
class Statistic:
    name: str
    unit: str
    text: str
    num: str
    den: str
    minus: tuple[str, str] | None = None
    """(numerator, denominator) of a second ratio subtracted from the first."""


def _diff(name, unit, text, first: Statistic, second: Statistic) -> Statistic:
    return Statistic(name, unit, text, first.num, first.den, (second.num, second.den))


_near = Statistic("speed_near_opening", "m/s", "body speed on steps starting within 1 m of a cabinet interior or "
                  "shelf", "speed_near_sum", "steps_near")
_far = Statistic("speed_elsewhere", "m/s", "body speed on the other steps", "speed_far_sum", "steps_far")
_pitch_in = Statistic("pitch_gaze_opening", "rad", "camera pitch while its centre is in a cabinet interior or on a "
                      "shelf", "pitch_gaze_opening_sum", "steps_gaze_opening")
_pitch_out = Statistic("pitch_gaze_elsewhere", "rad", "camera pitch on the other steps", "pitch_gaze_else_sum",
                       "steps_gaze_else")
_dwell_in = Statistic("dwell_opening", "steps", "length of an unbroken look into cabinet interiors and shelves",
                      "steps_gaze_opening", "opening_looks")
_dwell_top = Statistic("dwell_surface", "steps", "length of an unbroken look at other support surfaces (table, "
                       "counter and cabinet tops, seats)", "steps_gaze_surface", "surface_looks")
_back_in = Statistic("backward_share_before_sight", "share", "backward steps among the 5 steps up to the first "
                     "sight", "backward_in_window", "window_steps")
_back_out = Statistic("backward_share_other", "share", "backward steps among the other steps", "backward_other",
                      "other_steps")

STATISTICS: tuple[Statistic, ...] = (
    Statistic("success", "share", "episodes that found the target", "success", "episodes"),
    _near, _far,
    _diff("speed_near_minus_elsewhere", "m/s", "speed near openings minus elsewhere", _near, _far),
    Statistic("gaze_opening_share", "share", "steps with the camera's centre in a cabinet interior or on a shelf",
              "steps_gaze_opening", "steps"),
    _pitch_in, _pitch_out,
    _diff("pitch_opening_minus_elsewhere", "rad", "pitch looking into openings minus elsewhere", _pitch_in,
          _pitch_out),
    _dwell_in, _dwell_top,
    _diff("dwell_opening_minus_surface", "steps", "dwell on openings minus on other surfaces", _dwell_in, _dwell_top),
    Statistic("backward_share", "share", "steps that move the body back", "backward_steps", "steps"),
    _back_in, _back_out,
    _diff("backward_before_sight_minus_other", "share", "backward share just before first sight minus elsewhere",
          _back_in, _back_out),
    Statistic("head_yaw_sweep", "rad/episode", "head yaw turned per episode", "head_yaw_sweep", "episodes"),
    Statistic("body_turn", "rad/episode", "body heading turned per episode", "body_turn", "episodes"),
    Statistic("camera_sweep", "rad/episode", "camera heading (body + head) turned per episode", "camera_sweep",
              "episodes"),
    Statistic("body_turn_per_step", "rad/step", "body heading turned per step", "body_turn", "steps"),
    Statistic("body_share_of_turning", "share", "body turn / (body turn + head yaw turn)", "body_turn", "turning"),
    Statistic("seen_share", "share", "episodes that see the target at least once", "seen", "episodes"),
    Statistic("steps_to_first_sight", "steps", "steps before the first sight, episodes that see the target",
              "first_seen_steps", "seen"),
    Statistic("steps_sight_to_success", "steps", "steps from the first sight to success, successes",
              "sight_to_success", "success"),
    Statistic("lost_sight_share", "share", "episodes that lose sight of the target after seeing it, of those that "
              "see it", "lost_sight", "seen"),
    Statistic("revisit_share", "share", "steps ending in a 0.5 m floor square left earlier", "revisit_steps",
              "steps"),
)
_BY_NAME = {s.name: s for s in STATISTICS}


def _matrices(eps: pd.DataFrame, keys: pd.MultiIndex, columns: list[str]) -> tuple[dict[str, np.ndarray], list]:
    """(scenarios x seeds) sums of each column; 0 where a seed did not run a scenario (it adds nothing)."""
    seeds = sorted(eps["seed"].unique())
    out = {}
    for c in columns:
        wide = eps.pivot_table(index=["cell", "scenario_id"], columns="seed", values=c, aggfunc="sum")
        out[c] = wide.reindex(index=keys, columns=seeds).fillna(0.0).to_numpy(float)
    return out, seeds


def _estimate(stat: Statistic, sums: dict) -> np.ndarray | float:
    with np.errstate(invalid="ignore", divide="ignore"):
        value = np.divide(sums[stat.num], sums[stat.den])
        if stat.minus:
            value = value - np.divide(sums[stat.minus[0]], sums[stat.minus[1]])
    return value


def _columns(stats) -> list[str]:
    return sorted({c for s in stats for c in (s.num, s.den, *(s.minus or ()))})


def _counts(rng: np.random.Generator, b: int, n: int) -> np.ndarray:
    """How often each of ``n`` units is drawn in each of ``b`` resamples with replacement: (b, n)."""
    idx = rng.integers(0, n, (b, n)) + n * np.arange(b)[:, None]
    return np.bincount(idx.ravel(), minlength=b * n).reshape(b, n).astype(float)


def _drawn(sums: dict[str, np.ndarray], rows: np.ndarray, cols: np.ndarray) -> dict[str, np.ndarray]:
    """Each (scenarios x seeds) matrix summed over the drawn scenarios and seeds, per resample: ``rows``
    (B, S) and ``cols`` (B, K) count the draws (a product of counts, not a gather: one matrix product)."""
    names = list(sums)
    m = np.stack([sums[c] for c in names], axis=-1)
    s, k, c = m.shape
    out = np.einsum("bkc,bk->bc", (rows @ m.reshape(s, k * c)).reshape(-1, k, c), cols)
    return {name: out[:, i] for i, name in enumerate(names)}


def summarise(episodes: pd.DataFrame, pairs: Iterable[Pair] = DEFAULT_PAIRS, confidence: float = 0.95,
              n_resamples: int = 10_000, seed: int = 0, chunk: int = 1000) -> pd.DataFrame:
    """Every statistic per variant, and for each (head on, head off) pair of ``pairs`` whose two variants
    both have episodes, ``{head_on} - {head_off}`` on the scenarios both ran (rows with ``variant`` =
    ``"head_on - head_off"``, named by the two variants): value, interval, scenarios, seeds."""
    columns = _columns(STATISTICS)
    rows = []
    sides = {}
    for variant, eps in episodes.groupby("variant", sort=True):
        keys = pd.MultiIndex.from_frame(eps[["cell", "scenario_id"]].drop_duplicates().sort_values(["cell",
                                                                                                     "scenario_id"]))
        sums, seeds = _matrices(eps, keys, columns)
        sides[variant] = (keys, sums, seeds)
        rng = np.random.default_rng(seed)
        draws = {s.name: [] for s in STATISTICS}
        n_s, n_k = len(keys), len(seeds)
        for start in range(0, n_resamples, chunk):
            b = min(chunk, n_resamples - start)
            drawn = _drawn(sums, _counts(rng, b, n_s), _counts(rng, b, n_k))
            for s in STATISTICS:
                draws[s.name].append(_estimate(s, drawn))
        totals = {c: sums[c].sum() for c in columns}
        for s in STATISTICS:
            lo, hi = quantile_interval(np.concatenate(draws[s.name]), confidence)
            rows.append({"variant": variant, "statistic": s.name, "value": float(_estimate(s, totals)),
                         "ci_low": lo, "ci_high": hi, "unit": s.unit, "n_scenarios": n_s, "n_seeds": n_k,
                         "n_episodes": int(totals["episodes"]), "description": s.text})
    for head_on, head_off in pairs:
        if head_on in sides and head_off in sides:
            rows += _paired(sides[head_on], sides[head_off], f"{head_on} - {head_off}", confidence, n_resamples,
                            seed, chunk)
    return pd.DataFrame(rows)


def _paired(on, off, label, confidence, n_resamples, seed, chunk) -> list[dict]:
    shared = on[0].intersection(off[0])
    if len(shared) == 0:
        return []
    pick = [(side[1], side[0].get_indexer(shared), len(side[2])) for side in (on, off)]
    mats = [{c: m[idx] for c, m in sums.items()} for sums, idx, _ in pick]
    rng = np.random.default_rng(seed)
    n_s = len(shared)
    draws = {s.name: [] for s in STATISTICS}
    for start in range(0, n_resamples, chunk):
        b = min(chunk, n_resamples - start)
        r = _counts(rng, b, n_s)  # one draw of scenarios for both sides: the pairing
        ests = []
        for (_, _, n_k), m in zip(pick, mats):
            drawn = _drawn(m, r, _counts(rng, b, n_k))
            ests.append({s.name: _estimate(s, drawn) for s in STATISTICS})
        for s in STATISTICS:
            draws[s.name].append(ests[0][s.name] - ests[1][s.name])
    out = []
    for s in STATISTICS:
        values = [_estimate(s, {c: m[c].sum() for c in m}) for m in mats]
        lo, hi = quantile_interval(np.concatenate(draws[s.name]), confidence)
        out.append({"variant": label, "statistic": s.name, "value": float(values[0] - values[1]), "ci_low": lo,
                    "ci_high": hi, "unit": s.unit, "n_scenarios": n_s, "n_seeds": f"{pick[0][2]}+{pick[1][2]}",
                    "n_episodes": int(mats[0]["episodes"].sum() + mats[1]["episodes"].sum()),
                    "description": f"{s.text}: difference on the scenarios both ran"})
    return out


@dataclass(frozen=True)
class Claim:
    claim: str
    source: str
    measure: str
    statistic: str
    side: str
    """"on" (the head-on policy's own statistic) or "contrast" (head on minus head off)."""
    direction: int
    """+1: the sentence says the number is above 0; -1: below."""
    paper_size: float | None = None
    """The size the sentence states, in the measure's unit; None where it states only a direction."""
    body: bool = False
    """The sentence is about how the body steps and turns: not read on a searcher whose body steps are the
    frontier searcher's (a modular searcher, whose traces say ``learns`` "decisions")."""


CLAIMS: tuple[Claim, ...] = (
    Claim("the character tends to move slower around cabinets", "Section 6.3",
          "head-on body speed within 1 m of a cabinet interior or shelf minus elsewhere (m/s)",
          "speed_near_minus_elsewhere", "on", -1, body=True),
    Claim("and look carefully at the interior part where objects are likely to be placed", "Section 6.3",
          "head-on unbroken look into cabinet interiors and shelves minus one at other surfaces (steps)",
          "dwell_opening_minus_surface", "on", +1),
    Claim("The character also utilizes backward steps to have a better view of the surface in front of it",
          "Section 6.3", "head-on share of backward steps in the 5 steps up to the first sight minus elsewhere",
          "backward_before_sight_minus_other", "on", +1, body=True),
    Claim("the agent with head movements shows a 20% higher success rate than the agent without head movements",
          "Figure 6", "success, head on minus head off, paired by scenario", "success", "contrast", +1,
          PAPER_HEAD_GAIN),
    Claim("To look around the environment, the agent needs to rotate its entire body around", "Section 6.2",
          "body turn per step, head on minus head off (rad)", "body_turn_per_step", "contrast", -1, body=True),
)
CLAIM_COLUMNS = ("searchers", "claim", "source", "measure", "paper_size", "value", "ci_low", "ci_high", "n_scenarios",
                 "n_seeds", "sign", "size", "verdict", "detail")
"""``searchers``: the pair the row reads the claim on (:func:`pair_label`); ``sign``: :data:`SIGN_HOLDS`,
:data:`SIGN_NOT_SHOWN`, :data:`SIGN_OPPOSITE` or :data:`NOT_TESTABLE`;
``size``: :data:`SIZE_REPRODUCED`, :data:`SIZE_NOT_REPRODUCED`, :data:`NO_SIZE` or :data:`NOT_TESTABLE`;
``verdict``: the two read together (``sign holds, size not reproduced``); ``paper_size``: the sentence's
number in the measure's unit (empty where it gives none)."""
SIGN_HOLDS, SIGN_NOT_SHOWN, SIGN_OPPOSITE = "holds", "not shown", "opposite"
SIZE_REPRODUCED, SIZE_NOT_REPRODUCED, NO_SIZE = "size reproduced", "size not reproduced", "no size in the paper"
NOT_TESTABLE = "not testable here"


def sign_verdict(ci_low: float, ci_high: float, direction: int) -> str:
    """The sentence's direction against the 95% interval: :data:`SIGN_HOLDS` when the interval lies wholly
    on the sentence's side of 0, :data:`SIGN_OPPOSITE` when wholly on the other side, else
    :data:`SIGN_NOT_SHOWN` (the interval holds 0)."""
    low, high = (ci_low, ci_high) if direction > 0 else (-ci_high, -ci_low)
    if low > 0:
        return SIGN_HOLDS
    if high < 0:
        return SIGN_OPPOSITE
    return SIGN_NOT_SHOWN


def size_verdict(ci_low: float, ci_high: float, paper_size: float | None) -> str:
    """The paper's number against the 95% interval: :data:`SIZE_REPRODUCED` when the interval holds it,
    :data:`SIZE_NOT_REPRODUCED` when not, :data:`NO_SIZE` when the sentence states none. Read with the
    sign: an interval that holds both the paper's size and 0 does not show the size, it only does not
    rule it out."""
    if paper_size is None or not math.isfinite(paper_size):
        return NO_SIZE
    return SIZE_REPRODUCED if ci_low <= paper_size <= ci_high else SIZE_NOT_REPRODUCED


def combined_verdict(sign: str, size: str) -> str:
    """``sign holds, size not reproduced``; ``not testable here`` when the number is missing."""
    if sign == NOT_TESTABLE:
        return NOT_TESTABLE
    return f"sign {sign}, {size}"


_SIGN_DETAIL = {SIGN_HOLDS: "95% interval excludes 0 on the sentence's side",
                SIGN_NOT_SHOWN: "95% interval includes 0",
                SIGN_OPPOSITE: "95% interval lies on the other side of 0"}


def pair_label(pair: Pair) -> str:
    """``head_on / head_off``: a pair's name in the claims table."""
    return f"{pair[0]} / {pair[1]}"


NOT_LEARNED = ("not read: the body's steps are the frontier searcher's (a modular searcher learns where to explore "
               "and how to sweep the head)")
"""The detail of a body claim on a searcher whose body steps are not learned."""


def claims_frame(summary: pd.DataFrame, pairs: Iterable[Pair] = DEFAULT_PAIRS,
                 walked: Iterable[str] = ()) -> pd.DataFrame:
    """One row per pair and paper sentence (pairs in their order, the sentences in :data:`CLAIMS`' order
    within each): the number behind it, its 95% interval and two verdicts, read from that interval: the
    sign (:func:`sign_verdict`: holds / not shown / opposite) and, where the sentence states a number, the
    size (:func:`size_verdict`: the paper's number inside the interval or not); ``not testable here`` when
    the traces cannot give the number. Columns :data:`CLAIM_COLUMNS`."""
    walked = frozenset(walked)
    return pd.DataFrame([row for pair in pairs for row in _pair_claims(summary, *pair, walked=walked)],
                        columns=list(CLAIM_COLUMNS))


def _pair_claims(summary: pd.DataFrame, head_on: str, head_off: str, walked: frozenset = frozenset()) -> list[dict]:
    out = []
    for c in CLAIMS:
        variant = head_on if c.side == "on" else f"{head_on} - {head_off}"
        hit = summary[(summary["variant"] == variant) & (summary["statistic"] == c.statistic)]
        size = NO_SIZE if c.paper_size is None else NOT_TESTABLE
        row = {"searchers": pair_label((head_on, head_off)), "claim": c.claim, "source": c.source,
               "measure": c.measure,
               "paper_size": math.nan if c.paper_size is None else c.paper_size, "value": math.nan,
               "ci_low": math.nan, "ci_high": math.nan, "n_scenarios": 0, "n_seeds": "", "sign": NOT_TESTABLE,
               "size": size, "verdict": NOT_TESTABLE}
        if c.body and (head_on in walked or c.side == "contrast" and head_off in walked):
            row["detail"] = NOT_LEARNED
            out.append(row)
            continue
        if hit.empty:
            row["detail"] = (f"no traces of {head_off} on the scenarios {head_on} ran" if c.side == "contrast"
                             else f"no traces of {head_on}")
            out.append(row)
            continue
        r = hit.iloc[0]
        ref = summary[(summary["variant"] == head_off) & (summary["statistic"] == c.statistic)]
        row.update(value=r.value, ci_low=r.ci_low, ci_high=r.ci_high, n_scenarios=int(r.n_scenarios),
                   n_seeds=str(r.n_seeds))
        if not all(math.isfinite(v) for v in (r.value, r.ci_low, r.ci_high)):
            row["detail"] = "the traces hold no step the measure counts (e.g. none near a cabinet)"
            out.append(row)
            continue
        sign, size = sign_verdict(r.ci_low, r.ci_high, c.direction), size_verdict(r.ci_low, r.ci_high, c.paper_size)
        row.update(sign=sign, size=size, verdict=combined_verdict(sign, size), detail=_SIGN_DETAIL[sign])
        if c.paper_size is not None:
            inside = size == SIZE_REPRODUCED
            row["detail"] += f"; the paper's {_num(c.paper_size, 2)} is {'inside' if inside else 'outside'} it"
            if sign == SIGN_NOT_SHOWN and inside:
                row["detail"] += ", and so is 0: the size is not ruled out, not shown"
            if c.side == "contrast" and c.statistic == "success" and not ref.empty and math.isfinite(ref.iloc[0].value):
                # "20% higher" may also mean 20% of the head-off rate rather than 20 points.
                rate = float(ref.iloc[0].value)
                rel = c.paper_size * rate
                rel_inside = r.ci_low <= rel <= r.ci_high
                too = " too" if rel_inside == inside else ""
                row["detail"] += (f"; read as {c.paper_size:.0%} of {head_off}'s own rate {rate:.3f}, {_num(rel)}: "
                                  f"{'inside' if rel_inside else 'outside'} it{too}")
        if c.side == "on" and not ref.empty and math.isfinite(ref.iloc[0].value):
            f = ref.iloc[0]
            row["detail"] += f"; {head_off} for reference: {_num(f.value)} [{_num(f.ci_low)}, {_num(f.ci_high)}]"
        out.append(row)
    return out


def _num(x: float, digits: int = 3) -> str:
    return "–" if x is None or not math.isfinite(x) else f"{x:+.{digits}f}"


def _interval(r) -> str:
    return f"{_num(r.value)} [{_num(r.ci_low)}, {_num(r.ci_high)}]" if math.isfinite(r.value) else "–"


def _scenarios_by_seeds(r) -> str:
    return f"{r.n_scenarios} × {r.n_seeds}" if r.n_scenarios else "–"


def _paper_size(r) -> str:
    return _num(r.paper_size, 2) if math.isfinite(r.paper_size) else "none stated"


_HOW_TO_READ = ("Measured on the abstract searcher's evaluation episodes (the policy that plans the full-body "
                "character's steps), from per-step traces. Intervals: bootstrap over scenarios, then seeds; head on "
                "minus head off draws the scenarios both ran once for both sides. Two verdicts per sentence, both "
                "read from the 95% interval. Sign: *holds* when the interval lies wholly on the sentence's side of "
                "0, *not shown* when it holds 0, *opposite* when it lies wholly on the other side. Size, where the "
                "sentence states a number: *size reproduced* when the interval holds the paper's number, *size not "
                "reproduced* when it does not; *no size in the paper* where the sentence gives only a direction. "
                "\"Sign holds, size not reproduced\" means the direction was reproduced and the amount was not.")


def claims_markdown(claims: pd.DataFrame) -> str:
    """The claims table as Markdown, with how to read it: one row per sentence and a column per verdict for
    one pair of searchers; with several pairs, the pairs side by side (one column each, the first pair
    first) and each verdict's detail listed below the table."""
    if "searchers" not in claims.columns:
        claims = claims.assign(searchers="")
    pairs = list(dict.fromkeys(claims["searchers"]))
    if len(pairs) <= 1:
        lines = ["| paper (where) | measured as | paper's size | value [95% CI] | scenarios × seeds "
                 "| verdict: sign, size |", "|---|---|---|---|---|---|"]
        for r in claims.itertuples(index=False):
            lines.append(f"| \"{r.claim}\" ({r.source}) | {r.measure} | {_paper_size(r)} | {_interval(r)} | "
                         f"{_scenarios_by_seeds(r)} | **{r.verdict}** ({r.detail}) |")
        return "\n".join(lines) + "\n\n" + _HOW_TO_READ + "\n"
    lines = ["| paper (where) | measured as | paper's size | " + " | ".join(f"`{p}`" for p in pairs) + " |",
             "|---|---|---|" + "---|" * len(pairs)]
    notes = []
    for claim, rows in claims.groupby("claim", sort=False):
        by_pair = {r.searchers: r for r in rows.itertuples(index=False)}
        first = rows.iloc[0]
        cells = [f"{_interval(by_pair[p])}, {_scenarios_by_seeds(by_pair[p])}: **{by_pair[p].verdict}**"
                 if p in by_pair else "–" for p in pairs]
        lines.append(f"| \"{claim}\" ({first.source}) | {first.measure} | {_paper_size(first)} | "
                     + " | ".join(cells) + " |")
        notes.append(f"- \"{claim}\": " + "; ".join(f"`{p}`: {by_pair[p].detail}" for p in pairs if p in by_pair))
    return ("\n".join(lines) + "\n\nOne column per pair of searchers (the one that moves its head / the one that "
            "does not), each cell the value [95% CI], scenarios × seeds and the verdict. " + _HOW_TO_READ
            + "\n\nWhat each verdict rests on:\n\n" + "\n".join(notes) + "\n")


def behaviour_markdown(summary: pd.DataFrame, first: tuple[str, ...] = ("head_on", "head_off")) -> str:
    """Every statistic, one column per variant (``first`` leading) and the paired difference."""
    variants = list(dict.fromkeys(v for v in (*first, *summary["variant"]) if v in set(summary["variant"])))
    lines = ["| statistic | unit | " + " | ".join(variants) + " |", "|---|---|" + "---|" * len(variants)]
    for s in STATISTICS:
        cells = []
        for v in variants:
            hit = summary[(summary["variant"] == v) & (summary["statistic"] == s.name)]
            r = hit.iloc[0] if not hit.empty else None
            cells.append("–" if r is None or not math.isfinite(r.value) else
                         f"{r.value:.3f} [{_num(r.ci_low).lstrip('+')}, {_num(r.ci_high).lstrip('+')}]")
        lines.append(f"| {s.name} ({s.text}) | {s.unit} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def parse_pair(text: str) -> Pair:
    """``head_on:head_off`` -> ("head_on", "head_off")."""
    on, sep, off = text.partition(":")
    if not sep or not on or not off or ":" in off or on == off:
        raise ValueError(f"--pairs {text!r}: expected HEAD_ON:HEAD_OFF, two different searchers (e.g. "
                         "head_on:head_off)")
    return on, off


def check_pairs(pairs: Iterable[Pair], variants: Iterable[str]) -> None:
    """One line naming each variant of ``pairs`` that no trace file holds (a typo reads every claim as not
    testable otherwise)."""
    have = set(variants)
    missing = sorted({v for pair in pairs for v in pair} - have)
    if missing:
        raise ValueError(f"no trace files of {', '.join(missing)} (the pairs' variants); the files hold "
                         f"{', '.join(sorted(have))}")


def behaviour_report(paths: Iterable[PathLike], out_prefix: PathLike, pairs: Iterable[Pair] = DEFAULT_PAIRS,
                     n_resamples: int = 10_000) -> list[Path]:
    """``{prefix}_episodes.csv``, ``{prefix}.csv`` / ``.md`` (every statistic) and ``{prefix}_claims.csv`` /
    ``.md`` from trace files, the claims read on each (head on, head off) pair of ``pairs``; a folder as
    ``out_prefix`` (an existing one, or ending in ``/``) means ``folder/behaviour``."""
    pairs, paths = tuple(tuple(p) for p in pairs), list(paths)
    check_pairs(pairs, (parse_trace_path(p)["variant"] for p in paths))
    out = output_base(out_prefix, "behaviour")
    episodes = behaviour_episodes(paths)
    summary = summarise(episodes, pairs, n_resamples=n_resamples)
    claims = claims_frame(summary, pairs, walked=set(episodes.loc[episodes["learns"] == "decisions", "variant"]))
    written = [out.with_name(out.name + "_episodes.csv"), out.with_name(out.name + ".csv"),
               out.with_name(out.name + ".md"), out.with_name(out.name + "_claims.csv"),
               out.with_name(out.name + "_claims.md")]
    # six significant digits: the per-episode record stays under the repository's 10 MB per file
    episodes.to_csv(written[0], index=False, float_format="%.6g")
    summary.to_csv(written[1], index=False)
    written[2].write_text(behaviour_markdown(summary, tuple(v for pair in pairs for v in pair)), encoding="utf-8")
    claims.to_csv(written[3], index=False)
    written[4].write_text(claims_markdown(claims), encoding="utf-8")
    return written


def block_claims(root: Path, preset: str) -> str:
    """The README's claims block: the stored claims table, or a line saying it is not stored yet."""
    path = Path(root) / "paper_figs" / preset / "behaviour_claims.csv"
    if not path.exists():
        return (f"*Not yet stored: `{path.relative_to(root)}` is missing (traces: "
                f"`snakemake --cores 2 behaviour --config preset={preset}`).*\n")
    claims = pd.read_csv(path, keep_default_na=False, na_values=[""])
    return claims_markdown(claims) + f"\nFrom `{path.relative_to(root)}`.\n"

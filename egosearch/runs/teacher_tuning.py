"""The tuned teacher's tuning, as a command that can be run again (``egosearch tune --out DIR``, rule
``tune_teacher``): the training-side splits, the candidates, the choice on the fit split and the check on
the held-out one, written as a record.

:mod:`egosearch.searchers.frontier_tuned` gives the parameters, docs/baselines.md where they came from: two
splits of 540 training-side scenarios, never the stored sets. Each split is, at camera heights 0.45, 1.05 and
1.65 m and both placements, the paper's two homes with a scenario seed the stored sets do not use (fit 31, held
out 32; the stored sets use 2021, the fresh-set check 7), 25 scenarios a home and cell, and 20 generated homes
(fit 300-319, held out 400-419; the project stores 0-19 and 900000-900019), 2 scenarios a home and cell. Every
candidate runs the fit split beside the untuned searcher (the same scenarios and episode seeds, so the
difference is paired by scenario); the best mean over both head modes is chosen, and only it and the untuned
searcher run the held-out split.

The nine candidates the shipped parameters were chosen from were not recorded. :data:`CANDIDATES` is the
shipped parameters and, for each of the four weights that trade path against gain and distance, the same
with that one weight halved and doubled: the record says whether the shipped parameters still win on the fit
split, and what they do on the held-out one (docs/baselines.md shows the stored record).
"""

from __future__ import annotations

import csv
import json
import os
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from egosearch.core.csvio import write_csv_atomic
from egosearch.runs.evaluate import EPISODE_COLUMNS, evaluate
from egosearch.sim.body import EVAL_HEIGHTS
from egosearch.sim.scenarios import PLACEMENT_SCHEMES, Scenario, generate_scenarios

PAPER_HOMES = ("kitchen_living", "bedroom_bath")
PAPER_PER_CELL = 25
GENERATED_PER_HOME_AND_CELL = 2


@dataclass(frozen=True)
class TuningSplit:
    """One of the two training-side splits: the paper homes' scenario seed and the generated homes."""

    name: str
    paper_seed: int
    generated_homes: range


SPLITS = {"fit": TuningSplit("fit", 31, range(300, 320)),
          "held_out": TuningSplit("held_out", 32, range(400, 420))}
"""The fit split chooses, the held-out split checks (seeds and homes no stored set uses)."""

HEAD_MODES = {"head_on": "EgoSearch-v0", "head_off": "EgoSearchNoHead-v0"}
"""The env each head mode acts in: the tuned searcher and its untuned reference in both."""

UNTUNED = "untuned"
SHIPPED = "shipped"
NEIGHBOURS = {"GAIN_WEIGHT": (0.5, 2.0), "HYSTERESIS": (0.5, 2.0), "MIN_GAIN": (0.5, 2.0),
              "APPROACH_NEAR_COST": (0.5, 2.0)}
"""Each weight's factors around the shipped value: one at a time, the others as shipped."""


def candidates() -> dict[str, dict[str, float]]:
    """Candidate name -> the FrontierTunedPolicy attributes it overrides: the shipped parameters ({}) and
    each of :data:`NEIGHBOURS` halved and doubled (nine in all)."""
    from egosearch.searchers.frontier_tuned import FrontierTunedPolicy  # local: it loads the simulator

    out: dict[str, dict[str, float]] = {SHIPPED: {}}
    for attribute, factors in NEIGHBOURS.items():
        for factor in factors:
            out[f"{attribute.lower()}_x{factor:g}"] = {attribute: getattr(FrontierTunedPolicy, attribute) * factor}
    return out


def policy_maker(candidate: str):
    """``make(env) -> policy`` for ``candidate`` (:data:`UNTUNED` is the frontier searcher as Table 1 runs it)."""
    from egosearch.searchers.frontier import FrontierPolicy  # local: they load the simulator
    from egosearch.searchers.frontier_tuned import FrontierTunedPolicy

    if candidate == UNTUNED:
        return FrontierPolicy
    overrides = candidates().get(candidate)
    if overrides is None:
        raise ValueError(f"candidate {candidate!r}; allowed: {UNTUNED}, {', '.join(candidates())}")
    return type(f"Candidate_{candidate}", (FrontierTunedPolicy,), dict(overrides)) if overrides else FrontierTunedPolicy


def split_scenarios(split: TuningSplit, limit: int | None = None) -> list[Scenario]:
    """The split's scenarios, ids numbered through (episode ``i`` is seeded ``i``); ``limit`` keeps the first
    ``limit`` scenarios of each cell (a quick run: the paper homes' first, drawn as the full split draws them)."""
    out: list[Scenario] = []
    for placement in PLACEMENT_SCHEMES:
        for height in EVAL_HEIGHTS:
            draws = [(home, PAPER_PER_CELL, split.paper_seed) for home in PAPER_HOMES]
            draws += [(f"home{home}", GENERATED_PER_HOME_AND_CELL, split.paper_seed + home)
                      for home in split.generated_homes]
            cell: list[Scenario] = []
            for home, n, seed in draws:
                if limit and len(cell) >= limit:
                    break
                cell += generate_scenarios(home, placement, height, n, seed)
            for sc in cell[:limit] if limit else cell:
                out.append(replace(sc, scenario_id=len(out)))
    return out


def episodes_file(out_dir: Path, split: str, mode: str, candidate: str) -> Path:
    return out_dir / split / mode / f"{candidate}.csv"


def run_candidate(out_dir: Path, split: str, mode: str, candidate: str, scenarios: list[Scenario],
                  progress: bool = True) -> list[dict]:
    """Its episodes on the split (read back when a finished file of the same scenarios is there: the command
    resumes where a stopped run left)."""
    path = episodes_file(out_dir, split, mode, candidate)
    if path.exists():
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
        if [int(r["scenario_id"]) for r in rows] == [sc.scenario_id for sc in scenarios]:
            return [{k: float(v) for k, v in r.items()} for r in rows]
    rows = evaluate(HEAD_MODES[mode], policy_maker(candidate), scenarios, seed=0, progress=progress,
                    desc=f"{split} {mode} {candidate}")
    path.parent.mkdir(parents=True, exist_ok=True)
    write_csv_atomic(path, EPISODE_COLUMNS, rows)
    return rows


def paired_difference(reference: list[dict], candidate: list[dict], n_resamples: int = 10_000,
                      seed: int = 0) -> dict:
    """Candidate minus reference success, paired by scenario (one episode each: the scenarios are the unit),
    with a 95% percentile bootstrap interval over scenarios."""
    ref = np.array([r["success"] for r in reference], float)
    cand = np.array([r["success"] for r in candidate], float)
    d = cand - ref
    draws = np.random.default_rng(seed).integers(0, d.size, (n_resamples, d.size))
    means = d[draws].mean(axis=1)
    return {"reference": round(float(ref.mean()), 4), "candidate": round(float(cand.mean()), 4),
            "difference": round(float(d.mean()), 4), "low": round(float(np.quantile(means, 0.025)), 4),
            "high": round(float(np.quantile(means, 0.975)), 4), "scenarios": int(d.size)}


def tune(out_dir: str | os.PathLike, limit: int | None = None, progress: bool = True) -> dict:
    """Run the tuning (resumable) and write ``{out_dir}/record.json``; return the record."""
    out = Path(out_dir)
    fit, held_out = (split_scenarios(SPLITS[name], limit) for name in ("fit", "held_out"))
    names = list(candidates())
    on_fit: dict[str, dict] = {}
    for mode in HEAD_MODES:
        untuned = run_candidate(out, "fit", mode, UNTUNED, fit, progress)
        on_fit[mode] = {name: paired_difference(untuned, run_candidate(out, "fit", mode, name, fit, progress))
                        for name in names}
    mean_over_modes = {name: float(np.mean([on_fit[m][name]["candidate"] for m in HEAD_MODES])) for name in names}
    chosen = max(names, key=lambda name: (mean_over_modes[name], name == SHIPPED))
    checked = {}
    for mode in HEAD_MODES:
        untuned = run_candidate(out, "held_out", mode, UNTUNED, held_out, progress)
        checked[mode] = paired_difference(untuned, run_candidate(out, "held_out", mode, chosen, held_out, progress))
    record = {
        "what": "the tuned frontier searcher's tuning on training-side splits (egosearch.runs.teacher_tuning)",
        "splits": {name: {"paper_homes": list(PAPER_HOMES), "paper_seed": s.paper_seed,
                          "paper_per_cell": PAPER_PER_CELL, "per_cell_limit": limit,
                          "generated_homes": [s.generated_homes.start, s.generated_homes.stop],
                          "generated_per_home_and_cell": GENERATED_PER_HOME_AND_CELL,
                          "scenarios": len(fit if name == "fit" else held_out)} for name, s in SPLITS.items()},
        "candidates": {name: {"overrides": overrides, "fit_mean_over_head_modes": round(mean_over_modes[name], 4),
                              **{f"fit_{mode}": on_fit[mode][name] for mode in HEAD_MODES}}
                       for name, overrides in candidates().items()},
        "chosen": chosen,
        "chosen_is_shipped": chosen == SHIPPED,
        "held_out": checked,
    }
    out.mkdir(parents=True, exist_ok=True)
    (out / "record.json").write_text(json.dumps(record, indent=1) + "\n")
    return record


def summary_line(record: dict) -> str:
    """One line per head mode: the held-out check."""
    parts = [f"chosen on the fit split: {record['chosen']}"
             + ("" if record["chosen_is_shipped"] else " (not the shipped parameters)")]
    for mode, r in record["held_out"].items():
        parts.append(f"held out, {mode}: {r['reference']:.3f} -> {r['candidate']:.3f} "
                     f"({r['difference']:+.3f} [{r['low']:+.3f}, {r['high']:+.3f}], {r['scenarios']} scenarios)")
    return "; ".join(parts)

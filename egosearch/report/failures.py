"""How a searcher fails: stuck against the home, and the kinds of failure its per-step traces show.

An episode is **stuck** when it fails with :data:`STUCK_COLLISIONS` or more collisions in its steps (the
env's count, in every evaluation file: Table 1's extended CSV gives its share for every searcher). A
failed episode's **kind** is read from its trace (:mod:`egosearch.runs.trace`), first match wins:

1. ``never_saw``: the target mask was empty at every step;
2. ``saw_stuck``: it saw the target and was stuck;
3. ``timed_out_near``: it saw the target and ended within :data:`NEAR_M` of where the target counts as
   found (the trace's ``geodesic``), out of steps;
4. ``saw_lost``: it saw the target and had lost it (mask empty) at its last step;
5. ``saw_other``: it saw the target, had it in view at the end, farther than :data:`NEAR_M`, not stuck.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np
import pandas as pd

STUCK_COLLISIONS = 50
"""Collisions in an episode (of the env's 100 steps) from which a failure counts as stuck: half its steps."""
NEAR_M = 1.0
"""Geodesic metres from the found region within which a timed-out episode counts as having nearly arrived."""
TRACE_FILE = re.compile(r"^h(\d+(?:\.\d+)?)\.npz$")
KINDS = ("never_saw", "saw_lost", "saw_stuck", "timed_out_near", "saw_other")
KIND_WORDS = {"never_saw": "never saw the target", "saw_lost": "saw it and lost it",
              "saw_stuck": "saw it and was stuck", "timed_out_near": "timed out near it",
              "saw_other": "saw it, in view at the end, not near"}


def stuck(df: pd.DataFrame) -> pd.Series:
    """Per episode of an evaluation frame (``success``, ``collisions``): failed and stuck (0/1)."""
    return ((df["success"].astype(int) == 0) & (df["collisions"] >= STUCK_COLLISIONS)).astype(int)


def stuck_share(df: pd.DataFrame) -> float:
    """The share of an evaluation frame's episodes that are stuck (nan for no episode)."""
    return float(stuck(df).mean()) if len(df) else float("nan")


def episode_kinds(trace: Mapping) -> pd.DataFrame:
    """One row per episode of a trace file's arrays: ``scenario_id, success, collisions, kind`` (``kind`` is
    ``success`` for a success, else one of :data:`KINDS`, module docstring)."""
    df = pd.DataFrame({k: np.asarray(trace[k]) for k in TRACE_ARRAYS})
    rows = []
    for sid, ep in df.groupby("scenario_id", sort=True):
        ep = ep.sort_values("step")
        last = ep.iloc[-1]
        succeeded = bool(ep["success"].any())
        seen = bool(ep["visible"].any())
        collisions = int(last["collisions"])
        if succeeded:
            kind = "success"
        elif not seen:
            kind = "never_saw"
        elif collisions >= STUCK_COLLISIONS:
            kind = "saw_stuck"
        elif np.isfinite(last["geodesic"]) and last["geodesic"] <= NEAR_M:
            kind = "timed_out_near"
        elif not bool(last["visible"]):
            kind = "saw_lost"
        else:
            kind = "saw_other"
        rows.append({"scenario_id": int(sid), "success": int(succeeded), "collisions": collisions, "kind": kind})
    return pd.DataFrame(rows)


FAILURE_COLUMNS = ("method", "height", "placement", "episodes", "success", "stuck", *KINDS)
"""One row per method and cell (both homes pooled): ``success`` and ``stuck`` (failed, >= 50 collisions,
seen or not) and each failure kind as a share of ALL the cell's episodes (the kinds and ``success`` sum
to 1)."""


TRACE_ARRAYS = ("scenario_id", "step", "collisions", "visible", "success", "geodesic")
"""What :func:`episode_kinds` reads of a trace file (``egosearch evaluate --traces`` writes them)."""


def check_trace_file(path) -> None:
    """A trace file holds :data:`TRACE_ARRAYS` and at least one episode; ValueError naming it otherwise (the
    arrays are read only by name: numpy's KeyError, or pandas' on an empty table, would name neither)."""
    with np.load(path, allow_pickle=False) as trace:
        missing = [k for k in TRACE_ARRAYS if k not in trace.files]
        if missing:
            raise ValueError(f"{path}: not a per-step trace (it lacks {', '.join(missing)}); a trace file is written "
                             "by `egosearch evaluate --traces`")
        if trace["scenario_id"].size == 0:
            raise ValueError(f"{path}: a trace of no episode (its scenario set was empty); a failure table reads "
                             "at least one")


def failure_table(traces: Mapping[str, Iterable], out_csv=None) -> pd.DataFrame:
    """:data:`FAILURE_COLUMNS` from ``{method: [trace .npz paths]}`` (paths ``.../seed{N}/{home}/{placement}/
    h{height}.npz``); every seed and home of a cell pooled."""
    rows = []
    for method, paths in traces.items():
        per_cell: dict[tuple, list[pd.DataFrame]] = {}
        for path in paths:
            p = Path(path)
            match = TRACE_FILE.match(p.name)
            if match is None:
                raise ValueError(f"{path}: expected .../seed{{N}}/{{home}}/{{placement}}/h{{height}}.npz")
            height = float(match.group(1))
            with np.load(p, allow_pickle=False) as trace:
                per_cell.setdefault((height, p.parent.name), []).append(episode_kinds(trace))
        for (height, placement), frames in sorted(per_cell.items(),
                                                  key=lambda kv: (kv[0][0], kv[0][1] != "no_low_cabinets")):
            df = pd.concat(frames, ignore_index=True)
            n = len(df)
            row = {"method": method, "height": height, "placement": placement, "episodes": n,
                   "success": float((df["kind"] == "success").mean()), "stuck": stuck_share(df)}
            row.update({kind: float((df["kind"] == kind).mean()) for kind in KINDS})
            rows.append(row)
    out = pd.DataFrame(rows, columns=list(FAILURE_COLUMNS))
    if out_csv is not None:
        Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
        out.to_csv(out_csv, index=False, float_format="%.6g")
    return out


def failure_markdown(df: pd.DataFrame, source: str) -> str:
    """The failure-kind table as Markdown: per method and cell, each kind's share of all episodes (%)."""
    lines = ["| method | cell | success | stuck (any) | " + " | ".join(KIND_WORDS[k] for k in KINDS) + " |",
             "|---|---|---|---|" + "---|" * len(KINDS)]
    for r in df.itertuples(index=False):
        cell = f"{r.height:g} m {'excl.' if r.placement == 'no_low_cabinets' else 'everywhere'}"
        kinds = " | ".join(f"{getattr(r, k) * 100:.1f}" for k in KINDS)
        lines.append(f"| `{r.method}` | {cell} | {r.success * 100:.1f} | {r.stuck * 100:.1f} | {kinds} |")
    return "\n".join(lines) + f"\n\nShares of all episodes (%), both homes and every seed pooled; from `{source}`.\n"

"""How much memory the task asks for: the tuned frontier searcher held to its last K steps, per Table 1 cell, beside
the learned student that sees its last 5 frames.

In: per-episode CSVs of the memory-window searchers (``frontier_tuned_window{K}``, ``..._head_off_window{K}``,
:data:`egosearch.searchers.searcher_registry.MEMORY_WINDOWS`), of the whole-episode searchers and of the students (a
variant's seeds), all on Table 1's sets. Out: ``PREFIX.csv`` (one row per body, memory and cell: success with its
95 % interval, the stuck share), ``PREFIX.md`` (the table) and ``PREFIX.png``/``.pdf`` (success against K).

A searcher is deterministic, so its interval is Wilson's over the cell's scenarios (both homes pooled: the
scenario is what repeats). A student's level is the mean over its seeds and scenarios, and its interval the
two-level bootstrap over scenarios and seeds (:func:`egosearch.report.stats.two_level_ci`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from egosearch.report.data import output_base, parse_eval_path, read_episodes, suffixed
from egosearch.report.stats import scenario_seed_matrix, two_level_ci, wilson_ci

COLUMNS = ("body", "who", "memory_steps", "placement", "height", "n_episodes", "n_seeds", "success", "ci_low",
           "ci_high", "stuck_share")
"""The CSV's columns; ``memory_steps`` is empty for the whole episode and for a student (``who``: its variant)."""
BODIES = ("head moving", "head fixed")
PLACEMENT_LABELS = {"no_low_cabinets": "excl.", "everywhere": "everywhere"}


def _cell_rows(episodes: pd.DataFrame, body: str, who: str, memory: int | None) -> list[dict]:
    rows = []
    for (placement, height), df in episodes.groupby(["placement", "height"], sort=True):
        n_seeds = int(df["seed"].nunique())
        if n_seeds == 1:
            k, n = int(df["success"].sum()), len(df)
            mean, (lo, hi) = k / n, wilson_ci(k, n)
        else:  # scenario_set names the home, so a scenario is (home, cell, id): both homes pooled
            mean, lo, hi = two_level_ci(scenario_seed_matrix(df, "success")[0])
        rows.append({"body": body, "who": who, "memory_steps": memory, "placement": placement,
                     "height": float(height), "n_episodes": len(df), "n_seeds": n_seeds, "success": round(mean, 4),
                     "ci_low": round(float(lo), 4), "ci_high": round(float(hi), 4),
                     "stuck_share": round(float(df["stuck"].mean()), 4)})
    return rows


def _read(paths: Iterable[str]) -> pd.DataFrame:
    """Episodes with their home, placement and height read from each file's path."""
    paths = [str(p) for p in paths]
    df = read_episodes(paths)
    meta = {(m["seed"], "/".join(Path(p).parts[-3:])): m for p, m in ((p, parse_eval_path(p)) for p in paths)}
    for column in ("layout", "placement", "height"):
        df[column] = [meta[(s, sset)][column] for s, sset in zip(df["seed"], df["scenario_set"])]
    return df


def memory_window_inputs(searcher_paths: Iterable[str], student_paths: Iterable[str]):
    """Command-line paths -> (``searchers``, ``students``) of :func:`memory_window_frame`: each searcher's files by
    its body and memory window (read from its registered name and options), the students' by body (from the
    variant's head, which its files' name tells: a ``head_off`` variant is the head-fixed one). ValueError, one
    line, for a file of an unknown searcher or more than one student per body."""
    from egosearch.searchers import searcher_registry as registry

    searchers: dict[str, dict[int | None, list[str]]] = {}
    for path in searcher_paths:
        name = parse_eval_path(path)["variant"]
        if name not in registry.SEARCHERS or not name.startswith("frontier_tuned"):
            raise ValueError(f"{path}: {name!r} is not the tuned searcher or one of its memory windows "
                             f"({', '.join(registry.memory_window_searchers(True).values())}, and head-fixed)")
        searcher = registry.get(name)
        memory = dict(searcher.options).get("memory_window")
        body = BODIES[0] if searcher.head else BODIES[1]
        searchers.setdefault(body, {}).setdefault(memory, []).append(path)
    students: dict[str, tuple[str, list[str]]] = {}
    for path in student_paths:
        variant = parse_eval_path(path)["variant"]
        body = BODIES[1] if "head_off" in variant else BODIES[0]
        held = students.setdefault(body, (variant, []))
        if held[0] != variant:
            raise ValueError(f"{path}: a second {body} student ({variant}, after {held[0]}); allowed: one per body")
        held[1].append(path)
    return searchers, students


def memory_window_frame(searchers: Mapping[str, Mapping[int | None, Iterable[str]]],
                        students: Mapping[str, tuple[str, Iterable[str]]]) -> pd.DataFrame:
    """``searchers``: body -> {memory steps (None: the whole episode) -> its evaluation CSVs}; ``students``:
    body -> (variant, its evaluation CSVs, every seed). Every searcher and student must cover the same cells."""
    rows, cells = [], None
    for body, by_memory in searchers.items():
        for memory, paths in by_memory.items():
            df = _read(paths)
            seen = set(zip(df["layout"], df["placement"], df["height"]))
            if cells is None:
                cells = seen
            elif seen != cells:
                raise ValueError(f"the {body} searcher with memory {memory} covers other cells than the first "
                                 f"searcher: {sorted(seen ^ cells)}")
            rows += _cell_rows(df, body, "frontier_tuned" + ("" if body == BODIES[0] else "_head_off"), memory)
    for body, (variant, paths) in students.items():
        df = _read(paths)
        seen = set(zip(df["layout"], df["placement"], df["height"]))
        if cells is not None and seen != cells:
            raise ValueError(f"{variant} covers other cells than the searchers: {sorted(seen ^ cells)}")
        rows += _cell_rows(df, body, variant, None)
    out = pd.DataFrame(rows, columns=list(COLUMNS))
    out["memory_steps"] = out["memory_steps"].astype("Int64")
    return out


def _cell_label(placement: str, height: float) -> str:
    return f"{height:.2f} m {PLACEMENT_LABELS.get(placement, placement)}"


def memory_window_markdown(frame: pd.DataFrame) -> str:
    cells = sorted({(p, h) for p, h in zip(frame["placement"], frame["height"])},
                   key=lambda c: (c[1], c[0] != "no_low_cabinets"))
    head = "| body | memory | " + " | ".join(_cell_label(*c) for c in cells) + " |"
    lines = ["Success rate of the tuned frontier searcher held to the map and notes of its last K steps (the target's "
             "last-seen place kept), both homes pooled, with the 95 % interval (Wilson, over the cell's scenarios), "
             "and the learned student (its seeds' mean; interval: two-level bootstrap over scenarios and seeds), which "
             "sees its last 5 depth frames. Generated by `snakemake memory_window`.", "", head,
             "|" + "---|" * (len(cells) + 2)]
    for body in BODIES:
        part = frame[frame["body"] == body]
        searcher = part[part["who"].str.startswith("frontier_tuned")]
        order = sorted(searcher["memory_steps"].unique(), key=lambda m: math.inf if pd.isna(m) else m)
        for memory in order:
            sel = searcher[searcher["memory_steps"].isna()] if pd.isna(memory) else searcher[
                searcher["memory_steps"] == memory]
            label = "whole episode" if pd.isna(memory) else f"last {int(memory)} steps"
            lines.append(f"| {body} | {label} | " + " | ".join(_value(sel, c) for c in cells) + " |")
        for who in part.loc[~part["who"].str.startswith("frontier_tuned"), "who"].unique():
            sel = part[part["who"] == who]
            lines.append(f"| {body} | `{who}` (student, 5 frames) | " + " | ".join(_value(sel, c) for c in cells)
                         + " |")
    return "\n".join(lines) + "\n"


def _value(sel: pd.DataFrame, cell: tuple[str, float]) -> str:
    row = sel[(sel["placement"] == cell[0]) & (sel["height"] == cell[1])]
    if row.empty:
        return "–"
    r = row.iloc[0]
    return f"{r['success']:.2f} [{r['ci_low']:.2f}, {r['ci_high']:.2f}]"


def memory_window_figure(frame: pd.DataFrame):
    """Success against memory (log steps; the whole episode at the right), one panel per cell, the students as
    dashed levels in their body's colour."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    cells = sorted({(p, h) for p, h in zip(frame["placement"], frame["height"])},
                   key=lambda c: (c[0] != "no_low_cabinets", c[1]))
    placements = sorted({c[0] for c in cells}, key=lambda p: p != "no_low_cabinets")
    heights = sorted({c[1] for c in cells})
    fig = Figure(figsize=(3.2 * len(heights), 2.9 * len(placements)), constrained_layout=True)
    axes = fig.subplots(len(placements), len(heights), squeeze=False, sharey=True)
    windows = sorted(int(m) for m in frame["memory_steps"].dropna().unique())
    whole_x = (windows[-1] * 2.5) if windows else 1.0
    colours = {BODIES[0]: "#1f77b4", BODIES[1]: "#d62728"}
    for i, placement in enumerate(placements):
        for j, height in enumerate(heights):
            ax = axes[i][j]
            cell = frame[(frame["placement"] == placement) & (frame["height"] == height)]
            for body in BODIES:
                part = cell[cell["body"] == body]
                searcher = part[part["who"].str.startswith("frontier_tuned")].copy()
                if searcher.empty:
                    continue
                searcher["x"] = searcher["memory_steps"].astype("float").fillna(whole_x)
                searcher = searcher.sort_values("x")
                yerr = np.vstack([searcher["success"] - searcher["ci_low"], searcher["ci_high"] - searcher["success"]])
                ax.errorbar(searcher["x"], searcher["success"], yerr=yerr, color=colours[body], marker="o", ms=4,
                            capsize=2, lw=1.4, label=f"tuned searcher, {body}")
                for _, student in part[~part["who"].str.startswith("frontier_tuned")].iterrows():
                    ax.axhline(student["success"], color=colours[body], ls="--", lw=1.1,
                               label=f"student {student['who']} (5 frames), {body}")
                    ax.axhspan(student["ci_low"], student["ci_high"], color=colours[body], alpha=0.08, lw=0)
            ax.axvline(5, color="#999999", lw=0.8, ls=":")
            ax.set_xscale("log")
            ax.set_xticks(windows + [whole_x])
            ax.set_xticklabels([str(w) for w in windows] + ["all"])
            ax.minorticks_off()
            ax.set_ylim(0, 1)
            ax.set_title(_cell_label(placement, height), fontsize=9)
            if i == len(placements) - 1:
                ax.set_xlabel("memory (steps)")
            if j == 0:
                ax.set_ylabel("success rate")
            ax.grid(alpha=0.3)
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=2, fontsize=8, frameon=False)
    fig.suptitle("How much memory the search asks for (both homes; dotted: the student's 5 frames)", fontsize=10)
    return fig


def memory_window_report(searchers, students, out_prefix) -> list[Path]:
    """Write ``PREFIX.csv``, ``PREFIX.md``, ``PREFIX.png`` and ``PREFIX.pdf``; return their paths."""
    from egosearch.report.figures import save_figure

    frame = memory_window_frame(searchers, students)
    base = output_base(out_prefix, "memory_window")
    base.parent.mkdir(parents=True, exist_ok=True)
    csv_path, md_path = suffixed(base, ".csv"), suffixed(base, ".md")
    frame.to_csv(csv_path, index=False)
    md_path.write_text(memory_window_markdown(frame))
    return [csv_path, md_path, *save_figure(memory_window_figure(frame), base)]

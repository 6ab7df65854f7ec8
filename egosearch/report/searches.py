"""``egosearch report searches``: pictures of searches from per-step traces, on the home's floor plan.

- :func:`search_maps`: a few episodes of one trace file, drawn from above: the body's path, the
  camera's centre ray every :data:`GAZE_EVERY` steps (to what it meets; dashed to the sensor's range
  when it meets nothing), collisions, the start, the target and the first sight. The episodes are
  chosen by a rule written under the picture: the successes and the failures at the quantiles
  :data:`PICK_QUANTILES` of their path length (nearest rank).
- :func:`gaze_heatmap`: where the camera's centre ray lands over every step of every episode of one
  cell, one panel per variant.

Not imported by ``egosearch.report`` or its CLI module: it draws the floor plan with ``egosearch.scene``,
which loads trimesh (only when drawing: see the ``# local:`` imports).
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from egosearch.report.behaviour import OPENING_KINDS, parse_trace_path, read_trace_file

PathLike = str | os.PathLike

PICK_QUANTILES = (0.1, 0.5, 0.9)
GAZE_EVERY = 3
HEAT_BIN = 0.2
"""Side (m) of the heatmap's squares."""


def episode_table(steps: pd.DataFrame) -> pd.DataFrame:
    """Per episode: scenario_id, success, steps, path_length (summed from the trace's poses)."""
    rows = []
    for sid, ep in steps.groupby("scenario_id", sort=True):
        ep = ep.sort_values("step")
        rows.append({"scenario_id": int(sid), "success": bool(ep["success"].iloc[-1]), "steps": len(ep) - 1,
                     "path_length": float(np.hypot(np.diff(ep["x"]), np.diff(ep["y"])).sum())})
    return pd.DataFrame(rows)


def pick_episodes(table: pd.DataFrame, quantiles=PICK_QUANTILES) -> list[tuple[int, str]]:
    """(scenario_id, label) of the successes, then the failures, at ``quantiles`` of their path length:
    the episode of rank floor(q (n - 1) + 1/2) in path-length order (ties by scenario id), each once."""
    picked = []
    for success, word in ((True, "success"), (False, "failure")):
        group = table[table["success"] == success].sort_values(["path_length", "scenario_id"])
        ranks = dict.fromkeys(math.floor(q * (len(group) - 1) + 0.5) for q in quantiles) if len(group) else {}
        for rank in ranks:
            row = group.iloc[rank]
            q = rank / (len(group) - 1) if len(group) > 1 else 0.0
            picked.append((int(row.scenario_id), f"{word}, path {row.path_length:.1f} m (q{q:.2f} of "
                                                 f"{len(group)})"))
    return picked


def rule_text(quantiles=PICK_QUANTILES) -> str:
    qs = ", ".join(f"{q:g}" for q in quantiles)
    return (f"Episodes shown: among the successes, then among the failures of this file, those at the {qs} "
            f"quantiles of path length (nearest rank, halves up). Path blue, the camera's centre ray every "
            f"{GAZE_EVERY} steps grey (dashed: nothing within range), collisions red x, first sight green eye, "
            f"start blue disc, target star.")


def _draw_episode(ax, ep: pd.DataFrame, max_depth: float) -> None:
    x, y = ep["x"].to_numpy(float), ep["y"].to_numpy(float)
    heading = ep["theta"].to_numpy(float) + ep["head_yaw"].to_numpy(float)
    for t in range(0, len(ep), GAZE_EVERY):
        gx, gy = ep["gaze_x"].iloc[t], ep["gaze_y"].iloc[t]
        if math.isfinite(gx):
            ax.plot([x[t], gx], [y[t], gy], color=(0.35, 0.35, 0.35), lw=0.6, alpha=0.8, zorder=11)
        else:
            reach = max_depth * math.cos(float(ep["pitch"].iloc[t]))
            ax.plot([x[t], x[t] + reach * math.cos(heading[t])], [y[t], y[t] + reach * math.sin(heading[t])],
                    color=(0.35, 0.35, 0.35), lw=0.6, ls="--", alpha=0.6, zorder=11)
    ax.plot(x, y, color=(0.1, 0.35, 0.85), lw=1.6, zorder=12)
    hit = ep["collided"].to_numpy(bool) if "collided" in ep else np.zeros(len(ep), bool)
    ax.plot(x[hit], y[hit], "x", color=(0.85, 0.1, 0.1), ms=5, mew=1.4, zorder=13)
    seen = np.flatnonzero(ep["visible"].to_numpy(bool))
    if seen.size:
        ax.plot(x[seen[0]], y[seen[0]], marker="$\u25c9$", ms=11, color=(0.1, 0.6, 0.2), zorder=14)


def search_maps(trace: PathLike, out: PathLike, quantiles=PICK_QUANTILES) -> Path:
    """One picture of the episodes :func:`pick_episodes` chooses from ``trace`` (see the module docstring)."""
    matplotlib.use("Agg")
    # local: egosearch.scene loads trimesh (about 1 s), which the report layer imports only to draw a floor plan
    from egosearch.scene.layouts import get_scene
    from egosearch.scene.topdown import plot_topdown

    where = parse_trace_path(trace)
    steps, facts = read_trace_file(trace)
    picked = pick_episodes(episode_table(steps), quantiles)
    if not picked:
        raise ValueError(f"{trace}: no episodes")
    ncols = max(len(quantiles), 1)
    nrows = -(-len(picked) // ncols)
    layouts = steps.groupby("scenario_id")["layout"].first() if "layout" in steps else None
    first_scene = get_scene(layouts.iloc[0] if layouts is not None else where["layout"])
    x0, y0, x1, y1 = first_scene.bounds
    fig, axes = plt.subplots(nrows, ncols, figsize=(ncols * (1.0 + 0.55 * (x1 - x0)), nrows * (1.2 + 0.55 * (y1 - y0))),
                             squeeze=False)
    for ax in axes.ravel():
        ax.set_axis_off()
    for ax, (sid, label) in zip(axes.ravel(), picked):
        ep = steps[steps["scenario_id"] == sid].sort_values("step")
        scene = get_scene(layouts.loc[sid]) if layouts is not None else first_scene
        first = ep.iloc[0]
        plot_topdown(scene, ax=ax, targets=[(first.target_x, first.target_y)] if "target_x" in ep else (),
                     starts=[(first.x, first.y, first.theta)], title=f"scenario {sid}: {label}")
        _draw_episode(ax, ep, float(facts.get("max_depth", 5.0)))
    fig.suptitle(f"{where['variant']}, seed {where['seed']}, {where['layout']}, {where['placement']}, "
                 f"camera {where['height']:g} m", fontsize=12)
    fig.text(0.5, 0.005, rule_text(quantiles), ha="center", va="bottom", fontsize=8, wrap=True)
    fig.tight_layout(rect=(0, 0.03, 1, 0.97))
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def gaze_heatmap(traces: Iterable[PathLike], out: PathLike) -> Path:
    """Where the centre ray lands (its hit point seen from above; the ceiling's left out) over every
    step after a reset of every episode in ``traces`` (one cell: one home, placement and height; any
    variants and seeds), one panel per variant, as a share of that variant's steps per
    :data:`HEAT_BIN` square."""
    matplotlib.use("Agg")
    # local: egosearch.scene loads trimesh (about 1 s), which the report layer imports only to draw a floor plan
    from egosearch.scene.layouts import get_scene
    from egosearch.scene.topdown import plot_topdown

    by_variant: dict[str, list[pd.DataFrame]] = {}
    cells = set()
    for path in traces:
        where = parse_trace_path(path)
        cells.add((where["layout"], where["placement"], where["height"]))
        by_variant.setdefault(where["variant"], []).append(read_trace_file(path)[0])
    if len(cells) != 1:
        raise ValueError(f"a gaze heatmap draws one cell; got {sorted(cells)}")
    layout, placement, height = cells.pop()
    scene = get_scene(layout)
    x0, y0, x1, y1 = scene.bounds
    xe, ye = np.arange(x0, x1 + HEAT_BIN, HEAT_BIN), np.arange(y0, y1 + HEAT_BIN, HEAT_BIN)
    fig, axes = plt.subplots(1, len(by_variant), figsize=(len(by_variant) * (1.0 + 0.6 * (x1 - x0)),
                                                          1.6 + 0.6 * (y1 - y0)), squeeze=False)
    shares = {}
    for v, frames in by_variant.items():
        steps = pd.concat(frames, ignore_index=True)
        steps = steps[steps["step"] > 0]
        kind = steps["gaze_kind"].to_numpy(str)
        hit = np.isfinite(steps["gaze_x"].to_numpy(float)) & (kind != "ceiling")
        counts, _, _ = np.histogram2d(steps["gaze_x"][hit], steps["gaze_y"][hit], bins=(xe, ye))
        n = max(len(steps), 1)
        shares[v] = (counts / n, np.mean(kind == "none") if len(steps) else math.nan,
                     np.mean(kind == "ceiling") if len(steps) else math.nan,
                     np.isin(kind, OPENING_KINDS).mean() if len(steps) else math.nan, len(steps))
    top = max(float(s[0].max()) for s in shares.values()) or 1.0
    for ax, (v, (share, none, ceiling, opening, n)) in zip(axes[0], shares.items()):
        plot_topdown(scene, ax=ax, title=f"{v}: {n} steps; {opening:.0%} into cabinets or shelves, "
                                         f"{ceiling:.0%} at the ceiling, {none:.0%} nothing within range")
        image = ax.imshow(np.ma.masked_equal(share.T, 0.0), origin="lower", extent=(xe[0], xe[-1], ye[0], ye[-1]),
                          cmap="magma_r", vmin=0.0, vmax=top, alpha=0.85, zorder=20, interpolation="nearest")
    fig.colorbar(image, ax=list(axes[0]), shrink=0.7, label=f"share of steps per {HEAT_BIN:g} m square")
    fig.suptitle(f"Where the camera's centre ray lands: {layout}, {placement}, camera {height:g} m", fontsize=12)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return out


def searches_report(traces: Iterable[PathLike], out_dir: PathLike, seed: int = 0) -> list[Path]:
    """For each trace file of ``seed``: ``{variant}_{layout}_{placement}_h{height}.png`` (the chosen
    episodes); for each cell: ``gaze_{layout}_{placement}_h{height}.png`` over every file given."""
    traces = [Path(p) for p in traces]
    out_dir = Path(out_dir)
    written, cells = [], {}
    for path in traces:
        w = parse_trace_path(path)
        name = f"{w['layout']}_{w['placement']}_h{w['height']:g}"
        cells.setdefault(name, []).append(path)
        if w["seed"] == seed:
            written.append(search_maps(path, out_dir / f"{w['variant']}_{name}.png"))
    for name, paths in cells.items():
        written.append(gaze_heatmap(paths, out_dir / f"gaze_{name}.png"))
    return written

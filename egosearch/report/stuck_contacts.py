"""What a stuck searcher is pressed against, read from its per-step traces and the home's plain data.

For every stuck episode (:func:`egosearch.report.failures.stuck`) of a trace file:

- the **stuck run**: the longest run of steps that touched the home, gaps of up to :data:`RUN_GAP` steps
  allowed; ``t0`` its first step;
- the **object**: the piece of furniture (a scene part's first two name levels, ``living/sofa``) nearest the
  body's surface at the run's touching steps, the most frequent one (within :data:`CONTACT_M`); its kind,
  its top (m) and whether that top is below the camera;
- the **5 frames before contact** (the observations the policy acted on, rows ``t0-5 .. t0-1``): whether the
  camera's centre ray met that object (the trace's ``gaze_part``; the centre ray only, so a lower bound on
  "the camera saw it"), whether the object's nearest top edge lay below the lower edge of the vertical
  field of view, and whether the target was in view;
- the **actions in the run**: the share of steps with forward > 0.3, the path against the net displacement,
  and a behaviour: ``pushes_and_slides`` (forward in most steps, 1 m or more of path), ``pushes_in_place``
  (forward, less), ``backs_into_it`` (mean forward < -0.3), ``mixed``.

Only the traces and :mod:`egosearch.scene` are read: no simulation runs.
"""

from __future__ import annotations

import math
import re
from collections import Counter
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from egosearch.report.failures import STUCK_COLLISIONS
from egosearch.scene.layouts import get_scene

RUN_GAP = 2
"""Steps without a touch that a stuck run may hold."""
CONTACT_M = 0.06
"""How far (m) the body's surface may be from a part for the part to count as touched at a touching step."""
BODY_RADIUS = 0.2
"""The abstract body's radius (egosearch.sim.body.AgentConfig.body_radius)."""
HALF_VERTICAL_FOV = math.radians(45.0)
"""Half the camera's vertical field of view (90 degrees)."""
PRE_FRAMES = 5
TRACE_FILE = re.compile(r"^h(\d+(?:\.\d+)?)\.npz$")
AUX_TAGS = {"outer", "partition", "lintel", "cooktop", "books", "tv", "obstacle", "furniture", "lamp", "sink"}
KIND_ORDER = ("wall", "counter", "nightstand", "sink_cabinet", "low_cabinet", "wall_cabinet", "bookshelf")


def furniture_of(name: str) -> str:
    parts = name.split("/")
    return "wall" if parts[0] == "wall" else "/".join(parts[:2])


def _kind(parts) -> str:
    tags = set().union(*(set(p.tags) for p in parts))
    for kind in KIND_ORDER:
        if kind in tags:
            return kind
    rest = sorted(tags - AUX_TAGS)
    return rest[0] if rest else "other"


class HomeGeometry:
    """The obstacles of one home as arrays, grouped into furniture."""

    def __init__(self, home: str):
        scene = get_scene(home)
        self.parts = [p for p in scene.obstacles]
        self.group = [furniture_of(p.name) for p in self.parts]
        self.center = np.array([p.center for p in self.parts], float)
        self.half = np.array([p.size for p in self.parts], float) / 2
        self.yaw = np.array([p.yaw for p in self.parts], float)
        self.top = self.center[:, 2] + self.half[:, 2]
        self.kinds = {}
        for name in set(self.group):
            self.kinds[name] = _kind([p for p, g in zip(self.parts, self.group) if g == name])

    def nearest(self, x: float, y: float) -> tuple[np.ndarray, np.ndarray]:
        """Per part: the horizontal distance from (x, y) to its footprint, and the nearest point (n, 2)."""
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        dx, dy = x - self.center[:, 0], y - self.center[:, 1]
        lx, ly = c * dx + s * dy, -s * dx + c * dy
        qx = np.clip(lx, -self.half[:, 0], self.half[:, 0])
        qy = np.clip(ly, -self.half[:, 1], self.half[:, 1])
        px, py = self.center[:, 0] + c * qx - s * qy, self.center[:, 1] + s * qx + c * qy
        return np.hypot(px - x, py - y), np.column_stack([px, py])


def stuck_run(collided: np.ndarray) -> tuple[int, int] | None:
    """(first, last) step of the longest run of touching steps, gaps of up to :data:`RUN_GAP` allowed."""
    idx = np.flatnonzero(collided)
    if idx.size == 0:
        return None
    runs, start, prev = [], idx[0], idx[0]
    for i in idx[1:]:
        if i - prev > RUN_GAP + 1:
            runs.append((start, prev))
            start = i
        prev = i
    runs.append((start, prev))
    first, last = max(runs, key=lambda r: (r[1] - r[0], -r[0]))
    return int(first), int(last)


def _behaviour(forward: np.ndarray, path: float) -> str:
    if np.nanmean(forward) < -0.3:
        return "backs_into_it"
    if np.mean(forward > 0.3) >= 0.5:
        return "pushes_and_slides" if path >= 1.0 else "pushes_in_place"
    return "mixed"


def read_episode(ep: pd.DataFrame, home: HomeGeometry) -> dict | None:
    """One stuck episode's row (module docstring), None if it has no touching step."""
    ep = ep.sort_values("step").reset_index(drop=True)
    run = stuck_run(ep["collided"].to_numpy())
    if run is None:
        return None
    t0, t1 = run
    votes: Counter = Counter()
    for t in range(t0, t1 + 1):
        if not ep.at[t, "collided"]:
            continue
        dist, _ = home.nearest(float(ep.at[t, "x"]), float(ep.at[t, "y"]))
        touched = np.flatnonzero(dist - BODY_RADIUS <= CONTACT_M)
        if touched.size == 0:
            touched = np.array([int(np.argmin(dist))])
        for g in {home.group[i] for i in touched}:
            votes[g] += 1
    furniture = votes.most_common(1)[0][0]
    members = [i for i, g in enumerate(home.group) if g == furniture]
    camera = float(ep.at[t0, "camera_height"])
    x0, y0 = float(ep.at[t0, "x"]), float(ep.at[t0, "y"])
    dist, points = home.nearest(x0, y0)
    nearest = min(members, key=lambda i: dist[i])
    top = float(max(home.top[i] for i in members))
    pre = [t for t in range(t0 - PRE_FRAMES, t0) if t >= 0]
    gaze = {furniture_of(str(p)) for p in ep.loc[pre, "gaze_part"] if str(p)}
    below_view = False
    if pre:
        t = pre[-1]
        horizontal = float(np.hypot(points[nearest, 0] - ep.at[t, "x"], points[nearest, 1] - ep.at[t, "y"]))
        angle = math.atan2(float(home.top[nearest]) - camera, max(horizontal, 1e-6))
        below_view = bool(home.top[nearest] < camera and angle < float(ep.at[t, "pitch"]) - HALF_VERTICAL_FOV)
    forward = ep.loc[t0:t1, "a0"].to_numpy(float)
    xs, ys = ep.loc[t0:t1, "x"].to_numpy(float), ep.loc[t0:t1, "y"].to_numpy(float)
    path = float(np.sum(np.hypot(np.diff(xs), np.diff(ys))))
    kind = home.kinds[furniture]
    return {"scenario_id": int(ep.at[0, "scenario_id"]), "run_start": t0, "run_steps": t1 - t0 + 1,
            "furniture": furniture, "kind": kind, "top_m": top,
            "relation": "wall" if kind == "wall" else ("below the camera" if top < camera else "above the camera"),
            "centre_ray_met_it": bool(furniture in gaze), "below_the_view": below_view,
            "target_in_view_before": bool(ep.loc[pre, "visible"].any()) if pre else False,
            "target_in_view_in_run": float(ep.loc[t0:t1, "visible"].mean()),
            "forward_share": float(np.mean(forward > 0.3)), "path_m": path,
            "displacement_m": float(math.hypot(xs[-1] - xs[0], ys[-1] - ys[0])),
            "behaviour": _behaviour(forward, path)}


def stuck_contacts(traces: Mapping[str, Iterable], out_csv=None) -> pd.DataFrame:
    """One row per stuck episode of ``{method: [trace .npz paths]}`` (paths ``.../seed{N}/{home}/{placement}/
    h{height}.npz``), with the method, seed, home, placement and height."""
    homes: dict[str, HomeGeometry] = {}
    rows = []
    columns = ("scenario_id", "step", "collided", "collisions", "success", "visible", "x", "y", "pitch",
               "camera_height", "a0", "gaze_part")
    for method, paths in traces.items():
        for path in paths:
            p = Path(path)
            match = TRACE_FILE.match(p.name)
            if match is None:
                raise ValueError(f"{path}: expected .../seed{{N}}/{{home}}/{{placement}}/h{{height}}.npz")
            seed, home, placement = int(p.parts[-4][4:]), p.parts[-3], p.parts[-2]
            with np.load(p, allow_pickle=False) as trace:
                df = pd.DataFrame({c: np.asarray(trace[c]) for c in columns})
            if home not in homes:
                homes[home] = HomeGeometry(home)
            for _, ep in df.groupby("scenario_id", sort=True):
                last = ep.loc[ep["step"].idxmax()]
                if bool(ep["success"].any()) or int(last["collisions"]) < STUCK_COLLISIONS:
                    continue
                row = read_episode(ep, homes[home])
                if row is not None:
                    rows.append({"method": method, "seed": seed, "home": home, "placement": placement,
                                 "height": float(match.group(1)), **row})
    out = pd.DataFrame(rows)
    if out_csv is not None:
        Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
        out.to_csv(out_csv, index=False, float_format="%.4g")
    return out


def stuck_markdown(df: pd.DataFrame, method: str, source: str) -> str:
    """The stuck read of one method as Markdown: where, what, seen before, what it did."""
    d = df[df["method"] == method]
    if d.empty:
        return f"*`{method}` has no stuck episode in `{source}`.*\n"
    n = len(d)

    def pct(x) -> str:
        return f"{100 * x:.0f} %"

    lines = [f"`{method}`: {n} stuck episodes (every seed, both homes, the six cells; `{source}`).", "",
             "| home | stuck episodes |", "|---|---|"]
    lines += [f"| {home} | {count} |" for home, count in d["home"].value_counts().sort_index().items()]
    lines += ["", "What it is pressed against (the most-touched furniture of the stuck run):", "",
              "| kind | episodes | top (m), median | top below the camera |", "|---|---|---|---|"]
    for kind, g in sorted(d.groupby("kind"), key=lambda kv: -len(kv[1])):
        below = pct((g["relation"] == "below the camera").mean())
        lines.append(f"| {kind} | {len(g)} | {g['top_m'].median():.2f} | {below} |")
    most = d["furniture"].value_counts()
    lines += ["", f"The most-hit piece: `{most.index[0]}` in {most.iloc[0]} episodes ({pct(most.iloc[0] / n)}).", "",
              "| in the 5 frames before contact | share of stuck episodes |", "|---|---|",
              f"| the camera's centre ray met that furniture | {pct(d['centre_ray_met_it'].mean())} |",
              f"| its top was below the lower edge of the view (last frame) | {pct(d['below_the_view'].mean())} |",
              f"| the target was in view | {pct(d['target_in_view_before'].mean())} |", "",
              "| during the stuck run | value |", "|---|---|",
              f"| steps with forward > 0.3 (median over episodes) | {pct(d['forward_share'].median())} |",
              f"| path, median (m) | {d['path_m'].median():.2f} |",
              f"| net displacement, median (m) | {d['displacement_m'].median():.2f} |",
              f"| target in view, median share of the run's steps | {pct(d['target_in_view_in_run'].median())} |"]
    lines += ["", "| behaviour | episodes |", "|---|---|"]
    lines += [f"| {b.replace('_', ' ')} | {c} |" for b, c in d["behaviour"].value_counts().items()]
    return "\n".join(lines) + "\n"

"""Per-step traces of evaluation episodes: where the body was, where the camera looked, what it saw.

``egosearch evaluate --traces FILE.npz`` hands a :class:`TraceRecorder` to
:func:`egosearch.runs.evaluate.evaluate`; it writes one compressed ``.npz`` per scenario file (read back by
``egosearch.report.behaviour.read_trace_file``). Every array
of length N is a column (one row per step, episodes stacked); the 0-d arrays are the file's facts
(``env_id``, ``head``, ``step_seconds``, ``max_depth``, ``format``). Row 0 of an episode is the state
after ``reset`` (no action); row t > 0 is the state after the t-th action.

Columns:

- ``scenario_id``, ``layout`` (the home), ``step``; ``x``, ``y``, ``theta`` (body pose), ``pitch``, ``head_yaw`` (camera
  joints; fixed for the head-off body), ``camera_height``;
- ``a0`` ... ``a4``: the normalised action that led to this row, exactly as the policy returned it
  (float32, so that a replay steps through the same numbers); NaN on row 0 and, for the head-off
  body, in ``a3`` and ``a4``;
- ``visible`` (the target mask is not empty), ``success``, ``collisions`` (the env's count so far),
  ``collided`` (this step touched the home);
- ``distance``: the env's distance to the target (body surface to target centre, horizontal, m);
  ``geodesic``: the navgrid geodesic from the body to the nearest pose from which the target counts
  as found (the region behind the scenario's ``shortest_path``, so row 0 repeats that ℓ);
- ``gaze_x``, ``gaze_y``, ``gaze_z``: where the camera's centre ray first meets the home or the
  target within the sensor's range (NaN: nothing in range); ``gaze_part``: the part it meets
  (``target`` for the target); ``gaze_surface``: the support surface whose space holds that point
  (a cabinet level, a shelf, a table top; empty when none); ``gaze_kind``: one of
  :data:`GAZE_KINDS`;
- ``opening_distance``: horizontal distance (m) from the body's centre to the nearest opening (a
  low or wall cabinet's interior level or a shelf: :data:`OPENING_KINDS`), 0 over one;
- ``room``: the floor rectangle the body's centre is on (the nearest one in a doorway);
- ``target_x``, ``target_y``, ``target_z``: the episode's target centre (repeated per row; the
  compression makes it free).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from egosearch.scene.layouts import get_scene
from egosearch.scene.meshes import part_mesh, scene_meshes
from egosearch.scene.parts import TAG_FLOOR, TAG_WALL
from egosearch.sim.body import STEP_SECONDS
from egosearch.sim.scenarios import navgrid_for, shortest_path_region
from egosearch.sim.sensor import camera_axes

TRACE_FORMAT = 1
GAZE_KINDS = ("target", "low_cabinet_interior", "wall_cabinet_interior", "shelf", "surface", "floor", "wall",
              "furniture", "ceiling", "none")
"""What the camera's centre ray meets, most specific first: the target; the space of a support
surface (the three opening kinds, then any other surface: table and counter tops, seats, cabinet
tops); else the part's own kind."""
OPENING_KINDS = ("low_cabinet_interior", "wall_cabinet_interior", "shelf")
"""The support surfaces with sides and a board above: where a target can be *inside* furniture."""
SURFACE_MARGIN = 0.04
"""How far (m) a hit point may lie outside a surface's rectangle and still be in its space: the
panels round a cabinet level are 2 cm thick, so 4 cm takes in their inner faces and leaves out
their outer ones."""
ACTION_COLUMNS = tuple(f"a{i}" for i in range(5))
FLOAT_COLUMNS = ("x", "y", "theta", "pitch", "head_yaw", "camera_height", *ACTION_COLUMNS, "distance", "geodesic",
                 "gaze_x", "gaze_y", "gaze_z", "opening_distance", "target_x", "target_y", "target_z")
INT_COLUMNS = ("scenario_id", "step", "collisions")
BOOL_COLUMNS = ("visible", "success", "collided")
STR_COLUMNS = ("layout", "gaze_kind", "gaze_part", "gaze_surface", "room")
TRACE_COLUMNS = INT_COLUMNS + FLOAT_COLUMNS + BOOL_COLUMNS + STR_COLUMNS


def rectangle_distance(x, y, center, size, yaw) -> np.ndarray:
    """Horizontal distance (m) from points (x, y) to yawed rectangles (arrays of centres (n, 2), sizes
    (n, 2) and yaws (n,)), 0 inside: shape (points, rectangles)."""
    x, y = np.atleast_1d(np.asarray(x, float))[:, None], np.atleast_1d(np.asarray(y, float))[:, None]
    c, s = np.cos(yaw)[None, :], np.sin(yaw)[None, :]
    dx, dy = x - center[None, :, 0], y - center[None, :, 1]
    qx = np.abs(c * dx + s * dy) - size[None, :, 0] / 2
    qy = np.abs(-s * dx + c * dy) - size[None, :, 1] / 2
    return np.hypot(np.maximum(qx, 0.0), np.maximum(qy, 0.0))


def _rectangles(surfaces) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return (np.array([s.center[:2] for s in surfaces], float).reshape(-1, 2),
            np.array([s.size for s in surfaces], float).reshape(-1, 2), np.array([s.yaw for s in surfaces], float))


def _surface_kind(surface) -> str:
    return next((k for k in OPENING_KINDS if k in surface.tags), "surface")


class HomeProbe:
    """One home's fixed geometry for traces: its meshes for the centre ray, its openings and rooms."""

    def __init__(self, layout: str):
        import trimesh


        self.layout = layout
        self.scene = get_scene(layout)
        pairs = scene_meshes(self.scene)
        self._parts = [part for part, _ in pairs]
        self._first_face = np.cumsum([0] + [len(mesh.faces) for _, mesh in pairs])
        self._rays = trimesh.ray.ray_pyembree.RayMeshIntersector(trimesh.util.concatenate([m for _, m in pairs]))
        self._target_rays, self._target = None, None
        # Floors are rooms, not places to look into: a floor hit is classed by its part.
        self.surfaces = [s for s in self.scene.surfaces if TAG_FLOOR not in s.tags]
        self.openings = [s for s in self.surfaces if _surface_kind(s) != "surface"]
        self._openings = _rectangles(self.openings)
        floors = [s for s in self.scene.surfaces if TAG_FLOOR in s.tags]
        self._room_names = [s.name.split("/", 1)[-1] for s in floors]
        self._rooms = _rectangles(floors)

    def set_target(self, target) -> None:
        import trimesh


        if target is not self._target:
            self._target = target
            self._target_rays = (None if target is None
                                 else trimesh.ray.ray_pyembree.RayMeshIntersector(part_mesh(target)))

    def opening_distance(self, x: float, y: float) -> float:
        if not self.openings:
            return math.inf
        return float(rectangle_distance(x, y, *self._openings).min())

    def room(self, x: float, y: float) -> str:
        if not self._room_names:
            return ""
        return self._room_names[int(np.argmin(rectangle_distance(x, y, *self._rooms)[0]))]

    def surface_at(self, point) -> object | None:
        """The support surface whose space (its rectangle, an opening's grown by :data:`SURFACE_MARGIN`,
        from just under the surface up to its clearance) holds ``point``; an opening before any other,
        then the highest."""
        inside = []
        for s in self.surfaces:
            # an open top has no panels: the wall behind a sideboard is the wall
            margin = SURFACE_MARGIN if _surface_kind(s) != "surface" else 0.0
            if not s.center[2] - SURFACE_MARGIN <= point[2] <= s.center[2] + s.clearance:
                continue
            c, sn = math.cos(s.yaw), math.sin(s.yaw)
            dx, dy = point[0] - s.center[0], point[1] - s.center[1]
            if abs(c * dx + sn * dy) <= s.size[0] / 2 + margin and abs(-sn * dx + c * dy) <= s.size[1] / 2 + margin:
                inside.append(s)
        # an opening beats a top that shares its space; of two levels, the point rests above the higher
        best = max(inside, key=lambda s: (_surface_kind(s) != "surface", s.center[2]), default=None)
        return best

    def gaze(self, origin, direction, max_depth: float) -> tuple[tuple[float, float, float], str, str, str]:
        """Where the ray from ``origin`` along the unit ``direction`` first meets the home or the target
        within ``max_depth`` (m): (point, kind, part name, surface name)."""
        o, d = np.asarray([origin], float), np.asarray([direction], float)
        hits = []
        locs, _, tris = self._rays.intersects_location(o, d, multiple_hits=False)
        if len(tris):
            part = self._parts[int(np.searchsorted(self._first_face, tris[0], side="right") - 1)]
            hits.append((float(np.linalg.norm(locs[0] - o[0])), locs[0], part))
        if self._target_rays is not None:
            locs, _, tris = self._target_rays.intersects_location(o, d, multiple_hits=False)
            if len(tris):
                hits.append((float(np.linalg.norm(locs[0] - o[0])), locs[0], None))
        if not hits or min(h[0] for h in hits) > max_depth:
            return (math.nan, math.nan, math.nan), "none", "", ""
        _, point, part = min(hits, key=lambda h: h[0])
        point = tuple(float(v) for v in point)
        surface = self.surface_at(point)
        if part is None:
            return point, "target", "target", "" if surface is None else surface.name
        if surface is not None:
            kind = _surface_kind(surface)
        elif TAG_FLOOR in part.tags:
            kind = "floor"
        elif TAG_WALL in part.tags:
            kind = "wall"
        elif "ceiling" in part.tags:
            kind = "ceiling"
        else:
            kind = "furniture"
        return point, kind, part.name, "" if surface is None else surface.name


class TraceRecorder:
    """Collects the rows of every episode :func:`egosearch.runs.evaluate.run_episode` runs with it."""

    def __init__(self):
        self.columns: dict[str, list] = {name: [] for name in TRACE_COLUMNS}
        self.meta: dict = {}
        self._probes: dict[str, HomeProbe] = {}

    def start(self, env, scenario, info: dict, learns: str = "steps") -> None:
        """``learns``: what the policy decides, "steps" (every body step) or "decisions" (a modular searcher:
        where to explore and the head's sweep, its body steps the frontier searcher's)."""
        base = env.unwrapped
        if scenario.layout not in self._probes:
            self._probes[scenario.layout] = HomeProbe(scenario.layout)
        self._probe = self._probes[scenario.layout]
        self._probe.set_target(base.target)
        self._grid = navgrid_for(scenario.layout)
        self._field = self._grid.distances_to(shortest_path_region(scenario.layout, base.target, base.base_height),
                                              reachable=True)
        self._scenario_id, self._layout = scenario.scenario_id, scenario.layout
        self.meta.update(env_id=env.spec.id if env.spec is not None else "", head=bool(base.spec_agent.head),
                         step_seconds=_step_seconds(), max_depth=float(base.sensor.max_depth), learns=learns)
        self._add(base, None, info, collided=False)

    def step(self, env, action, info: dict) -> None:
        self._add(env.unwrapped, action, info, collided=bool(info.get("collided", False)))

    def _add(self, base, action, info: dict, collided: bool) -> None:
        s, target, probe = base.state, base.target, self._probe
        point, kind, part, surface = probe.gaze(s.camera_position, camera_axes(s.camera_yaw, s.pitch)[2],
                                                base.sensor.max_depth)
        acts = np.full(len(ACTION_COLUMNS), np.nan, np.float32)
        if action is not None:
            a = np.asarray(action, np.float32).ravel()
            acts[:len(a)] = a
        row = {"scenario_id": self._scenario_id, "step": info["steps"], "collisions": info["collisions"],
               "x": s.x, "y": s.y, "theta": s.theta, "pitch": s.pitch, "head_yaw": s.head_yaw,
               "camera_height": s.camera_height, **dict(zip(ACTION_COLUMNS, acts)), "distance": info["distance"],
               "geodesic": self._grid.lower_bound_length(self._field, s.x, s.y), "gaze_x": point[0],
               "gaze_y": point[1], "gaze_z": point[2], "opening_distance": probe.opening_distance(s.x, s.y),
               "target_x": target.center[0], "target_y": target.center[1], "target_z": target.center[2],
               "visible": info["visible"], "success": info["success"], "collided": collided, "gaze_kind": kind,
               "gaze_part": part, "gaze_surface": surface, "room": probe.room(s.x, s.y), "layout": self._layout}
        for name, value in row.items():
            self.columns[name].append(value)

    def arrays(self) -> dict[str, np.ndarray]:
        out = {}
        for name in INT_COLUMNS:
            out[name] = np.asarray(self.columns[name], np.int32)
        for name in FLOAT_COLUMNS:
            # float32 keeps a 200-episode file near 1 MB; the actions are float32 already
            out[name] = np.asarray(self.columns[name], np.float32)
        for name in BOOL_COLUMNS:
            out[name] = np.asarray(self.columns[name], bool)
        for name in STR_COLUMNS:
            out[name] = np.asarray(self.columns[name], dtype=str)
        return out

    def write(self, path: str | os.PathLike) -> Path:
        """The trace file, written to a temporary name and renamed into place."""
        path = Path(path)
        if path.suffix != ".npz":
            raise ValueError(f"{path}: a trace file must end in .npz")
        path.parent.mkdir(parents=True, exist_ok=True)
        facts = {name: np.asarray(value) for name, value in {**self.meta, "format": TRACE_FORMAT}.items()}
        tmp = path.with_name(path.name + ".tmp.npz")
        np.savez_compressed(tmp, **self.arrays(), **facts)
        os.replace(tmp, path)
        return path


def _step_seconds() -> float:
    return STEP_SECONDS

"""Evaluation scenarios as plain data: generation, CSV round-trip, validation.

A scenario fixes everything an episode depends on (home, start pose, target object and pose,
camera height, placement scheme), so that every policy is evaluated on the same 100 (paper
6.1). It also stores ℓ, the geodesic length from the start to the nearest body position that
satisfies success (within :data:`SUCCESS_DISTANCE` of the target *and* seeing it at this
camera height). ℓ counts every position where the env may leave the body, in contact with
furniture too, so that it is a lower bound on the path of every success, up to
:data:`egosearch.sim.navgrid.LOWER_BOUND_SLACK`. A scenario is kept only when the privileged oracle's
route, through surely free cells, reaches a success within :data:`MAX_SHORTEST_PATH`.
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import asdict, dataclass, fields, replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from egosearch.core.csvio import write_csv_atomic
from egosearch.scene import layouts as layouts_mod
from egosearch.scene.meshes import scene_meshes
from egosearch.scene.objects import TARGET_OBJECTS, get_object, target_part
from egosearch.scene.parts import Part, Scene
from egosearch.scene.placement import PLACEMENT_SCHEMES, sample_target
from egosearch.sim.body import AgentSpec, check_height
from egosearch.sim.navgrid import DEFAULT_RESOLUTION as NAVGRID_RESOLUTION
from egosearch.sim.navgrid import NavGrid

SUCCESS_DISTANCE = 0.5
"""Paper 4.1: success when the target is within 0.5 m and seen. We measure it horizontally from
the body's surface (the cylinder) to the target's centre: from the camera (on the body axis) a
target at the back of a table would be out of reach of any body that stands at the table."""

MAX_STEPS = 100
"""T_max of paper 4.1."""

MAX_SHORTEST_PATH = 0.6 * MAX_STEPS * AgentSpec().max_forward
"""Longest accepted route of the oracle (m): 60% of what a body walking straight at full speed
covers in T_max steps, leaving time to turn and look. Longer scenarios are rejected at generation."""


@dataclass(frozen=True)
class Scenario:
    """One evaluation episode, fully determined."""

    scenario_id: int
    layout: str
    placement: str
    height: float
    start_x: float
    start_y: float
    start_theta: float
    target_object: str
    target_x: float
    target_y: float
    target_z: float
    """Height of the target's bottom, i.e. of the surface it rests on (m)."""
    target_yaw: float
    shortest_path: float
    """ℓ of SPL (m): a lower bound on the path of any success (see :func:`shortest_path_length`)."""

    def target(self) -> Part:
        return target_part(get_object(self.target_object), self.target_x, self.target_y,
                           self.target_z, self.target_yaw)


COLUMNS = tuple(f.name for f in fields(Scenario))
_TYPES = {f.name: (int if f.type in ("int", int) else str if f.type in ("str", str) else float)
          for f in fields(Scenario)}


class ScenarioFileError(ValueError):
    """A scenario CSV that cannot be used: the message names the file, row and field."""


def check_placement(placement: str) -> str:
    if placement not in PLACEMENT_SCHEMES:
        raise ValueError(f"placement={placement!r} is unknown; allowed: {', '.join(PLACEMENT_SCHEMES)}")
    return placement


def write_scenarios(path: str | os.PathLike, scenarios: list[Scenario]) -> None:
    """Write atomically: a reader never sees half a file. Floats keep every digit (repr)."""
    write_csv_atomic(path, COLUMNS, ({k: (repr(v) if isinstance(v, float) else v) for k, v in asdict(sc).items()}
                                     for sc in scenarios))


def read_scenarios(path: str | os.PathLike) -> list[Scenario]:
    """Read and validate a scenario CSV; any defect is one line naming the row and field."""
    path = Path(path)
    if not path.exists():
        raise ScenarioFileError(f"{path}: no such scenario file")
    try:
        return _read_scenarios(path)
    except UnicodeDecodeError as err:
        raise ScenarioFileError(f"{path}: not a text CSV file (byte 0x{err.object[err.start]:02x} is not UTF-8 "
                                "text); a scenario file is written by `egosearch scenarios`") from None


def other_separator(header: list[str]) -> str | None:
    """The separator a CSV's header line was written with when it is not ',' (';', a tab, '|'): the expected
    columns found in a header read as one column; None otherwise."""
    if len(header) != 1:
        return None
    for separator in (";", "\t", "|"):
        if sum(name.strip() in COLUMNS for name in header[0].split(separator)) >= 2:
            return separator
    return None


def _read_scenarios(path: Path) -> list[Scenario]:
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        header = reader.fieldnames or []
        if not header:
            raise ScenarioFileError(f"{path}: empty file; a scenario CSV starts with the header line "
                                    f"{','.join(COLUMNS)}")
        missing = [c for c in COLUMNS if c not in header]
        separator = other_separator(header)
        if missing and separator:
            # a spreadsheet's export: the header is one column, and "missing" would list them all
            raise ScenarioFileError(f"{path} is separated by {separator!r}, not ','; a scenario CSV is comma-"
                                    "separated, as `egosearch scenarios` writes it")
        if missing:
            raise ScenarioFileError(f"{path}: missing columns {', '.join(missing)}; "
                                    f"expected {', '.join(COLUMNS)}")
        out = []
        first_line: dict[int, int] = {}
        for line, row in enumerate(reader, start=2):
            values = {}
            for name in COLUMNS:
                raw = (row.get(name) or "").strip()
                try:
                    value = _TYPES[name](raw)
                except ValueError:
                    raise ScenarioFileError(f"{path}:{line}: {name}={raw!r} is not a valid "
                                            f"{_TYPES[name].__name__}") from None
                if isinstance(value, float) and not math.isfinite(value):
                    raise ScenarioFileError(f"{path}:{line}: {name}={raw!r} is not finite")
                values[name] = value
            try:
                scene = layouts_mod.get_scene(values["layout"])
                check_placement(values["placement"])
                check_height(values["height"])
                get_object(values["target_object"])
                _check_in_home(values, scene)
            except ValueError as err:
                raise ScenarioFileError(f"{path}:{line}: {err}") from None
            # ℓ < 0 would give a failure SPL 0 and a success SPL 1 whatever the path; ℓ = 0 is a start
            # that may already see the target
            if values["shortest_path"] < 0:
                raise ScenarioFileError(f"{path}:{line}: shortest_path={values['shortest_path']!r} is negative; "
                                        "it is the length (m) of the shortest route to a success, >= 0")
            floor = _straight_line_bound(values)
            if values["shortest_path"] < floor:
                # an edited ℓ scores every success of the row against a route no body can walk
                raise ScenarioFileError(f"{path}:{line}: shortest_path={values['shortest_path']!r} is shorter than "
                                        f"the straight line from the start to where the target is within reach "
                                        f"({floor:.2f} m); ℓ is >= that")
            if values["scenario_id"] in first_line:
                raise ScenarioFileError(f"{path}:{line}: scenario_id={values['scenario_id']} repeats the id of line "
                                        f"{first_line[values['scenario_id']]}; every scenario of a file needs its "
                                        "own id (episodes are seeded and joined by it)")
            first_line[values["scenario_id"]] = line
            out.append(Scenario(**values))
    if not out:
        raise ScenarioFileError(f"{path}: holds no scenarios")
    return out


def _check_in_home(values: dict, scene: Scene) -> None:
    """The start and the target lie within the home's bounds: outside, an episode would still run
    and score a failure, or ℓ and the path length would mean nothing."""
    x0, y0, x1, y1 = scene.bounds
    for what in ("start", "target"):
        x, y = values[f"{what}_x"], values[f"{what}_y"]
        if not (x0 <= x <= x1 and y0 <= y <= y1):
            raise ValueError(f"{what} ({x:g}, {y:g}) is outside the home {values['layout']}, whose floor spans "
                             f"x in [{x0:g}, {x1:g}], y in [{y0:g}, {y1:g}] m")
    if not 0 <= values["target_z"] <= scene.wall_height:
        raise ValueError(f"target_z={values['target_z']:g} is outside the home {values['layout']}, whose height "
                         f"range is [0, {scene.wall_height:g}] m (target_z: the height of the surface it rests on)")


def _straight_line_bound(values: dict) -> float:
    """The shortest ℓ a row may hold: the straight line from the start to the target, less the reach
    of a success (:data:`SUCCESS_DISTANCE` from the body's surface) and the grid's two half cells
    (ℓ is measured from the start's cell to cells within reach: see :func:`shortest_path_region`)."""
    reach = SUCCESS_DISTANCE + AgentSpec().body_radius + NAVGRID_RESOLUTION * math.sqrt(2)
    straight = math.hypot(values["target_x"] - values["start_x"], values["target_y"] - values["start_y"])
    return max(0.0, straight - reach)


# -- generation ----------------------------------------------------------------------------

@lru_cache(maxsize=8)
def navgrid_for(layout: str) -> NavGrid:
    return NavGrid(layouts_mod.get_scene(layout), AgentSpec())


@lru_cache(maxsize=8)
def _ray_mesh(layout: str):
    """The home as one ray-castable mesh (ceiling excluded: it never blocks a look down)."""
    import trimesh

    scene = layouts_mod.get_scene(layout)
    meshes = [m for part, m in scene_meshes(scene) if "ceiling" not in part.tags]
    return trimesh.ray.ray_pyembree.RayMeshIntersector(trimesh.util.concatenate(meshes))


def target_probe_points(target: Part) -> np.ndarray:
    """Points on and in the target a camera must see at least one of: centre, top centre and
    the corners of its box shrunk towards the centre."""
    cx, cy, cz = target.center
    hx, hy, hz = (0.35 * s for s in target.size)
    c, s = math.cos(target.yaw), math.sin(target.yaw)
    pts = [(cx, cy, cz), (cx, cy, cz + 0.45 * target.size[2])]
    for sx in (-1, 1):
        for sy in (-1, 1):
            for sz in (-1, 1):
                lx, ly = sx * hx, sy * hy
                pts.append((cx + c * lx - s * ly, cy + s * lx + c * ly, cz + sz * hz))
    return np.asarray(pts)


def target_surface_points(target: Part, per_edge: int = 5) -> np.ndarray:
    """Points of a lattice over the whole surface of the target's box (``per_edge`` per edge: 98 for
    5). The env's sensor may see any sliver of the target, a thin object's edge included, which the
    inner probes of :func:`target_probe_points` can all miss; ℓ must count such poses."""
    cx, cy, cz = target.center
    c, s = math.cos(target.yaw), math.sin(target.yaw)
    grid = np.linspace(-0.5, 0.5, per_edge)
    lx, ly, lz = (a.ravel() for a in np.meshgrid(grid, grid, grid, indexing="ij"))
    on_surface = (np.abs(lx) == 0.5) | (np.abs(ly) == 0.5) | (np.abs(lz) == 0.5)
    lx, ly, lz = (a[on_surface] * size for a, size in zip((lx, ly, lz), target.size))
    return np.column_stack([cx + c * lx - s * ly, cy + s * lx + c * ly, cz + lz])


#: A pose sees the target when this many probe points are in plain sight: one alone can be a
#: sliver that the camera's pixels miss.
MIN_VISIBLE_PROBES = 2


def visible_from(layout: str, cameras: np.ndarray, target: Part, min_probes: int = MIN_VISIBLE_PROBES,
                 points: np.ndarray | None = None) -> np.ndarray:
    """For each camera position (N x 3), whether straight lines reach at least ``min_probes`` of the
    target's ``points`` (default: :func:`target_probe_points`) unblocked by the home."""
    points = target_probe_points(target) if points is None else np.asarray(points, dtype=float)
    origins = np.repeat(cameras, len(points), axis=0)
    ends = np.tile(points, (len(cameras), 1))
    vec = ends - origins
    dist = np.linalg.norm(vec, axis=1)
    dirs = vec / dist[:, None]
    locs, index_ray, _ = _ray_mesh(layout).intersects_location(origins, dirs, multiple_hits=False)
    hit = np.full(len(origins), np.inf)
    hit[index_ray] = np.linalg.norm(locs - origins[index_ray], axis=1)
    clear = hit >= dist - 1e-3
    return clear.reshape(len(cameras), len(points)).sum(axis=1) >= min_probes


def success_region(layout: str, target: Part, height: float, distance: float = SUCCESS_DISTANCE) -> np.ndarray:
    """Grid cells where the body is within ``distance`` of the target and its camera sees it."""
    grid = navgrid_for(layout)
    near = grid.success_region(target.center[:2], distance) & grid.main_region
    rows, cols = np.nonzero(near)
    if len(rows) == 0:
        return near
    cams = np.column_stack([grid.xs[cols], grid.ys[rows], np.full(len(rows), height)])
    seen = visible_from(layout, cams, target)
    region = np.zeros_like(near)
    region[rows[seen], cols[seen]] = True
    return region


def shortest_path_region(layout: str, target: Part, height: float, distance: float = SUCCESS_DISTANCE) -> np.ndarray:
    """Grid cells holding at least one pose where the env might declare success: reachable by
    the body (in contact with furniture too), some point of the cell within ``distance``, and
    any point of the target's surface in sight (:func:`target_surface_points`). Wider than
    :func:`success_region` on purpose: ℓ measured to it must not exceed the path of any success."""
    grid = navgrid_for(layout)
    near = grid.touch_region(target.center[:2], distance)
    rows, cols = np.nonzero(near)
    if len(rows) == 0:
        return near
    cams = np.column_stack([grid.xs[cols], grid.ys[rows], np.full(len(rows), height)])
    seen = visible_from(layout, cams, target, min_probes=1, points=target_surface_points(target))
    region = np.zeros_like(near)
    region[rows[seen], cols[seen]] = True
    return region


def shortest_path_length(layout: str, target: Part, height: float, x: float, y: float) -> float:
    """ℓ of SPL from a start at (x, y): a lower bound on the path of every success, up to
    :data:`egosearch.sim.navgrid.LOWER_BOUND_SLACK`."""
    grid = navgrid_for(layout)
    return grid.lower_bound_length(grid.distances_to(shortest_path_region(layout, target, height), reachable=True),
                                   x, y)


def _sample_start(grid: NavGrid, rng: np.random.Generator) -> tuple[float, float, float]:
    rows, cols = np.nonzero(grid.main_region)
    i = int(rng.integers(len(rows)))
    jitter = rng.uniform(-0.5, 0.5, 2) * grid.resolution * 0.5
    x, y = grid.center(rows[i], cols[i])
    return float(x + jitter[0]), float(y + jitter[1]), float(rng.uniform(-math.pi, math.pi))


def generate_scenarios(layout: str, placement: str, height: float, n: int, seed: int,
                       objects: tuple[str, ...] | None = None, progress: bool = False,
                       ) -> list[Scenario]:
    """``n`` solvable scenarios, the same for the same arguments on any machine."""
    scene: Scene = layouts_mod.get_scene(layout)
    check_placement(placement)
    height = check_height(height)
    names = tuple(objects) if objects else tuple(sorted(TARGET_OBJECTS))
    for name in names:
        get_object(name)
    grid = navgrid_for(layout)
    rng = np.random.default_rng([seed, n])
    out: list[Scenario] = []
    rejected = 0
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=n, desc=f"scenarios {layout}/{placement}/{height:g}m", unit="scn")
    while len(out) < n:
        if rejected > 50 * n + 100:
            raise RuntimeError(f"{layout}/{placement}/{height} m: too many unsolvable scenarios "
                               f"({rejected} rejected for {len(out)} kept)")
        obj = get_object(names[int(rng.integers(len(names)))])
        target = sample_target(scene, obj, placement, rng)
        region = success_region(layout, target, height)
        start = _sample_start(grid, rng)
        if not region.any():
            rejected += 1
            continue
        # Solvable: the privileged oracle's route, through surely free cells, is short enough.
        route = grid.path_length(grid.distances_to(region), start[0], start[1])
        if not math.isfinite(route) or route > MAX_SHORTEST_PATH:
            rejected += 1
            continue
        start = tuple(round(v, 4) for v in start)
        scenario = Scenario(
            scenario_id=len(out), layout=layout, placement=placement, height=height,
            start_x=start[0], start_y=start[1], start_theta=start[2],
            target_object=obj.name, target_x=round(target.center[0], 4),
            target_y=round(target.center[1], 4), target_z=round(target.z_min, 5),
            target_yaw=round(target.yaw, 4), shortest_path=0.0)
        # ℓ of the target as the record rebuilds it (rounded pose), which is what the env evaluates:
        # the unrounded one can differ by a grid cell at a region's edge.
        ell = shortest_path_length(layout, scenario.target(), height, start[0], start[1])
        out.append(replace(scenario, shortest_path=round(ell, 4)))
        if bar is not None:
            bar.update(1)
    if bar is not None:
        bar.close()
    return out

"""ℓ, the shortest path behind SPL, is a lower bound on the path of every success the env can produce.

The bound is stated in :data:`egosearch.sim.navgrid.LOWER_BOUND_SLACK` and checked by
:func:`egosearch.sim.navgrid.lower_bound_holds`. It is checked here on hand-built scenes, on the stored
evaluations, and by driving the env on the stored scenario sets with four searchers: the oracle,
random actions, a beeline that walks straight at the target into whatever is in the way, and a
follower of ℓ's own grid that walks into contact with furniture when that is shorter. The default run
takes the two shortest scenarios of each stored set; ``-m slow`` adds every 5th scenario of Table 1's sets,
and ``-m exhaustive`` every scenario of them (the stored ℓ are recomputed the same way: the first three of
each set, every 5th, every one).
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest

import egosearch.sim.scenarios as scenarios_mod
from egosearch.scene import layouts
from egosearch.scene.objects import get_object, target_part
from egosearch.scene.parts import TAG_OBSTACLE, TAG_TARGET, TAG_WALL, Part, Scene
from egosearch.searchers.policies import OraclePolicy, RandomPolicy
from egosearch.sim.body import AgentSpec, wrap_angle
from egosearch.sim.env import SearchEnv
from egosearch.sim.navgrid import LOWER_BOUND_SLACK, MAX_PENETRATION, NavGrid, lower_bound_holds
from egosearch.sim.scenarios import (
    SUCCESS_DISTANCE,
    navgrid_for,
    read_scenarios,
    shortest_path_length,
    shortest_path_region,
    success_region,
    visible_from,
)
from egosearch.sim.world import PENETRATION_TOLERANCE

ROOT = Path(__file__).resolve().parents[1]
STORED_SETS = sorted(ROOT.glob("results/*/scenarios/*/*/h*.csv"))
WALL = frozenset({TAG_OBSTACLE, TAG_WALL})
R = AgentSpec().body_radius


def test_the_stated_slack():
    assert LOWER_BOUND_SLACK == {"relative": 0.03, "additive": 0.08}
    assert lower_bound_holds(2.08 + 0.03 * 2.0, 2.0)
    assert not lower_bound_holds(2.09 + 0.03 * 2.0, 2.0)
    # The env's own rule on how deep a body may end a step must sit inside what ℓ allows for.
    assert PENETRATION_TOLERANCE <= MAX_PENETRATION


# --------------------------------------------------------------------------------------------- hand-built scenes
def diner(gap: float = 0.42) -> Scene:
    """A 6 x 4 m room; a 1.2 x 0.8 m table at the west end; a partition at x = 1 from wall to wall
    but for one gap of ``gap`` m centred on y = 0."""
    half = (4.0 - gap) / 2
    parts = [
        Part("north", "box", (0, 2.05, 1.3), (6.2, 0.1, 2.6), tags=WALL),
        Part("south", "box", (0, -2.05, 1.3), (6.2, 0.1, 2.6), tags=WALL),
        Part("east", "box", (3.05, 0, 1.3), (0.1, 4.0, 2.6), tags=WALL),
        Part("west", "box", (-3.05, 0, 1.3), (0.1, 4.0, 2.6), tags=WALL),
        Part("part_n", "box", (1.0, 2.0 - half / 2, 1.3), (0.1, half, 2.6), tags=WALL),
        Part("part_s", "box", (1.0, -2.0 + half / 2, 1.3), (0.1, half, 2.6), tags=WALL),
        Part("table", "box", (-1.5, 0.0, 0.375), (1.2, 0.8, 0.75), tags={TAG_OBSTACLE}),
    ]
    return Scene("diner", tuple(parts), (), (-3.0, -2.0, 3.0, 2.0))


def test_free_cells_are_reachable_and_contact_cells_too():
    grid = NavGrid(diner(), AgentSpec())
    assert not (grid.free & ~grid.reachable).any()
    # Bodies touching the table's east edge (x = -0.9) or pressed MAX_PENETRATION into it: their
    # cells are reachable.
    for depth in (0.0, MAX_PENETRATION):
        for y in np.linspace(-0.4, 0.4, 9):
            assert grid.reachable[grid.cell(-0.9 + R - depth, y)], (depth, y)
    # No surely-free cell holds a body 5 mm from contact (its centre at -0.725 clears by 0.175 m).
    assert not grid.free[grid.cell(-0.9 + R + 0.005, 0.0)]
    # The cell spanning x in [-0.80, -0.75] has no point where the body is less than 4 cm inside.
    assert not grid.reachable[grid.cell(-0.9 + R - 0.06, 0.0)]


def test_a_gap_the_body_fits_through_is_open_to_ell_and_a_narrower_one_is_not():
    spec = AgentSpec()
    wide = NavGrid(diner(gap=2 * R + 0.02), spec)
    goal = np.zeros(wide.shape, bool)
    goal[wide.cell(2.5, 0.0)] = True
    through = wide.lower_bound_length(wide.distances_to(goal, reachable=True), -0.5, 0.0)
    assert through == pytest.approx(3.0, abs=0.03 * 3.0 + wide.resolution)
    # The surely-free cells keep a margin of up to a cell diagonal: they close this gap.
    assert not np.isfinite(wide.distances_to(goal)[wide.cell(-0.5, 0.0)])
    narrow = NavGrid(diner(gap=2 * (R - MAX_PENETRATION) - 0.03), spec)
    assert not np.isfinite(narrow.distances_to(goal, reachable=True)[narrow.cell(-0.5, 0.0)])


@pytest.fixture()
def diner_layout(monkeypatch):
    """``layout="diner"`` names :func:`diner` for every layout-keyed helper (scenarios, env)."""
    real = layouts.get_scene
    monkeypatch.setattr(layouts, "get_scene", lambda name: diner() if name == "diner" else real(name))
    scenarios_mod.navgrid_for.cache_clear()
    scenarios_mod._ray_mesh.cache_clear()
    yield "diner"
    scenarios_mod.navgrid_for.cache_clear()
    scenarios_mod._ray_mesh.cache_clear()


def test_visible_from_on_a_hand_built_scene(diner_layout):
    # A 10 cm cube on the table; the partition (2.6 m high) hides it from the east but for the gap.
    cube = Part("target", "box", (-1.2, 0.0, 0.8), (0.1, 0.1, 0.1), tags={TAG_TARGET})
    cams = np.array([
        [-0.5, 0.0, 1.6],   # west of the partition, above the table: sees it
        [-0.5, 0.0, 0.5],   # same place, below the table top: the table's edge hides it
        [2.5, 1.5, 1.6],    # east of the partition: the straight line crosses part_n at y = 0.89
        [2.5, 0.0, 0.8],    # east, in line with the gap, at the cube's height: sees it through
    ])
    assert visible_from(diner_layout, cams, cube).tolist() == [True, False, False, True]
    # Through the 0.42 m gap all 10 probe points of the 0.1 m cube are in sight.
    assert visible_from(diner_layout, cams[3:], cube, min_probes=10).tolist() == [True]
    assert visible_from(diner_layout, cams[1:3], cube, min_probes=1).tolist() == [False, False]


def test_success_region_on_a_hand_built_scene(diner_layout):
    target = target_part(get_object("keys"), -1.0, 0.0, 0.75)
    grid = navgrid_for(diner_layout)
    region = success_region(diner_layout, target, 1.6)
    rows, cols = np.nonzero(region)
    assert len(rows) > 0
    reach = SUCCESS_DISTANCE + R
    for r, c in zip(rows, cols):
        x, y = grid.center(r, c)
        assert math.hypot(x - target.center[0], y - target.center[1]) <= reach + 1e-9
        assert grid.free[r, c] and x < 1.0  # never east of the partition
    # A surely-free cell 0.6 m east of the keys, in plain sight: in.
    assert region[grid.cell(-0.4, 0.0)]
    # A cell whose centre is 0.025 m or more beyond the body-surface distance: out.
    assert not region[grid.cell(-1.0 + reach + 0.05, 0.0)]
    # Touching the table beside the keys (not a surely-free cell): out of success_region, in the
    # region that ℓ is measured to.
    touch = (-0.9 + R - 0.005, 0.0)
    assert not region[grid.cell(*touch)]
    assert shortest_path_region(diner_layout, target, 1.6)[grid.cell(*touch)]


def test_ell_bounds_a_success_in_contact_with_the_table(diner_layout):
    """The issue's case, in the env: keys 0.48 m beyond the table's east edge, so that from the east
    only a body touching the edge is within 0.5 m. From 10 cm east of contact one step succeeds;
    ℓ measured to surely-free cells was the way round the table's corner."""
    from dataclasses import replace

    from egosearch.sim.scenarios import Scenario

    keys = (-0.9 - 0.48, 0.0)
    sc = Scenario(scenario_id=0, layout=diner_layout, placement="everywhere", height=1.6, start_x=-0.9 + R + 0.1,
                  start_y=0.0, start_theta=math.pi, target_object="keys", target_x=keys[0], target_y=keys[1],
                  target_z=0.75, target_yaw=0.0, shortest_path=0.0)
    grid = navgrid_for(diner_layout)
    ell = shortest_path_length(diner_layout, sc.target(), sc.height, sc.start_x, sc.start_y)
    old = grid.path_length(grid.distances_to(success_region(diner_layout, sc.target(), sc.height)),
                           sc.start_x, sc.start_y)
    env = SearchEnv(diner_layout, "everywhere", head=True, height=sc.height)
    try:
        env.reset(seed=0, options={"scenario": replace(sc, shortest_path=ell)})
        s = env.state.copy()
        s.pitch = math.atan2(0.76 - sc.height, 0.58)  # at the keys from where the body will stop
        env.set_agent_state(s)
        _, _, terminated, _, info = env.step(np.array([0.6, 0, 0, 0, 0], np.float32))  # 0.15 m asked, 0.1 m free
    finally:
        env.close()
    assert terminated and info["success"] and info["collided"]
    p = info["path_length"]
    assert p == pytest.approx(0.1, abs=0.01)
    assert lower_bound_holds(ell, p)
    assert not lower_bound_holds(old, p) and old > 0.5


# --------------------------------------------------------------------------------------------- searchers
class Beeline:
    """Walks straight at the target (turning first) and looks at it, whatever is in the way."""

    def __init__(self, env):
        self.env = env.unwrapped

    def reset(self, seed=None):
        pass

    def act(self, obs):
        env = self.env
        s, spec, t = env.state, env.spec_agent, env.target
        heading = math.atan2(t.center[1] - s.y, t.center[0] - s.x)
        turn = wrap_angle(heading - s.theta)
        action = [1.0 if abs(turn) < 0.5 else 0.0, 0.0, float(np.clip(turn / spec.max_turn, -1, 1))]
        horizontal = math.hypot(t.center[0] - s.x, t.center[1] - s.y)
        pitch = math.atan2(t.center[2] - s.camera_height, horizontal)
        action += [float(np.clip((pitch - s.pitch) / spec.max_pitch_rate, -1, 1)),
                   float(np.clip(-s.head_yaw / spec.max_yaw_rate, -1, 1))]
        return np.asarray(action, np.float32)


class Follower(OraclePolicy):
    """The oracle on ℓ's own grid and goal region: it walks into contact when that is shorter."""

    def _plan(self):
        env = self.env
        self.grid = navgrid_for(env.layout)
        self.dist = self.grid.distances_to(shortest_path_region(env.layout, env.target, env.base_height),
                                           reachable=True)
        self._cells_xy = np.meshgrid(self.grid.xs, self.grid.ys)

    def _line_free(self, x0, y0, x1, y1):
        n = max(2, int(math.hypot(x1 - x0, y1 - y0) / (self.grid.resolution / 2)) + 1)
        return all(self.grid.reachable[self.grid.cell(x0 + t * (x1 - x0), y0 + t * (y1 - y0))]
                   for t in np.linspace(0, 1, n))


SEARCHERS = {"oracle": OraclePolicy, "random": lambda env: RandomPolicy(5, seed=0), "beeline": Beeline,
             "follower": Follower}


def _check_sets(pick, sets=None) -> dict[str, int]:
    """Run every searcher on ``pick(scenarios, index of the set)`` of each stored set; every success must
    respect ℓ."""
    sets = STORED_SETS if sets is None else sets
    assert sets, "no stored scenario sets under results/*/scenarios"
    successes = dict.fromkeys(SEARCHERS, 0)
    broken = []
    for index, path in enumerate(sets):
        chosen = pick(read_scenarios(path), index)
        env = SearchEnv(chosen[0].layout, chosen[0].placement, head=True, height=chosen[0].height)
        try:
            for sc in chosen:
                if sc.layout != env.layout:     # a generalisation group's set: one scenario per home in turn
                    env.close()
                    env = SearchEnv(sc.layout, sc.placement, head=True, height=sc.height)
                for name, make in SEARCHERS.items():
                    policy = make(env)
                    obs, _ = env.reset(seed=sc.scenario_id, options={"scenario": sc})
                    policy.reset(seed=sc.scenario_id)
                    done = False
                    while not done:
                        obs, _, terminated, truncated, info = env.step(policy.act(obs))
                        done = terminated or truncated
                    if info["success"]:
                        successes[name] += 1
                        if not lower_bound_holds(sc.shortest_path, info["path_length"]):
                            broken.append((path.name, sc.scenario_id, name, sc.shortest_path, info["path_length"]))
        finally:
            env.close()
    assert not broken, broken
    return successes


def test_ell_bounds_every_success_on_the_shortest_stored_scenarios():
    successes = _check_sets(lambda scs, _: sorted(scs, key=lambda s: s.shortest_path)[:2])
    # Each searcher must have produced successes for the check to mean anything.
    assert all(successes.values()), successes


TABLE1_SETS = [p for p in STORED_SETS if p.parts[-3] in ("kitchen_living", "bedroom_bath")]
# The slow spread checks (CI's) take every 5th scenario of each set, starting at a different place in each set
SPREAD_STEP = 5


def _spread(scenarios: list, set_index: int) -> list:
    return scenarios[set_index % SPREAD_STEP::SPREAD_STEP]


def test_the_spread_covers_every_scenario_of_a_set_once_over_its_five_offsets():
    ids = list(range(23))
    picked = [i for offset in range(SPREAD_STEP) for i in _spread(ids, offset)]
    assert sorted(picked) == ids
    assert _spread(ids, 2) == [2, 7, 12, 17, 22] and _spread(ids, 7) == _spread(ids, 2)


@pytest.mark.slow
def test_ell_bounds_every_success_on_a_spread_of_the_stored_scenarios():
    # A fifth of Table 1's sets; the generalisation groups' sets (800 more scenarios over 40 homes) are
    # checked on their shortest scenarios by the test above
    successes = _check_sets(_spread, TABLE1_SETS)
    assert successes["oracle"] >= 0.9 * sum(len(_spread(read_scenarios(p), i)) for i, p in enumerate(TABLE1_SETS))
    assert all(successes.values()), successes


@pytest.mark.slow
@pytest.mark.exhaustive
def test_ell_bounds_every_success_on_every_stored_scenario():
    # Table 1's sets whole (about 10 CPU-minutes): run it when the scenario sets, ℓ or the body change
    successes = _check_sets(lambda scs, _: scs, TABLE1_SETS)
    assert successes["oracle"] >= 0.9 * sum(len(read_scenarios(p)) for p in TABLE1_SETS), successes
    assert all(successes.values()), successes


# --------------------------------------------------------------------------------------------- stored files
def _stored_ell_matches(pick) -> None:
    for index, path in enumerate(STORED_SETS):
        for sc in pick(read_scenarios(path), index):
            ell = shortest_path_length(sc.layout, sc.target(), sc.height, sc.start_x, sc.start_y)
            assert sc.shortest_path == pytest.approx(round(ell, 4), abs=1e-9), (path, sc.scenario_id)


def test_stored_ell_is_what_the_code_computes_now():
    _stored_ell_matches(lambda scs, _: scs[:3])


@pytest.mark.slow
def test_a_spread_of_the_stored_ell_is_what_the_code_computes_now():
    _stored_ell_matches(_spread)


@pytest.mark.slow
@pytest.mark.exhaustive
def test_every_stored_ell_is_what_the_code_computes_now():
    _stored_ell_matches(lambda scs, _: scs)


# Stored scenarios whose ℓ a stored success undercuts, with what was found; a defect of ℓ to mend
# when the scenario sets are next regenerated. Listed so that any other violation still fails.
KNOWN_ELL_VIOLATIONS: dict[tuple[str, int], str] = {}


def test_ell_region_sees_a_thin_object_edge_that_the_inner_probes_miss():
    # A book (3 cm thick) on a 0.55 m surface in bedroom_bath, from a 0.45 m camera: the env's
    # sensor sees its near edge from close by, where no inner probe point is in sight. Stored
    # policies succeeded here after 1.3-1.9 m while ℓ over the inner probes was 2.50 m.
    book = target_part(get_object("book"), 7.4354, 2.3387, 0.55, 1.4841)
    grid = navgrid_for("bedroom_bath")
    rows, cols = np.nonzero(grid.touch_region(book.center[:2], SUCCESS_DISTANCE))
    cams = np.column_stack([grid.xs[cols], grid.ys[rows], np.full(len(rows), 0.45)])
    inner = visible_from("bedroom_bath", cams, book, min_probes=1)
    surface = visible_from("bedroom_bath", cams, book, min_probes=1,
                           points=scenarios_mod.target_surface_points(book))
    assert len(scenarios_mod.target_surface_points(book)) == 98
    assert not (inner & ~surface).any() and (surface & ~inner).sum() > 50
    assert shortest_path_length("bedroom_bath", book, 0.45, 5.531, 1.8198) < 1.3


def test_stored_evaluation_successes_respect_the_current_ell():
    """Every stored evaluation's success against ℓ of its scenario set as stored now (the rows
    themselves may carry an older ℓ)."""
    checked = 0
    violations = set()
    for path in sorted(ROOT.glob("results/*/eval/*/seed*/*/*/h*.csv")):
        preset, layout, placement, height = path.parts[-7], path.parts[-3], path.parts[-2], path.name
        ells = {sc.scenario_id: sc.shortest_path
                for sc in read_scenarios(ROOT / "results" / preset / "scenarios" / layout / placement / height)}
        with open(path, newline="") as f:
            for row in csv.DictReader(f):
                if int(row["success"]):
                    checked += 1
                    ell, p = ells[int(row["scenario_id"])], float(row["path_length"])
                    if not lower_bound_holds(ell, p):
                        violations.add((f"{preset}/scenarios/{layout}/{placement}/{height}", int(row["scenario_id"])))
    assert not violations - set(KNOWN_ELL_VIOLATIONS), sorted(violations - set(KNOWN_ELL_VIOLATIONS))
    stored = {k for k in KNOWN_ELL_VIOLATIONS if (ROOT / "results" / k[0]).exists()}
    assert stored <= violations, f"mended (remove from KNOWN_ELL_VIOLATIONS): {sorted(stored - violations)}"
    if not checked:
        pytest.skip("no stored evaluations")

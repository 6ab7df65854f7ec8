"""Physics invariants of the abstract body on a hand-built room (no layout needed)."""

import math

import numpy as np
import pytest

from egosearch.scene.geometry import deepest_penetration
from egosearch.scene.parts import TAG_OBSTACLE, TAG_WALL, Part, Scene
from egosearch.sim.body import AgentSpec
from egosearch.sim.navgrid import MAX_PENETRATION, NavGrid
from egosearch.sim.world import PENETRATION_TOLERANCE, SWEEP_TOLERANCE, World, random_free_pose

WALL = frozenset({TAG_OBSTACLE, TAG_WALL})


def room() -> Scene:
    """A 6 x 4 m room split by a wall with a 1 m doorway (y in [-0.5, 0.5]), plus a round table and a thin post."""
    parts = [
        Part("north", "box", (0, 2.05, 1.3), (6.2, 0.1, 2.6), tags=WALL),
        Part("south", "box", (0, -2.05, 1.3), (6.2, 0.1, 2.6), tags=WALL),
        Part("east", "box", (3.05, 0, 1.3), (0.1, 4.0, 2.6), tags=WALL),
        Part("west", "box", (-3.05, 0, 1.3), (0.1, 4.0, 2.6), tags=WALL),
        Part("split_a", "box", (0, 1.25, 1.3), (0.1, 1.5, 2.6), tags=WALL),
        Part("split_b", "box", (0, -1.25, 1.3), (0.1, 1.5, 2.6), tags=WALL),
        Part("table", "cylinder", (-1.5, -1.2, 0.375), (0.9, 0.9, 0.75), tags={TAG_OBSTACLE}),
        Part("post", "box", (1.5, -1.0, 0.5), (0.05, 0.05, 1.0), yaw=0.6, tags={TAG_OBSTACLE}),
    ]
    return Scene("room", tuple(parts), (), (-3.0, -2.0, 3.0, 2.0))


@pytest.fixture(scope="module")
def world():
    w = World(room(), AgentSpec())
    yield w
    w.close()


def test_free_motion_tracks_the_command(world):
    world.reset_agent(-2.0, 1.0, 0.0)
    pose, collided = world.move(0.2, 0.1, 0.3)
    assert not collided
    assert pose == pytest.approx((-1.8, 1.1, 0.3), abs=2e-3)
    # Body frame: a forward step after turning by 90 degrees goes along +y.
    world.reset_agent(-2.0, 1.0, math.pi / 2)
    pose, _ = world.move(0.2, 0.0, 0.0)
    assert pose[:2] == pytest.approx((-2.0, 1.2), abs=2e-3)


def test_wall_stops_the_body_and_counts(world):
    world.reset_agent(-0.5, -1.0, 0.0)  # facing the split wall at x = -0.05
    hits = 0
    for _ in range(5):
        pose, collided = world.move(0.25, 0.0, 0.0)
        hits += collided
    assert hits >= 3
    assert pose[0] <= -0.05 - 0.2 + PENETRATION_TOLERANCE
    assert world.penetration() <= PENETRATION_TOLERANCE


def test_a_move_into_a_panel_during_the_last_substep_is_backed_off():
    """Replayed from home65, where the body ended 5.7 cm inside the 2 cm side panel of a tv
    stand: no contact was reported on the way (contacts come from before each sub-step's
    integration), so the back-off never ran."""
    parts = (
        Part("south", "box", (7.0, -0.05, 1.3), (3.0, 0.1, 2.6), tags=WALL),
        Part("east", "box", (8.25, 1.0, 1.3), (0.1, 2.0, 2.6), tags=WALL),
        Part("panel", "box", (7.48, 0.225, 0.24), (0.02, 0.45, 0.48), tags={TAG_OBSTACLE}),
        Part("top", "box", (6.74, 0.225, 0.49), (1.5, 0.45, 0.02), tags={TAG_OBSTACLE}),
    )
    spec = AgentSpec()
    w = World(Scene("corner", parts, (), (5.5, 0.0, 8.2, 2.0)), spec)
    start = (7.571637218686341, 0.6337970227645554, -1.405864936803238)
    w.reset_agent(*start)
    pose, collided = w.move(0.19145529987870125, 0.02076291233053293, 0.06469050338721148)
    depth, _ = deepest_penetration(parts, pose[0], pose[1], spec.body_radius, spec.body_clearance,
                                   spec.body_clearance + spec.body_height)
    assert depth <= PENETRATION_TOLERANCE and w.penetration() <= PENETRATION_TOLERANCE
    assert collided  # it did hit the panel
    # Backed off along its own path: between the start and the pose the physics reached.
    assert start[1] - 0.2 <= pose[1] <= start[1] + 1e-9
    w.close()


def test_the_body_is_not_squeezed_through_a_gap_narrower_than_itself():
    """Replayed from kitchen_living, where a head-off policy passed between an armchair arm and a
    sofa arm whose corners are 33 cm apart: the 40 cm body went 4.5 cm deep at the pinch, ended
    the step outside both, and so reached the target by a way shorter than ℓ."""
    parts = (
        Part("armchair_arm", "box", (3.8, 1.735, 0.31), (0.65, 0.18, 0.62), tags={TAG_OBSTACLE}),
        Part("sofa_arm", "box", (4.39, 2.45, 0.31), (0.18, 0.7, 0.62), tags={TAG_OBSTACLE}),
    )
    spec = AgentSpec()
    w = World(Scene("pinch", parts, (), (3.0, 1.0, 5.5, 3.5)), spec)
    start, end = (4.091, 2.071), (4.323, 1.849)
    heading = math.atan2(end[1] - start[1], end[0] - start[0])
    w.reset_agent(*start, heading)
    pose, collided = w.move(math.dist(start, end), 0.0, 0.0)
    assert collided
    assert math.dist(pose[:2], start) < 0.1  # stopped before the pinch, not through it
    for x, y, _ in w.swept_poses:
        depth, _ = deepest_penetration(parts, x, y, spec.body_radius, spec.body_clearance,
                                       spec.body_clearance + spec.body_height)
        assert depth <= SWEEP_TOLERANCE
    # A gap wider than the body still lets it through.
    w.reset_agent(4.7, 1.2, 0.0)
    pose, collided = w.move(0.25, 0.0, 0.0)
    assert not collided and pose[0] == pytest.approx(4.95, abs=2e-3)
    w.close()


def test_the_body_never_goes_deeper_than_the_grid_of_ell_assumes():
    assert PENETRATION_TOLERANCE < SWEEP_TOLERANCE < MAX_PENETRATION


def test_random_actions_never_end_inside_anything(world):
    rng = np.random.default_rng(0)
    spec = world.spec
    scale = spec.action_scale()[:3]
    world.reset_agent(*random_free_pose(world, rng))
    worst = 0.0
    for step in range(1500):
        if step % 300 == 0:
            world.reset_agent(*random_free_pose(world, rng))
        world.move(*(rng.uniform(-1, 1, 3) * scale))
        worst = max(worst, world.penetration())
        x, y, _ = world.pose()
        assert -3.0 + spec.body_radius - 0.01 <= x <= 3.0 - spec.body_radius + 0.01
        assert -2.0 + spec.body_radius - 0.01 <= y <= 2.0 - spec.body_radius + 0.01
    assert worst <= PENETRATION_TOLERANCE


def test_navgrid_geodesic_goes_through_the_door():
    grid = NavGrid(room(), AgentSpec())
    goal = np.zeros(grid.shape, bool)
    goal[grid.cell(2.0, 1.0)] = True
    dist = grid.distances_to(goal)
    # From (-2, 1) the straight line is blocked by split_a, which ends at y = 0.5: the body's
    # centre must pass the doorway at y <= 0.3.
    detour = grid.path_length(dist, -2.0, 1.0)
    via_door = 2 * math.hypot(2.0, 0.7)
    assert detour > 4.0 + 0.3  # longer than the blocked straight line
    assert detour == pytest.approx(via_door, rel=0.06)
    # In open floor the 16-connected grid is within 3% of Euclid, plus a cell for the ends.
    goal2 = np.zeros(grid.shape, bool)
    goal2[grid.cell(2.5, 1.5)] = True
    d2 = grid.distances_to(goal2)
    straight = math.hypot(2.5 - 0.6, 1.5 - 0.7)
    assert grid.path_length(d2, 0.6, 0.7) == pytest.approx(straight, abs=0.03 * straight + grid.resolution)


def test_navgrid_free_cells_really_clear_the_body(world):
    grid = NavGrid(room(), AgentSpec())
    rows, cols = np.nonzero(grid.free)
    rng = np.random.default_rng(1)
    for i in rng.choice(len(rows), 200, replace=False):
        x, y = grid.center(rows[i], cols[i])
        assert world.clearance_at(x, y) > -1e-3

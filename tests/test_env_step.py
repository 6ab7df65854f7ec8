"""SearchEnv.step itself: what counts as success, when an episode ends, and the running collision count."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from egosearch.sim.env import COLLISION_PENALTY_FLOOR, SearchEnv
from egosearch.sim.scenarios import MAX_STEPS, SUCCESS_DISTANCE, generate_scenarios, navgrid_for, success_region

STAY = np.zeros(5, np.float32)


@pytest.fixture(scope="module")
def scenario():
    return generate_scenarios("kitchen_living", "everywhere", 1.65, n=1, seed=4)[0]


@pytest.fixture(scope="module")
def env():
    e = SearchEnv("kitchen_living", "everywhere", head=True, height=1.65)
    yield e
    e.close()


def _aim(env, pitch_only: bool = False) -> None:
    """Point the camera of the body where it stands at the target (pitch; and yaw unless
    ``pitch_only``), as a head could."""
    s, t = env.state.copy(), env.target
    horizontal = math.hypot(t.center[0] - s.x, t.center[1] - s.y)
    s.pitch = math.atan2(t.center[2] - s.camera_height, horizontal)
    if not pitch_only:
        s.head_yaw = 0.0
        s.theta = math.atan2(t.center[1] - s.y, t.center[0] - s.x)
    env.set_agent_state(s)


def _near_pose(scenario):
    """The centre of the success-region cell nearest the target: within the success distance
    and in sight of the target from the camera at the scenario's height."""
    grid = navgrid_for(scenario.layout)
    region = success_region(scenario.layout, scenario.target(), scenario.height)
    rows, cols = np.nonzero(region)
    d = np.hypot(grid.xs[cols] - scenario.target_x, grid.ys[rows] - scenario.target_y)
    i = int(np.argmin(d))
    return grid.center(rows[i], cols[i])


def test_close_but_not_seeing_the_target_is_no_success(env, scenario):
    x, y = _near_pose(scenario)
    toward = math.atan2(scenario.target_y - y, scenario.target_x - x)
    env.reset(seed=0, options={"scenario": replace(scenario, start_x=x, start_y=y, start_theta=toward + math.pi)})
    _, reward, terminated, truncated, info = env.step(STAY)
    assert info["distance"] <= SUCCESS_DISTANCE
    assert not info["visible"] and not info["success"] and not terminated and not truncated
    assert (info["r_s"], info["r_d"]) == (0.0, 0.0)
    assert reward == pytest.approx(-0.1)  # the live penalty alone
    # The same place with the camera on the target: success, and the episode ends.
    env.reset(seed=0, options={"scenario": replace(scenario, start_x=x, start_y=y, start_theta=toward)})
    _aim(env)
    _, reward, terminated, truncated, info = env.step(STAY)
    assert info["visible"] and info["success"] and terminated and not truncated
    assert info["r_s"] == 10.0 and info["r_d"] == pytest.approx(-info["distance"])
    assert reward == pytest.approx(10.0 - info["distance"] - 0.1)


def test_seeing_the_target_from_too_far_is_no_success(env, scenario):
    x, y = _near_pose(scenario)
    toward = math.atan2(scenario.target_y - y, scenario.target_x - x)
    # Back off along the line from the target until the body surface is 0.3 m beyond the
    # success distance, if that spot is free; else the test could not tell.
    gap = math.hypot(scenario.target_x - x, scenario.target_y - y) - env.spec_agent.body_radius
    back = SUCCESS_DISTANCE + 0.3 - gap
    fx, fy = x - back * math.cos(toward), y - back * math.sin(toward)
    if not navgrid_for(scenario.layout).is_free(fx, fy):
        pytest.skip("no free pose behind the success region on this line")
    env.reset(seed=0, options={"scenario": replace(scenario, start_x=fx, start_y=fy, start_theta=toward)})
    _aim(env)
    _, _, terminated, _, info = env.step(STAY)
    if not info["visible"]:
        pytest.skip("the target is hidden from the farther pose")
    assert info["distance"] == pytest.approx(SUCCESS_DISTANCE + 0.3, abs=1e-6)
    assert not info["success"] and not terminated and info["r_d"] == pytest.approx(-info["distance"])


def test_truncation_at_exactly_t_max(env, scenario):
    assert env.max_steps == MAX_STEPS == 100
    # Standing still far from the target: the 100th step truncates.
    _, info = env.reset(seed=0, options={"scenario": scenario})
    assert info["distance"] > SUCCESS_DISTANCE
    for t in range(1, MAX_STEPS + 1):
        _, _, terminated, truncated, info = env.step(STAY)
        assert info["steps"] == t and not terminated and not info["success"]
        assert truncated == (t == MAX_STEPS), t


def test_a_success_on_the_last_step_terminates_and_does_not_truncate(scenario):
    env = SearchEnv("kitchen_living", "everywhere", head=True, height=1.65, max_steps=1)
    try:
        x, y = _near_pose(scenario)
        env.reset(seed=0, options={"scenario": replace(scenario, start_x=x, start_y=y)})
        _aim(env)
        _, _, terminated, truncated, info = env.step(STAY)
    finally:
        env.close()
    assert info["success"] and terminated and not truncated


def test_the_collision_penalty_counts_every_collision_of_the_episode(env, scenario):
    """Walking into the nearest wall: r_c reads the episode's running count, not this step's hit."""
    grid = navgrid_for(scenario.layout)
    x, y = scenario.start_x, scenario.start_y
    # Face the nearest obstacle: down the gradient of the exact clearance field, squared to the
    # home's axis-aligned walls (the frictionless body slides off a corner it is pushed into).
    row, col = grid.cell(x, y)
    gy, gx = np.gradient(grid.clearance)
    heading = round(math.atan2(-gy[row, col], -gx[row, col]) / (math.pi / 2)) * (math.pi / 2)
    env.reset(seed=0, options={"scenario": replace(scenario, start_theta=heading)})
    collided, counts, r_c = [], [], []
    for _ in range(40):
        _, reward, terminated, truncated, info = env.step(np.array([1, 0, 0, 0, 0], np.float32))
        collided.append(info["collided"])
        counts.append(info["collisions"])
        r_c.append(info["r_c"])
        assert reward == pytest.approx(info["r_s"] + info["r_d"] + info["r_l"] + 0.1 * info["r_c"])
        if terminated or truncated:
            break
    assert counts == list(np.cumsum(collided))
    assert sum(collided) >= 31  # pushed against the wall every step once it is reached
    assert r_c == [pytest.approx(max(COLLISION_PENALTY_FLOOR, -0.1 * n)) for n in counts]
    # Away from the wall (the first step leaves the contact), a step that touches nothing still
    # pays for every earlier collision.
    s = env.state.copy()
    s.theta += math.pi
    env.set_agent_state(s)
    _, _, _, _, before = env.step(np.array([1, 0, 0, 0, 0], np.float32))
    _, _, _, _, info = env.step(np.array([1, 0, 0, 0, 0], np.float32))
    assert not info["collided"] and info["collisions"] == before["collisions"] >= counts[-1]
    assert info["r_c"] == COLLISION_PENALTY_FLOOR
    # A new episode starts from zero.
    env.reset(seed=0, options={"scenario": scenario})
    _, _, _, _, info = env.step(STAY)
    assert info["collisions"] == 0 and info["r_c"] == 0.0

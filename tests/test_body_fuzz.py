"""Fuzz: no env step and no reset leaves the body more than 1 cm inside an obstacle, nor passes
more than 1 cm deep through one on the way (every sub-step's pose is checked).

Random, mostly forward actions in generated homes. Each pose is checked against the scene's
own parts (:mod:`egosearch.scene.geometry`), not against pybullet, so a pybullet shape that
differed from its part would be caught as well as a solver or back-off that leaves the body
inside.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from egosearch.scene.geometry import deepest_penetration, part_penetration
from egosearch.scene.parts import TAG_OBSTACLE, Part
from egosearch.sim.body import AgentSpec
from egosearch.sim.env import SearchEnv
from egosearch.sim.scenarios import _sample_start, navgrid_for

#: The rule of the body: never more than this deep (m) in the home after a step or a reset.
MAX_DEPTH = 0.01
#: The rule on the way: never more than this deep after any sub-step either (ℓ's grid assumes it).
MAX_SWEEP_DEPTH = 0.01
#: Scenario starts drawn per home (evaluation resets put the body there directly).
SCENARIO_STARTS = 50
#: Long episodes: a mostly-forward body spends more of them pushing against furniture, where
#: the solver can leave it inside (home65 ended steps 5.7 cm inside a tv stand's side panel
#: before every step was checked; ``tests/test_world.py`` replays that step).
EPISODE_STEPS = 250


def _mostly_forward(rng: np.random.Generator, dim: int) -> np.ndarray:
    a = rng.uniform(-1.0, 1.0, dim)
    a[0] = rng.uniform(0.2, 1.0) if rng.random() < 0.85 else a[0]
    a[1] *= 0.3
    a[2] *= 0.5
    return a


def fuzz(seeds, episodes: int, episode_steps: int = EPISODE_STEPS) -> dict:
    """Run ``episodes`` episodes in each home ``home<seed>``; the deepest pose found and counts."""
    spec = AgentSpec()
    z0, z1 = spec.body_clearance, spec.body_clearance + spec.body_height
    worst = {"depth": 0.0, "where": None, "sweep": 0.0, "sweep_where": None}
    steps = resets = 0

    def check(scene, x, y, where, on_the_way=False):
        depth, part = deepest_penetration(scene.parts, x, y, spec.body_radius, z0, z1)
        key, at = ("sweep", "sweep_where") if on_the_way else ("depth", "where")
        if depth > worst[key]:
            worst.update({key: depth, at: f"{where}: {depth * 100:.2f} cm in {part}"})

    for seed in seeds:
        layout = f"home{seed}"
        env = SearchEnv(layout=layout, max_steps=episode_steps)
        rng = np.random.default_rng(seed)
        grid = navgrid_for(layout)
        for k in range(SCENARIO_STARTS):
            x, y, _ = _sample_start(grid, rng)
            check(env.scene, x, y, f"{layout} scenario start {k}")
        resets += SCENARIO_STARTS
        for episode in range(episodes):
            _, info = env.reset(seed=int(rng.integers(2**31)))
            resets += 1
            check(env.scene, *info["pose"][:2], f"{layout} reset {episode}")
            done = False
            while not done:
                _, _, terminated, truncated, info = env.step(_mostly_forward(rng, env.action_space.shape[0]))
                steps += 1
                done = terminated or truncated
                where = f"{layout} episode {episode} step {info['steps']}"
                assert env.world.swept_poses[-1][:2] == pytest.approx(info["pose"][:2])
                check(env.scene, *info["pose"][:2], where)
                for k, (x, y, _) in enumerate(env.world.swept_poses[:-1]):
                    check(env.scene, x, y, f"{where} sub-step {k}", on_the_way=True)
        env.close()
    return {"worst": worst["depth"], "where": worst["where"], "worst_sweep": worst["sweep"],
            "sweep_where": worst["sweep_where"], "steps": steps, "resets": resets}


def test_fuzz_small_slice():
    found = fuzz((65, 38), episodes=1, episode_steps=150)
    assert found["resets"] == 2 * (SCENARIO_STARTS + 1)
    assert found["steps"] >= 2 * 20  # mostly-forward episodes rarely find the target fast
    assert found["worst"] <= MAX_DEPTH, found["where"]
    assert found["worst_sweep"] <= MAX_SWEEP_DEPTH, found["sweep_where"]


@pytest.mark.slow
def test_fuzz_hundred_homes():
    found = fuzz(range(100), episodes=2)
    print(f"\nbody fuzz: 100 homes, {found['steps']} steps, {found['resets']} resets, "
          f"deepest {found['worst'] * 100:.2f} cm ({found['where']}), on the way "
          f"{found['worst_sweep'] * 100:.2f} cm ({found['sweep_where']})")
    assert found["worst"] <= MAX_DEPTH, found["where"]
    assert found["worst_sweep"] <= MAX_SWEEP_DEPTH, found["sweep_where"]


# -- the geometry the fuzz relies on, on hand-worked cases ---------------------------------------
OBSTACLE = frozenset({TAG_OBSTACLE})


def _box(yaw=0.0, z=(0.0, 1.0)):
    """A 1 x 0.5 m box centred at the origin."""
    return Part("box", "box", (0.0, 0.0, (z[0] + z[1]) / 2), (1.0, 0.5, z[1] - z[0]), yaw, OBSTACLE)


@pytest.mark.parametrize("x, y, expected", [
    (0.65, 0.0, 0.05),  # 0.15 m from the short side: 0.2 - 0.15
    (0.0, 0.4, 0.05),  # 0.15 m from the long side
    (0.5 + 0.12, 0.25 + 0.16, 0.0),  # 0.2 m from the corner exactly: touching
    (0.5 + 0.06, 0.25 + 0.08, 0.1),  # 0.1 m from the corner
    (0.0, 0.0, 0.45),  # axis at the centre: leave by the long side, 0.25 + 0.2
    (0.45, 0.0, 0.25),  # 0.05 m inside the short side: 0.05 + 0.2
    (0.9, 0.0, 0.0),  # apart
])
def test_box_penetration(x, y, expected):
    assert part_penetration(_box(), x, y, 0.2, 0.05, 1.75) == pytest.approx(expected, abs=1e-12)


def test_yawed_box_and_vertical_overlap():
    # Turned by 90 degrees the long side faces x: 0.4 m from the centre is 0.15 m from it.
    assert part_penetration(_box(math.pi / 2), 0.4, 0.0, 0.2, 0.05, 1.75) == pytest.approx(0.05)
    # A 3 cm thin base under the body (it starts at 5 cm) never touches it.
    assert part_penetration(_box(z=(0.0, 0.03)), 0.0, 0.0, 0.2, 0.05, 1.75) == 0.0
    # A shelf 2 cm into the top of the body: lifting it out is the shorter move.
    assert part_penetration(_box(z=(1.73, 2.0)), 0.0, 0.0, 0.2, 0.05, 1.75) == pytest.approx(0.02)


def test_cylinder_penetration_and_non_obstacles():
    pot = Part("pot", "cylinder", (1.0, 0.0, 0.5), (0.4, 0.4, 1.0), tags=OBSTACLE)
    assert part_penetration(pot, 1.0 - 0.35, 0.0, 0.2, 0.05, 1.75) == pytest.approx(0.05)
    assert part_penetration(pot, 1.0 - 0.41, 0.0, 0.2, 0.05, 1.75) == 0.0
    rug = Part("rug", "box", (0.0, 0.0, 0.5), (1.0, 1.0, 1.0), tags=frozenset({"rug"}))
    assert deepest_penetration([rug, pot], 0.65, 0.0, 0.2, 0.05, 1.75) == (pytest.approx(0.05), "pot")
    assert deepest_penetration([rug], 0.0, 0.0, 0.2, 0.05, 1.75) == (0.0, None)

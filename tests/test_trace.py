"""Per-step traces: what the centre ray meets in a known home, a replay of a recorded episode, the file's size."""

import math

import numpy as np
import pytest

from egosearch.report.behaviour import read_trace_file
from egosearch.runs.evaluate import evaluate, make_env
from egosearch.runs.trace import TRACE_COLUMNS, HomeProbe, TraceRecorder
from egosearch.searchers.policies import RandomPolicy
from egosearch.sim.scenarios import generate_scenarios


@pytest.fixture(scope="module")
def probe():
    return HomeProbe("kitchen_living")


# kitchen_living's north counter: section 0 spans x 0.85..1.65 with its back panel's inner face at
# y = 7.98; level0 is its bottom shelf (0.10 m up), level1 the board at 0.49 m. The wall cabinet nw's
# back is also at y = 7.98, its lower level from 1.47 m.
@pytest.mark.parametrize("origin, direction, kind, part, surface, point", [
    ((1.25, 6.9, 0.3), (0, 1, 0), "low_cabinet_interior", "kitchen/counter_north/sec0/back",
     "kitchen/counter_north/sec0/level0", (1.25, 7.98, 0.3)),
    ((1.25, 6.9, 0.65), (0, 1, 0), "low_cabinet_interior", "kitchen/counter_north/sec0/back",
     "kitchen/counter_north/sec0/level1", (1.25, 7.98, 0.65)),
    ((1.21, 6.9, 1.6), (0, 1, 0), "wall_cabinet_interior", "kitchen/wall_cabinet_nw/back",
     "kitchen/wall_cabinet_nw/level0_col0", (1.21, 7.98, 1.6)),
    # between the two wall cabinets, above the counter top: the north wall
    ((2.15, 6.9, 1.75), (0, 1, 0), "wall", "wall/north/seg0", "", (2.15, 8.0, 1.75)),
    ((4.0, 3.2, 1.65), (0, 0, -1), "floor", "floor", "", (4.0, 3.2, 0.0)),
    ((4.0, 3.2, 1.65), (0, 0, 1), "ceiling", "ceiling", "", (4.0, 3.2, 2.6)),
    # 45 degrees down from 1.65 m, 0.9 m short of the dining table's top (0.75 m high): its centre line
    ((6.5, 5.0, 1.65), (0, math.sqrt(0.5), -math.sqrt(0.5)), "surface", "dining/table/top",
     "dining/table/top_surface", (6.5, 5.9, 0.75)),
])
def test_centre_ray_names_what_it_meets(probe, origin, direction, kind, part, surface, point):
    hit, got_kind, got_part, got_surface = probe.gaze(origin, direction, max_depth=5.0)
    assert (got_kind, got_part, got_surface) == (kind, part, surface)
    assert hit == pytest.approx(point, abs=1e-6)


def test_nothing_within_range_is_none(probe):
    # the nearest thing along +x from the living room's middle is metres away
    hit, kind, part, surface = probe.gaze((4.0, 3.2, 1.65), (1, 0, 0), max_depth=0.5)
    assert (kind, part, surface) == ("none", "", "") and all(math.isnan(v) for v in hit)


def test_the_target_hides_what_is_behind_it(probe):
    from egosearch.scene.parts import Part

    target = Part("target", "box", (1.25, 7.5, 0.3), (0.1, 0.1, 0.1))
    probe.set_target(target)
    try:
        hit, kind, part, surface = probe.gaze((1.25, 6.9, 0.3), (0, 1, 0), max_depth=5.0)
    finally:
        probe.set_target(None)
    assert (kind, part, surface) == ("target", "target", "kitchen/counter_north/sec0/level0")
    assert hit == pytest.approx((1.25, 7.45, 0.3), abs=1e-6)


def test_opening_distance_and_room(probe):
    # 1 m in front of the north counter's section 1 (x 1.75..2.55, front edge y = 7.45)
    assert probe.opening_distance(2.15, 6.45) == pytest.approx(1.0, abs=1e-9)
    assert probe.opening_distance(2.15, 7.7) == 0.0
    assert probe.room(1.0, 6.0) == "kitchen" and probe.room(5.5, 2.0) == "living"


@pytest.fixture(scope="module")
def recorded():
    scenarios = generate_scenarios("kitchen_living", "everywhere", 1.65, n=2, seed=3)
    recorder = TraceRecorder()
    rows = evaluate("EgoSearch-v0", lambda env: RandomPolicy(5, seed=11), scenarios, seed=5, recorder=recorder)
    return scenarios, rows, recorder


def test_a_trace_has_a_row_per_step_and_starts_at_the_scenarios_shortest_path(recorded):
    scenarios, rows, recorder = recorded
    cols = recorder.arrays()
    assert set(cols) == set(TRACE_COLUMNS)
    for sc, row in zip(scenarios, rows):
        ep = cols["scenario_id"] == sc.scenario_id
        assert list(cols["step"][ep]) == list(range(row["steps"] + 1))
        assert cols["collisions"][ep][-1] == row["collisions"]
        assert bool(cols["success"][ep][-1]) == bool(row["success"]) and not cols["success"][ep][:-1].any()
        start = np.flatnonzero(ep)[0]
        assert (cols["x"][start], cols["y"][start]) == pytest.approx((sc.start_x, sc.start_y), abs=1e-5)
        assert np.isnan([cols[f"a{i}"][start] for i in range(5)]).all()
        # row 0's geodesic is ℓ itself (the scenario file keeps 4 decimals; the trace float32)
        assert cols["geodesic"][start] == pytest.approx(sc.shortest_path, abs=2e-4)
        # the path the body walked is the one the per-episode row reports
        walked = np.hypot(np.diff(cols["x"][ep]), np.diff(cols["y"][ep])).sum()
        assert walked == pytest.approx(row["path_length"], abs=1e-3)


def test_replaying_a_traces_actions_walks_the_same_poses(recorded, tmp_path):
    scenarios, _, recorder = recorded
    path = recorder.write(tmp_path / "cell.npz")
    cols, facts = read_trace_file(path)
    assert facts["head"] is True and facts["env_id"] == "EgoSearch-v0"
    for sc in scenarios:
        ep = cols["scenario_id"] == sc.scenario_id
        env = make_env("EgoSearch-v0", sc)
        _, info = env.reset(seed=5 + sc.scenario_id, options={"scenario": sc})
        poses = [info["pose"]]
        collisions, visible = [info["collisions"]], [info["visible"]]
        for t in np.flatnonzero(ep)[1:]:
            _, _, _, _, info = env.step(np.array([cols[f"a{i}"][t] for i in range(5)], np.float32))
            poses.append(info["pose"])
            collisions.append(info["collisions"])
            visible.append(info["visible"])
        env.close()
        recorded_poses = np.column_stack([cols[k][ep] for k in ("x", "y", "theta", "pitch", "head_yaw")])
        np.testing.assert_allclose(np.asarray(poses), recorded_poses, atol=1e-5)
        assert collisions == list(cols["collisions"][ep]) and visible == list(cols["visible"][ep])


def test_a_three_seed_cell_of_incompressible_steps_stays_under_10_mb(tmp_path):
    # 3 seeds x 200 episodes x 101 rows of random numbers: the worst the compression can do
    n = 3 * 200 * 101
    rng = np.random.default_rng(0)
    recorder = TraceRecorder()
    recorder.meta.update(env_id="EgoSearch-v0", head=True, step_seconds=0.15, max_depth=5.0)
    for name in recorder.columns:
        recorder.columns[name] = rng.random(n)
    for name in ("gaze_part", "gaze_surface"):
        recorder.columns[name] = rng.choice([f"kitchen/counter_north/sec{i}/level{j}" for i in range(4)
                                             for j in range(2)], n)
    path = recorder.write(tmp_path / "big.npz")
    assert path.stat().st_size < 10 * 2**20
    assert len(read_trace_file(path)[0]) == n


def test_evaluate_refuses_a_trace_file_that_is_not_npz_before_running(recorded, tmp_path, capsys):
    from egosearch.cli import main
    from egosearch.sim.scenarios import write_scenarios

    scenarios = tmp_path / "s.csv"
    write_scenarios(scenarios, recorded[0])
    out = tmp_path / "e.csv"
    code = main(["evaluate", "--policy", "random", "--scenarios", str(scenarios), "--out", str(out),
                 "--traces", str(tmp_path / "t.csv")])
    assert code == 2 and "must end in .npz" in capsys.readouterr().err and not out.exists()

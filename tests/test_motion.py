"""Full-body characters, motion generators and Algorithm 1 (egosearch.motion)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pybullet
import pytest
from pybullet_utils import bullet_client

from egosearch.motion import mocap, quat, skeleton
from egosearch.motion.base import SUBSTEP_SECONDS, IdentityMG
from egosearch.motion.collision import PENETRATION_DEPTH, PenetrationCounter
from egosearch.motion.fetch import FETCH_CAMERA_HEIGHT, FetchMG
from egosearch.motion.humanoid import HUMANOID_SCALE, HumanoidBody, pose_frames
from egosearch.motion.matching import MatchingMG
from egosearch.motion.phase import PhaseMG
from egosearch.motion.replan import (
    FULLBODY_COLUMNS,
    METHODS,
    evaluate_fullbody,
    run_fullbody_episode,
)
from egosearch.motion.video import TARGET_RING_COLOR
from egosearch.searchers.policies import OraclePolicy
from egosearch.sim.body import STEP_SECONDS, AgentSpec, AgentState, wrap_angle
from egosearch.sim.scenarios import Scenario, generate_scenarios

LAYOUT = "kitchen_living"


@pytest.fixture(scope="module")
def scenarios():
    return generate_scenarios(LAYOUT, "everywhere", 1.65, 4, seed=0)


@pytest.fixture(scope="module")
def env(scenarios):
    from egosearch.runs.evaluate import make_env

    e = make_env("EgoSearch-v0", scenarios[0])
    yield e
    e.close()


# -- mocap and the humanoid ------------------------------------------------------------------------

def test_walk_clip_is_a_plausible_walk():
    m = mocap.measure("walk", HUMANOID_SCALE)
    assert 1.0 <= m["forward_speed_mps"] <= 1.6
    assert 0.01 <= m["head_oscillation_m"] <= 0.06
    assert m["eye_height_mean_m"] == pytest.approx(1.65, abs=0.01)
    assert 1.0 <= m["stride_length_m"] <= 1.8  # two steps
    clip = mocap.load_clip("walk", HUMANOID_SCALE)
    assert clip.root_pos[:, 2].min() > 0.8  # z is up: the pelvis is above the floor
    assert clip.root_pos[-1, 0] - clip.root_pos[0, 0] > 1.0  # walks along +x


def test_forward_kinematics_matches_pybullet():
    clip = mocap.load_clip("walk", HUMANOID_SCALE)
    cf = mocap.character_frames(clip)
    p = bullet_client.BulletClient(pybullet.DIRECT)
    try:
        body = HumanoidBody(p)
        from egosearch.motion.base import FullBodyPose

        for k in (0, 11, 25):
            pose = FullBodyPose(1.0, -2.0, 0.9, 1.65, joints={n: v[k] for n, v in clip.joints.items()},
                                root_z=cf.root_z[k], root_local=cf.root_local[k])
            body.set_pose(pose)
            frames = pose_frames(pose)
            for name, j in body.joint_index.items():
                state = p.getLinkState(body.body_id, j, computeForwardKinematics=True)
                pos, rot = frames[skeleton.load_skeleton().joint(name).child]
                assert np.allclose(state[4], pos, atol=1e-5)
                assert quat.angle_between(np.array(state[5]), rot) < 1e-4
    finally:
        p.disconnect()


# -- motion generators respect their limits --------------------------------------------------------

def demanding_plan(n: int = 40, seed: int = 3) -> list[AgentState]:
    """Full-speed abstract moves, sideways and backwards steps, hard turns and head sweeps."""
    spec = AgentSpec()
    rng = np.random.default_rng(seed)
    s = AgentState(0.0, 0.0, 0.0)
    plan = [s.copy()]
    a = np.zeros(5)
    for i in range(n):
        if i % 5 == 0:
            a = rng.choice([-1.0, 1.0], 5) * spec.action_scale()
            a[0] = abs(a[0]) if i % 10 == 0 else a[0]
        c, sn = math.cos(s.theta), math.sin(s.theta)
        s = AgentState(s.x + c * a[0] - sn * a[1], s.y + sn * a[0] + c * a[1], s.theta + a[2],
                       float(np.clip(s.pitch + a[3], *spec.pitch_limits)),
                       float(np.clip(s.head_yaw + a[4], *spec.yaw_limits)), 1.65)
        plan.append(s)
    return plan


@pytest.mark.parametrize("mg_class", [PhaseMG, MatchingMG, FetchMG])
def test_motion_generator_limits(mg_class):
    plan = demanding_plan()
    mg = mg_class()
    lim = mg.limits
    mg.substeps = []
    poses = mg.generate(plan, len(plan) - 1)
    assert len(poses) == len(plan) - 1
    start = mg.initial_pose(plan[0])
    sub = np.array([(start.x, start.y, start.theta)] + mg.substeps)
    dt = SUBSTEP_SECONDS
    d = np.diff(sub, axis=0)
    d[:, 2] = (d[:, 2] + math.pi) % (2 * math.pi) - math.pi
    v = d[:, :2] / dt
    om = d[:, 2] / dt
    eps = 1e-6
    # Turn rate and turn acceleration.
    assert np.all(np.abs(om) <= lim.max_turn_rate + eps)
    assert np.all(np.abs(np.diff(np.concatenate([[0.0], om]))) <= lim.max_turn_accel * dt + eps)
    # Body-frame speed box; a differential drive moves along its (mid-sub-step) heading only.
    heading = sub[1:, 2] if mg_class is not FetchMG else sub[:-1, 2] + 0.5 * d[:, 2]
    fwd = np.cos(heading) * v[:, 0] + np.sin(heading) * v[:, 1]
    lat = -np.sin(heading) * v[:, 0] + np.cos(heading) * v[:, 1]
    # Acceleration (from rest): of the velocity for a walker, of the wheel speed for Fetch.
    if mg_class is FetchMG:
        half = 0.5 * d[:, 2]
        arc = fwd * np.where(np.abs(half) > 1e-12, half / np.sin(np.where(half == 0, 1.0, half)), 1.0)
        assert np.all(np.abs(np.diff(np.concatenate([[0.0], arc]))) <= lim.max_accel * dt + eps)
    else:
        dv = np.diff(np.vstack([[0.0, 0.0], v]), axis=0)
        assert np.all(np.hypot(dv[:, 0], dv[:, 1]) <= lim.max_accel * dt + eps)
    assert np.all(fwd <= lim.max_forward + eps) and np.all(fwd >= -lim.max_backward - eps)
    assert np.all(np.abs(lat) <= lim.max_lateral + eps)
    if mg_class is FetchMG:
        assert np.abs(lat).max() < 1e-9
        assert all(q.camera_height == FETCH_CAMERA_HEIGHT and q.joints is None for q in poses)
    else:
        assert all(q.joints is not None and q.root_z > 0.8 for q in poses)
    # At the env step rate too: speed and turn per 0.15 s.
    xy = np.array([(q.x, q.y) for q in [start] + poses])
    step_speed = np.hypot(*np.diff(xy, axis=0).T) / STEP_SECONDS
    assert step_speed.max() <= lim.max_speed + eps
    th = np.array([q.theta for q in [start] + poses])
    assert np.abs([wrap_angle(t) for t in np.diff(th)]).max() <= lim.max_turn_rate * STEP_SECONDS + eps
    # The head stays within its range and rates.
    pitch = np.array([q.pitch for q in [start] + poses])
    yaw = np.array([q.head_yaw for q in [start] + poses])
    assert pitch.min() >= lim.pitch_limits[0] - eps and pitch.max() <= lim.pitch_limits[1] + eps
    assert yaw.min() >= lim.yaw_limits[0] - eps and yaw.max() <= lim.yaw_limits[1] + eps
    assert np.abs(np.diff(pitch)).max() <= lim.max_pitch_rate * STEP_SECONDS + eps
    assert np.abs(np.diff(yaw)).max() <= lim.max_yaw_rate * STEP_SECONDS + eps
    # Its own limits make it deviate from the plan.
    err = [math.hypot(q.x - s.x, q.y - s.y) for q, s in zip(poses, plan[1:])]
    assert max(err) > 0.1


def test_phase_mg_head_oscillates_while_walking():
    plan = [AgentState(0.15 * i, 0.0, 0.0) for i in range(41)]  # 1 m/s straight
    poses = PhaseMG().generate(plan, 40)
    z = np.array([q.camera_height for q in poses[15:]])
    assert 0.01 <= z.max() - z.min() <= 0.06
    assert abs(z.mean() - 1.65) < 0.03
    phases = np.array([q.phase for q in poses])
    assert len(np.unique(np.round(phases, 3))) > 20  # the phase moves with the distance


def test_generators_continue_from_start_pose():
    plan = demanding_plan(20)
    for mg in (PhaseMG(), MatchingMG(), FetchMG()):
        whole = mg.generate(plan, 10)
        first = mg.generate(plan, 4)
        rest = mg.generate(plan[4:], 6, start=first[-1])
        if isinstance(mg, FetchMG):
            continue  # Fetch restarts its waypoint pursuit with every new plan
        assert rest[-1].x == pytest.approx(whole[-1].x, abs=1e-9)
        assert rest[-1].theta == pytest.approx(whole[-1].theta, abs=1e-9)


# -- collisions ------------------------------------------------------------------------------------

def test_root_stops_at_walls_and_penetration_is_counted(env):
    u = env.unwrapped
    world = u.world
    x0, y0, x1, y1 = u.scene.bounds
    # A plan straight through the west wall.
    xs = x0 + 0.6
    y = next(y for y in np.arange(y0 + 0.5, y1 - 0.5, 0.1)
             if all(world.is_free(x, y, 0.05) for x in np.arange(x0 + 0.26, xs + 0.01, 0.05)))
    plan = [AgentState(xs - 0.25 * i, y, math.pi) for i in range(15)]
    for mg in (PhaseMG(world), MatchingMG(world), FetchMG(world)):
        poses = mg.generate(plan, 14)
        assert any(q.blocked for q in poses), mg.name
        assert all(world.clearance_at(q.x, q.y, 0.05) > -1e-3 for q in poses), mg.name
        assert min(q.x for q in poses) > x0 + 0.15
    counter = PenetrationCounter(u.scene, "humanoid")
    try:
        mg = PhaseMG()
        free = mg.initial_pose(AgentState(xs, y, 0.0))
        assert counter.depth(free) == 0.0
        inside = mg.initial_pose(AgentState(x0 - 0.05, y, 0.0))  # straddling the wall
        assert counter.depth(inside) > PENETRATION_DEPTH and counter.penetrates(inside)
    finally:
        counter.close()


# -- Algorithm 1 -----------------------------------------------------------------------------------

def open_loop(env, policy, scenario, n):
    obs, _ = env.reset(seed=0, options={"scenario": scenario})
    policy.reset(seed=0)
    states, observations = [env.unwrapped.state.copy()], [obs]
    for _ in range(n):
        obs, _, terminated, truncated, _ = env.step(policy.act(obs))
        states.append(env.unwrapped.state.copy())
        observations.append(obs)
        if terminated or truncated:
            break
    return states, observations


@pytest.mark.parametrize("M,T", [(10, 10), (4, 10)])
def test_replanning_with_identity_mg_equals_open_loop(env, scenarios, M, T):
    sc = scenarios[1]
    policy = OraclePolicy(env)
    trace = []
    row = run_fullbody_episode(env, policy, IdentityMG(), sc, T=T, M=M, seed=0, trace=trace, max_steps=12)
    states, observations = open_loop(env, policy, sc, row["steps"])
    assert len(trace) == len(states)
    for item, s, o in zip(trace, states, observations):
        got = item["state"]
        assert (got.x, got.y, got.theta, got.pitch, got.head_yaw, got.camera_height) == \
            (s.x, s.y, s.theta, s.pitch, s.head_yaw, s.camera_height)
        for key in ("depth", "mask", "proprio"):
            assert np.array_equal(item["obs"][key], o[key]), key


def test_restored_depth_history_matches_fresh_renders(env, scenarios):
    u = env.unwrapped
    trace = []
    run_fullbody_episode(env, OraclePolicy(env), PhaseMG(), scenarios[0], T=10, M=3, seed=0, trace=trace,
                         max_steps=9)
    last = trace[-1]["obs"]["depth"]
    for k, item in enumerate(trace[-5:]):
        s = item["state"]
        # The realised camera (gait oscillation included) and the policy's head.
        assert s.camera_height == item["pose"].camera_height
        fresh, _ = u.sensor.render_uint8(s.camera_position, s.camera_yaw, s.pitch)
        assert np.array_equal(last[k], fresh)
    assert len({round(item["state"].camera_height, 4) for item in trace}) > 3  # it oscillates


class ScriptedPolicy:
    """Walk forward at full speed, tilting the head down."""

    def reset(self, seed=None):
        pass

    def act(self, obs):
        return np.array([1.0, 0.0, 0.0, -1.0, 0.0], np.float32)


def test_bookkeeping_on_a_hand_worked_case(env):
    """A phone on the floor 2.15 m straight ahead of an abstract body walking 0.25 m/step with its head
    tilting 0.25 rad/step down: after 6 steps the body's surface is 2.15 - 1.5 - 0.2 = 0.45 m <= 0.5 m
    from it and the camera (pitch -1.0) sees it; after 5 it is 0.7 m away. With M = 4: 2 plans; path
    1.5 m; with l = 1.2 m, SPL = 1.2 / 1.5 = 0.8."""
    u = env.unwrapped
    world = u.world
    spec = AgentSpec()
    grid_x0, grid_y0, grid_x1, grid_y1 = u.scene.bounds
    start = None
    for x in np.arange(grid_x0 + 0.5, grid_x1 - 2.6, 0.1):
        for y in np.arange(grid_y0 + 0.5, grid_y1 - 0.5, 0.1):
            if all(world.clearance_at(x + d, y, 0.3) >= 0.3 for d in np.arange(0.0, 2.4, 0.1)):
                start = (float(x), float(y))
                break
        if start:
            break
    assert start is not None
    sc = Scenario(scenario_id=99, layout=LAYOUT, placement="everywhere", height=1.65, start_x=start[0],
                  start_y=start[1], start_theta=0.0, target_object="phone", target_x=start[0] + 2.15,
                  target_y=start[1], target_z=0.0, target_yaw=0.0, shortest_path=1.2)
    row = run_fullbody_episode(env, ScriptedPolicy(), IdentityMG(), sc, T=8, M=4, seed=0)
    assert row["success"] == 1 and row["steps"] == 6
    assert row["attempts"] == 2
    assert row["path_length"] == pytest.approx(6 * spec.max_forward)
    assert row["spl"] == pytest.approx(0.8, abs=1e-4)
    assert row["collisions"] == 0 and row["penetrations"] == 0 and row["penetration_rate"] == 0.0
    # Never finding it: capped at max_steps, one plan per M steps, SPL 0.
    far = replace(sc, target_x=start[0] + 30.0)
    row = run_fullbody_episode(env, ScriptedPolicy(), IdentityMG(), far, T=8, M=3, seed=0, max_steps=7)
    assert (row["success"], row["steps"], row["attempts"], row["spl"]) == (0, 7, 3, 0.0)


# -- evaluation smoke ------------------------------------------------------------------------------

@pytest.mark.parametrize("method", sorted(METHODS))
def test_evaluate_fullbody_smoke(scenarios, method):
    rows = evaluate_fullbody("EgoSearch-v0", OraclePolicy, scenarios[:2], method=method, mg_name="humanoid_phase",
                             M=5 if METHODS[method].kind == "replan" else None, T=10, seed=0)
    assert len(rows) == 2
    for r in rows:
        assert tuple(r) == FULLBODY_COLUMNS
        assert r["method"] == method and r["mg"] == "humanoid_phase"
        assert 1 <= r["steps"] <= 100 and r["attempts"] >= 1
        assert 0.0 <= r["spl"] <= 1.0 and 0.0 <= r["penetration_rate"] <= 1.0
        assert r["spl"] == 0.0 or r["success"] == 1


@pytest.mark.parametrize("mg_name", ["humanoid_matching", "fetch"])
def test_evaluate_fullbody_other_characters(scenarios, mg_name):
    rows = evaluate_fullbody("EgoSearch-v0", OraclePolicy, scenarios[2:4], method="ours", mg_name=mg_name, M=5,
                             T=10, seed=0)
    assert [r["mg"] for r in rows] == [mg_name, mg_name]
    assert all(r["attempts"] == math.ceil(r["steps"] / 5) for r in rows)


def test_search_video(tmp_path, scenarios):
    pytest.importorskip("pyrender")
    from egosearch.motion.video import write_search_video

    try:
        row = write_search_video(LAYOUT, "humanoid_phase", OraclePolicy, scenarios[2], tmp_path / "search.gif",
                                 tmp_path / "still.png", M=5, T=10)
    except Exception as err:  # noqa: BLE001 - no OpenGL here
        if "EGL" in repr(err) or "OpenGL" in repr(err) or "context" in repr(err).lower():
            pytest.skip(f"no offscreen OpenGL: {err}")
        raise
    import imageio.v2 as imageio

    still = imageio.imread(tmp_path / "still.png")
    assert still.shape[0] == 384 and still.shape[1] == 384 + 512
    frames = imageio.mimread(tmp_path / "search.gif")
    assert len(frames) == row["steps"] + 1
    # The third-person half rings the target in the mask's red (the still is lossless); shading
    # never gives that exact colour, so these pixels are the ring.
    assert (still[:, 384:, :3] == TARGET_RING_COLOR).all(axis=2).sum() > 20
    # The step, visibility and distance are written in the margins above and below the depth image.
    first = np.asarray(frames[0])[..., :3]
    assert (first[:40, :384] < 100).all(axis=2).any() and (first[-40:, :384] < 100).all(axis=2).any()


def test_frame_label_and_clean_candidates():
    import pandas as pd

    from egosearch.motion.video import clean_successes, frame_label

    assert frame_label(0, 100, False, 3.456, False) == ("step 0 / 100", "target not seen, 3.46 m away")
    assert frame_label(7, 100, True, 0.4, True) == ("step 7 / 100", "target found, 0.40 m away")
    runs = pd.DataFrame({"scenario_id": [4, 0, 1, 2, 3], "success": [1, 1, 1, 0, 1], "steps": [30, 40, 8, 100, 25],
                         "penetrations": [0, 2, 0, 0, 0]})
    # scenario 0 succeeded through the furniture, 1 too quickly, 2 not at all
    assert clean_successes(runs, min_steps=20) == [3, 4]
    assert clean_successes(runs) == [1, 3, 4]


def test_gif_is_kept_under_its_size_by_dropping_steps(tmp_path):
    import imageio.v2 as imageio

    from egosearch.motion.video import write_gif

    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 256, (64, 64, 3), dtype=np.uint8) for _ in range(21)]  # noise: no compression
    k = write_gif(tmp_path / "a.gif", frames, max_bytes=10**9)
    assert k == 1 and len(imageio.mimread(tmp_path / "a.gif")) == 21
    one_frame = (tmp_path / "a.gif").stat().st_size / 21
    k = write_gif(tmp_path / "b.gif", frames, max_bytes=int(8 * one_frame))
    kept = imageio.mimread(tmp_path / "b.gif")
    assert k > 1 and len(kept) == len(range(0, 20, k)) + 1 and (tmp_path / "b.gif").stat().st_size <= 8 * one_frame
    assert np.array_equal(np.asarray(kept[-1])[..., :3], np.asarray(imageio.mimread(tmp_path / "a.gif")[-1])[..., :3])


def test_video_refuses_to_film_a_penetrating_replay(tmp_path, scenarios, capsys):
    """A full-body CSV that calls an episode clean is not trusted: the replay is checked, and a
    replay with a limb inside the home is never filmed."""
    import pandas as pd

    from egosearch.cli import main
    from egosearch.sim.scenarios import write_scenarios

    write_scenarios(tmp_path / "s.csv", scenarios)
    # The oracle's humanoid brushes furniture in scenario 3 (its replay below has penetrating poses).
    pd.DataFrame({"scenario_id": [3], "success": [1], "steps": [26], "penetrations": [0]}).to_csv(
        tmp_path / "fb.csv", index=False)
    code = main(["video", "--policy", "oracle", "--scenarios", str(tmp_path / "s.csv"), "--first-success",
                 str(tmp_path / "fb.csv"), "--T", "10", "--out", str(tmp_path / "v.gif"), "--still",
                 str(tmp_path / "v.png")])
    captured = capsys.readouterr()
    assert code == 2 and "the replay differs" in captured.out and "penetrating pose" in captured.err
    assert not (tmp_path / "v.gif").exists()


def test_fullbody_command_with_an_actor_needs_its_weights(tmp_path, capsys):
    from egosearch.cli import main

    scen = tmp_path / "s.csv"
    code = main(["fullbody", "--setting", "ours-M5-humanoid_phase", "--scenarios", str(scen), "--out",
                 str(tmp_path / "out.csv")])
    assert code == 2 and "--weights" in capsys.readouterr().err
    assert not (tmp_path / "out.csv").exists()

"""The training sensor (depth + target mask), its mask feature, and the pyrender cross-check."""

from __future__ import annotations

import dataclasses
import math
import os

import numpy as np
import pytest

from egosearch.scene.parts import TAG_FLOOR, TAG_FURNITURE, TAG_WALL, Part, Scene
from egosearch.sim.sensor import (
    BACKENDS,
    MASK_FEATURE_DIM,
    DepthMaskSensor,
    bench_sensor,
    camera_axes,
    mask_feature,
    random_poses,
)

# ----------------------------------------------------------------------------------------------
# mask_feature
# ----------------------------------------------------------------------------------------------


def test_mask_feature_empty_is_zero():
    f = mask_feature(np.zeros((100, 100), bool))
    assert f.shape == (MASK_FEATURE_DIM,) == (30,)
    assert f.dtype == np.float32
    assert not f.any()


def test_mask_feature_top_right_block():
    m = np.zeros((100, 100), bool)
    m[0:20, 80:100] = True  # exactly the top-right 20x20 block
    f = mask_feature(m)
    # mean pixel centre: column 90.0, row 10.0 -> x = 90/50 - 1, y = 1 - 10/50
    assert f[0] == pytest.approx(0.8, abs=1e-6)
    assert f[1] == pytest.approx(0.8, abs=1e-6)
    assert f[2] == pytest.approx(0.8 * math.sqrt(2), abs=1e-6)
    assert f[3] == pytest.approx(math.pi / 4, abs=1e-6)
    grid = f[4:29].reshape(5, 5)
    expected = np.zeros((5, 5))
    expected[0, 4] = 1.0  # top row, rightmost column
    np.testing.assert_allclose(grid, expected, atol=1e-7)
    assert f[29] == 1.0


def test_mask_feature_single_pixels():
    m = np.zeros((100, 100), bool)
    m[0, 0] = True  # top-left pixel: centre (0.5, 0.5)
    f = mask_feature(m)
    assert f[0] == pytest.approx(-0.99, abs=1e-6)
    assert f[1] == pytest.approx(0.99, abs=1e-6)
    assert f[3] == pytest.approx(math.atan2(0.99, -0.99), abs=1e-6)
    assert f[4] == pytest.approx(1 / 400)
    assert f[5:29].sum() == 0

    m = np.zeros((100, 100), bool)
    m[99, 49] = True  # bottom row, just left of the centre line
    f = mask_feature(m)
    assert f[0] == pytest.approx(49.5 / 50 - 1, abs=1e-6)
    assert f[1] == pytest.approx(-0.99, abs=1e-6)
    grid = f[4:29].reshape(5, 5)
    assert grid[4, 2] == pytest.approx(1 / 400) and grid.sum() == pytest.approx(1 / 400)


def test_mask_feature_full_mask():
    f = mask_feature(np.ones((100, 100), bool))
    np.testing.assert_allclose(f[:4], 0.0, atol=1e-6)
    np.testing.assert_allclose(f[4:29], 1.0)
    assert f[29] == 1.0


def test_mask_feature_area_average_for_any_size():
    rng = np.random.default_rng(0)
    for shape in ((84, 84), (100, 100), (64, 48)):
        m = rng.random(shape) < 0.3
        grid = mask_feature(m)[4:29]
        assert grid.mean() == pytest.approx(m.mean(), abs=1e-6)  # equal-area blocks
        np.testing.assert_allclose(mask_feature(np.ones(shape, bool))[4:29], 1.0, atol=1e-6)
    m = np.zeros((84, 84), bool)
    m[:, :42] = True  # left half: columns 0-1 full, column 2 half, columns 3-4 empty
    grid = mask_feature(m)[4:29].reshape(5, 5)
    np.testing.assert_allclose(grid, np.tile([1, 1, 0.5, 0, 0], (5, 1)), atol=1e-6)


# ----------------------------------------------------------------------------------------------
# Sensor against analytic geometry
# ----------------------------------------------------------------------------------------------


def _box(name, center, size, tags=frozenset({TAG_FURNITURE}), **kw):
    return Part(name, "box", center, size, tags=tags, **kw)


def _scene(*parts, bounds=(-5.0, -5.0, 5.0, 5.0)):
    return Scene("test", tuple(parts), (), bounds)


WALL_X3 = _box("wall_x3", (3.05, 0.0, 1.3), (0.1, 40.0, 40.0), tags=frozenset({TAG_WALL}))
FLOOR = _box("floor", (0.0, 0.0, -0.05), (40.0, 40.0, 0.1), tags=frozenset({TAG_FLOOR}))


def _sensor(scene, backend, **kw):
    try:
        return DepthMaskSensor(scene, backend=backend, **kw)
    except Exception as exc:  # noqa: BLE001
        pytest.skip(f"sensor backend {backend!r} unavailable here: {exc}")


@pytest.fixture(params=BACKENDS)
def backend(request):
    return request.param


def test_camera_axes_convention():
    right, up, forward = camera_axes(0.0, 0.0)
    np.testing.assert_allclose(forward, (1, 0, 0), atol=1e-12)
    np.testing.assert_allclose(right, (0, -1, 0), atol=1e-12)  # +y is on the left
    np.testing.assert_allclose(up, (0, 0, 1), atol=1e-12)
    _, _, forward = camera_axes(math.pi / 2, 0.3)
    assert forward[1] > 0 and forward[2] > 0  # yaw turns counter-clockwise, pitch looks up
    for yaw, pitch in ((0.3, -0.7), (-2.0, 0.4)):
        axes = camera_axes(yaw, pitch)
        np.testing.assert_allclose(axes @ axes.T, np.eye(3), atol=1e-12)
        np.testing.assert_allclose(np.cross(axes[0], axes[1]), -axes[2], atol=1e-12)  # OpenGL-like


def test_fronto_parallel_wall_has_constant_z_depth(backend):
    s = _sensor(_scene(WALL_X3), backend)
    depth, mask = s.render((0.0, 0.0, 1.3), 0.0, 0.0)
    assert depth.shape == (100, 100) and depth.dtype == np.float32
    assert mask.shape == (100, 100) and mask.dtype == np.bool_ and not mask.any()
    assert abs(depth[49:51, 49:51] - 3.0).max() < 1e-3
    assert abs(depth - 3.0).max() < 1e-3  # z-depth, not ray length: flat to the corners


def test_looking_straight_down_at_the_floor(backend):
    s = _sensor(_scene(FLOOR), backend)
    depth, _ = s.render((0.3, -0.2, 1.5), 0.7, -math.pi / 2)
    assert abs(depth - 1.5).max() < 1e-3


def test_misses_and_far_hits_read_max_depth(backend):
    far_wall = _box("far", (7.05, 0.0, 1.3), (0.1, 40.0, 40.0))
    s = _sensor(_scene(far_wall), backend)
    depth, _ = s.render((0.0, 0.0, 1.3), 0.0, 0.0)
    assert np.all(depth == np.float32(5.0))
    depth, _ = s.render((0.0, 0.0, 1.3), math.pi, 0.0)  # looking away: nothing at all
    assert np.all(depth == np.float32(5.0))
    d8, _ = s.render_uint8((0.0, 0.0, 1.3), 0.0, 0.0)
    assert d8.dtype == np.uint8 and np.all(d8 == 255)


def test_yaw_pitch_and_image_orientation(backend):
    """A target at +y is on the LEFT at yaw 0; above the eye it is in the TOP half."""
    s = _sensor(_scene(FLOOR), backend)
    eye = (0.0, 0.0, 1.0)
    s.set_target(_box("t", (2.0, 1.0, 1.0), (0.2, 0.2, 0.2)))
    _, mask = s.render(eye, 0.0, 0.0)
    cols = np.nonzero(mask)[1]
    assert cols.size and cols.max() < 50
    s.set_target(_box("t", (2.0, 0.0, 1.8), (0.2, 0.2, 0.2)))
    _, mask = s.render(eye, 0.0, 0.0)
    rows = np.nonzero(mask)[0]
    assert rows.size and rows.max() < 50
    # pitching up by atan(0.8 / 2) brings it to the image centre
    _, mask = s.render(eye, 0.0, math.atan2(0.8, 2.0))
    f = mask_feature(mask)
    assert abs(f[0]) < 0.05 and abs(f[1]) < 0.05
    # yaw = +pi/2 looks along +y
    s.set_target(_box("t", (0.0, 2.0, 1.0), (0.2, 0.2, 0.2)))
    depth, mask = s.render(eye, math.pi / 2, 0.0)
    f = mask_feature(mask)
    assert f[29] == 1.0 and abs(f[0]) < 0.03 and abs(f[1]) < 0.03
    assert depth[49:51, 49:51] == pytest.approx(1.9, abs=1e-3)  # the target's near face


def test_target_projects_where_expected(backend):
    """Column / row of a target's centre from the pinhole model with the 90 deg horizontal FOV."""
    s = _sensor(_scene(), backend)
    # a thin square facing the camera, 1 m to the right and 0.5 m above the eye, 2 m ahead
    s.set_target(_box("t", (2.0, -1.0, 1.5), (0.01, 0.2, 0.2)))
    depth, mask = s.render((0.0, 0.0, 1.0), 0.0, 0.0)
    rows, cols = np.nonzero(mask)
    # f = 50 px: column = 50 + 50 * 1 / 2, row = 50 - 50 * 0.5 / 2 (pixel centres at i + 0.5)
    assert cols.mean() + 0.5 == pytest.approx(75.0, abs=0.3)
    assert rows.mean() + 0.5 == pytest.approx(37.5, abs=0.3)
    assert cols.max() - cols.min() + 1 == pytest.approx(5, abs=1)
    assert np.all((depth[mask] > 1.994) & (depth[mask] < 2.006))


def test_occlusion(backend):
    target = _box("t", (3.0, 0.0, 1.3), (0.3, 0.3, 0.3))
    blocker = _box("blocker", (2.0, 0.0, 1.3), (0.1, 2.0, 2.0))
    eye = (0.0, 0.0, 1.3)
    hidden = _sensor(_scene(FLOOR, blocker), backend)
    hidden.set_target(target)
    depth, mask = hidden.render(eye, 0.0, 0.0)
    assert not mask.any()
    assert depth[50, 50] == pytest.approx(1.95, abs=1e-3)
    seen = _sensor(_scene(FLOOR, dataclasses.replace(WALL_X3, center=(4.05, 0.0, 1.3))), backend)
    seen.set_target(target)
    depth, mask = seen.render(eye, 0.0, 0.0)
    assert mask[48:52, 48:52].all()
    assert depth[50, 50] == pytest.approx(2.85, abs=1e-3)  # the target occludes the wall
    assert depth[40, 5] == pytest.approx(4.0, abs=1e-3)  # the wall beside it
    assert not mask[:, :30].any()
    seen.set_target(None)
    assert not seen.render(eye, 0.0, 0.0)[1].any()


def test_other_image_sizes(backend):
    s = _sensor(_scene(WALL_X3), backend, width=84, height=84)
    depth, mask = s.render((0.0, 0.0, 1.3), 0.0, 0.0)
    assert depth.shape == mask.shape == (84, 84)
    assert abs(depth - 3.0).max() < 1e-3
    s = _sensor(_scene(WALL_X3), backend, width=64, height=48)
    s.set_target(_box("t", (2.0, 0.0, 1.3), (0.2, 0.2, 0.2)))
    depth, mask = s.render((0.0, 0.0, 1.3), 0.0, 0.0)
    assert depth.shape == mask.shape == (48, 64)
    assert mask[24, 32] and not mask[0, 0]


# ----------------------------------------------------------------------------------------------
# Backends agree; a furnished room
# ----------------------------------------------------------------------------------------------


def _furnished_scene() -> Scene:
    try:
        from egosearch.scene.layouts import get_scene

        return get_scene("kitchen_living")
    except Exception:  # noqa: BLE001 - layouts not available: a room of boxes and cylinders
        rng = np.random.default_rng(0)
        parts = [FLOOR,
                 _box("ceiling", (3, 3, 2.65), (6.2, 6.2, 0.1), tags=frozenset({"ceiling"})),
                 _box("w0", (3, -0.05, 1.3), (6.2, 0.1, 2.6), tags=frozenset({TAG_WALL})),
                 _box("w1", (3, 6.05, 1.3), (6.2, 0.1, 2.6), tags=frozenset({TAG_WALL})),
                 _box("w2", (-0.05, 3, 1.3), (0.1, 6.2, 2.6), tags=frozenset({TAG_WALL})),
                 _box("w3", (6.05, 3, 1.3), (0.1, 6.2, 2.6), tags=frozenset({TAG_WALL}))]
        for i in range(40):
            h = rng.uniform(0.3, 1.5)
            parts.append(_box(f"b{i}", (rng.uniform(0.5, 5.5), rng.uniform(0.5, 5.5), h / 2),
                              tuple(rng.uniform(0.2, 0.8, 2)) + (h,), yaw=rng.uniform(0, 3)))
            d = rng.uniform(0.1, 0.5)
            parts.append(Part(f"c{i}", "cylinder", (rng.uniform(0.5, 5.5), rng.uniform(0.5, 5.5), 0.4),
                              (d, d, 0.8)))
        return Scene("room", tuple(parts), (), (0.0, 0.0, 6.0, 6.0))


@pytest.fixture(scope="module")
def furnished():
    scene = _furnished_scene()
    x0, y0, x1, y1 = scene.bounds
    target = _box("target", ((x0 + x1) / 2, (y0 + y1) / 2, 0.9), (0.25, 0.25, 0.25), color=(0.9, 0.1, 0.1))
    poses = random_poses(scene, 8, seed=1)
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    for k in range(4):  # and four poses looking at the target from 1.5 m
        a = k * math.pi / 2 + 0.3
        eye = (cx - 1.5 * math.cos(a), cy - 1.5 * math.sin(a), 1.4)
        poses.append((eye, a, math.atan2(0.9 - 1.4, 1.5)))
    return scene, target, poses


def test_backends_agree(furnished):
    scene, target, poses = furnished
    sensors = {}
    for name in BACKENDS:
        try:
            sensors[name] = DepthMaskSensor(scene, backend=name)
        except Exception:  # noqa: BLE001
            continue
    if len(sensors) < 2:
        pytest.skip("fewer than two sensor backends available")
    for s in sensors.values():
        s.set_target(target)
    ref_name = "embree" if "embree" in sensors else next(iter(sensors))
    ref = sensors[ref_name]
    seen = 0
    for pose in poses:
        d0, m0 = ref.render(*pose)
        seen += m0.any()
        for name, s in sensors.items():
            d, m = s.render(*pose)
            assert np.mean(np.abs(d - d0) > 1e-3) <= 0.002, (name, pose)  # edge pixels at most
            assert np.mean(m != m0) <= 0.002, (name, pose)
    assert seen >= 3


# ----------------------------------------------------------------------------------------------
# Where the rasteriser comes from: built at install, compiled on first use, or Embree instead
# ----------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def raster_frames(furnished):
    """The furnished poses through the rasteriser as this install loads it (before any test below
    takes it away)."""
    scene, target, poses = furnished
    fast = _sensor(scene, "raster")
    fast.set_target(target)
    return [fast.render(*pose) for pose in poses]


@pytest.fixture
def fresh_loader(monkeypatch, tmp_path):
    """The loader forgets what it loaded, and compiles on first use into an empty cache."""
    import egosearch.sim.sensor as sensor_mod

    monkeypatch.setenv("EGOSEARCH_CACHE_DIR", str(tmp_path))
    sensor_mod._load_raster_library.cache_clear()
    yield sensor_mod
    sensor_mod._load_raster_library.cache_clear()


def test_the_library_built_at_install_is_the_one_loaded(fresh_loader, tmp_path):
    from pathlib import Path

    installed = fresh_loader._installed_library()
    if installed is None:
        pytest.skip("the rasteriser was not built at install (pip install found no C compiler)")
    assert installed.parent == Path(fresh_loader.__file__).resolve().parent
    assert Path(fresh_loader._load_raster_library()._name) == installed
    assert DepthMaskSensor(_scene(WALL_X3)).backend == "raster"
    assert not list(tmp_path.iterdir())  # nothing compiled on first use


def test_a_library_built_for_another_cpu_is_not_loaded_but_compiled_anew(fresh_loader, tmp_path, monkeypatch):
    """An install shared by unlike machines: its -march=native build could stop on an illegal
    instruction, so the sensor compiles its own (when a compiler is there)."""
    import ctypes
    from pathlib import Path

    from egosearch.sim import rasterbuild
    installed = fresh_loader._installed_library()
    if installed is None or fresh_loader._find_compiler() is None:
        pytest.skip("needs the library built at install and a C compiler")
    build = fresh_loader._build_of(ctypes.CDLL(str(installed)))
    if build.endswith(f" {rasterbuild.PORTABLE}"):
        pytest.skip("the library was built portable (EGOSEARCH_NATIVE_BUILD=0): it fits any CPU")
    assert rasterbuild.usable_here(build) is None
    monkeypatch.setattr(rasterbuild, "cpu_key", lambda: "0123456789abcdef")
    assert rasterbuild.usable_here(build) == "it was tuned for another CPU (-march=native)"
    assert Path(fresh_loader._load_raster_library()._name).parent == tmp_path


def test_a_build_is_usable_only_from_this_source_and_for_this_cpu():
    from egosearch.sim import rasterbuild
    here = f"{rasterbuild.source_key()} {rasterbuild.cpu_key()}"
    assert rasterbuild.usable_here(here) is None
    assert rasterbuild.usable_here(f"{rasterbuild.source_key()} {rasterbuild.PORTABLE}") is None
    assert rasterbuild.usable_here(f"0000000000000000 {rasterbuild.PORTABLE}") == (
        "it was built from another raster.c (reinstall: pip install -e .)")
    assert rasterbuild.usable_here("unknown") is not None  # a library that does not say


def test_without_the_library_or_a_compiler_the_sensor_uses_embree_and_sees_the_same(
        furnished, raster_frames, fresh_loader, monkeypatch):
    scene, target, poses = furnished
    monkeypatch.setattr(fresh_loader, "_installed_library", lambda: None)
    monkeypatch.setattr(fresh_loader, "_find_compiler", lambda: None)
    with pytest.warns(RuntimeWarning, match=r"fell back to the 'embree' backend \(raster: not built at install; "
                                            r"no C compiler \(cc/gcc/clang\) found to build it on first use\)"):
        try:
            slow = DepthMaskSensor(scene)
        except RuntimeError as err:
            pytest.skip(f"no Embree here either: {err}")
    assert slow.backend == "embree"
    slow.set_target(target)
    # Both sample the pixel centres: they differ only on triangle edges (at most 0.2% of the pixels
    # by more than 1 mm of depth, or in the mask).
    for pose, (depth, mask) in zip(poses, raster_frames):
        slow_depth, slow_mask = slow.render(*pose)
        assert np.mean(np.abs(slow_depth - depth) > 1e-3) <= 0.002, pose
        assert np.mean(slow_mask != mask) <= 0.002, pose
    assert sum(mask.any() for _, mask in raster_frames) >= 3  # the target was in sight, so masks were compared


def test_bench_sensor_reports():
    rng = np.random.default_rng(0)
    parts = [FLOOR] + [_box(f"b{i}", (rng.uniform(-4, 4), rng.uniform(-4, 4), 0.5), (0.5, 0.5, 1.0))
                       for i in range(20)]
    out = bench_sensor(_scene(*parts), n_frames=30)
    assert out["triangles"] == 12 * 21
    assert out["sensor_frames_per_s"] > 0
    assert out["sensor_ms_per_frame"] == pytest.approx(1e3 / out["sensor_frames_per_s"])


# ----------------------------------------------------------------------------------------------
# pyrender agrees with the sensor
# ----------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def scene_renderer(furnished):
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    scene, target, _ = furnished
    try:
        from egosearch.sim.render import SceneRenderer

        renderer = SceneRenderer(scene, target=target)
        renderer.depth((1.0, 1.0, 1.0), 0.0, 0.0, width=8, height=8)  # initialises EGL
    except Exception as exc:  # noqa: BLE001
        pytest.skip(f"pyrender / EGL cannot be initialised here: {type(exc).__name__}: {exc}")
    yield renderer
    renderer.close()


def test_pyrender_depth_matches_sensor(furnished, scene_renderer):
    scene, target, poses = furnished
    sensor = DepthMaskSensor(scene)
    sensor.set_target(target)
    for pose in poses:
        d_sensor, _ = sensor.render(*pose)
        d_gl = scene_renderer.depth(*pose)
        assert d_gl.shape == (100, 100) and d_gl.dtype == np.float32
        both = (d_sensor < 4.999) & (d_gl < 4.999)
        assert both.mean() > 0.2
        diff = np.abs(d_sensor - d_gl)[both]
        assert np.median(diff) <= 0.01, pose
        assert np.mean(diff > 0.05) < 0.01, pose  # only silhouette pixels may differ


def test_pyrender_pictures(furnished, scene_renderer):
    scene, target, poses = furnished
    rgb = scene_renderer.first_person_rgb(*poses[-1], width=64, height=48)
    assert rgb.shape == (48, 64, 3) and rgb.dtype == np.uint8
    x0, y0, x1, y1 = scene.bounds
    top = scene_renderer.third_person_rgb((x0 - 1, y0 - 1, 6.0), ((x0 + x1) / 2, (y0 + y1) / 2, 0.0),
                                          width=80, height=60)
    assert top.shape == (60, 80, 3) and top.std() > 5
    from egosearch.sim.render import depth_to_colormap

    d, m = DepthMaskSensor(scene).render(*poses[0])
    m[:3, :3] = True
    pic = depth_to_colormap(d, m)
    assert pic.shape == (100, 100, 3) and pic.dtype == np.uint8
    assert tuple(pic[0, 0]) == (230, 30, 30)


def test_an_install_without_the_rasteriser_and_without_a_compiler_is_told_once(tmp_path, monkeypatch):
    """pip shows a build's warning only under -v: the first egosearch command says it instead, once."""
    from egosearch.sim import rasterbuild

    marker = tmp_path / "noted"
    monkeypatch.setattr(rasterbuild, "installed_library", lambda: None)
    monkeypatch.setattr(rasterbuild, "find_compiler", lambda: None)
    assert rasterbuild.notice_once(marker) == rasterbuild.NOT_BUILT and marker.exists()
    assert rasterbuild.notice_once(marker) is None
    monkeypatch.setattr(rasterbuild, "find_compiler", lambda: "/usr/bin/cc")  # compiles on first use: nothing to say
    assert rasterbuild.notice_once(tmp_path / "other") is None

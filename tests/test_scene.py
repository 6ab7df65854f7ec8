"""The homes as data: layouts, surfaces, placement, free-space connectivity."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest
from scipy import ndimage

from egosearch.scene import (
    LAYOUT_NAMES,
    PLACEMENT_SCHEMES,
    TAG_FLOOR,
    TAG_FURNITURE,
    TAG_LOW_CABINET_INTERIOR,
    TAG_OBSTACLE,
    TAG_TARGET,
    TAG_WALL,
    TARGET_OBJECTS,
    Part,
    Scene,
    get_object,
    get_scene,
    layouts,
    random_home,
    sample_target,
)
from egosearch.scene.furniture import TAG_WALL_CABINET_INTERIOR
from egosearch.scene.meshes import part_mesh, triangle_count
from egosearch.scene.objects import target_part
from egosearch.scene.parts import to_local
from egosearch.scene.placement import (
    PlacementError,
    eligible_surfaces,
    overlaps_obstacle,
    rests_on_support,
)

HOMES = [f"home{i}" for i in range(10)]
ALL = list(LAYOUT_NAMES) + HOMES


def _build_home(seed: int) -> Scene:
    """random_home without its cache, so reproducibility is really tested."""
    return random_home.__wrapped__(seed)


# ----------------------------------------------------------------------------------- layouts
@pytest.mark.parametrize("name, lo, hi", [("kitchen_living", (10, 7), (12, 9)), ("bedroom_bath", (8, 6), (10, 8))])
def test_layout_sizes(name, lo, hi):
    sx, sy = get_scene(name).size_xy
    assert lo[0] <= sx <= hi[0] and lo[1] <= sy <= hi[1]


@pytest.mark.parametrize("name", HOMES)
def test_random_home_size_and_name(name):
    scene = get_scene(name)
    sx, sy = scene.size_xy
    assert 8 <= sx <= 12 and 6 <= sy <= 9
    assert scene.name == name
    assert len(scene.meta["rooms"]) >= 2


@pytest.mark.parametrize("name", ALL)
def test_names_unique_and_tags(name):
    scene = get_scene(name)
    names = [p.name for p in scene.parts] + [s.name for s in scene.surfaces]
    assert len(names) == len(set(names))
    for p in scene.parts:
        if TAG_WALL in p.tags:
            assert TAG_OBSTACLE in p.tags
        elif TAG_FURNITURE in p.tags:
            assert TAG_OBSTACLE in p.tags and len(p.tags) >= 3  # + a kind tag
        else:
            assert p.name in ("floor", "ceiling") and not p.is_obstacle
    floor, ceiling = scene.part("floor"), scene.part("ceiling")
    assert TAG_FLOOR in floor.tags and floor.z_max == pytest.approx(0.0, abs=1e-12)
    assert ceiling.z_min == pytest.approx(scene.wall_height)
    assert any("floor" in s.tags for s in scene.surfaces)


def test_get_scene_errors_and_lookup():
    for bad in ("kitchen", "home", "homeX", "home-1", "Kitchen_Living", ""):
        with pytest.raises(ValueError) as err:
            get_scene(bad)
        msg = str(err.value)
        assert repr(bad) in msg and "kitchen_living, bedroom_bath, studio, home<seed>" in msg and "\n" not in msg
    assert get_scene("kitchen_living") is get_scene("kitchen_living")
    assert get_scene("home3") == _build_home(3)


def test_random_home_reproducible_and_varied():
    a, b = _build_home(5), _build_home(5)
    assert a is not b and a == b
    homes = [_build_home(s) for s in range(4)]
    assert len({(h.bounds, h.parts) for h in homes}) == 4
    assert a != _build_home(6)


#: The piece each kind of room must hold, by the prefix of its part names.
_REQUIRED = {"kitchen": "kitchen/kitchen_run0/", "kitchen + living": "kitchen/kitchen_run0/",
             "bedroom": "bedroom/bed_group0/", "study": "study/desk_group0/", "bathroom": "bathroom/sink0/"}


def _assert_valid_home(seed: int) -> Scene:
    scene = _build_home(seed)
    sx, sy = scene.size_xy
    assert scene.name == f"home{seed}" and scene.meta["seed"] == seed
    assert 8 <= sx <= 12 and 6 <= sy <= 9, f"home{seed}: {sx} x {sy} m"
    labels = [label for label, _ in scene.meta["rooms"]]
    assert len(labels) >= 2
    for label in labels:
        if label in _REQUIRED:
            assert any(p.name.startswith(_REQUIRED[label]) for p in scene.parts), f"home{seed}: {label} lacks its piece"
    assert _largest_share(_free_cells(scene)) >= 0.95, f"home{seed}: free space split"
    return scene


@pytest.mark.slow
def test_random_home_redraws_a_failed_seed():
    # Seeds 380 and 805 were the first to fail in 0..2000: their first draw leaves the
    # bedroom without a bed. They now build from the second draw, and say so.
    for seed in (380, 805):
        with pytest.raises(layouts._RequiredPieceMissing, match="required 'bedroom/bed_group0'"):
            layouts._draw_home(seed, 0)
        scene = _assert_valid_home(seed)
        assert scene.meta["attempt"] == 1
        assert scene == layouts._draw_home(seed, 1) == _build_home(seed)
    # A seed whose first draw works is the very home it always was.
    assert _build_home(3).meta["attempt"] == 0 and _build_home(3) == layouts._draw_home(3, 0)


def test_a_home_seed_must_be_a_non_negative_integer():
    for bad in (-1, 2.0, "3", True):
        with pytest.raises(ValueError, match="allowed: an integer >= 0"):
            _build_home(bad)


@pytest.mark.slow
def test_every_7th_seed_builds_a_valid_home():
    # 172 of the seeds 0-1199 (seeds 380 and 805, the redrawn ones, are checked by the test above)
    for seed in range(0, 1200, 7):
        _assert_valid_home(seed)


@pytest.mark.slow
@pytest.mark.exhaustive
def test_every_seed_builds_a_valid_home():
    # seeds 0-1199 (about 5 CPU-minutes): run it when the home generator changes
    attempts = [_assert_valid_home(seed).meta["attempt"] for seed in range(1200)]
    assert max(attempts) >= 1  # the range holds redrawn seeds (380, 805): the retry is exercised


@pytest.mark.parametrize("name", ALL)
def test_cabinet_surfaces(name):
    scene = get_scene(name)
    low = [s for s in scene.surfaces if TAG_LOW_CABINET_INTERIOR in s.tags]
    wall = [s for s in scene.surfaces if TAG_WALL_CABINET_INTERIOR in s.tags]
    need_low, need_wall = (3, 2) if name in LAYOUT_NAMES else (2, 2)
    assert len(low) >= need_low and len(wall) >= need_wall
    assert all(s.center[2] < 0.9 for s in low)
    assert all(1.3 <= s.center[2] <= 2.0 for s in wall)
    # Cabinet tops are never low-cabinet interiors.
    assert not any("cabinet_top" in s.tags and TAG_LOW_CABINET_INTERIOR in s.tags for s in scene.surfaces)


_INTERIOR = {TAG_LOW_CABINET_INTERIOR, TAG_WALL_CABINET_INTERIOR, "shelf", "lower_shelf"}


def _contains(part: Part, surface) -> bool:
    """Whether the surface rectangle lies inside the part's footprint."""
    from egosearch.scene.parts import rectangle_corners

    for c in rectangle_corners(surface.center[:2], surface.size, surface.yaw):
        lx, ly = to_local(c, part.center[:2], part.yaw)
        if part.shape == "cylinder":
            if math.hypot(lx, ly) > part.size[0] / 2 + 1e-9:
                return False
        elif abs(lx) > part.size[0] / 2 + 1e-9 or abs(ly) > part.size[1] / 2 + 1e-9:
            return False
    return True


@pytest.mark.parametrize("name", ALL)
def test_surfaces_lie_on_a_part_top(name):
    scene = get_scene(name)
    obstacles = scene.obstacles
    boxes = _aabbs(obstacles)
    for s in scene.surfaces:
        if "floor" in s.tags:
            assert s.center[2] == 0.0
            continue
        under = [p for p in obstacles if abs(p.z_max - s.center[2]) < 1e-9 and _contains(p, s)]
        assert under, f"{s.name} does not lie on a part"
        if s.tags & _INTERIOR:
            # The board (or top) above closes it exactly at the clearance...
            above = [p for p in obstacles if abs(p.z_min - (s.center[2] + s.clearance)) < 1e-6
                     and _contains(p, s)]
            assert above, f"{s.name}: nothing at its clearance {s.clearance:.3f}"
            # ...and nothing but what rests on it (books) cuts the free space in between.
            vol = Part("probe", "box", (*s.center[:2], s.center[2] + s.clearance / 2),
                       (*s.size, s.clearance - 2e-3), s.yaw)
            cut = [n for n in _hits(vol, obstacles, boxes) if abs(scene.part(n).z_min - s.center[2]) > 1e-9]
            assert not cut, f"{cut} cut into {s.name}"


@pytest.mark.parametrize("yaw", [0.0, math.pi / 2, 0.4])
def test_builders_at_any_yaw(yaw):
    from egosearch.scene import furniture as F

    builds = [
        F.open_cabinet("c", 1, 2, yaw, n_boards=2), F.wall_cabinet("w", 1, 2, yaw), F.bookshelf("b", 1, 2, yaw),
        F.counter("k", 1, 2, yaw, sink_at=-0.5, cooktop_at=0.6), F.kitchen_island("i", 1, 2, yaw),
        F.table("t", 1, 2, yaw), F.coffee_table("ct", 1, 2, yaw), F.chair("ch", 1, 2, yaw),
        F.sofa("s", 1, 2, yaw), F.bed("bd", 1, 2, yaw), F.nightstand("n", 1, 2, yaw),
        F.tv_stand("tv", 1, 2, yaw), F.desk("d", 1, 2, yaw), F.sink_cabinet("sk", 1, 2, yaw),
        F.toilet("to", 1, 2, yaw), F.bathtub("ba", 1, 2, yaw), F.wardrobe("wd", 1, 2, yaw),
        F.shelf_unit("sh", 1, 2, yaw), F.round_table("r", 1, 2),
    ]
    for parts, surfaces in builds:
        assert parts and all(TAG_OBSTACLE in p.tags and TAG_FURNITURE in p.tags for p in parts)
        for s in surfaces:
            assert any(abs(p.z_max - s.center[2]) < 1e-9 and _contains(p, s) for p in parts), s.name
    # The open front faces local -y: a cabinet against the north wall (yaw 0) opens to the south.
    parts, _ = F.open_cabinet("c", 0, 0, 0.0, width=1.0, depth=0.4)
    back = next(p for p in parts if p.name == "c/back")
    assert back.center[1] > 0.15
    parts, _ = F.wall("w", (0, 0), (4, 0), gaps=[(1.0, 0.9)])
    segs = sorted((p for p in parts if "lintel" not in p.tags), key=lambda p: p.center[0])
    assert [round(p.size[0], 6) for p in segs] == [1.0, 2.1]


def test_kitchen_living_triangles():
    assert 3_000 <= triangle_count(get_scene("kitchen_living")) <= 30_000


def _footprint_overlaps(a: Part, b: Part, shrink: float = 1e-3) -> bool:
    """Independent of placement.py: sample a's footprint on a grid and look inside b."""
    if not (a.z_min < b.z_max - 1e-6 and b.z_min < a.z_max - 1e-6):
        return False
    hx, hy = a.size[0] / 2 - shrink, a.size[1] / 2 - shrink
    u, v = np.meshgrid(np.linspace(-hx, hx, 7), np.linspace(-hy, hy, 7))
    c, s = math.cos(a.yaw), math.sin(a.yaw)
    wx, wy = a.center[0] + c * u - s * v, a.center[1] + s * u + c * v
    lx, ly = to_local((wx, wy), b.center[:2], b.yaw)
    return bool(np.any((np.abs(lx) < b.size[0] / 2) & (np.abs(ly) < b.size[1] / 2)))


def _aabbs(parts) -> np.ndarray:
    return np.array([[*np.min(p.footprint_corners(), 0), *np.max(p.footprint_corners(), 0), p.z_min, p.z_max]
                     for p in parts])


def _near(box: np.ndarray, boxes: np.ndarray, tol: float = 1e-6) -> np.ndarray:
    """Indices of boxes whose AABB overlaps ``box`` by more than ``tol``."""
    return np.nonzero((boxes[:, 0] < box[2] - tol) & (boxes[:, 2] > box[0] + tol) & (boxes[:, 1] < box[3] - tol)
                      & (boxes[:, 3] > box[1] + tol) & (boxes[:, 4] < box[5] - tol) & (boxes[:, 5] > box[4] + tol))[0]


def _hits(part: Part, obstacles, boxes, shrink: float = 1e-3) -> list[str]:
    near = _near(_aabbs([part])[0], boxes)
    return [obstacles[j].name for j in near if _footprint_overlaps(part, obstacles[j], shrink)]


def test_furniture_pieces_do_not_overlap_each_other():
    def group(n):
        return "/".join(n.split("/")[:2])

    for name in ALL:
        obstacles = get_scene(name).obstacles
        boxes = _aabbs(obstacles)
        for i, a in enumerate(obstacles):
            for j in _near(boxes[i], boxes, 2e-3):
                b = obstacles[j]
                assert group(a.name) == group(b.name) or not _footprint_overlaps(a, b, 2e-3), \
                    f"{name}: {a.name} overlaps {b.name}"


# ----------------------------------------------------------------------------------- objects
def test_objects():
    assert {"mustard_bottle", "glasses_case", "mug", "remote", "duck", "teddy"} <= set(TARGET_OBJECTS)
    assert get_object("mug").size[1] == pytest.approx(0.12)
    assert get_object("mug").size[2] == pytest.approx(0.1, abs=0.01)
    assert get_object("teddy").size[1] == pytest.approx(0.25)
    with pytest.raises(ValueError, match="allowed: .*mustard_bottle"):
        get_object("banana")
    for obj in TARGET_OBJECTS.values():
        part = target_part(obj, 1.0, 2.0, 0.75, 0.3)
        assert part.name == "target" and part.tags == {TAG_TARGET}
        assert part.z_min == pytest.approx(0.75) and part.size == tuple(obj.size)
        if obj.shape == "mesh":  # the drawn mesh is exactly `size`
            upright = part_mesh(target_part(obj, 0.0, 0.0, 0.0, 0.0))
            np.testing.assert_allclose(upright.extents, obj.size, atol=1e-9)
            np.testing.assert_allclose(upright.bounds[0][2], 0.0, atol=1e-9)


# ----------------------------------------------------------------------------------- placement
def test_placement_helpers():
    scene = get_scene("kitchen_living")
    mug = get_object("mug")
    table = scene.part("dining/table/top")
    on_table = target_part(mug, table.center[0], table.center[1], table.z_max)
    assert not overlaps_obstacle(scene, on_table)
    assert rests_on_support(scene, on_table).name == "dining/table/top_surface"
    floating = target_part(mug, table.center[0], table.center[1], table.z_max + 0.05)
    assert rests_on_support(scene, floating) is None
    inside_top = target_part(mug, table.center[0], table.center[1], table.z_max - 0.02)
    assert overlaps_obstacle(scene, inside_top)
    leg = scene.part("dining/table/leg0")
    at_leg = target_part(mug, leg.center[0] + 0.05, leg.center[1] + 0.05, 0.0, 0.7)
    assert overlaps_obstacle(scene, at_leg) and rests_on_support(scene, at_leg) is not None
    with pytest.raises(ValueError, match="placement scheme='cabinets'; allowed: no_low_cabinets, everywhere"):
        eligible_surfaces(scene, "cabinets")
    with pytest.raises(ValueError, match="allowed: no_low_cabinets, everywhere"):
        sample_target(scene, mug, "nowhere", np.random.default_rng(0))
    tall = type(mug)("pole", "box", (0.1, 0.1, 3.0))
    with pytest.raises(PlacementError):
        sample_target(scene, tall, "everywhere", np.random.default_rng(0))


@pytest.mark.parametrize("name", LAYOUT_NAMES)
@pytest.mark.parametrize("scheme", PLACEMENT_SCHEMES)
def test_sampled_targets_rest_and_do_not_collide(name, scheme):
    scene = get_scene(name)
    rng = np.random.default_rng(1234)
    objs = list(TARGET_OBJECTS.values())
    obstacles = scene.obstacles
    boxes = _aabbs(obstacles)
    n_low = 0
    for k in range(200):
        obj = objs[k % len(objs)]
        part = sample_target(scene, obj, scheme, rng)
        surface = rests_on_support(scene, part)
        assert surface is not None
        assert part.z_min == pytest.approx(surface.center[2], abs=1e-9)
        assert part.z_max <= surface.center[2] + surface.clearance + 1e-9
        assert not overlaps_obstacle(scene, part)
        assert not _hits(part, obstacles, boxes)
        n_low += TAG_LOW_CABINET_INTERIOR in surface.tags
    if scheme == "no_low_cabinets":
        assert n_low == 0
    else:
        assert n_low >= 1


def test_sampling_is_seeded():
    scene = get_scene("bedroom_bath")
    obj = get_object("remote")
    a = [sample_target(scene, obj, "everywhere", np.random.default_rng(7)) for _ in range(2)]
    assert a[0] == a[1]
    assert a[0] != sample_target(scene, obj, "everywhere", np.random.default_rng(8))


# ----------------------------------------------------------------------------------- free space
def _free_cells(scene: Scene, radius: float = 0.2, res: float = 0.05, z_top: float = 1.8) -> np.ndarray:
    x0, y0, x1, y1 = scene.bounds
    xs = np.arange(x0 + res / 2, x1, res)
    ys = np.arange(y0 + res / 2, y1, res)
    gx, gy = np.meshgrid(xs, ys)
    free = np.ones(gx.shape, dtype=bool)
    for p in scene.obstacles:
        if p.z_min >= z_top:
            continue
        lx, ly = to_local((gx, gy), p.center[:2], p.yaw)
        dx = np.maximum(np.abs(lx) - p.size[0] / 2, 0.0)
        dy = np.maximum(np.abs(ly) - p.size[1] / 2, 0.0)
        free &= np.hypot(dx, dy) > radius
    return free


def _largest_share(free: np.ndarray) -> float:
    labels, n = ndimage.label(free)
    counts = np.bincount(labels.ravel())[1:]
    return counts.max() / counts.sum() if n else 0.0


@pytest.mark.parametrize("name", ALL)
def test_free_space_is_connected(name):
    scene = get_scene(name)
    free = _free_cells(scene)
    assert free.mean() > 0.3  # not trivially connected by being nearly all blocked
    assert _largest_share(free) >= 0.95


def test_connectivity_check_can_fail():
    scene = get_scene("bedroom_bath")
    x0, y0, x1, y1 = scene.bounds
    blocker = Part("blocker", "box", ((x0 + x1) / 2, (y0 + y1) / 2, 1.0), (0.1, y1 - y0, 2.0),
                   tags=frozenset({TAG_OBSTACLE, TAG_WALL}))
    assert _largest_share(_free_cells(scene.with_parts((blocker,)))) < 0.95


def test_topdown_smoke():
    from egosearch.scene.topdown import plot_topdown

    scene = get_scene("bedroom_bath")
    target = sample_target(scene, get_object("mug"), "everywhere", np.random.default_rng(0))
    fig = plot_topdown(scene, targets=[target], starts=[(1.0, 1.0, 0.5)])
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=40)
    assert buf.tell() > 1000


@pytest.mark.parametrize("layout", ["kitchen_living", "bedroom_bath"])
def test_everywhere_puts_a_real_share_inside_low_cabinets(layout):
    """Pieces are drawn uniformly, so the floor does not swallow the cabinets (area weighting
    would put only 4-9% of targets inside low cabinets)."""
    from egosearch.scene.placement import piece_of

    scene = get_scene(layout)
    rng = np.random.default_rng(7)
    names = sorted(TARGET_OBJECTS)
    low = floor = 0
    for i in range(300):
        surface = rests_on_support(scene, sample_target(scene, get_object(names[i % len(names)]), "everywhere", rng))
        low += TAG_LOW_CABINET_INTERIOR in surface.tags
        floor += piece_of(surface).startswith("floor/")
    assert 0.10 <= low / 300 <= 0.35
    assert floor / 300 <= 0.3


def test_studio_is_small_connected_and_named():
    from egosearch.sim.body import AgentSpec
    from egosearch.sim.navgrid import NavGrid

    scene = get_scene("studio")
    assert scene.size_xy == (4.5, 4.0)
    nav = NavGrid(scene, AgentSpec())
    assert nav.main_region.sum() >= 0.95 * nav.free.sum() > 0

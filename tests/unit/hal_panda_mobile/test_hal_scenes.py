"""Scenes as data: built-ins, from_map, random, ground-truth grid, and errors that name the field."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import yaml

from hal_panda_mobile.files import available_scenes, load_robot_description, load_scene, robot_from_dict
from hal_panda_mobile.sim import OdomNoise, PandaMobileSim, SimConfigError
from hal_panda_mobile.sim.raster import rasterize, reachable
from hal_panda_mobile.sim.scene import first_collision
from hal_panda_mobile.sim.worldgen import MIN_ROOMS, ROBOT_CLEAR_RADIUS, _room_grid
from rbnx.demo.goals import choose_goals
from robonix_api.mapfile import save_map_yaml
from robonix_common.grid import FREE, OCCUPIED, GridMap, merge_cells

from .conftest import make_sim, ray_distances, room

BUILTIN = ["apartment", "office", "warehouse", "kitchen"]


@pytest.mark.parametrize("name", BUILTIN)
def test_builtin_scene_loads_free_start_reachable_waypoints(robot, name):
    scene = load_scene(name)
    assert name in available_scenes()
    xmin, ymin, xmax, ymax = scene.bounds
    assert 8 <= max(xmax - xmin, ymax - ymin) <= 20
    assert first_collision(robot, scene.obstacles(), *scene.start, clearance=0.05) is None
    # doorways/corridors let the base through: every waypoint connects to the start in free space
    # inflated by the base's half-width + margin
    grid = rasterize(scene.obstacles(), scene.bounds, 0.05, inflate=ROBOT_CLEAR_RADIUS, overlap=False)
    assert len(scene.waypoints) >= 3
    assert all(reachable(grid, scene.start[:2], list(scene.waypoints.values())))
    PandaMobileSim(robot, scene)


def test_outer_walls_are_closed(robot):
    """No beam escapes: from every waypoint of every built-in scene all 360 beams of a long-range lidar
    return (the stock 12 m lidar legitimately sees nothing down a 16 m corridor)."""
    data = dataclasses.asdict(robot)
    data["lidar"]["range_max"] = 40.0
    long_range = robot_from_dict(data)
    for name in BUILTIN:
        scene = load_scene(name)
        sim = PandaMobileSim(long_range, scene)
        for x, y in scene.waypoints.values():
            sim.teleport(x, y, 0.0)
            assert np.all(np.isfinite(sim.scan().ranges)), name


@pytest.mark.parametrize("seed", [0, 1, 7, 42])
def test_random_scene_seeded_and_valid(robot, seed):
    a, b = load_scene(f"random:{seed}"), load_scene({"random": {"seed": seed}})
    assert a == b
    assert load_scene(f"random:{seed + 100}") != a
    grid = rasterize(a.obstacles(), a.bounds, 0.05, inflate=ROBOT_CLEAR_RADIUS - 0.05, overlap=False)
    assert all(reachable(grid, a.start[:2], list(a.waypoints.values())))
    PandaMobileSim(robot, a)  # start free, compiles


def test_random_scenes_1_to_50_all_have_rooms_to_drive_to(robot):
    """Every generated scene is a usable demo: >= MIN_ROOMS room centres, one farther than 1 m from the start,
    all reachable from the start with the base's clearance, and five goals for `rbnx demo --goals 5`."""
    for seed in range(1, 51):
        scene = load_scene(f"random:{seed}", robot=robot)
        assert len(scene.waypoints) >= MIN_ROOMS, seed
        far = [p for p in scene.waypoints.values() if math.dist(p, scene.start[:2]) > 1.0]
        assert far, seed
        grid = rasterize(scene.obstacles(), scene.bounds, 0.05, inflate=ROBOT_CLEAR_RADIUS - 0.05, overlap=False)
        assert all(reachable(grid, scene.start[:2], list(scene.waypoints.values()))), seed
        # what `rbnx demo --scene random:N --goals 5` will drive: five goals, none within 1 m of the robot
        assert len(choose_goals(dict(scene.waypoints), scene.start[:2], 5, None, 1.0)) == 5, seed


def test_one_room_draw_is_redrawn_and_two_room_seeds_keep_their_world(robot):
    """random:1's first room-grid draw is a single room: the scene comes from a re-draw (same every time);
    random:2's first draw already has rooms, so its world is the first draw's, as before the re-draw rule."""
    _, _, xs, ys = _room_grid(np.random.default_rng(1))
    assert (len(xs) - 1) * (len(ys) - 1) == 1
    one = load_scene("random:1", robot=robot)
    assert len(one.waypoints) >= MIN_ROOMS
    assert one == load_scene("random:1", robot=robot)
    w, h, xs, ys = _room_grid(np.random.default_rng(2))
    assert (len(xs) - 1) * (len(ys) - 1) >= MIN_ROOMS
    assert load_scene("random:2", robot=robot).bounds == (0.0, 0.0, w, h)


def test_merge_cells_covers_exactly():
    rng = np.random.default_rng(0)
    occ = rng.random((40, 30)) < 0.3
    occ[5:15, 3:9] = True
    rebuilt = np.zeros_like(occ)
    rects = merge_cells(occ)
    for r0, r1, c0, c1 in rects:
        assert not rebuilt[r0:r1, c0:c1].any()  # no overlaps
        rebuilt[r0:r1, c0:c1] = True
    assert np.array_equal(rebuilt, occ)
    assert len(rects) < occ.sum()


def _write_map(tmp_path) -> str:
    """4 x 3 m map at 5 cm: a 2-cell border and a block; origin (-2, -1.5)."""
    data = np.full((60, 80), FREE, dtype=np.int8)
    data[:2, :] = data[-2:, :] = OCCUPIED
    data[:, :2] = data[:, -2:] = OCCUPIED
    data[20:30, 50:60] = OCCUPIED  # x in [0.5, 1.0], y in [-0.5, 0.0]
    return str(save_map_yaml(GridMap(data, 0.05, -2.0, -1.5), tmp_path / "small_map.yaml"))


def test_from_map_scan_matches_map_walls(robot, tmp_path):
    path = _write_map(tmp_path)
    scene = load_scene({"from_map": path, "start": [-0.5, 0.3, 0.7]})
    assert len(scene.boxes) <= 8  # row-run merging, not one box per cell
    sim = PandaMobileSim(robot, scene)
    scan = sim.scan()
    rects = [(0.0, -1.45, 4.0, 0.1, 0.0), (0.0, 1.45, 4.0, 0.1, 0.0), (-1.95, 0.0, 0.1, 3.0, 0.0),
             (1.95, 0.0, 0.1, 3.0, 0.0), (0.75, -0.25, 0.5, 0.5, 0.0)]
    expected = ray_distances((-0.5, 0.3), 0.7 + scan.angles(), rects, [])
    assert np.max(np.abs(scan.ranges - expected)) < 0.01
    # without a start pose the generator picks the free cell farthest from the walls
    auto = load_scene(path)
    assert first_collision(robot, auto.obstacles(), *auto.start, clearance=0.1) is None
    # a scene YAML may point at a map relative to itself
    (tmp_path / "world.yaml").write_text(yaml.safe_dump({"from_map": "small_map.yaml", "wall_height": 0.8}))
    assert load_scene(tmp_path / "world.yaml").boxes[0].height == 0.8


def test_ground_truth_grid_matches_scene(robot):
    sim = make_sim(robot, room(boxes=[{"center": [1.0, 1.0], "size": [1.0, 0.5], "height": 0.5}]))
    g = sim.ground_truth_grid(0.05)
    assert (g.width, g.height) == (160, 120)
    assert (g.origin_x, g.origin_y) == (-4.0, -3.0)

    def at(x, y):
        c, r = g.world_to_cell(x, y)
        return int(g.data[r, c])

    assert at(0.0, 0.0) == FREE
    assert at(1.0, 1.0) == OCCUPIED
    assert at(-3.95, 0.0) == OCCUPIED
    assert at(1.6, 1.0) == FREE
    low = sim.ground_truth_grid(0.05, min_height=0.6)  # the 0.5 m box is below a 0.6 m plane
    c, r = low.world_to_cell(1.0, 1.0)
    assert low.data[r, c] == FREE
    assert sim.scene_info()["name"] == "test_room"


# ---------------------------------------------------------------- errors name the field
def test_unknown_scene_lists_available():
    with pytest.raises(SimConfigError) as exc:
        load_scene("castle")
    assert "castle" in str(exc.value)
    assert all(n in str(exc.value) for n in BUILTIN)


def test_malformed_yaml(tmp_path):
    p = tmp_path / "bad.yaml"
    p.write_text("name: x\nwalls: [ {start: [0, 0]\n")
    with pytest.raises(SimConfigError, match="malformed YAML"):
        load_scene(p)


def test_bad_wall_thickness_names_field():
    scene = room()
    scene["walls"][3]["thickness"] = -0.1
    with pytest.raises(SimConfigError, match=r"walls\[3\]\.thickness: must be > 0"):
        load_scene(scene)


@pytest.mark.parametrize(("patch", "field"), [
    ({"bounds": [0, 0, -1, 5]}, "bounds"),
    ({"boxes": [{"center": [1, 1], "size": [0, 1]}]}, r"boxes\[0\]\.size"),
    ({"cylinders": [{"center": [1, 1], "radius": 0.2, "hieght": 1}]}, r"cylinders\[0\]\.hieght: unknown field"),
    ({"start": [9.0, 0.0]}, "outside bounds"),
])
def test_scene_validation_names_field(patch, field):
    with pytest.raises(SimConfigError, match=field):
        load_scene({**room(), **patch})


def test_start_in_collision_names_obstacle():
    with pytest.raises(SimConfigError, match=r"start: .*boxes\[0\] 'sofa'"):
        load_scene(room(boxes=[{"center": [0.3, 0.0], "size": [1.0, 1.0], "name": "sofa"}]))
    with pytest.raises(SimConfigError, match=r"walls\[1\]"):
        load_scene("apartment", start=[11.95, 5.0, 0.0])


def test_negative_rates_name_field(robot):
    scene = load_scene(room())
    with pytest.raises(SimConfigError, match=r"^sim: odom_rate_hz: must be within \(0, 1000\], got -5$"):
        PandaMobileSim(robot, scene, odom_rate_hz=-5.0)
    with pytest.raises(SimConfigError, match=r"v_scale_std: must be >= 0"):
        PandaMobileSim(robot, scene, odom_noise=OdomNoise(v_scale_std=-1))
    with pytest.raises(SimConfigError, match="timestep"):
        PandaMobileSim(robot, scene, timestep=0.01)  # below 500 Hz
    data = dataclasses.asdict(robot)
    data["lidar"]["rate_hz"] = -10
    with pytest.raises(SimConfigError, match=r"lidar\.rate_hz: must be > 0"):
        robot_from_dict(data)


def test_from_map_missing_file(tmp_path):
    with pytest.raises(SimConfigError, match="from_map"):
        load_scene({"from_map": str(tmp_path / "nope.yaml")})


def test_robot_description_is_the_repo_config():
    r = load_robot_description()
    assert r.footprint_box == (0.0, 0.0, 0.7, 0.5)
    assert r.lidar.beams == 360
    assert math.isclose(r.limits.max_wz, 1.9)

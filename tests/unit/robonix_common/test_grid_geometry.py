"""Shared grid and SE(2) helpers: map files round-trip, conventions hold."""

import math

import numpy as np
import pytest

from robonix_api.mapfile import MapFileError, load_map_yaml, save_map_yaml
from robonix_common.geometry import compose, inverse, quat_to_yaw, relative, wrap_angle, yaw_to_quat
from robonix_common.grid import GridMap


def test_map_roundtrip_keeps_rows_and_values(tmp_path):
    data = np.full((4, 6), -1, dtype=np.int8)
    data[0, :] = 0
    data[3, 5] = 100
    g = GridMap(data, 0.05, origin_x=-1.0, origin_y=2.0)
    path = save_map_yaml(g, tmp_path / "m.yaml")
    back = load_map_yaml(path)
    assert back.data.tolist() == data.tolist()
    assert (back.resolution, back.origin_x, back.origin_y) == (0.05, -1.0, 2.0)
    # The PGM's first row is the top of the map: the occupied cell (row 3) is in image row 0.
    raw = (tmp_path / "m.pgm").read_bytes()
    assert raw.startswith(b"P5")
    assert raw[-(4 * 6) + 5] == 0


def test_world_cell_conversions():
    g = GridMap(np.zeros((10, 20), np.int8), 0.5, origin_x=-5.0, origin_y=-2.5)
    col, row = g.world_to_cell(0.1, 0.1)
    assert (int(col), int(row)) == (10, 5)
    x, y = g.cell_to_world(col, row)
    assert math.isclose(float(x), 0.25)
    assert math.isclose(float(y), 0.25)


def test_bad_map_files_name_the_problem(tmp_path):
    p = tmp_path / "bad.yaml"
    p.write_text("image: x.pgm\nresolution: 0.05\n")
    with pytest.raises(MapFileError, match="origin"):
        load_map_yaml(p)
    p.write_text("image: missing.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n")
    with pytest.raises(MapFileError, match="cannot read image"):
        load_map_yaml(p)


def test_se2_compose_inverse():
    a = np.array([1.0, 2.0, 0.7])
    b = np.array([-0.3, 0.5, -2.0])
    assert np.allclose(compose(a, inverse(a)), 0.0, atol=1e-12)
    assert np.allclose(relative(a, compose(a, b)), b)
    assert math.isclose(quat_to_yaw(*yaw_to_quat(2.5)), 2.5)
    assert math.isclose(wrap_angle(3 * math.pi), -math.pi)

"""Issue 37 abuse cases at the file and JSON boundaries, in-process (no servers): a Driver's config_json
with NaN, a nav2 ``params_file`` of /dev/zero or a huge file, and hostile map YAMLs (NaN origin,
resolution 1e-300, decompression bombs, images or map folders outside the maps root). Each was accepted
(or crashed with a TypeError / MemoryError, answered INTERNAL) before the fix."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest

from robonix_api.driver import parse_config_json
from robonix_api.mapfile import MapFileError, load_map_yaml, save_map_yaml
from robonix_common.grid import GridMap
from slam_service.maps import MapStore, MapStoreError

# ----------------------------------------------------------------------------- item 5: config_json


@pytest.mark.parametrize(("text", "field"), [
    ('{"x": NaN}', "x"), ('{"a": {"b": [1, Infinity]}}', "a.b[1]"), ('{"speed": 1e999}', "speed"),
    ('{"speed": -Infinity}', "speed"),
])
def test_config_json_refuses_non_finite_numbers_naming_the_field(text: str, field: str) -> None:
    with pytest.raises(ValueError, match="^config_json: " + re.escape(field) + ": must be a finite number"):
        parse_config_json(text)
    assert parse_config_json('{"x": 1.5, "y": [1, 2e300]}') == {"x": 1.5, "y": [1, 2e300]}


# ----------------------------------------------------------------------------- item 6: params_file


def _nav_cfg(params_file: str):
    from nav2_wrapper.config import parse_config

    return parse_config({"params_file": params_file})


def test_params_file_dev_zero_is_refused_before_reading() -> None:
    with pytest.raises(ValueError, match=r"^params_file: .*(outside the allowed folders|not a regular file)"):
        _nav_cfg("/dev/zero").params_text()


def test_params_file_must_be_a_small_regular_file_under_an_allowed_root(tmp_path: Path,
                                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    from nav2_wrapper.config import PARAMS_MAX_BYTES, PARAMS_ROOTS_ENV

    outside = tmp_path / "outside.yaml"
    outside.write_text("controller_server: {}\n")
    with pytest.raises(ValueError, match=r"^params_file: .*outside the allowed folders"):
        _nav_cfg(str(outside)).params_text()
    allowed = tmp_path / "allowed"
    allowed.mkdir()
    monkeypatch.setenv(PARAMS_ROOTS_ENV, str(allowed))
    ok = allowed / "nav.yaml"
    ok.write_text("controller_server: {}\n")
    assert _nav_cfg(str(ok)).params_text() == "controller_server: {}\n"
    huge = allowed / "huge.yaml"
    with open(huge, "wb") as fh:  # sparse: the size is what counts, nothing is read
        fh.truncate(4 * 1024**3)
    with pytest.raises(ValueError, match=rf"^params_file: .* is {4 * 1024**3} bytes, more than the {PARAMS_MAX_BYTES}"):
        _nav_cfg(str(huge)).params_text()
    (allowed / "zero").symlink_to("/dev/zero")  # a link inside the root leading out of it
    with pytest.raises(ValueError, match=r"^params_file: .*outside the allowed folders"):
        _nav_cfg(str(allowed / "zero")).params_text()
    fifo = allowed / "fifo.yaml"
    os.mkfifo(fifo)
    with pytest.raises(ValueError, match=r"^params_file: .*not a regular file"):
        _nav_cfg(str(fifo)).params_text()


# ----------------------------------------------------------------------------- item 7: maps


def _saved(root: Path, map_id: str = "m") -> Path:
    store = MapStore(root)
    data = np.zeros((20, 30), np.int8)
    store.save(map_id, GridMap(data, 0.05, -1.0, -0.5), None, "")
    return root / map_id


def _rewrite(yaml_path: Path, old: str, new: str) -> None:
    text = yaml_path.read_text()
    assert old in text, text
    yaml_path.write_text(text.replace(old, new))


@pytest.mark.parametrize(("old", "new", "field"), [
    ("- -1.0\n", "- .nan\n", r"origin\[0\]: must be a finite number"),
    ("- -0.5\n", "- .inf\n", r"origin\[1\]: must be a finite number"),
    ("resolution: 0.05", "resolution: 1.0e-300", "resolution: must be"),
    ("resolution: 0.05", "resolution: .nan", "resolution: must be a finite number"),
    ("resolution: 0.05", "resolution: [1]", "resolution: must be a number"),
    ("image: map.pgm", "image: ../../outside.pgm", "image: .*outside the map folder"),
    ("image: map.pgm", "image: /etc/hostname", "image: .*outside the map folder"),
])
def test_bad_map_yaml_values_are_refused_naming_the_key(tmp_path: Path, old: str, new: str, field: str) -> None:
    folder = _saved(tmp_path)
    save_map_yaml(GridMap(np.zeros((4, 4), np.int8), 0.05), tmp_path.parent / "outside.yaml")
    _rewrite(folder / "map.yaml", old, new)
    with pytest.raises(MapStoreError, match=field):
        MapStore(tmp_path).load("m", with_session=False)


def _pgm_header(path: Path, w: int, h: int) -> None:
    path.write_bytes(f"P5\n{w} {h}\n255\n".encode() + b"\0" * 64)  # claims w*h pixels, holds 64


def test_decompression_bombs_are_refused_from_the_header(tmp_path: Path) -> None:
    import zlib

    from robonix_api.mapfile import MAX_PIXELS

    folder = _saved(tmp_path)
    _pgm_header(folder / "map.pgm", 100_000, 100_000)
    with pytest.raises(MapStoreError, match=r"image: .*(100000x100000 pixels|decompression bomb)"):
        MapStore(tmp_path).load("m", with_session=False)
    # a PNG of 8000 x 8000 grey pixels (under Pillow's own bomb limit) is ~64 kB of compressed zeros
    import struct

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    w = h = 8_000
    raw = zlib.compress(b"\0" * ((w + 1) * h), 9)
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)) + \
        chunk(b"IDAT", raw) + chunk(b"IEND", b"")
    (folder / "map.png").write_bytes(png)
    _rewrite(folder / "map.yaml", "image: map.pgm", "image: map.png")
    with pytest.raises(MapStoreError, match=rf"image: map.png is 8000x8000 pixels, more than the {MAX_PIXELS}"):
        MapStore(tmp_path).load("m", with_session=False)


def test_symlinked_map_folder_and_oversized_yaml_are_refused(tmp_path: Path) -> None:
    root, elsewhere = tmp_path / "root", tmp_path / "elsewhere"
    root.mkdir()
    _saved(elsewhere, "real")
    (root / "linked").symlink_to(elsewhere / "real", target_is_directory=True)
    with pytest.raises(MapStoreError, match=r"^map_id: .*symbolic link"):
        MapStore(root).load("linked", with_session=False)
    folder = _saved(root)
    (folder / "map.yaml").unlink()
    (folder / "map.yaml").symlink_to("/dev/zero")
    with pytest.raises(MapFileError, match="not a regular file"):
        load_map_yaml(folder / "map.yaml")
    (folder / "map.yaml").unlink()
    with open(folder / "map.yaml", "wb") as fh:
        fh.truncate(1 << 30)
    with pytest.raises(MapFileError, match="more than the"):
        load_map_yaml(folder / "map.yaml")


def test_robot_description_dev_zero_is_refused_before_reading() -> None:
    from nav2_wrapper.robot_io import RobotDescriptionError, load_robot

    with pytest.raises(RobotDescriptionError, match="not a regular file"):
        load_robot("/dev/zero")

"""Map store and config, without processes: ids, atomic saves that never leave a mixed map, field-named errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robonix_api.mapfile import load_map_yaml
from robonix_common.grid import GridMap
from slam_service.config import ConfigError, load_footprint, parse_config
from slam_service.maps import MapIdError, MapStore, MapStoreError, check_id


def _grid(v: int) -> GridMap:
    data = np.full((20, 30), -1, dtype=np.int8)
    data[5:15, 5:25] = v
    return GridMap(data, 0.05, -1.0, -0.5)


@pytest.mark.parametrize("bad", ["", "../x", "a/b", "..", ".hidden", "x" * 65, "a\\b", "a b", "ok\n"])
def test_map_ids_are_plain_names(bad: str) -> None:
    with pytest.raises(MapIdError, match="map_id"):
        check_id(bad)
    assert check_id("room_1.v2-final") == "room_1.v2-final"


def _visible(folder: Path) -> list[str]:
    """Entries except the store's lock file (staging folders are hidden but must not be left behind)."""
    return sorted(p.name for p in folder.iterdir() if p.name != ".robonix-maps.lock")


def test_failed_save_keeps_the_previous_map_and_leaves_no_staging(tmp_path: Path) -> None:
    store = MapStore(tmp_path)
    store.save("m", _grid(0), None, "first")
    before = {p.name: p.read_bytes() for p in (tmp_path / "m").iterdir()}

    def broken_session(path: Path) -> None:
        raise OSError(28, "No space left on device")

    with pytest.raises(MapStoreError, match="No space left"):
        store.save("m", _grid(100), broken_session, "second")
    assert {p.name: p.read_bytes() for p in (tmp_path / "m").iterdir()} == before
    assert _visible(tmp_path) == ["m"]
    assert np.count_nonzero(load_map_yaml(tmp_path / "m" / "map.yaml").data == 0) == 200
    store.save("m", _grid(100), None, "third")  # overwrite swaps the folder in whole
    assert store.list()[0]["note"] == "third"
    assert _visible(tmp_path) == ["m"]
    store.delete("m")
    with pytest.raises(MapStoreError, match="no map 'm'"):
        store.load("m", with_session=False)


def test_config_defaults_and_errors(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("ROBONIX_MAP_DIR", str(tmp_path))
    cfg, slam = parse_config({})
    assert (cfg.mode, cfg.map_dir, cfg.frames.base, cfg.use_sim_time, cfg.map_publish_period_s) == \
        ("mapping", str(tmp_path), "base_link", True, 1.0)
    assert slam.resolution == 0.05
    for raw, field in (({"slam": {"nope": 1}}, "nope"), ({"topic_remap": {"scan": "a b"}}, "topic_remap.scan"),
                       ({"mode": "localization"}, "mode"), ({"initial_pose": {"x": 1, "y": 2}}, "initial_pose"),
                       ({"tf_period_s": 0.5}, "tf_period_s"), ({"provider_ids": {"lidar": "x"}}, "provider_ids.lidar")):
        with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
            parse_config(raw)
    assert len(load_footprint("config/panda_mobile.yaml")) == 4
    with pytest.raises(ConfigError, match="robot_description"):
        load_footprint(str(tmp_path / "missing.yaml"))

"""Config and request bounds without processes: CMD_INIT values that pass the type checks but make no
physical sense, config_json size and depth (checked before parsing, in linear time), and error texts
that never echo unbounded input."""

from __future__ import annotations

import time

import grpc
import pytest

from hal_panda_mobile.config import parse_config as hal_config
from hal_panda_mobile.sim import SimConfigError
from robonix_api.driver import Reply, json_depth, parse_config_json
from robonix_api.grpc_contracts import StatusError, check_strings
from robonix_api.proto_gen import map_pb2, navigation_pb2
from slam_service.config import ConfigError, parse_config


@pytest.mark.parametrize(("raw", "field"), [
    ({"real_time_factor": 1e308}, "real_time_factor"), ({"real_time_factor": 100.5}, "real_time_factor"),
    ({"rates": {"physics_rate_hz": 1e308}}, "rates.physics_rate_hz"),
    ({"rates": {"scan_rate_hz": 1e6}}, "rates.scan_rate_hz"),
    ({"seed": 2**70}, "seed"), ({"scene": "s" * 5000}, "scene"),
])
def test_hal_config_out_of_range(raw: dict, field: str) -> None:
    with pytest.raises(SimConfigError, match=f"^{field.replace('.', '[.]')}"):
        hal_config(raw)
    assert hal_config({"real_time_factor": 100}).real_time_factor == 100
    assert hal_config({"real_time_factor": 0}).real_time_factor == 0  # as fast as possible


@pytest.mark.parametrize(("slam", "field"), [
    ({"resolution": 1e-9}, "slam.resolution"), ({"angular_step": 1e-300}, "slam.angular_step"),
    ({"max_range": 1e308}, "slam.max_range"), ({"search_window_xy": 1e6}, "slam.search_window_xy"),
    ({"grid_chunk": 10**9}, "slam.grid_chunk"),
])
def test_slam_tunables_out_of_range(slam: dict, field: str) -> None:
    with pytest.raises(ConfigError, match=f"^{field.replace('.', '[.]')}: must be within"):
        parse_config({"slam": slam})
    with pytest.raises(ConfigError, match="^map_id"):
        parse_config({"map_id": "m" * 1_000_000})


def test_config_json_depth_and_size_are_checked_before_parsing() -> None:
    t0 = time.perf_counter()
    with pytest.raises(ValueError, match=r"^config_json: nested too deeply \(100000 levels, at most 32\)"):
        parse_config_json("[" * 100_000 + "]" * 100_000)
    with pytest.raises(ValueError, match="^config_json: nested too deeply"):
        parse_config_json('{"a":' * 100_000 + "1" + "}" * 100_000)
    with pytest.raises(ValueError, match="^config_json: at most 1048576 bytes"):
        parse_config_json('{"a": "' + "x" * (1 << 20) + '"}')
    # strings are skipped, unterminated ones too, in one pass: no quadratic input
    assert json_depth('{"a": "[[[[[[[[", "b": [[1]]}') == 3
    for hostile in ('"\\' * 300_000, '"' * 1_000_000, '"' + "a\\" * 400_000):
        with pytest.raises(ValueError, match="^config_json: invalid JSON"):
            parse_config_json(hostile)
    assert time.perf_counter() - t0 < 20  # generous: linear work is well under a second even when loaded
    at_limit = parse_config_json('{"a": ' + "[" * 31 + "]" * 31 + "}")  # 32 levels: still accepted
    assert list(at_limit) == ["a"]
    assert json_depth(str(at_limit["a"])) == 31


def test_errors_never_echo_unbounded_input() -> None:
    assert len(StatusError(grpc.StatusCode.INVALID_ARGUMENT, "x" * 10**6).message) <= 1024
    assert len(Reply(False, "error", "e" * 10**6).to_proto().error) <= 1024
    with pytest.raises(StatusError, match="^INVALID_ARGUMENT: map_id: at most 65536 characters, got 1000000$"):
        check_strings(map_pb2.SaveMap_Request(map_id="m" * 1_000_000))
    req = navigation_pb2.Navigate_Request()
    req.goal.header.frame_id = "f" * 70_000
    with pytest.raises(StatusError, match="goal[.]header[.]frame_id: at most 65536"):
        check_strings(req)
    check_strings(map_pb2.SaveMap_Request(map_id="ok", note="n" * 4096))

"""CMD_INIT with bad inputs answers ok=false/state=error naming the field, and the Driver keeps serving."""

from __future__ import annotations

import json

import pytest

from hal_panda_mobile.config import build_sim, parse_config
from hal_panda_mobile.sim import SimConfigError
from robonix_api.proto_gen import robonix_contracts_pb2_grpc, sim_pb2

from .conftest import HalProcess

BAD = [
    ({"scene": "foo"}, "scene: unknown scene 'foo'"),
    ({"scene": {"walls": "not-a-list"}}, "scene: "),
    ({"scene": "apartment", "start": {"x": 2.5, "y": 0.6}}, "start: pose (2.5, 0.6, 0) collides with"),
    ({"rates": {"scan_rate_hz": -1}}, "rates.scan_rate_hz: must be > 0"),
    ({"rates": {"odom_rate_hz": 0}}, "rates.odom_rate_hz: must be > 0"),
    ({"real_time_factor": -2}, "real_time_factor: must be >= 0"),
    ({"topics": {"scan": "bad topic"}}, "topics.scan"),
    ({"odom_noise": "weird"}, "odom_noise: must be 'none', 'realistic'"),
    ({"scene": {"from_map": "/nonexistent/map.yaml"}}, "scene: from_map:"),
    ({"bogus": 1}, "bogus: unknown field"),
]


@pytest.mark.parametrize(("cfg", "needle"), BAD)
def test_config_errors_name_the_field(cfg: dict, needle: str) -> None:
    with pytest.raises(SimConfigError) as exc:
        build_sim(parse_config(cfg))
    assert needle in str(exc.value)


def test_bad_inits_then_good_init_in_one_process(hal_factory) -> None:  # type: ignore[no-untyped-def]
    hal: HalProcess = hal_factory("hal_init")
    gt = hal.stub("robonix/primitive/sim/ground_truth", robonix_contracts_pb2_grpc.RobonixPrimitiveSimGroundTruthStub)
    import grpc

    with pytest.raises(grpc.RpcError) as exc:  # sim contracts answer FAILED_PRECONDITION before INIT
        gt.GetGroundTruth(sim_pb2.GetGroundTruth_Request(), timeout=30)
    assert exc.value.code() == grpc.StatusCode.FAILED_PRECONDITION

    for cfg, needle in BAD:
        ok, state, error = hal.init(cfg)
        assert (ok, state) == (False, "error"), (cfg, error)
        assert needle in error, (cfg, error)
        assert hal.proc.poll() is None
    ok, state, error = hal.init({"scene": "apartment", "start": {"x": 2.5, "y": 4.0, "yaw": 0.5},
                                 "real_time_factor": 0})
    assert (ok, state, error) == (True, "inactive", "")
    resp = gt.GetGroundTruth(sim_pb2.GetGroundTruth_Request(), timeout=30)
    assert resp.ok
    assert abs(resp.x - 2.5) < 1e-6
    assert abs(resp.theta - 0.5) < 1e-6
    assert resp.sim_time == 0.0
    info = hal.stub("robonix/primitive/sim/scene_info", robonix_contracts_pb2_grpc.RobonixPrimitiveSimSceneInfoStub)
    data = json.loads(info.GetSceneInfo(sim_pb2.GetSceneInfo_Request(), timeout=30).info_json)
    assert data["name"] == "apartment"
    assert data["mode"] == "held"

    # rtf 0 runs as fast as it can once active; a re-INIT with a changed topic is refused by field.
    assert hal.activate()[:2] == (True, "active")
    pytest.importorskip("mujoco")
    from .conftest import wait_until

    wait_until(lambda: gt.GetGroundTruth(sim_pb2.GetGroundTruth_Request(), timeout=30).sim_time > 5.0, 120,
               "sim time to pass 5 s at rtf 0")
    assert hal.deactivate()[:2] == (True, "inactive")
    ok, state, error = hal.init({"topics": {"odom": "/other_odom"}})
    assert not ok
    assert "topics.odom" in error
    assert hal.init({"scene": "office"})[:2] == (True, "inactive")
    assert hal.stop() == 0

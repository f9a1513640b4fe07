"""CMD_INIT with bad inputs answers ok=false/state=error naming the field, and the Driver keeps serving."""

from __future__ import annotations

import json

import pytest
from support.procs import wait_until
from unit.hal_panda_mobile.test_hal_provider_init import BAD

from robonix_api.proto_gen import robonix_contracts_pb2_grpc, sim_pb2

from .conftest import HalProcess


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
    wait_until(lambda: gt.GetGroundTruth(sim_pb2.GetGroundTruth_Request(), timeout=30).sim_time > 5.0, 120,
               "sim time to pass 5 s at rtf 0")
    assert hal.deactivate()[:2] == (True, "inactive")
    ok, state, error = hal.init({"topics": {"odom": "/other_odom"}})
    assert not ok
    assert "topics.odom" in error
    assert hal.init({"scene": "office"})[:2] == (True, "inactive")
    assert hal.stop() == 0

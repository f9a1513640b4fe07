"""Values that used to pass validation and break the simulator or the Driver, sent to a real HAL process:
teleport x = 1e308 (NaN in MuJoCo until reset), real_time_factor 1e308, huge boxes, 100 000-deep and
oversized config_json. Each is refused naming the field, briefly; the sim stays finite and alive."""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterator

import grpc
import pytest
from support.procs import ACTIVATE, DEACTIVATE, HAL, INIT, Proc

from robonix_api.proto_gen import lifecycle_pb2, sim_pb2
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as rpc

from .scene import HAL_CONFIG

pytestmark = pytest.mark.integration
SIM = "robonix/primitive/sim/"


@pytest.fixture(scope="module")
def hal(procs: Callable[..., Proc]) -> Iterator[Proc]:
    p = procs(HAL, "trust_hal")
    for bad, field in (({**HAL_CONFIG, "real_time_factor": 1e308}, "real_time_factor"),
                       ({**HAL_CONFIG, "real_time_factor": 101}, "real_time_factor"),
                       ({**HAL_CONFIG, "rates": {"physics_rate_hz": 1e308}}, "rates.physics_rate_hz"),
                       ({**HAL_CONFIG, "seed": 10**40}, "seed")):
        ok, state, err = p.driver(INIT, bad)
        assert not ok, (field, err)
        assert field in err, (field, err)
        assert len(err) < 1024, (field, err)
    assert p.driver(INIT, {**HAL_CONFIG, "real_time_factor": 100}) == (True, "inactive", "")
    assert p.driver(INIT, HAL_CONFIG) == (True, "inactive", "")
    assert p.driver(ACTIVATE) == (True, "active", "")
    yield p
    assert p.proc.poll() is None, p.log()[-3000:]
    assert "Traceback" not in p.log(), p.log()[-3000:]


def _invalid(call: Callable[[], object], field: str) -> str:
    with pytest.raises(grpc.RpcError) as info:
        call()
    assert info.value.code() == grpc.StatusCode.INVALID_ARGUMENT, info.value
    details = info.value.details() or ""
    assert details.startswith(field + ":"), details
    assert len(details) <= 1024, details
    return details


def test_teleport_and_spawn_out_of_bounds_are_refused(hal: Proc) -> None:
    tp = hal.stub(SIM + "teleport", rpc.RobonixPrimitiveSimTeleportStub)
    gt = hal.stub(SIM + "ground_truth", rpc.RobonixPrimitiveSimGroundTruthStub)
    spawn = hal.stub(SIM + "spawn_obstacle", rpc.RobonixPrimitiveSimSpawnObstacleStub)
    for req, field in ((sim_pb2.Teleport_Request(x=1e308, y=1.5), "x"),
                       (sim_pb2.Teleport_Request(x=1.5, y=-1e308), "y"),
                       (sim_pb2.Teleport_Request(x=1.5, y=1.5, theta=1e308), "theta"),
                       (sim_pb2.Teleport_Request(x=8.5, y=1.5), "x")):  # bounds [0, 6] + 2 m margin
        _invalid(lambda r=req: tp.Teleport(r, timeout=30), field)
    for req, field in ((sim_pb2.SpawnObstacle_Request(x=3, y=3, size_x=1e308, size_y=1), "size_x"),
                       (sim_pb2.SpawnObstacle_Request(x=1e300, y=3, size_x=1, size_y=1), "x"),
                       (sim_pb2.SpawnObstacle_Request(x=3, y=3, size_x=1, size_y=1, name="b" * 65), "name"),
                       (sim_pb2.SpawnObstacle_Request(x=3, y=3, size_x=1, size_y=1, name="a\nb"), "name")):
        _invalid(lambda r=req: spawn.SpawnObstacle(r, timeout=30), field)
    g = gt.GetGroundTruth(sim_pb2.GetGroundTruth_Request(), timeout=30)
    assert all(math.isfinite(v) for v in (g.x, g.y, g.theta, g.vx, g.vy, g.wz)), g
    assert abs(g.x - 1.5) < 0.2, g
    ok = tp.Teleport(sim_pb2.Teleport_Request(x=2.0, y=2.5, theta=0.3), timeout=30)
    assert ok.ok, ok.detail  # in bounds: still works


def test_deep_and_oversized_config_json_are_refused(hal: Proc) -> None:
    driver = hal.stub("robonix/lifecycle/driver", rpc.RobonixLifecycleDriverStub)
    assert hal.driver(DEACTIVATE) == (True, "inactive", "")  # INIT is only taken while not ACTIVE
    for text, what in (("[" * 100_000 + "]" * 100_000, "nested too deeply (100000 levels, at most 32)"),
                       ('{"a":' * 33 + "1" + "}" * 33, "nested too deeply (33 levels"),
                       (json.dumps({"scene": "x" * (1 << 20)}), "at most 1048576 bytes")):
        with pytest.raises(grpc.RpcError) as info:
            driver.Driver(lifecycle_pb2.Driver_Request(command=INIT, config_json=text), timeout=60)
        assert info.value.code() == grpc.StatusCode.INVALID_ARGUMENT
        assert (info.value.details() or "").startswith("config_json: ")
        assert what in info.value.details()
    resp = driver.Driver(lifecycle_pb2.Driver_Request(command=ACTIVATE), timeout=60)  # the session is intact
    assert (resp.ok, resp.state) == (True, "active")

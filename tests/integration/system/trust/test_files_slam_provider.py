"""The map store's boundary through a real SLAM provider (gRPC + Driver), next to a real HAL: a map_dir
outside the maps root, delete_map on a folder the store did not write, a 3.9 MB note and a 1 MB map id,
``"ok\\n"`` as a map id, out-of-range poses. Each is refused naming the field; no file outside the maps
root changes; list_maps keeps working for everyone."""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Iterator
from pathlib import Path

import grpc
import pytest
from support.procs import ACTIVATE, DEACTIVATE, HAL, INIT, SLAM, Proc, wait_until

from robonix_api.proto_gen import map_pb2
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as rpc

from .scene import HAL_CONFIG

pytestmark = pytest.mark.integration
M = "robonix/service/map/"


class Slam:
    def __init__(self, proc: Proc, map_dir: Path) -> None:
        self.proc, self.map_dir = proc, map_dir
        self._stubs: dict[str, object] = {}

    def rpc(self, name: str) -> object:
        if name not in self._stubs:
            cls = getattr(rpc, "RobonixServiceMap" + "".join(w.title() for w in name.split("_")) + "Stub")
            self._stubs[name] = self.proc.stub(M + name, cls)
        return self._stubs[name]


@pytest.fixture(scope="module")
def slam(procs: Callable[..., Proc], tmp_path_factory: pytest.TempPathFactory) -> Iterator[Slam]:
    root = Path(os.environ["ROBONIX_MAPS_ROOT"])
    map_dir = tmp_path_factory.mktemp("trust_maps")
    assert map_dir.resolve().is_relative_to(root.resolve())
    hal = procs(HAL, "trust_sim")
    assert hal.driver(INIT, HAL_CONFIG) == (True, "inactive", "")
    assert hal.driver(ACTIVATE) == (True, "active", "")
    p = procs(SLAM, "trust_mapping")
    assert p.init({"map_dir": str(map_dir)}, 60) == (True, "inactive", ""), p.log()[-3000:]
    assert p.driver(ACTIVATE) == (True, "active", "")
    yield Slam(p, map_dir)
    assert p.proc.poll() is None, p.log()[-3000:]
    assert "Traceback" not in p.log(), p.log()[-3000:]


def test_map_dir_outside_the_maps_root_is_refused(slam: Slam, tmp_path_factory: pytest.TempPathFactory) -> None:
    outside = Path(os.path.realpath(os.environ["ROBONIX_MAPS_ROOT"])).parent / f"trust-outside-{os.getpid()}"
    assert slam.proc.driver(DEACTIVATE) == (True, "inactive", "")  # INIT is only taken while not ACTIVE
    for bad in (str(outside), "/", "/etc", str(slam.map_dir / ".." / ".." / "..")):
        ok, state, err = slam.proc.driver(INIT, {"map_dir": bad})
        assert not ok, (bad, state, err)
        assert err.startswith("map_dir: "), (bad, state, err)
        assert "outside the maps root" in err, (bad, state, err)
    assert not outside.exists()
    # a refused INIT is an Err (state ERROR, as robonix does); a good one brings the service back
    assert slam.proc.driver(INIT, {"map_dir": str(slam.map_dir)}) == (True, "inactive", "")
    assert slam.proc.driver(ACTIVATE) == (True, "active", "")
    saved = slam.rpc("save_map").SaveMap(map_pb2.SaveMap_Request(map_id="kept"), timeout=60)
    assert saved.ok, saved.detail
    assert (slam.map_dir / "kept" / ".robonix-map").is_file(), saved.detail


def test_delete_map_spares_folders_the_store_did_not_write(slam: Slam) -> None:
    precious = slam.map_dir / "precious"
    precious.mkdir()
    (precious / "thesis.txt").write_text("years of work")
    r = slam.rpc("delete_map").DeleteMap(map_pb2.DeleteMap_Request(map_id="precious"), timeout=30)
    assert not r.ok, r.detail
    assert "marker" in r.detail, r.detail
    assert (precious / "thesis.txt").read_text() == "years of work", r.detail
    saved = slam.rpc("save_map").SaveMap(map_pb2.SaveMap_Request(map_id="precious"), timeout=60)
    assert not saved.ok, saved.detail
    assert "marker" in saved.detail, saved.detail
    assert (precious / "thesis.txt").is_file(), saved.detail
    ok = slam.rpc("save_map").SaveMap(map_pb2.SaveMap_Request(map_id="scratch"), timeout=60)
    assert ok.ok, ok.detail
    r = slam.rpc("delete_map").DeleteMap(map_pb2.DeleteMap_Request(map_id="scratch"), timeout=30)
    assert r.ok, r.detail
    assert not (slam.map_dir / "scratch").exists(), r.detail


@pytest.mark.parametrize(("map_id", "note", "field"), [
    ("big_note", "n" * 3_900_000, "note"),
    ("x" * 1_000_000, "", "map_id"),
    ("ok\n", "", "map_id"),
    ("a" * 65, "", "map_id"),
])
def test_oversized_and_malformed_names_are_refused_briefly(slam: Slam, map_id: str, note: str, field: str) -> None:
    with pytest.raises(grpc.RpcError) as info:
        slam.rpc("save_map").SaveMap(map_pb2.SaveMap_Request(map_id=map_id, note=note), timeout=60)
    assert info.value.code() == grpc.StatusCode.INVALID_ARGUMENT, info.value
    details = info.value.details() or ""
    assert details.startswith(field + ":"), details[:300]
    assert len(details) <= 1024, details[:300]
    assert not any("\n" in p.name for p in slam.map_dir.iterdir())
    listed = slam.rpc("list_maps").ListMaps(map_pb2.ListMaps_Request(), timeout=30)
    assert listed.ok
    assert all(len(m["note"]) <= 4096 for m in json.loads(listed.maps_json))


def test_poses_out_of_range_are_refused(slam: Slam) -> None:
    for req, field in ((map_pb2.PoseEstimate_Request(x=1e308, y=0), "x"),
                       (map_pb2.PoseEstimate_Request(x=0, y=0, theta=-1e308), "theta")):
        with pytest.raises(grpc.RpcError) as info:
            slam.rpc("pose_estimate").PoseEstimate(req, timeout=30)
        assert info.value.code() == grpc.StatusCode.INVALID_ARGUMENT
        assert info.value.details().startswith(field + ":")
    wait_until(lambda: slam.rpc("get_mode").GetMode(map_pb2.GetMode_Request(), timeout=30).ok, 30, "SLAM answering")


@pytest.mark.parametrize(("old", "new", "field"), [
    ("origin:\n- ", "origin:\n- .nan\n#- ", "origin[0]: must be a finite number"),  # was: loaded, Navigate INTERNAL
    ("resolution: 0.05", "resolution: 1.0e-300", "resolution: must be"),  # was INTERNAL TypeError
    ("image: map.pgm", "image: ../../../../../../etc/hostname", "outside the map folder"),
])
def test_hostile_map_yaml_is_invalid_argument_naming_the_key(slam: Slam, old: str, new: str, field: str) -> None:
    """Issue 37 item 7 through the real provider: every such map was loaded or crashed INTERNAL."""
    saved = slam.rpc("save_map").SaveMap(map_pb2.SaveMap_Request(map_id="hostile"), timeout=60)
    assert saved.ok, saved.detail
    yaml_path = slam.map_dir / "hostile" / "map.yaml"
    text = yaml_path.read_text()
    assert old in text, text
    yaml_path.write_text(text.replace(old, new, 1))
    with pytest.raises(grpc.RpcError) as info:
        slam.rpc("load_map").LoadMap(map_pb2.LoadMap_Request(map_id="hostile", mode="localization"), timeout=60)
    assert info.value.code() == grpc.StatusCode.INVALID_ARGUMENT, info.value.details()
    assert field in info.value.details(), info.value.details()


def test_non_finite_config_json_is_refused_by_the_driver(slam: Slam) -> None:
    """Issue 37 item 5 at the Driver: NaN in config_json fails the RPC naming the field; state unchanged."""
    assert slam.proc.driver(DEACTIVATE) == (True, "inactive", "")
    try:
        for value in (float("nan"), float("inf")):
            with pytest.raises(grpc.RpcError) as info:
                slam.proc.driver(INIT, {"map_dir": str(slam.map_dir), "map_publish_period_s": value})
            assert info.value.code() == grpc.StatusCode.INVALID_ARGUMENT, info.value.details()
            assert info.value.details().startswith("config_json: map_publish_period_s: must be a finite number")
    finally:
        assert slam.proc.driver(ACTIVATE) == (True, "active", "")  # still the INIT it had

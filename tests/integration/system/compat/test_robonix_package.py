"""Acceptance: packages written only against robonix-api 0.1.0rc1 (tests/compat/robonix_pkg) run
unchanged under ``rbnx boot``: both reach ACTIVE (the service after answering Deferred), the lidar
publishes on DDS, and the service's handlers answer over gRPC and MCP; SIGINT leaves no process."""

from __future__ import annotations

import asyncio
import shutil
from pathlib import Path

import grpc
import pytest
from support.boot import RbnxBoot
from support.procs import wait_until

from robonix_api.atlas_client import AtlasClient
from robonix_api.dds import DdsNode, LaserScan
from robonix_api.proto_gen import map_pb2, robonix_contracts_pb2_grpc
from robonix_api.types import LifecycleState, Transport

pytestmark = pytest.mark.integration

PKG = Path(__file__).resolve().parent / "robonix_pkg"
LIDAR = "robonix/primitive/lidar/lidar"
GET_MODE = "robonix/service/map/get_mode"
GET_POSE = "robonix/service/map/get_pose"


def _call_mcp(url: str) -> tuple[list[str], dict]:  # type: ignore[type-arg]
    from mcp import Client

    async def talk() -> tuple[list[str], dict]:  # type: ignore[type-arg]
        async with Client(url) as client:
            tools = await client.list_tools()
            res = await client.call_tool("get_pose", {})
            assert not res.is_error, res.content
            return [t.name for t in tools.tools], dict(res.structured_content or {})

    return asyncio.run(asyncio.wait_for(talk(), 60))


def test_robonix_api_package_runs_unchanged_under_rbnx_boot(tmp_path: Path) -> None:
    if shutil.which("bash") is None:
        pytest.skip("rbnx runs start: with bash")
    pkg = shutil.copytree(PKG, tmp_path / "robonix_pkg", ignore=shutil.ignore_patterns("__pycache__", ".rbnx-built"))
    # --serial: the service starts alone, so it must answer Deferred (in parallel the lidar may be up first)
    with RbnxBoot(pkg / "deploy.yaml", tmp_path, "--serial") as boot:
        boot.wait_ready(2)
        out = boot.output()
        assert f"deferred(waiting for {LIDAR})" in out, out
        st = boot.state()
        with AtlasClient(st["atlas"]) as client:
            for pid in ("compat_lidar", "compat_scan_watch"):
                (prov,) = client.query(id=pid)
                assert prov.state == LifecycleState.ACTIVE, (pid, prov.state, prov.state_detail)
            (lidar,) = client.query(id="compat_lidar")
            assert lidar.kind.label == "primitive"
            assert LIDAR in {c.contract_id for c in lidar.capabilities}

            # The scan, read on DDS by our own subscriber at the topic the atlas hands out.
            with client.connect_capability(consumer_id="compat_test", provider_id="compat_lidar",
                                           contract_id=LIDAR, transport="ros2") as ch:
                topic, qos = ch.endpoint, ch.qos_profile
            assert topic == "/compat_scan"
            assert qos == "best_effort"
            with DdsNode(name="compat_test") as node:
                scan = node.wait_for_message(topic, LaserScan, 60, "best_effort")
            assert scan is not None
            assert len(scan.ranges) == 180
            assert scan.header.frame_id == "laser"
            assert all(abs(r - 2.0) < 1e-6 for r in scan.ranges)

            # gRPC: the @provides_grpc handler, reached at the endpoint the atlas hands out.
            with client.connect_capability(consumer_id="compat_test", provider_id="compat_scan_watch",
                                           contract_id=GET_MODE, transport=Transport.GRPC) as ch:
                assert ch.params.service_name == "RobonixServiceMapGetMode"
                assert ch.params.method == "GetMode"
                with grpc.insecure_channel(ch.endpoint) as chan:
                    stub = robonix_contracts_pb2_grpc.RobonixServiceMapGetModeStub(chan)

                    def counted() -> bool:
                        r = stub.GetMode(map_pb2.GetMode_Request(), timeout=10)
                        assert r.ok
                        assert r.mode == "watching"
                        return int(r.detail.split()[0]) > 0

                    wait_until(counted, 60, "the service to count lidar scans (gRPC get_mode)")

            # MCP: the @provides_mcp handler as tool get_pose, with the official mcp client.
            (cap,) = client.find_capability(contract_id=GET_POSE, transport="mcp")
            assert cap.provider_id == "compat_scan_watch"
            assert cap.description == "Mean range of the last lidar scan (as x) and its frame."
            with client.connect_capability(consumer_id="compat_test", provider_id="compat_scan_watch",
                                           contract_id=GET_POSE, transport="mcp") as ch:
                tools, pose = _call_mcp(ch.endpoint)
            assert tools == ["get_pose"]
            assert pose["ok"] is True
            assert abs(pose["x"] - 2.0) < 1e-6
            assert pose["frame_id"] == "laser"

        boot.interrupt()
        boot.wait_all_exited()
        for entry in ("compat_lidar", "compat_scan_watch"):
            log = boot.log(entry)
            assert "Traceback" not in log, log[-3000:]

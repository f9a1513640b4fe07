"""Conformance: robonix-api 0.1.0rc1 itself (its wheel from the package registry, in a virtualenv of
its own) against this project.

- its unmodified ``ATLAS`` client drives our atlas: register, declare, query (incl.
  query_primitives/services/skills), find, connect, disconnect, heartbeat, set state, unregister;
- the robonix-api-only packages of tests/compat/robonix_pkg import and call only names the real
  robonix-api has, so they would run there too.

The virtualenv is built once per test session; without the registry the tests skip, saying so.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import google.protobuf
import grpc
import pytest

pytestmark = pytest.mark.integration

HERE = Path(__file__).resolve().parent
WHEEL = "robonix-api==0.1.0rc1"
#: what importing robonix-api's atlas client needs (its other requirements, fastmcp/mcp/pyyaml, serve
#: its MCP and codegen helpers); pinned to this project's versions
CLIENT_DEPS = (f"grpcio=={grpc.__version__}", f"protobuf=={google.protobuf.__version__}")
_OFFLINE_HINTS = ("Could not find a version", "No matching distribution", "NewConnectionError",
                  "Temporary failure in name resolution", "Max retries exceeded", "Network is unreachable",
                  "ConnectTimeout", "ReadTimeout", "Connection refused")


def _pip(py: Path, *args: str) -> None:
    res = subprocess.run([str(py), "-m", "pip", "install", "-q", *args], capture_output=True, text=True,
                         timeout=900)
    if res.returncode != 0:
        text = res.stdout + res.stderr
        if any(h in text for h in _OFFLINE_HINTS):
            pytest.skip(f"package registry unreachable, cannot install {' '.join(args)}: {text.strip()[-300:]}")
        raise AssertionError(f"pip install {' '.join(args)} failed:\n{text[-3000:]}")


@pytest.fixture(scope="session")
def robonix_python(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The python of a fresh virtualenv holding the real robonix-api wheel (built once per session)."""
    venv = tmp_path_factory.mktemp("robonix_api_venv")
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=300)
    py = venv / "bin" / "python"
    _pip(py, "--no-deps", WHEEL)
    _pip(py, *CLIENT_DEPS)
    return py


def _run(py: Path, script: str, *args: str, env: dict[str, str] | None = None) -> dict[str, Any]:
    # Run outside the repo so `robonix_api` can only be the wheel's, never this project's.
    res = subprocess.run([str(py), str(HERE / script), *args], capture_output=True, text=True, timeout=300,
                         cwd=py.parent, env={**os.environ, **(env or {}), "PYTHONPATH": ""})
    assert res.returncode == 0, res.stderr[-3000:]
    return json.loads(res.stdout)


@pytest.fixture
def atlas_address() -> Iterator[str]:
    from atlas.server import AtlasServer

    server = AtlasServer(listen="127.0.0.1:0", heartbeat_timeout_ms=60000, eviction_interval_ms=1000)
    server.start()
    try:
        yield server.address
    finally:
        server.stop()


def test_robonix_api_atlas_client_against_our_atlas(robonix_python: Path, atlas_address: str) -> None:
    out = _run(robonix_python, "robonix_atlas_client.py", env={"ROBONIX_ATLAS": atlas_address})
    assert str(robonix_python.parent.parent) in out["sdk_file"]  # the wheel's client, not ours

    assert out["register"] == ["rbx_lidar", "rbx_map", "rbx_skill"]
    assert out["declare"] == ["/rbx_scan", "127.0.0.1:1", "http://127.0.0.1:2/mcp/"]
    lidar_caps = [["robonix/primitive/lidar/lidar", "ROS2"]]
    map_caps = [["robonix/service/map/get_mode", "GRPC"], ["robonix/service/map/get_pose", "MCP"]]
    # a first declared capability moves a REGISTERED provider to INACTIVE (robonix's atlas does the same)
    assert out["query_all"] == [["rbx_lidar", "PRIMITIVE", "INACTIVE", "", lidar_caps],
                                ["rbx_map", "SERVICE", "INACTIVE", "", map_caps],
                                ["rbx_skill", "SKILL", "REGISTERED", "", []]]
    assert [r[0] for r in out["query_primitives"]] == ["rbx_lidar"]
    assert [r[0] for r in out["query_services"]] == ["rbx_map"]
    assert [r[0] for r in out["query_skills"]] == ["rbx_skill"]
    assert out["query_by_kind_str"] == ["rbx_lidar"]
    assert out["find"] == [["rbx_lidar", "PRIMITIVE", "ROS2", "a test lidar", "best_effort"]]
    assert out["find_unique"] == ["rbx_map", '{"type": "object"}', "pose tool"]
    assert out["find_unique_none"].startswith("ValueError: ")
    assert out["query_contract"][:4] == ["robonix/primitive/lidar/lidar", "topic_out",
                                         "sensor_msgs/msg/LaserScan", "PRIMITIVE"]
    assert out["query_contract"][4] == ["header", "angle_min", "angle_max"]
    assert out["query_contract_missing"] is True
    assert "robonix/service/map/get_mode" in out["list_contracts"]
    assert all(c.startswith("robonix/service/map/") for c in out["list_contracts"])

    assert out["connect"] == ["/rbx_scan", True, "Ros2Params", "best_effort"]
    assert out["inspect_has_channel"] is True
    assert out["disconnect"] == [True, False]
    assert out["connect_grpc"] == ["127.0.0.1:1", "RobonixServiceMapGetMode", "GetMode", "robonix_contracts.proto"]
    assert out["with_closed"] is True

    assert out["heartbeat_advanced"] is True
    assert out["start_heartbeat"] == ["Thread", True, True]
    assert out["set_state"] == ["ACTIVE", "scanning"]
    assert out["query_active"] == ["rbx_lidar"]

    assert out["unregister"] == [True, False, True]
    assert out["after_unregister"] == ["rbx_map"]
    assert out["find_after_unregister"] is True


def test_robonix_pkg_uses_only_robonix_api_names(robonix_python: Path) -> None:
    files = sorted(str(p) for p in (HERE / "robonix_pkg").rglob("*.py"))
    assert len(files) == 2
    out = _run(robonix_python, "check_robonix_names.py", *files)
    assert out["missing"] == []
    # the check really looked at what the packages use
    assert {"robonix_api.Primitive", "robonix_api.ros.resolve_msg_type", "lidar.create_publisher", "lidar.emit",
            "svc.provides_grpc", "svc.provides_mcp", "svc.connect_capability",
            "svc.create_subscription_from_channel", "ATLAS.find_capability"} <= set(out["checked"])

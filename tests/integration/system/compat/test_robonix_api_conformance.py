"""Conformance: robonix-api 0.1.0rc1 itself (its wheel from the package registry, in a virtualenv of
its own) against this project.

- its unmodified ``ATLAS`` client drives our atlas: register, declare, query (incl.
  query_primitives/services/skills), find, connect, disconnect, heartbeat, set state, unregister;
- every public name of robonix-api (its modules, classes, methods, dataclass fields, constants) exists
  in this SDK, call-compatible, except the differences listed (and explained) in robonix_api/COMPAT.md;
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

pytestmark = [pytest.mark.integration, pytest.mark.slow]

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
            pytest.skip(f"package registry unreachable (or without {' '.join(args)}): {text.strip()[-300:]}")
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


#: Where a robonix-api call does not map 1:1 onto ours (robonix_api/COMPAT.md explains each). The
#: positional orders of the three dataclasses are still accepted at run time (test_robonix_compat.py).
DOCUMENTED_DIFFERENCES = {
    "Capability(description): positional place 4 differs",
    "Capability(params): positional place 5 differs",
    "CapabilityProvider(capabilities): default () != <factory>",
    *(f"Channel({f}): positional place {i} differs"
      for i, f in enumerate(("provider_id", "contract_id", "transport", "endpoint", "channel_id", "params",
                             "_closer"))),
    *(f"ContractDescriptor({f}): positional place {i} differs"
      for i, f in enumerate(("description", "msg_fields", "srv_request_fields", "srv_response_fields"), start=7)),
    "Primitive.create_subscription(declare): default True != False",
}


def compare_surfaces(theirs: dict[str, Any], ours: dict[str, Any]) -> list[str]:
    """What robonix-api code could call that ours would not accept the same way."""
    diffs = []
    for key, t in sorted(theirs.items()):
        o = ours.get(key)
        if o is None:
            diffs.append(f"{key}: missing")
        elif t["type"] in ("enum", "value", "module") and t != o:
            diffs.append(f"{key}: {t} != {o}")
        elif t.get("params") is not None and o.get("params") is not None:
            diffs.extend(f"{key}{d}" for d in _param_diffs(t["params"], o["params"]))
    return diffs


def _param_diffs(theirs: list[list[Any]], ours: list[list[Any]]) -> list[str]:
    out = []
    by_name = {p[0]: p for p in ours}
    takes_kwargs = any(p[1] == "VAR_KEYWORD" for p in ours)
    for i, (name, kind, has_default, default) in enumerate(theirs):
        if kind in ("VAR_POSITIONAL", "VAR_KEYWORD"):
            continue
        mine = by_name.get(name)
        if mine is None:
            if not (kind == "KEYWORD_ONLY" and takes_kwargs):
                out.append(f"({name}): missing parameter")
            continue
        if kind == "POSITIONAL_OR_KEYWORD" and (i >= len(ours) or ours[i][:2] != [name, kind]):
            out.append(f"({name}): positional place {i} differs")
        if kind == "KEYWORD_ONLY" and mine[1] not in ("KEYWORD_ONLY", "POSITIONAL_OR_KEYWORD"):
            out.append(f"({name}): not accepted as a keyword")
        if has_default and (not mine[2] or mine[3] != default):
            out.append(f"({name}): default {default} != {mine[3] if mine[2] else 'required'}")
    names = {p[0] for p in theirs}
    out.extend(f"({p[0]}): extra required parameter" for p in ours
               if p[0] not in names and not p[2] and p[1] not in ("VAR_POSITIONAL", "VAR_KEYWORD"))
    return out


def _normalise(diff: str) -> str:
    """One entry per difference: the same class is re-exported by several modules and kinds."""
    for prefix in ("robonix_api.atlas_types.", "robonix_api.capability.", "robonix_api."):
        diff = diff.removeprefix(prefix)
    for kind in ("Service.", "Skill."):
        diff = diff.replace(kind, "Primitive.")
    return diff


def test_every_robonix_api_name_exists_call_compatible(robonix_python: Path) -> None:
    theirs = _run(robonix_python, "dump_api.py")
    ours = _run(Path(sys.executable), "dump_api.py")
    assert len(theirs) > 250
    assert "robonix_api.Primitive.provides_mcp" in theirs
    diffs = {_normalise(d) for d in compare_surfaces(theirs, ours)}
    assert diffs == DOCUMENTED_DIFFERENCES

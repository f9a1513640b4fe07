"""Helpers for the whole-deployment tests (tests/integration/system, the container test): an isolated
environment for the real `rbnx` CLI, PIDs checked through /proc, a goal driven over gRPC like any consumer."""

from __future__ import annotations

import json
import os
from pathlib import Path

from robonix_api import auth
from robonix_api.atlas_client import AtlasClient
from robonix_api.proto_gen import navigation_pb2, sim_pb2
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as stubs

from .boot import rbnx_cmd
from .procs import wait_until

REPO = Path(__file__).resolve().parents[2]
SIM_DEPLOY = REPO / "examples" / "sim" / "deploy.yaml"
__all__ = ["SIM_DEPLOY", "e2e_env", "grpc_endpoint", "navigate", "rbnx_cmd", "recorded_pids", "wait_until"]


def e2e_env(tmp: Path, **extra: str) -> dict[str, str]:
    """Isolated state dir, an atlas port of the OS's choosing, a DDS domain no other test run uses."""
    from rbnx.demo.boot import pick_domain_id

    env = dict(os.environ, RBNX_STATE_DIR=str(tmp / "state"), RBNX_ATLAS_LISTEN="127.0.0.1:0",
               PYTHONUNBUFFERED="1", ROS_DOMAIN_ID=str(pick_domain_id()))
    for name in ("ROBONIX_ATLAS", "RBNX_INSTANCE_NAME", "RBNX_DEPLOY_MANAGED"):
        env.pop(name, None)
    env.update(extra)
    return env


def recorded_pids(state_file: Path) -> list[tuple[str, int, int | None]]:
    """Every process a boot recorded: itself, the atlas, each entry (and its extra PIDs)."""
    st = json.loads(state_file.read_text())
    out = [("rbnx boot", int(st["pid"]), st.get("start_ticks"))]
    if st.get("atlas_proc"):
        out.append(("atlas", int(st["atlas_proc"]["pid"]), st["atlas_proc"].get("start_ticks")))
    for c in st.get("children") or []:
        out.append((c["name"], int(c["pid"]), c.get("start_ticks")))
        out.extend((c["name"], int(p), t) for p, t in c.get("extra_pids") or [])
    return out


def grpc_endpoint(client: AtlasClient, contract: str) -> str:
    cap = client.find_unique_capability(contract_id=contract, transport="grpc")
    with client.connect_capability(consumer_id="e2e-test", provider_id=cap.provider_id, contract_id=contract,
                                   transport="grpc") as ch:
        return ch.endpoint.removeprefix("grpc://")


def navigate(atlas: str, x: float, y: float, timeout_s: float, token: str = "") -> tuple[str, str, tuple[float, float]]:
    """Navigate over gRPC like any robonix consumer; returns (final state, detail, ground-truth xy).
    ``token``: the deployment's token (from its boot state file), sent on every call."""
    before = os.environ.get("ROBONIX_DEPLOY_TOKEN")
    if token:
        os.environ["ROBONIX_DEPLOY_TOKEN"] = token
    try:
        return _navigate(atlas, x, y, timeout_s)
    finally:
        if before is None:
            os.environ.pop("ROBONIX_DEPLOY_TOKEN", None)
        else:
            os.environ["ROBONIX_DEPLOY_TOKEN"] = before


def _navigate(atlas: str, x: float, y: float, timeout_s: float) -> tuple[str, str, tuple[float, float]]:
    with AtlasClient(atlas) as client:
        nav_ep = grpc_endpoint(client, "robonix/service/navigation/navigate")
        status_ep = grpc_endpoint(client, "robonix/service/navigation/navigate/status")
        gt_ep = grpc_endpoint(client, "robonix/primitive/sim/ground_truth")
    req = navigation_pb2.Navigate_Request()
    req.goal.header.frame_id = "map"
    req.goal.pose.position.x, req.goal.pose.position.y = x, y
    req.goal.pose.orientation.w = 1.0
    with auth.channel(nav_ep) as nav_ch, auth.channel(status_ep) as st_ch, auth.channel(gt_ep) as gt_ch:
        resp = stubs.RobonixServiceNavigationNavigateStub(nav_ch).Navigate(req, timeout=10)
        assert resp.accepted, resp.detail
        status = stubs.RobonixServiceNavigationNavigateStatusStub(st_ch)

        def terminal() -> navigation_pb2.GetNavigationStatus_Response | None:
            st = status.GetNavigationStatus(navigation_pb2.GetNavigationStatus_Request(run_id=resp.run_id),
                                            timeout=5)
            return st if st.state in ("SUCCEEDED", "FAILED", "CANCELED") else None

        st = wait_until(terminal, timeout_s, f"goal {resp.run_id} to finish", 0.5)
        gt = stubs.RobonixPrimitiveSimGroundTruthStub(gt_ch).GetGroundTruth(sim_pb2.GetGroundTruth_Request(),
                                                                            timeout=5)
    return st.state, st.detail, (gt.x, gt.y)

"""Helpers of the fault tests: a navigate call that rides out a busy provider's slow status replies, and
adopting a boot's deployment token (the SDK's and rbnx's clients send ``$ROBONIX_DEPLOY_TOKEN``)."""

from __future__ import annotations

import json
from pathlib import Path

import grpc
import pytest
from e2e.conftest import _grpc_endpoint
from support.procs import wait_until

from robonix_api import auth
from robonix_api.atlas_client import AtlasClient
from robonix_api.proto_gen import navigation_pb2
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as stubs


def navigate(atlas: str, x: float, y: float, timeout_s: float, accept_within_s: float = 10.0) -> tuple[str, str]:
    """Send a goal over gRPC and wait for its end; a status call that times out (a just-restarted process
    still warming up on a loaded machine) is asked again, not taken as the answer. A goal rejected because
    an upstream "left the atlas" is sent again for ``accept_within_s``: navigation re-checks its
    upstreams every 2 s, so right after a restart it may not have seen the new provider yet."""
    with AtlasClient(atlas) as client:
        nav_ep = _grpc_endpoint(client, "robonix/service/navigation/navigate")
        status_ep = _grpc_endpoint(client, "robonix/service/navigation/navigate/status")
    req = navigation_pb2.Navigate_Request()
    req.goal.header.frame_id = "map"
    req.goal.pose.position.x, req.goal.pose.position.y = x, y
    req.goal.pose.orientation.w = 1.0
    with auth.channel(nav_ep) as nav_ch, auth.channel(status_ep) as st_ch:
        nav = stubs.RobonixServiceNavigationNavigateStub(nav_ch)

        def accepted() -> navigation_pb2.Navigate_Response | None:
            r = nav.Navigate(req, timeout=30)
            assert r.accepted or "left the atlas" in r.detail, r.detail
            return r if r.accepted else None

        resp = wait_until(accepted, accept_within_s, "navigation to accept the goal", 0.25)
        status = stubs.RobonixServiceNavigationNavigateStatusStub(st_ch)

        def terminal() -> navigation_pb2.GetNavigationStatus_Response | None:
            try:
                st = status.GetNavigationStatus(navigation_pb2.GetNavigationStatus_Request(run_id=resp.run_id),
                                                timeout=10)
            except grpc.RpcError as exc:
                if exc.code() == grpc.StatusCode.DEADLINE_EXCEEDED:
                    return None
                raise
            return st if st.state in ("SUCCEEDED", "FAILED", "CANCELED") else None

        st = wait_until(terminal, timeout_s, f"goal {resp.run_id} to finish", 0.5)
    return st.state, st.detail


def adopt_token(state_file: Path, monkeypatch: pytest.MonkeyPatch) -> str:
    """This test acts as a client of the deployment: its token for the test's duration."""
    token = str(json.loads(state_file.read_text()).get("token") or "")
    if token:
        monkeypatch.setenv("ROBONIX_DEPLOY_TOKEN", token)
    return token

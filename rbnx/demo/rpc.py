"""The contracts `rbnx demo` calls, found the way any robonix consumer finds them (atlas Query → Connect →
endpoint), wrapped as small typed methods. Every gRPC failure becomes a DemoError with one line."""

from __future__ import annotations

import contextlib
import json
import math
from dataclasses import dataclass, field
from typing import Any

import grpc

from rbnx.atlas_rpc import GRPC_OPTIONS
from rbnx.demo.boot import DemoError
from rbnx.demo.goals import Goal
from robonix_api import auth
from robonix_api.atlas_client import AtlasClient
from robonix_api.proto_gen import map_pb2, navigation_pb2, sim_pb2
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as stubs

SIM = "robonix/primitive/sim/"
NAV = "robonix/service/navigation/"
SCENE_INFO, GROUND_TRUTH, COLLISIONS = SIM + "scene_info", SIM + "ground_truth", SIM + "collisions"
NAVIGATE, STATUS, CANCEL = NAV + "navigate", NAV + "navigate/status", NAV + "navigate/cancel"
MAP_CARD = "robonix/service/map/map_card"
CONSUMER = "rbnx-demo"


@dataclass
class GroundTruth:
    x: float
    y: float
    theta: float
    sim_time: float


@dataclass
class NavStatus:
    known: bool
    state: str
    detail: str


@dataclass
class Collision:
    sim_time: float
    robot_geom: str
    other_geom: str
    x: float
    y: float

    def as_dict(self) -> dict[str, Any]:
        return {"sim_time": round(self.sim_time, 3), "robot_geom": self.robot_geom,
                "other_geom": self.other_geom, "x": round(self.x, 3), "y": round(self.y, 3)}


@dataclass
class DemoRpc:
    """gRPC channels to the providers of the contracts the demo uses (one channel per endpoint)."""

    atlas: str
    timeout: float = 5.0
    _channels: dict[str, grpc.Channel] = field(default_factory=dict)
    _endpoints: dict[str, str] = field(default_factory=dict)

    def _endpoint(self, contract: str) -> str:
        if contract not in self._endpoints:
            try:
                with AtlasClient(self.atlas) as client:
                    cap = client.find_unique_capability(contract_id=contract, transport="grpc")
                    with client.connect_capability(consumer_id=CONSUMER, provider_id=cap.provider_id,
                                                   contract_id=contract, transport="grpc") as ch:
                        self._endpoints[contract] = ch.endpoint.removeprefix("grpc://")
            except ValueError as exc:
                raise DemoError(str(exc)) from None
            except grpc.RpcError as exc:
                raise DemoError(f"atlas {self.atlas}: cannot resolve {contract}: {exc.code().name}") from None
        return self._endpoints[contract]

    def _stub(self, contract: str, stub_cls: Any) -> Any:
        ep = self._endpoint(contract)
        if ep not in self._channels:
            self._channels[ep] = auth.channel(ep, options=GRPC_OPTIONS)
        return stub_cls(self._channels[ep])

    def _call(self, contract: str, stub_cls: Any, method: str, req: Any, timeout: float | None = None) -> Any:
        try:
            return getattr(self._stub(contract, stub_cls), method)(req, timeout=timeout or self.timeout)
        except grpc.RpcError as exc:
            raise DemoError(f"{contract}: {exc.code().name}: {exc.details()}") from None

    def forget(self, contract: str) -> None:
        """Look ``contract`` up on the atlas again on the next call (its provider restarted elsewhere)."""
        self._endpoints.pop(contract, None)

    def close(self) -> None:
        for ch in self._channels.values():
            ch.close()
        self._channels.clear()

    # ------------------------------------------------------------------ sim

    def scene_info(self) -> dict[str, Any]:
        r = self._call(SCENE_INFO, stubs.RobonixPrimitiveSimSceneInfoStub, "GetSceneInfo",
                       sim_pb2.GetSceneInfo_Request())
        if not r.ok:
            raise DemoError(f"scene_info: {r.detail}")
        return json.loads(r.info_json)

    def ground_truth(self) -> GroundTruth:
        r = self._call(GROUND_TRUTH, stubs.RobonixPrimitiveSimGroundTruthStub, "GetGroundTruth",
                       sim_pb2.GetGroundTruth_Request(), timeout=2.0)
        if not r.ok:
            raise DemoError(f"ground_truth: {r.detail}")
        return GroundTruth(r.x, r.y, r.theta, r.sim_time)

    def collisions(self, since_sim_time: float) -> list[Collision]:
        r = self._call(COLLISIONS, stubs.RobonixPrimitiveSimCollisionsStub, "GetCollisions",
                       sim_pb2.GetCollisions_Request(since_sim_time=since_sim_time))
        return [Collision(e.stamp.sec + e.stamp.nanosec * 1e-9, e.robot_geom, e.other_geom, e.x, e.y)
                for e in r.events]

    # ------------------------------------------------------------------ navigation

    def navigate(self, goal: Goal, frame: str = "map") -> tuple[bool, str, str]:
        """(accepted, run_id, detail) for a goal in ``frame`` (the map frame unless told)."""
        req = navigation_pb2.Navigate_Request()
        req.goal.header.frame_id = frame
        req.goal.pose.position.x, req.goal.pose.position.y = goal.x, goal.y
        req.goal.pose.orientation.z = math.sin(goal.yaw / 2)
        req.goal.pose.orientation.w = math.cos(goal.yaw / 2)
        r = self._call(NAVIGATE, stubs.RobonixServiceNavigationNavigateStub, "Navigate", req, timeout=10.0)
        return bool(r.accepted), r.run_id, r.detail

    def status(self, run_id: str) -> NavStatus:
        r = self._call(STATUS, stubs.RobonixServiceNavigationNavigateStatusStub, "GetNavigationStatus",
                       navigation_pb2.GetNavigationStatus_Request(run_id=run_id), timeout=3.0)
        return NavStatus(bool(r.known), r.state, r.detail)

    def cancel(self, run_id: str) -> None:
        """Best effort: used on timeout and Ctrl-C, where a failure must not hide the real reason."""
        with contextlib.suppress(DemoError):
            self.cancel_run(run_id)

    def cancel_run(self, run_id: str) -> tuple[bool, str]:
        """(accepted, detail) of CancelNavigation; an empty ``run_id`` means the latest run."""
        r = self._call(CANCEL, stubs.RobonixServiceNavigationNavigateCancelStub, "CancelNavigation",
                       navigation_pb2.CancelNavigation_Request(run_id=run_id), timeout=3.0)
        return bool(r.accepted), r.detail

    # ------------------------------------------------------------------ map

    def map_card(self) -> map_pb2.GetMapCard_Response:
        return self._call(MAP_CARD, stubs.RobonixServiceMapMapCardStub, "GetMapCard",
                          map_pb2.GetMapCard_Request(), timeout=15.0)

"""Simulation-only contracts (``robonix/primitive/sim/...``), served over gRPC and as MCP tools.

Malformed requests (NaN, non-positive sizes) answer INVALID_ARGUMENT naming the field; a request the
world refuses (a teleport into a wall, a box on top of the robot) answers ``ok=false`` with the reason;
before a successful CMD_INIT every call answers FAILED_PRECONDITION.

``reset`` keeps sim time monotonic (a /clock running backwards makes ROS consumers drop their TF
buffers): it removes spawned boxes, puts the base back at the scene's start pose with odometry reset,
and hides earlier collision events; the noise RNG streams carry on.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import grpc

from hal_panda_mobile.loop import SimLoop
from hal_panda_mobile.sim import PandaMobileSim, SimConfigError
from robonix_api import StatusError
from robonix_api.dds.messages import Time
from robonix_api.proto_gen import builtin_interfaces_pb2, sim_pb2
from robonix_api.validation import ID_MAX, clip, require_finite, require_len, require_range

PREFIX = "robonix/primitive/sim/"
#: Positions may lie this far outside the scene bounds (the floor extends 5 m beyond them).
BOUNDS_MARGIN_M = 2.0
#: Headings beyond this many radians are refused (finite but physically meaningless, and lossy in float).
MAX_ABS_ANGLE = 1000.0
#: Largest side of a spawned box, metres.
MAX_BOX_SIZE_M = 50.0
GROUND_TRUTH = PREFIX + "ground_truth"
COLLISIONS = PREFIX + "collisions"
TELEPORT = PREFIX + "teleport"
RESET = PREFIX + "reset"
SCENE_INFO = PREFIX + "scene_info"
SPAWN_OBSTACLE = PREFIX + "spawn_obstacle"
RPC_CONTRACTS = (GROUND_TRUTH, COLLISIONS, TELEPORT, RESET, SCENE_INFO, SPAWN_OBSTACLE)


def _stamp(t: float) -> Any:
    msg = Time.from_sec(t)
    return builtin_interfaces_pb2.Time(sec=int(msg.sec), nanosec=int(msg.nanosec))


class SimHandlers:
    """Handlers bound to whatever session the provider currently has (``session()`` may return None)."""

    def __init__(self, session: Callable[[], Any]) -> None:
        self._session = session

    def _check_position(self, s: SimLoop, req: Any, angle: str) -> None:
        """x, y inside the scene bounds +- BOUNDS_MARGIN_M and a sane heading, else INVALID_ARGUMENT: a
        finite but huge value (1e308) would put NaN into MuJoCo's state."""
        xmin, ymin, xmax, ymax = (float(b) for b in s.sim.scene.bounds)
        require_range(req, "x", xmin - BOUNDS_MARGIN_M, xmax + BOUNDS_MARGIN_M, " m (scene bounds + margin)")
        require_range(req, "y", ymin - BOUNDS_MARGIN_M, ymax + BOUNDS_MARGIN_M, " m (scene bounds + margin)")
        require_range(req, angle, -MAX_ABS_ANGLE, MAX_ABS_ANGLE, " rad")

    def _live(self) -> SimLoop:
        """The running sim loop, or FAILED_PRECONDITION before a successful CMD_INIT."""
        s = self._session()
        if s is None:
            raise StatusError(grpc.StatusCode.FAILED_PRECONDITION, "simulator not initialized (send CMD_INIT)")
        return s.work

    def ground_truth(self, req: sim_pb2.GetGroundTruth_Request) -> sim_pb2.GetGroundTruth_Response:
        """Ground-truth base pose (world frame) and body-frame velocity, at the current sim time."""
        s = self._live()
        gt, t = s.call(lambda sim: (sim.ground_truth(), sim.time))
        return sim_pb2.GetGroundTruth_Response(ok=True, x=gt[0], y=gt[1], theta=gt[2], vx=gt[3], vy=gt[4],
                                               wz=gt[5], sim_time=t, detail=f"scene {s.sim.scene.name}")

    def collisions(self, req: sim_pb2.GetCollisions_Request) -> sim_pb2.GetCollisions_Response:
        """Collision episodes of the base (first contact of each) after since_sim_time, oldest first."""
        require_finite(req, "since_sim_time")
        s = self._live()
        since = max(req.since_sim_time, s.cleared_at)
        events = s.call(lambda sim: sim.collisions(since))
        out = [sim_pb2.CollisionEvent(stamp=_stamp(e.time), robot_geom=e.robot_geom, other_geom=e.other_geom,
                                      x=e.x, y=e.y) for e in events]
        return sim_pb2.GetCollisions_Response(ok=True, count=len(out), events=out)

    def teleport(self, req: sim_pb2.Teleport_Request) -> sim_pb2.Teleport_Response:
        """Place the base at rest at (x, y, theta) in the world frame; refused if it would collide."""
        require_finite(req, "x", "y", "theta")
        s = self._live()
        self._check_position(s, req, "theta")
        try:
            s.call(lambda sim: sim.teleport(req.x, req.y, req.theta), republish=True)
        except SimConfigError as exc:
            return sim_pb2.Teleport_Response(ok=False, detail=str(exc))
        return sim_pb2.Teleport_Response(ok=True, detail=f"at ({req.x:g}, {req.y:g}, {req.theta:g})")

    def reset(self, req: sim_pb2.ResetSim_Request) -> sim_pb2.ResetSim_Response:
        """Remove spawned obstacles, return the base to the start pose, forget earlier collisions."""
        s = self._live()

        def do(sim: PandaMobileSim) -> int:
            spawned = [o["name"] for o in sim.scene_info()["obstacles"] if str(o["ref"]).startswith("spawned")]
            for name in spawned:
                sim.remove_box(name)
            sim.teleport(*sim.scene.start)
            s.cleared_at = sim.time
            return len(spawned)

        removed = s.call(do, republish=True)
        return sim_pb2.ResetSim_Response(ok=True, detail=f"base at start pose; {removed} spawned obstacle(s) "
                                                         "removed; sim time kept monotonic")

    def scene_info(self, req: sim_pb2.GetSceneInfo_Request) -> sim_pb2.GetSceneInfo_Response:
        """Scene name, bounds, start, waypoints and obstacles (incl. spawned) as JSON, plus loop stats."""
        s = self._live()
        info = s.call(lambda sim: {**sim.scene_info(), "sim_time": sim.time})
        info["loop"] = s.stats.as_dict()
        info["mode"] = s.mode
        return sim_pb2.GetSceneInfo_Response(ok=True, scene=info["name"], info_json=json.dumps(info))

    def spawn_obstacle(self, req: sim_pb2.SpawnObstacle_Request) -> sim_pb2.SpawnObstacle_Response:
        """Drop a static box (full sizes size_x, size_y; 0.8 m tall, so the lidar sees it) into the world."""
        require_finite(req, "x", "y", "size_x", "size_y", "yaw")
        for name in ("size_x", "size_y"):
            if getattr(req, name) <= 0:
                raise StatusError(grpc.StatusCode.INVALID_ARGUMENT, f"{name}: must be > 0, got {getattr(req, name)}")
            require_range(req, name, 0.0, MAX_BOX_SIZE_M, " m")
        require_len(req, "name", ID_MAX)
        if any(not (c.isprintable() and not c.isspace()) for c in req.name.strip()):
            raise StatusError(grpc.StatusCode.INVALID_ARGUMENT,
                              f"name: {clip(req.name)} has spaces or control characters")
        s = self._live()
        self._check_position(s, req, "yaw")
        name = req.name.strip() or f"obstacle_{s.spawn_count}"
        try:
            s.call(lambda sim: sim.spawn_box(name, req.x, req.y, req.size_x, req.size_y, req.yaw),
                          republish=True)
        except SimConfigError as exc:
            return sim_pb2.SpawnObstacle_Response(ok=False, detail=str(exc))
        s.spawn_count += 1
        return sim_pb2.SpawnObstacle_Response(ok=True, detail=name)

    def table(self) -> dict[str, Callable[..., Any]]:
        """contract id -> handler, for ``robonix_api.hosting.serve_contracts``."""
        return {GROUND_TRUTH: self.ground_truth, COLLISIONS: self.collisions, TELEPORT: self.teleport,
                RESET: self.reset, SCENE_INFO: self.scene_info, SPAWN_OBSTACLE: self.spawn_obstacle}

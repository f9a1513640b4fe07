"""The map RPC contracts (``robonix/service/map/...``), one handler each, served over gRPC and MCP.

Handlers are live from process start: before a successful CMD_INIT they answer ``ok=false`` with
"not initialized". Malformed arguments (NaN pose, a map_id with a path in it) answer INVALID_ARGUMENT
naming the field; an operation that fails (unwritable map_dir, a corrupt map file) answers ``ok=false``
with the reason and leaves the running state and the files on disk as they were.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Callable
from typing import Any

import grpc

from robonix_api import StatusError
from robonix_api.proto_gen import map_pb2
from robonix_api.validation import clip_message, require_finite, require_range
from slam_service.core import SlamEngine
from slam_service.map_paths import check_note, clip
from slam_service.maps import MapIdError, MapInvalidError, MapStore, MapStoreError, check_id, load_engine
from slam_service.render import render_map_png

log = logging.getLogger("slam_service.handlers")
NS = "robonix/service/map/"
NOT_INIT = "not initialized (send CMD_INIT)"
MODES = ("mapping", "localization")
#: A map-frame pose beyond this many metres from the origin (or a heading beyond MAX_ABS_ANGLE rad) is refused.
MAX_ABS_COORD_M = 10_000.0
MAX_ABS_ANGLE = 1000.0


def _pose_in_range(req: Any) -> None:
    require_finite(req, "x", "y", "theta")
    for name in ("x", "y"):
        require_range(req, name, -MAX_ABS_COORD_M, MAX_ABS_COORD_M, " m")
    require_range(req, "theta", -MAX_ABS_ANGLE, MAX_ABS_ANGLE, " rad")


def _map_id(map_id: str) -> str:
    try:
        return check_id(map_id)
    except MapIdError as exc:
        raise StatusError(grpc.StatusCode.INVALID_ARGUMENT, str(exc)) from None


class MapHandlers:
    """Handlers bound to whatever session the provider has (``session()`` returns None before INIT).

    A session's ``setup`` is the provider's ``SlamSetup`` (config, map store, footprint) and its ``work``
    the running :class:`~slam_service.loop.SlamLoop`.
    """

    def __init__(self, session: Callable[[], Any]) -> None:
        self._session = session

    def table(self) -> dict[str, Callable[..., Any]]:
        """contract id -> handler, for ``robonix_api.hosting.serve_contracts``."""
        return {NS + name: getattr(self, name) for name in (
            "save_map", "load_map", "list_maps", "delete_map", "switch_mode", "get_mode", "get_pose", "reset_map",
            "pose_estimate", "map_card")}

    # ---------------------------------------------------------------- maps on disk
    def save_map(self, req: map_pb2.SaveMap_Request) -> map_pb2.SaveMap_Response:
        """Save the current map as <map_dir>/<map_id>/ (map.yaml + map.pgm, session.npz, meta.json)."""
        map_id = _map_id(req.map_id)
        try:
            check_note(req.note)
        except ValueError as exc:
            raise StatusError(grpc.StatusCode.INVALID_ARGUMENT, str(exc)) from None
        s = self._session()
        if s is None:
            return map_pb2.SaveMap_Response(ok=False, map_id=map_id, detail=NOT_INIT)
        with s.work.lock:  # consistent grid + session; scans wait meanwhile
            engine: SlamEngine = s.work.engine
            engine.flush()  # a saved map shows every node at its optimised pose (the live map may lag a little)
            grid = engine.map()
            session = engine.session() if engine.graph.n_nodes else None
        writer = None
        if session is not None:
            from slam_service.session_io import save_session

            def writer(path: Any) -> None:
                save_session(session, path)
        try:
            path = s.setup.store.save(map_id, grid, writer, req.note)
        except MapStoreError as exc:
            log.warning("save_map: %s", exc)
            return map_pb2.SaveMap_Response(ok=False, map_id=map_id, detail=str(exc))
        return map_pb2.SaveMap_Response(ok=True, map_id=map_id,
                                        detail=f"saved {grid.width}x{grid.height} @ {grid.resolution} m to {path}")

    def load_map(self, req: map_pb2.LoadMap_Request) -> map_pb2.LoadMap_Response:
        """Load a saved map: localization (grid) by default, or mapping (continue the saved session)."""
        map_id = _map_id(req.map_id)
        mode = req.mode.strip() or "localization"
        if mode not in MODES:
            raise StatusError(grpc.StatusCode.INVALID_ARGUMENT,
                              f"mode: must be mapping or localization, got {clip(mode)}")
        if req.has_initial_pose:
            _pose_in_range(req)
        s = self._session()
        if s is None:
            return map_pb2.LoadMap_Response(ok=False, detail=NOT_INIT)
        pose = (req.x, req.y, req.theta) if req.has_initial_pose else None
        try:
            engine = load_engine(s.setup.store, s.setup.slam, map_id, mode, pose)
        except MapInvalidError as exc:
            log.warning("load_map: %s", exc)
            raise StatusError(grpc.StatusCode.INVALID_ARGUMENT, clip_message(str(exc))) from None
        except (MapStoreError, ValueError) as exc:
            log.warning("load_map: %s", exc)
            return map_pb2.LoadMap_Response(ok=False, detail=str(exc))
        s.work.replace_engine(engine, map_id)  # only once the map loaded: on any error the running engine is kept
        log.info("loaded map %r in %s mode", map_id, mode)
        return map_pb2.LoadMap_Response(ok=True, detail=f"loaded {map_id!r} in {mode} mode"
                                        + (f" at ({req.x:g}, {req.y:g}, {req.theta:g})" if pose else ""))

    def list_maps(self, req: map_pb2.ListMaps_Request) -> map_pb2.ListMaps_Response:
        """Saved maps as JSON: [{map_id, path, note, created, resolution, width, height, has_session}]."""
        s = self._session()
        if s is None:
            return map_pb2.ListMaps_Response(ok=False, detail=NOT_INIT, maps_json="[]")
        store: MapStore = s.setup.store
        maps, total = store.listing()
        shown = f"{len(maps)} map(s)" if len(maps) == total else f"newest {len(maps)} of {total} map(s) (reply capped)"
        return map_pb2.ListMaps_Response(ok=True, detail=f"{shown} in {store.root}", maps_json=json.dumps(maps))

    def delete_map(self, req: map_pb2.DeleteMap_Request) -> map_pb2.DeleteMap_Response:
        """Delete a saved map's folder (the map in memory is not affected)."""
        map_id = _map_id(req.map_id)
        s = self._session()
        if s is None:
            return map_pb2.DeleteMap_Response(ok=False, map_id=map_id, detail=NOT_INIT)
        try:
            s.setup.store.delete(map_id)
        except MapStoreError as exc:
            return map_pb2.DeleteMap_Response(ok=False, map_id=map_id, detail=str(exc))
        return map_pb2.DeleteMap_Response(ok=True, map_id=map_id, detail="deleted")

    # ---------------------------------------------------------------- mode, pose, reset
    def switch_mode(self, req: map_pb2.SwitchMode_Request) -> map_pb2.SwitchMode_Response:
        """mapping <-> localization (localization on the loaded map, or on the map built so far)."""
        mode = req.mode.strip()
        if mode not in MODES:
            raise StatusError(grpc.StatusCode.INVALID_ARGUMENT,
                              f"mode: must be mapping or localization, got {clip(mode)}")
        s = self._session()
        if s is None:
            return map_pb2.SwitchMode_Response(ok=False, detail=NOT_INIT)
        with s.work.lock:
            try:
                s.work.engine.set_mode(mode)
            except ValueError as exc:
                return map_pb2.SwitchMode_Response(ok=False, detail=str(exc))
        s.work.map_changed()
        return map_pb2.SwitchMode_Response(ok=True, detail=f"mode {mode}")

    def get_mode(self, req: map_pb2.GetMode_Request) -> map_pb2.GetMode_Response:
        """Current mode; detail is JSON: integrating (ACTIVE) or paused, plus input/skip counters."""
        s = self._session()
        if s is None:
            return map_pb2.GetMode_Response(ok=False, detail=NOT_INIT)
        st = s.work.stats()
        return map_pb2.GetMode_Response(ok=True, mode=st["mode"], detail=json.dumps(st))

    def get_pose(self, req: map_pb2.GetPose_Request) -> map_pb2.GetPose_Response:
        """Robot (base) pose in the map frame: last map->odom estimate composed with the latest odometry."""
        s = self._session()
        if s is None:
            return map_pb2.GetPose_Response(ok=False, detail=NOT_INIT)
        x, y, th = s.work.robot_pose()
        n = s.work.engine.stats.scans_integrated
        return map_pb2.GetPose_Response(ok=True, x=x, y=y, theta=th, frame_id=s.setup.cfg.frames.map,
                                        detail=f"{n} scan(s) integrated")

    def reset_map(self, req: map_pb2.ResetMap_Request) -> map_pb2.ResetMap_Response:
        """Forget the map and trajectory (a map loaded for localization is kept)."""
        s = self._session()
        if s is None:
            return map_pb2.ResetMap_Response(ok=False, detail=NOT_INIT)
        with s.work.lock:
            s.work.engine.reset()
        s.work.map_changed()
        return map_pb2.ResetMap_Response(ok=True, detail="map cleared")

    def pose_estimate(self, req: map_pb2.PoseEstimate_Request) -> map_pb2.PoseEstimate_Response:
        """Set the robot's map-frame pose (applied at the next scan), e.g. to relocalize."""
        _pose_in_range(req)
        s = self._session()
        if s is None:
            return map_pb2.PoseEstimate_Response(ok=False, detail=NOT_INIT)
        s.work.set_pose((req.x, req.y, req.theta))
        return map_pb2.PoseEstimate_Response(ok=True, detail=f"pose set to ({req.x:g}, {req.y:g}, {req.theta:g}); "
                                                             "applied at the next scan")

    # ---------------------------------------------------------------- dashboard card
    def map_card(self, req: map_pb2.GetMapCard_Request) -> map_pb2.GetMapCard_Response:
        """PNG of the grid (unknown grey, free white, occupied black) + size, origin, robot pose, footprint."""
        s = self._session()
        if s is None:
            return map_pb2.GetMapCard_Response(ok=False, detail=NOT_INIT)
        with s.work.lock:
            engine: SlamEngine = s.work.engine
            grid = engine.map()
            traj = engine.trajectory() if engine.mode == "mapping" else None
            has_pose = engine.stats.scans_received > 0 or engine.mode == "localization"
        pose = s.work.robot_pose() if has_pose else None
        png = render_map_png(grid, pose, s.setup.footprint if pose is not None else None, traj)
        flat = [v for xy in s.setup.footprint for v in xy]
        resp = map_pb2.GetMapCard_Response(ok=True, detail=f"mode {engine.mode}", png=png, width=grid.width,
                                           height=grid.height, resolution=grid.resolution, origin_x=grid.origin_x,
                                           origin_y=grid.origin_y, frame_id=s.setup.cfg.frames.map,
                                           has_robot_pose=pose is not None, footprint_polygon_xy=flat)
        if pose is not None:
            resp.robot_x, resp.robot_y, resp.robot_yaw = pose
        return resp

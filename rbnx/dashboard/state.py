"""What the dashboard shows, gathered the way any robonix consumer gathers it.

DDS (data plane): /map (latched), /tf + /tf_static (robot pose = map->base_link), /scan (points put into
the map frame through TF), /plan. Atlas + gRPC (control plane): the providers and their lifecycle
states, the map card's footprint polygon, navigate / status / cancel, and each provider's lifecycle
Driver for activate / deactivate. ``snapshot()`` is one JSON-ready dict; ``version`` increases whenever
something shown changed, so the server pushes only then.
"""

from __future__ import annotations

import hashlib
import io
import logging
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from rbnx.atlas_rpc import CMD, STATE_NAMES, Atlas, AtlasError, Driver, driver_capability
from rbnx.demo.boot import DemoError
from rbnx.demo.goals import TERMINAL, Goal
from rbnx.demo.rpc import DemoRpc

log = logging.getLogger(__name__)
MAX_PLAN_POINTS = 400
ATLAS_POLL_S = 0.5
STATUS_POLL_S = 0.5


class DashboardError(ValueError):
    """A request the dashboard refuses; str() is one line (sent to the browser with HTTP 400/502)."""


def grid_png(width: int, height: int, data: np.ndarray) -> bytes:
    """OccupancyGrid cells -> greyscale PNG, north up (row 0 = highest y): free white, occupied black,
    unknown grey, probabilities in between."""
    from PIL import Image

    cells = np.asarray(data, dtype=np.int16).reshape(height, width)
    img = np.full(cells.shape, 205, dtype=np.uint8)
    known = cells >= 0
    img[known] = (255 - np.clip(cells[known], 0, 100) * 255 // 100).astype(np.uint8)
    buf = io.BytesIO()
    Image.fromarray(np.flipud(img), mode="L").save(buf, format="PNG", compress_level=1)
    return buf.getvalue()


@dataclass
class MapImage:
    version: int
    width: int
    height: int
    resolution: float
    origin_x: float
    origin_y: float
    frame_id: str
    png: bytes

    def meta(self) -> dict[str, Any]:
        return {"version": self.version, "width": self.width, "height": self.height,
                "resolution": self.resolution, "origin_x": self.origin_x, "origin_y": self.origin_y,
                "frame_id": self.frame_id}


class LiveState:
    """DDS subscriptions + atlas polling behind a lock; safe to read from the web server's threads."""

    def __init__(self, atlas: str | Callable[[], str | None], domain_id: int | None = None,
                 frames: tuple[str, str] = ("map", "base_link")) -> None:
        self._atlas_src = atlas
        self.domain_id = domain_id
        self.map_frame, self.base_frame = frames
        self.version = 0
        self._lock = threading.Lock()
        self._changed = threading.Condition(self._lock)
        self._map: MapImage | None = None
        self._map_digest = b""
        self._scan: tuple[str, np.ndarray, np.ndarray] | None = None  # frame, angles, ranges
        self._plan: list[list[float]] = []
        self._providers: list[dict[str, Any]] = []
        self._footprint: list[list[float]] = []
        self._goal: dict[str, float] | None = None
        self._nav: dict[str, str] | None = None
        self._run_id = ""
        self._last_pose: tuple[float, float, float] | None = None
        self._stop = threading.Event()
        self._node: Any = None
        self._tf: Any = None
        self._rpc: DemoRpc | None = None
        self._rpc_atlas = ""
        self._rpc_lock = threading.Lock()
        self._thread = threading.Thread(target=self._poll, name="dashboard-poll", daemon=True)

    # ------------------------------------------------------------------ lifecycle

    def start(self) -> None:
        from robonix_api.dds import DdsNode, LaserScan, OccupancyGrid, TfBuffer
        from robonix_api.dds import Path as PathMsg

        self._node = DdsNode(domain_id=self.domain_id, name="rbnx_dashboard")
        self._tf = TfBuffer(self._node)
        self._node.create_subscription("/map", OccupancyGrid, self._on_map, "latched", 1)
        self._node.create_subscription("/scan", LaserScan, self._on_scan, "best_effort", 5)
        self._node.create_subscription("/plan", PathMsg, self._on_plan, "reliable", 5)
        self._node.create_subscription("/tf", _tf_type(), self._on_tf, "reliable", 100)
        self._thread.start()

    def close(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(5.0)
        for thing in (self._tf, self._node):
            if thing is not None:
                thing.close()
        self._tf = self._node = None
        if self._rpc is not None:
            self._rpc.close()

    def atlas(self) -> str | None:
        return self._atlas_src() if callable(self._atlas_src) else self._atlas_src

    # ------------------------------------------------------------------ DDS callbacks

    def _bump(self) -> None:
        self.version += 1
        self._changed.notify_all()

    def _on_tf(self, _msg: Any) -> None:
        """The TfBuffer has its own subscription; this one only says "the pose may have moved"."""
        pose = self.pose()
        with self._lock:
            if pose is not None and pose != self._last_pose:
                self._last_pose = pose
                self._bump()

    def _on_map(self, msg: Any) -> None:
        data = np.asarray(msg.data, dtype=np.int8)
        info = msg.info
        digest = hashlib.blake2b(data.tobytes(), digest_size=16).digest() + repr(
            (info.width, info.height, info.resolution, info.origin.position.x, info.origin.position.y)).encode()
        if digest == self._map_digest:
            return  # republished but unchanged: the browser keeps its image
        png = grid_png(int(info.width), int(info.height), data)
        with self._lock:
            self._map_digest = digest
            v = (self._map.version if self._map else 0) + 1
            self._map = MapImage(v, int(info.width), int(info.height), float(info.resolution),
                                 float(info.origin.position.x), float(info.origin.position.y),
                                 msg.header.frame_id or self.map_frame, png)
            self._bump()

    def _on_scan(self, msg: Any) -> None:
        ranges = np.asarray(msg.ranges, dtype=np.float64)
        angles = msg.angle_min + np.arange(ranges.size) * msg.angle_increment
        ok = np.isfinite(ranges) & (ranges > max(msg.range_min, 1e-3)) & (ranges < msg.range_max)
        with self._lock:
            self._scan = (msg.header.frame_id.strip().lstrip("/") or "laser", angles[ok], ranges[ok])
            self._bump()

    def _on_plan(self, msg: Any) -> None:
        pts = [[p.pose.position.x, p.pose.position.y] for p in msg.poses]
        step = max(1, math.ceil(len(pts) / MAX_PLAN_POINTS))
        pts = pts[::step] + (pts[-1:] if pts and (len(pts) - 1) % step else [])
        with self._lock:
            self._plan = [[round(x, 3), round(y, 3)] for x, y in pts]
            self._bump()

    # ------------------------------------------------------------------ views

    def pose(self) -> tuple[float, float, float] | None:
        tf = self._tf
        if tf is None:
            return None
        try:
            x, y, yaw = tf.lookup_pose2d(self.map_frame, self.base_frame)
        except Exception:
            return None
        return round(x, 4), round(y, 4), round(yaw, 4)

    def _scan_points(self, scan: tuple[str, np.ndarray, np.ndarray] | None) -> list[list[float]]:
        if scan is None or self._tf is None:
            return []
        frame, angles, ranges = scan
        try:
            x, y, yaw = self._tf.lookup_pose2d(self.map_frame, frame)
        except Exception:
            return []
        a = angles + yaw
        px, py = x + ranges * np.cos(a), y + ranges * np.sin(a)
        return np.round(np.stack([px, py], axis=1), 3).tolist()

    def map_image(self) -> MapImage | None:
        with self._lock:
            return self._map

    def snapshot(self) -> dict[str, Any]:
        pose = self.pose()
        with self._lock:
            scan = self._scan
            snap = {"version": self.version, "t": time.time(), "map": self._map.meta() if self._map else None,
                    "plan": self._plan, "providers": self._providers, "footprint": self._footprint,
                    "goal": self._goal, "nav": self._nav}
        snap["pose"] = None if pose is None else {"x": pose[0], "y": pose[1], "yaw": pose[2]}
        snap["scan"] = self._scan_points(scan)
        return snap

    def wait_change(self, since: int, timeout: float) -> int:
        with self._changed:
            self._changed.wait_for(lambda: self.version != since, timeout)
            return self.version

    # ------------------------------------------------------------------ control plane

    def _client(self) -> DemoRpc:
        addr = self.atlas()
        if not addr:
            raise DashboardError("no atlas address yet (is the system booted?)")
        with self._rpc_lock:
            if self._rpc is None or self._rpc_atlas != addr:
                if self._rpc is not None:
                    self._rpc.close()
                self._rpc, self._rpc_atlas = DemoRpc(addr), addr
            return self._rpc

    def _forget_client(self) -> None:
        """After a failed call: resolve the providers through the atlas again next time (one may have
        restarted on another port)."""
        with self._rpc_lock:
            if self._rpc is not None:
                self._rpc.close()
            self._rpc = None

    def send_goal(self, x: float, y: float, yaw: float) -> dict[str, Any]:
        for name, v in (("x", x), ("y", y), ("yaw", yaw)):
            if not isinstance(v, int | float) or not math.isfinite(v):
                raise DashboardError(f"{name}: must be a finite number")
        try:
            accepted, run_id, detail = self._client().navigate(Goal("dashboard", x, y, yaw), self.map_frame)
        except DemoError as exc:
            self._forget_client()
            raise DashboardError(str(exc)) from None
        with self._lock:
            self._goal = {"x": x, "y": y, "yaw": yaw}
            if accepted:
                self._run_id = run_id
                self._nav = {"run_id": run_id, "state": "ACCEPTED", "detail": detail}
            else:
                self._nav = {"run_id": "", "state": "REJECTED", "detail": detail}
            self._bump()
        return {"accepted": accepted, "run_id": run_id, "detail": detail}

    def cancel(self) -> dict[str, Any]:
        try:
            accepted, detail = self._client().cancel_run(self._run_id)
        except DemoError as exc:
            self._forget_client()
            raise DashboardError(str(exc)) from None
        return {"accepted": accepted, "detail": detail}

    def lifecycle(self, provider: str, command: str) -> dict[str, Any]:
        cmds = {"activate": CMD.CMD_ACTIVATE, "deactivate": CMD.CMD_DEACTIVATE}
        if command not in cmds:
            raise DashboardError(f"command: must be activate or deactivate, got {command!r}")
        addr = self.atlas()
        if not addr:
            raise DashboardError("no atlas address yet")
        try:
            with Atlas(addr, timeout=3.0) as atlas:
                prov = atlas.provider(provider)
                cid = driver_capability(prov) if prov else None
                if cid is None:
                    raise DashboardError(f"provider: {provider!r} is not registered with a lifecycle Driver")
                endpoint, _ = atlas.endpoint(provider, cid, 1)
        except AtlasError as exc:
            raise DashboardError(str(exc)) from None
        d = Driver(endpoint)
        try:
            reply = d.call(cmds[command], None, 10.0)
        finally:
            d.close()
        self._refresh_providers()
        return {"ok": reply.ok, "state": reply.state, "error": reply.error}

    # ------------------------------------------------------------------ polling thread

    def _refresh_providers(self) -> None:
        addr = self.atlas()
        if not addr:
            return
        try:
            with Atlas(addr, timeout=2.0) as atlas:
                provs = atlas.query()
        except AtlasError:
            return
        rows = [{"id": p.id, "state": STATE_NAMES.get(p.state, str(p.state)),
                 "lifecycle": driver_capability(p) is not None} for p in provs]
        rows.sort(key=lambda r: r["id"])
        with self._lock:
            if rows != self._providers:
                self._providers = rows
                self._bump()

    def _refresh_nav(self) -> None:
        with self._lock:
            run_id, nav = self._run_id, self._nav
        if not run_id or (nav and nav["state"] in TERMINAL):
            return
        try:
            st = self._client().status(run_id)
        except DemoError:
            self._forget_client()
            return
        except DashboardError:
            return
        new = {"run_id": run_id, "state": st.state if st.known else "UNKNOWN", "detail": st.detail}
        with self._lock:
            if new != self._nav and run_id == self._run_id:
                self._nav = new
                self._bump()

    def _refresh_footprint(self) -> None:
        if self._footprint or self._map is None:
            return
        try:
            card = self._client().map_card()
        except (DemoError, DashboardError):
            return
        xy = list(card.footprint_polygon_xy)
        if len(xy) >= 6:
            with self._lock:
                self._footprint = [[round(xy[i], 3), round(xy[i + 1], 3)] for i in range(0, len(xy) - 1, 2)]
                self._bump()

    def _poll(self) -> None:
        while not self._stop.is_set():
            for step in (self._refresh_providers, self._refresh_nav, self._refresh_footprint):
                try:
                    step()
                except Exception:
                    log.exception("dashboard poll step %s failed", step.__name__)
            self._stop.wait(min(ATLAS_POLL_S, STATUS_POLL_S))


def _tf_type() -> type:
    from robonix_api.dds import TFMessage

    return TFMessage

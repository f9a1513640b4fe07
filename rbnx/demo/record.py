"""What `rbnx demo` records while it drives: ground truth (sim contract, for honest path length and final
error), the map-frame pose from TF (what the map image shows), the latest /map and every /plan, and the
final map.png rendered from them."""

from __future__ import annotations

import contextlib
import math
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import grpc
import numpy as np

from rbnx.demo.boot import DemoError
from rbnx.demo.rpc import DemoRpc, GroundTruth
from robonix_api.atlas_client import AtlasClient

MAX_IMAGE_PX = 1600
GT_ODOM = "robonix/primitive/sim/ground_truth_odom"
GT_ODOM_TOPIC = "/ground_truth/odom"


@dataclass
class PlanRecord:
    seq: int
    points: np.ndarray  # (N, 2) map frame


class Recorder:
    """A background thread sampling poses at ``rate_hz`` (wall) plus DDS subscriptions to /plan and /map."""

    def __init__(self, rpc: DemoRpc, domain_id: int, rate_hz: float = 10.0) -> None:
        self.rpc = rpc
        self.domain_id = domain_id
        self.period = 1.0 / rate_hz
        self.gt: list[GroundTruth] = []
        self.gt_odom: list[tuple[float, float, float, float]] = []  # (sim time, x, y, yaw) from the dense topic
        self.map_traj: list[tuple[float, float, float]] = []
        self.plans: list[PlanRecord] = []
        self.grid_msg: Any = None
        self.warnings: list[str] = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="rbnx-demo-recorder", daemon=True)
        self._node: Any = None
        self._tf: Any = None
        self._plan_sub: Any = None

    # ------------------------------------------------------------------ lifecycle

    def start(self) -> None:
        try:
            from robonix_api.dds import DdsNode, OccupancyGrid, Odometry, TfBuffer
            from robonix_api.dds import Path as PathMsg

            self._node = DdsNode(domain_id=self.domain_id, name="rbnx_demo")
            self._tf = TfBuffer(self._node)
            self._plan_sub = self._node.create_subscription("/plan", PathMsg, self._on_plan, "reliable", 10)
            self._node.create_subscription("/map", OccupancyGrid, self._on_map, "latched", 1)
            self._node.create_subscription(self._gt_topic(), Odometry, self._on_gt_odom, "reliable", 50)
        except Exception as exc:
            self.warnings.append(f"DDS unavailable ({exc}); map.png from the map card, no plan overlay")
            print(f"warning: {self.warnings[-1]}", file=sys.stderr)
            self._close_dds()
        self._thread.start()

    def wait_ready(self, timeout_s: float, stop: threading.Event) -> bool:
        """Until TF map→base_link resolves and /plan is matched: the nav publishes a plan once per change on
        a volatile topic, so a goal sent before DDS discovery finished would lose its first plan."""
        if self._node is None:
            return False
        deadline = time.monotonic() + timeout_s
        while not stop.is_set() and time.monotonic() < deadline:
            if self.map_pose() is not None and self._plan_sub.matched_count() > 0:
                return True
            stop.wait(0.1)
        self.warnings.append(f"DDS not ready after {timeout_s:g}s (TF map->base_link / /plan): "
                             "trajectory or plan overlay may start late")
        return False

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(5.0)
        self._close_dds()

    def _close_dds(self) -> None:
        tf, node, self._tf, self._node = self._tf, self._node, None, None
        for thing in (tf, node):
            if thing is not None:
                with contextlib.suppress(Exception):  # best effort at teardown
                    thing.close()

    # ------------------------------------------------------------------ inputs

    def _on_plan(self, msg: Any) -> None:
        pts = np.array([[p.pose.position.x, p.pose.position.y] for p in msg.poses], dtype=float).reshape(-1, 2)
        with self._lock:
            self.plans.append(PlanRecord(len(self.plans), pts))

    def _gt_topic(self) -> str:
        """The HAL's ground-truth odometry topic, looked up like any consumer does (default if absent)."""
        try:
            with AtlasClient(self.rpc.atlas) as client:
                caps = client.find_capability(contract_id=GT_ODOM, transport="ros2")
                if caps:
                    with client.connect_capability(consumer_id="rbnx-demo", provider_id=caps[0].provider_id,
                                                   contract_id=GT_ODOM, transport="ros2") as ch:
                        return ch.endpoint or GT_ODOM_TOPIC
        except (grpc.RpcError, ValueError):
            pass
        return GT_ODOM_TOPIC

    def _on_gt_odom(self, msg: Any) -> None:
        t = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
        with self._lock:
            self.gt_odom.append((t, p.x, p.y, yaw))

    def _on_map(self, msg: Any) -> None:
        with self._lock:
            self.grid_msg = msg

    def _run(self) -> None:
        while not self._stop.is_set():
            self.sample()
            self._stop.wait(self.period)

    def sample(self) -> GroundTruth | None:
        """One ground-truth + TF sample (also called by the goal loop at goal boundaries)."""
        try:
            gt = self.rpc.ground_truth()
        except DemoError:
            return None
        pose = self.map_pose()
        with self._lock:
            self.gt.append(gt)
            if pose is not None:
                self.map_traj.append(pose)
        return gt

    def map_pose(self) -> tuple[float, float, float] | None:
        tf = self._tf
        if tf is None:
            return None
        try:
            return tuple(tf.lookup_pose2d("map", "base_link"))  # type: ignore[return-value]
        except Exception:
            return None

    # ------------------------------------------------------------------ views

    def mark(self) -> tuple[int, int]:
        """Positions in the (ground truth, plans) logs, to slice one goal's share later."""
        with self._lock:
            return len(self.gt), len(self.plans)

    def gt_between(self, start: int, end: int) -> list[GroundTruth]:
        with self._lock:
            return list(self.gt[start:end])

    def gt_path(self, t0: float, t1: float) -> list[tuple[float, float]]:
        """Dense ground-truth positions stamped within [t0, t1] sim seconds (empty without DDS)."""
        with self._lock:
            return [(x, y) for t, x, y, _ in self.gt_odom if t0 <= t <= t1]

    def gt_poses(self, t0: float, t1: float) -> list[tuple[float, float, float]]:
        """Dense ground-truth poses (x, y, yaw) stamped within [t0, t1] sim seconds (empty without DDS)."""
        with self._lock:
            return [(x, y, yaw) for t, x, y, yaw in self.gt_odom if t0 <= t <= t1]

    def pose_before(self, sim_time: float) -> tuple[float, float, float, float] | None:
        """The latest ground-truth (sim time, x, y, yaw) stamped at or before ``sim_time``: the dense topic's
        when it has one, else the sampled poses' (None when neither does)."""
        with self._lock:
            dense = [s for s in self.gt_odom if s[0] <= sim_time]
            if dense:
                return dense[-1]
            sampled = [g for g in self.gt if g.sim_time <= sim_time]
        return (sampled[-1].sim_time, sampled[-1].x, sampled[-1].y, sampled[-1].theta) if sampled else None

    def plan_for(self, start: int, end: int, target: tuple[float, float]) -> np.ndarray | None:
        """The goal's first plan that ends near its target (the route as first planned), else its last one."""
        with self._lock:
            plans = [p.points for p in self.plans[start:end] if len(p.points) >= 2]
        for pts in plans:
            if math.hypot(pts[-1, 0] - target[0], pts[-1, 1] - target[1]) < 0.6:
                return pts
        return plans[-1] if plans else None


def render_map(path: Path, rec: Recorder, rpc: DemoRpc, plans: list[np.ndarray]) -> str:
    """Write map.png: /map (else the provider's map card) + map-frame trajectory + plans + footprint.
    Returns a one-line description of what was drawn."""
    card = None
    try:
        card = rpc.map_card()
    except DemoError as exc:
        rec.warnings.append(f"map_card: {exc}")
    footprint = None
    if card is not None and len(card.footprint_polygon_xy) >= 6:
        footprint = np.asarray(card.footprint_polygon_xy, dtype=float).reshape(-1, 2)
    with rec._lock:
        msg = rec.grid_msg
        traj = np.asarray([p[:2] for p in rec.map_traj], dtype=float).reshape(-1, 2)
    pose = rec.map_pose() or (rec.map_traj[-1] if rec.map_traj else None)
    if pose is None and card is not None and card.has_robot_pose:
        pose = (card.robot_x, card.robot_y, card.robot_yaw)
    if msg is None:
        if card is None or not card.ok or not card.png:
            raise DemoError("no map to draw: no /map message and no map card")
        _write(path, card.png)
        return f"{card.width}x{card.height} px map card from the mapping service (no /map over DDS)"
    from robonix_api.dds.convert import msg_to_grid
    from slam_service.render import render_map_png

    grid = msg_to_grid(msg)
    scale = max(1, min(4, MAX_IMAGE_PX // max(grid.width, grid.height, 1)))
    plan = np.concatenate(plans) if plans else None
    png = render_map_png(grid, pose, footprint, traj if len(traj) >= 2 else None, plan, scale=scale)
    _write(path, png)
    return (f"{grid.width * scale}x{grid.height * scale} px, {grid.resolution:g} m/cell x{scale}: map, "
            f"trajectory ({len(traj)} poses, blue), {len(plans)} plan(s) (green), robot + footprint (red)")


def _write(path: Path, data: bytes) -> None:
    tmp = path.with_suffix(".png.tmp")
    tmp.write_bytes(data)
    tmp.replace(path)

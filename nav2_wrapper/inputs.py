"""The navigation provider's DDS inputs: latest map, odometry and scan, the TF buffer and the (sim) clock.

Callbacks only store the newest sample (with a sequence number, so the loop feeds the costmaps each
new map or scan once) and the clock time it arrived; every decision is made by the loop thread.

Each input also knows whether its source is alive: DDS liveliness of the writers (a killed or stopped
provider is noticed within the writers' lease, 0.5 s by default), the atlas' TERMINATED notice (set by
the upstream watch), and staleness. ``lost()`` turns that into {source: why} for the loop's pause/grace
logic; ``rebind()`` follows a restarted provider to new topics without restarting navigation.
"""

from __future__ import annotations

import logging
import math
import threading
from dataclasses import dataclass
from typing import Any

import numpy as np

from nav2_wrapper.core import Scan
from robonix_api.dds import LaserScan, OccupancyGrid, Odometry, SimClock, TfBuffer, TfError
from robonix_api.dds.convert import msg_to_grid
from robonix_common.geometry import Pose2D, compose
from robonix_common.grid import GridMap

from .config import Frames
from .upstream import Binding

log = logging.getLogger("nav2_wrapper.inputs")
FUTURE_TF_S = 0.5  # clock s a TF sample may be stamped after the clock (delivery order) before it is distrusted


@dataclass
class RobotState:
    pose: Pose2D                  # base in the map frame
    vel: tuple[float, float, float]  # body-frame twist from odometry
    tf_age: float               # s (clock time) since the latest odom→base (must be fresh)
    map_tf_age: float = 0.0     # s since the latest map→odom (a slow SLAM correction; may lag)


class Inputs:
    def __init__(self, node: Any, bindings: dict[str, Binding], frames: Frames, use_sim_time: bool) -> None:
        self.frames, self.bindings = frames, bindings
        self.clock = SimClock(node, use_sim_time)
        self.tf = TfBuffer(node)
        self._lock = threading.Lock()
        self.grid: GridMap | None = None
        self.grid_seq = 0
        self.odom_vel: tuple[float, float, float] = (0.0, 0.0, 0.0)
        self.odom_t: float | None = None   # clock time of the last odometry
        self.scan: LaserScan | None = None
        self.scan_seq = 0
        self._warned_frame = False
        self.node = node
        self._had_writer: dict[str, bool] = {}
        self._terminated: dict[str, str] = {}   # role -> why (the atlas' TERMINATED notice)
        self._subs: dict[str, Any] = {}
        for role in ("map", "odom", "scan"):
            if role in bindings:
                self._subscribe(role, bindings[role])

    _TYPES: dict[str, type] = {"map": OccupancyGrid, "odom": Odometry, "scan": LaserScan}

    def _subscribe(self, role: str, b: Binding) -> None:
        cb = {"map": self._on_map, "odom": self._on_odom, "scan": self._on_scan}[role]
        self._had_writer[role] = False
        self._subs[role] = self.node.create_subscription(
            b.topic, self._TYPES[role], cb, b.qos, on_liveliness=lambda h, alive: self._on_live(role, alive))

    def rebind(self, role: str, b: Binding) -> None:
        """Follow a (restarted) provider to a new topic/QoS for ``role``: new reader, old one closed."""
        old = self._subs.pop(role, None)
        self.bindings[role] = b
        self._subscribe(role, b)
        if old is not None:
            old.close()
        log.info("%s rebound to %s (qos %s, provider %s)", role, b.topic, b.qos, b.provider_id or "-")

    def set_terminated(self, role: str, why: str) -> None:
        """The atlas says the provider of ``role`` is TERMINATED ("" clears it)."""
        with self._lock:
            if why:
                self._terminated[role] = why
            else:
                self._terminated.pop(role, None)

    def _on_live(self, role: str, alive: bool) -> None:
        if alive:
            self._had_writer[role] = True

    def writer_lost(self, role: str) -> bool:
        """True when ``role``'s topic had a live writer and now has none (killed, stopped or gone)."""
        sub = self._subs.get(role)
        return sub is not None and self._had_writer.get(role, False) and not sub.alive_writers()

    def source_name(self, role: str) -> str:
        """How a lost input is named to people: the provider id when the atlas gave it, else the topic."""
        b = self.bindings.get(role)
        if b is None:
            return role
        return b.provider_id or b.topic

    # ---- callbacks (DDS dispatch thread) -----------------------------------------------------------
    def _on_map(self, msg: OccupancyGrid) -> None:
        try:
            grid = msg_to_grid(msg)
        except ValueError as exc:
            log.warning("dropping a malformed map on %s: %s", self.bindings["map"].topic, exc)
            return
        if grid.frame_id.lstrip("/") != self.frames.map and not self._warned_frame:
            self._warned_frame = True
            log.warning("map on %s is in frame %r, expected %r: treated as %r", self.bindings["map"].topic,
                        grid.frame_id, self.frames.map, self.frames.map)
        with self._lock:
            self.grid, self.grid_seq = grid, self.grid_seq + 1

    def _on_odom(self, msg: Odometry) -> None:
        t = msg.twist.twist
        vel = (float(t.linear.x), float(t.linear.y), float(t.angular.z))
        with self._lock:
            self.odom_vel, self.odom_t = vel, self.clock.now()

    def _on_scan(self, msg: LaserScan) -> None:
        with self._lock:
            self.scan, self.scan_seq = msg, self.scan_seq + 1

    # ---- reads (loop thread) -----------------------------------------------------------------------
    def latest_grid(self, seen: int) -> tuple[GridMap | None, int]:
        """The map if newer than sequence ``seen`` (else None) and the current sequence."""
        with self._lock:
            return (self.grid if self.grid_seq != seen else None), self.grid_seq

    def latest_scan(self, seen: int) -> tuple[LaserScan | None, int]:
        with self._lock:
            return (self.scan if self.scan_seq != seen else None), self.scan_seq

    def odom_age(self, now: float) -> float:
        with self._lock:
            return math.inf if self.odom_t is None else max(0.0, now - self.odom_t)

    def robot_state(self, now: float) -> RobotState:
        """Base pose in map (map→odom ∘ odom→base, each at its latest stamp); TfError if a link is missing."""
        f = self.frames
        m_o = self.tf.lookup_transform(f.map, f.odom)
        o_b = self.tf.lookup_transform(f.odom, f.base)
        if self.clock.use_sim_time and o_b.stamp > now + FUTURE_TF_S:
            # stamped after the clock: a sample of an earlier clock epoch (the simulator restarted from
            # t = 0). Its age would read 0 (fresh); it is not where the robot is.
            raise TfError(f"TF {f.odom}→{f.base} stamped {o_b.stamp:.2f} s, after the clock ({now:.2f} s)")
        pose = compose(m_o.to_pose2d(), o_b.to_pose2d())
        def age(tr: Any) -> float:
            return max(0.0, now - tr.stamp) if tr.stamp > 0.0 else 0.0  # stamp 0: a static link

        with self._lock:
            vel = self.odom_vel
        return RobotState((float(pose[0]), float(pose[1]), float(pose[2])), vel, age(o_b), age(m_o))

    def pose_at(self, stamp: float, fallback: Pose2D) -> Pose2D:
        """Base pose in map when a sensor sample was taken: map→odom (latest; slow) ∘ odom→base at ``stamp``.

        Placing a scan at the *current* pose instead smears its returns by the motion since it was taken
        (5 cm and several degrees at speed), which marks false obstacles in doorways.
        """
        f = self.frames
        if stamp <= 0.0:
            return fallback
        try:
            m_o = self.tf.lookup_transform(f.map, f.odom)
            o_b = self.tf.lookup_transform(f.odom, f.base, stamp)
        except TfError:
            return fallback  # e.g. the scan is newer than the latest odom→base: the latest pose is closest
        p = compose(m_o.to_pose2d(), o_b.to_pose2d())
        return (float(p[0]), float(p[1]), float(p[2]))

    def core_scan(self, msg: LaserScan, robot: Pose2D) -> tuple[Scan, Pose2D] | None:
        """The scan for the costmaps and the laser's pose in map at the scan's stamp (base ∘ base→laser)."""
        frame = msg.header.frame_id.lstrip("/") or self.frames.base
        try:
            mount = self.tf.lookup_pose2d(self.frames.base, frame)
        except TfError as exc:
            log.debug("no TF %s -> %s for the scan: %s", self.frames.base, frame, exc)
            return None
        sp = compose(self.pose_at(msg.header.stamp.to_sec(), robot), mount)
        scan = Scan(np.asarray(msg.ranges, dtype=np.float64), float(msg.angle_min), float(msg.angle_increment),
                        float(msg.range_min), float(msg.range_max))
        return scan, (float(sp[0]), float(sp[1]), float(sp[2]))

    def missing(self) -> list[str]:
        """What CMD_INIT still waits for (empty when map, odometry and the TF chain are all in)."""
        out = []
        with self._lock:
            grid, odom = self.grid, self.odom_t
        if grid is None:
            out.append(f"no {self.bindings['map'].topic} received")
        if odom is None:
            out.append(f"no {self.bindings['odom'].topic} received")
        f = self.frames
        for a, b in ((f.map, f.odom), (f.odom, f.base)):
            if not self.tf.can_transform(a, b):
                out.append(f"no TF {a}→{b}")
        return out

    def lost(self, now: float, state: RobotState | None, data_timeout_s: float,
             map_tf_timeout_s: float, stale_checks: bool = True,
             liveliness_checks: bool = True) -> tuple[dict[str, str], dict[str, str]]:
        """({source: why} of lost *required* inputs (map→odom, odom), the same for optional ones (scan)).

        Lost means: its DDS writer lost liveliness, the atlas reports its provider TERMINATED, or its
        data is older than the timeout (unless ``stale_checks`` is off: right after this process itself
        was frozen, everything looks old until the queued samples are read; ``liveliness_checks`` the same
        for writers' leases, which ran out in our frozen process). A source is named by provider id
        (e.g. ``mapping``).
        """
        with self._lock:
            term = dict(self._terminated)
        req: dict[str, list[str]] = {}
        opt: dict[str, list[str]] = {}
        for role, why in (("map", self._map_lost(term, state, map_tf_timeout_s, stale_checks, liveliness_checks)),
                          ("odom", self._odom_lost(term, now, state, data_timeout_s, stale_checks,
                                                   liveliness_checks))):
            if why:
                req.setdefault(self.source_name(role), []).extend(why)
        why = self._scan_lost(term, liveliness_checks)
        if why:
            opt.setdefault(self.source_name("scan"), []).extend(why)
        return ({k: "; ".join(v) for k, v in req.items()}, {k: "; ".join(v) for k, v in opt.items()})

    def _map_lost(self, term: dict[str, str], state: RobotState | None, map_tf_timeout_s: float,
                  stale_checks: bool, liveliness_checks: bool) -> list[str]:
        """Why map→odom (the map provider's TF) counts as lost; empty when it does not."""
        f = self.frames
        why = [term["map"]] if "map" in term else []
        if liveliness_checks and self.tf.link_lost(f.odom):
            why.append(f"TF {f.map}→{f.odom} stopped (DDS liveliness lost)")
        elif stale_checks and state is not None and state.map_tf_age > map_tf_timeout_s:
            why.append(f"TF {f.map}→{f.odom} is stale ({state.map_tf_age:.1f} s old)")
        return why

    def _odom_lost(self, term: dict[str, str], now: float, state: RobotState | None, data_timeout_s: float,
                   stale_checks: bool, liveliness_checks: bool) -> list[str]:
        """Why odometry (the chassis: its topic and TF odom→base) counts as lost; empty when it does not."""
        f = self.frames
        why = [term["odom"]] if "odom" in term else []
        odom_topic = self.bindings["odom"].topic
        if liveliness_checks and self.writer_lost("odom"):
            why.append(f"{odom_topic} stopped (DDS liveliness lost)")
        elif liveliness_checks and self.tf.link_lost(f.base):
            why.append(f"TF {f.odom}→{f.base} stopped (DDS liveliness lost)")
        elif stale_checks:
            age = self.odom_age(now)
            if age > data_timeout_s:
                why.append(f"no odometry on {odom_topic} for {age:.1f} s" if math.isfinite(age)
                           else f"no odometry on {odom_topic}")
            elif state is not None and state.tf_age > data_timeout_s:
                why.append(f"TF {f.odom}→{f.base} is stale ({state.tf_age:.1f} s old)")
        return why

    def _scan_lost(self, term: dict[str, str], liveliness_checks: bool) -> list[str]:
        """Why the (optional) scan counts as lost; empty when it does not or there is no scan binding."""
        if "scan" not in self.bindings:
            return []
        why = [term["scan"]] if "scan" in term else []
        if liveliness_checks and self.writer_lost("scan"):
            why.append(f"{self.bindings['scan'].topic} stopped (DDS liveliness lost)")
        return why

    def close(self) -> None:
        for s in self._subs.values():
            s.close()
        self._subs = {}
        self.tf.close()
        self.clock.close()

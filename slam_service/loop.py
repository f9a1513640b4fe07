"""The running work of the SLAM service: scan queue -> worker thread -> SlamEngine; /map and TF map->odom.

The DDS callback only queues scans (:class:`~slam_service.scan_queue.ScanQueue`: the oldest is dropped
when the worker is behind, counted, and the deepest backlog is kept), so a slow optimisation never stalls
the data plane. The worker pairs each scan with the odometry pose at the
scan's stamp (TF odom->base, interpolated; the latest /odom as a fallback) and the lidar mount
(static TF base->laser). Bad input is skipped with a counter and a rate-limited warning, never raised.
A publisher thread keeps map->odom on /tf alive (also while paused) and publishes /map when it changed,
at most once per ``map_publish_period_s``.
"""

from __future__ import annotations

import collections
import logging
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from robonix_api.dds import LaserScan, Odometry, SimClock, TfBroadcaster, TfBuffer, TfError
from robonix_api.dds.convert import grid_to_msg, pose_to_xyyaw
from robonix_api.upstream import Binding
from robonix_common.geometry import compose
from slam_service.config import Frames
from slam_service.core import Scan, SlamEngine, Update, kernels
from slam_service.scan_queue import ScanQueue

CLOCK_EPOCH_BACK_S = 1.0  # s a scan's stamp must be behind the last one to count as a new clock epoch
log = logging.getLogger("slam_service.loop")
ODOM_FALLBACK_S = 0.1  # latest /odom accepted for a scan this close in time when TF is missing
TF_WAIT_S = 0.3  # wall time the worker waits for odom->base at the scan stamp


class RateLimitedLog:
    """At most one warning per key every ``period_s``; the suppressed count is added to the next one."""

    def __init__(self, period_s: float = 5.0) -> None:
        self.period_s = period_s
        self._last: dict[str, float] = {}
        self._suppressed: dict[str, int] = collections.defaultdict(int)

    def __call__(self, key: str, msg: str) -> None:
        now = time.monotonic()
        if now - self._last.get(key, -math.inf) < self.period_s:
            self._suppressed[key] += 1
            return
        n = self._suppressed.pop(key, 0)
        self._last[key] = now
        log.warning("%s%s", msg, f" (+{n} similar suppressed)" if n else "")


class EngineLogFilter(logging.Filter):
    """Rate-limits the core's per-scan "skipped scan" warnings (one per counter every ``period_s``)."""

    def __init__(self, period_s: float = 5.0) -> None:
        super().__init__()
        self.period_s = period_s
        self._last: dict[str, float] = {}

    def filter(self, record: logging.LogRecord) -> bool:
        if record.levelno != logging.WARNING or "skipped scan" not in str(record.msg):
            return True
        args = record.args if isinstance(record.args, tuple) else ()
        key = str(args[1]) if len(args) >= 2 else str(record.msg)
        now = time.monotonic()
        if now - self._last.get(key, -math.inf) < self.period_s:
            return False
        self._last[key] = now
        return True


def install_engine_log_filter() -> None:
    eng = logging.getLogger("slam_service.core.engine")
    if not any(isinstance(f, EngineLogFilter) for f in eng.filters):
        eng.addFilter(EngineLogFilter())


RECENT_PROCESS_CALLS = 1000  # process() calls the status percentiles cover (100 s of scans at 10 Hz)


@dataclass(frozen=True)
class ScanTiming:
    """Where one processed scan's time went (wall s): waiting in the queue, then inside the worker."""

    wait_s: float  # from the DDS callback queueing it to the worker taking it
    process_s: float  # SlamEngine.process alone
    process_cpu_s: float  # its CPU time on the worker thread: what it costs without neighbours competing
    handle_s: float  # the worker's whole handling: TF/odometry lookup + process + map->odom out
    integrated: bool
    loop_closed: bool

    @property
    def latency_s(self) -> float:
        """Arrival to done: what the scan's age is when its pose reaches map->odom."""
        return self.wait_s + self.handle_s


class SlamLoop:
    """The work of one session (see ``robonix_api.hosting``): subscriptions, worker and publisher threads."""

    def __init__(self, node: Any, bindings: dict[str, Binding], frames: Frames, engine: SlamEngine, map_pub: Any,
                 *, use_sim_time: bool, map_period_s: float, tf_period_s: float, queue_size: int,
                 map_id: str = "", on_map: Callable[[Any], None] | None = None,
                 on_change: Callable[[], None] | None = None,
                 autosave: Callable[[Any], None] | None = None, autosave_period_s: float = 2.0,
                 resume_map_to_odom: tuple[float, float, float] | None = None,
                 on_scan_done: Callable[[ScanTiming], None] | None = None,
                 on_tf: Callable[[tuple[float, float, float], float], None] | None = None) -> None:
        self.frames, self.bindings = frames, bindings
        self.map_id = map_id  # the saved map this session runs on ("" = a new map)
        self._on_map = on_map  # after each /map publication, with the grid (telemetry)
        self._on_change = on_change  # after the map was replaced or reset (lifecycle announcements)
        self._on_scan_done = on_scan_done  # per processed scan, on the worker thread (benches)
        self._on_tf = on_tf  # each map->odom sent (kept for a crash-restart: slam_service.continuity)
        self.engine = engine
        self.lock = threading.RLock()  # guards the engine (worker, RPC handlers, publisher)
        self.integrating = False
        self._resumed = False  # first scan after a pause: the robot may have moved meanwhile
        self.clock = SimClock(node, use_sim_time)
        self.use_sim_time = use_sim_time
        self.tf = TfBuffer(node)
        self._tf_out = TfBroadcaster(node)
        self._map_pub = map_pub
        self._map_period, self._tf_period = map_period_s, tf_period_s
        self._queue: ScanQueue[LaserScan] = ScanQueue(queue_size)
        self._stop = threading.Event()
        self._warn = RateLimitedLog()
        self._mounts: dict[str, tuple[float, float, float]] = {}
        self._odom: tuple[float, tuple[float, float, float]] | None = None  # (stamp, pose) of the latest /odom
        self._m2o = engine.map_to_odom()
        # resumed after a crash: map->odom at the autosave; the first scan re-anchors on today's odometry
        self._resume_m2o = resume_map_to_odom
        if resume_map_to_odom is not None:
            self._m2o = np.asarray(resume_map_to_odom, dtype=float)
            self._resumed = True
        self._autosave, self._autosave_period = autosave, autosave_period_s
        self._saved_version: tuple[int, int, int] | None = None
        self._last_stamp = 0.0  # latest scan stamp processed
        self._last_tf_wall = -math.inf
        self._map_dirty = self._has_map()
        self._publishing = False  # a map taken for /map (no longer dirty) not yet handed to DDS: see idle()
        self._map_clock, self._map_wall = -math.inf, -math.inf
        self.counters: dict[str, int] = collections.Counter()
        # always in the status, also when 0: "no scan was dropped" is the claim the status must show
        self.counters["scans_dropped_behind"] = 0
        self.counters["process_over_100ms"] = 0
        self.process_ms_max = 0.0  # slowest SlamEngine.process call so far (wall ms)
        # the latest calls' cost, for percentiles in the status (a soak watches p99 stay flat); bounded
        self._process_ms: collections.deque[float] = collections.deque(maxlen=RECENT_PROCESS_CALLS)
        # the same calls' CPU time on the worker thread: flat or not whatever else the host runs
        self._process_cpu_ms: collections.deque[float] = collections.deque(maxlen=RECENT_PROCESS_CALLS)
        self._subs = [
            node.create_subscription(bindings["scan"].topic, LaserScan, self._on_scan, bindings["scan"].qos),
            node.create_subscription(bindings["odom"].topic, Odometry, self._on_odom, bindings["odom"].qos),
        ]
        self._threads = [threading.Thread(target=self._work, name="slam-worker", daemon=True),
                         threading.Thread(target=self._publish_loop, name="slam-publisher", daemon=True)]
        if autosave is not None and autosave_period_s > 0:
            self._threads.append(threading.Thread(target=self._autosave_loop, name="slam-autosave", daemon=True))
        for th in self._threads:
            th.start()

    # ---------------------------------------------------------------- callbacks (DDS thread)
    def _on_scan(self, msg: LaserScan) -> None:
        self.counters["scans_received"] += 1
        if not self.integrating:
            self.counters["scans_paused"] += 1
            return
        if self._queue.put(msg):
            self.counters["scans_dropped_behind"] += 1
            self._warn("queue", f"SLAM is behind: dropped the oldest queued scan "
                                f"({self.counters['scans_dropped_behind']} so far)")

    def _on_odom(self, msg: Odometry) -> None:
        if msg.header.frame_id.strip().lstrip("/") != self.frames.odom:
            self.counters["odom_wrong_frame"] += 1
            self._warn("odom_frame", f"/odom in frame {msg.header.frame_id!r}, expected {self.frames.odom!r}: ignored")
            return
        self._odom = (msg.header.stamp.to_sec(), pose_to_xyyaw(msg.pose.pose))

    # ---------------------------------------------------------------- worker
    def _work(self) -> None:
        while not self._stop.is_set():
            item = self._queue.get(0.5)
            if item is None:
                continue
            arrived, msg = item
            start = time.monotonic()
            try:
                upd = self._handle(msg)
            except Exception as exc:  # a bug or an odd message must not kill mapping
                self.counters["worker_errors"] += 1
                log.exception("scan processing failed: %s", exc)
                continue
            finally:
                self._queue.done()
            if upd is not None:
                self.counters["scans_processed"] += 1
                if self._on_scan_done is not None:
                    update, process_s, cpu_s = upd
                    self._on_scan_done(ScanTiming(start - arrived, process_s, cpu_s, time.monotonic() - start,
                                                  update.integrated, update.loop_closed))

    def _skip(self, counter: str, msg: str) -> None:
        self.counters[counter] += 1
        self._warn(counter, f"skipped scan: {msg} ({counter}={self.counters[counter]})")

    def _mount(self, frame: str) -> tuple[float, float, float]:
        if frame not in self._mounts:
            if not self.tf.wait_for_transform(self.frames.base, frame, None, TF_WAIT_S):
                raise TfError(f"no TF {self.frames.base} -> {frame}")
            self._mounts[frame] = self.tf.lookup_pose2d(self.frames.base, frame)
        return self._mounts[frame]

    def _odom_at(self, t: float) -> tuple[float, float, float] | None:
        f = self.frames
        if self.tf.wait_for_transform(f.odom, f.base, t, TF_WAIT_S):
            try:
                return self.tf.lookup_pose2d(f.odom, f.base, t)
            except TfError:
                pass
        latest = self._odom
        if latest is not None and abs(latest[0] - t) <= ODOM_FALLBACK_S:
            return latest[1]
        return None

    def _handle(self, msg: LaserScan) -> tuple[Update, float, float] | None:
        """Process one scan; (the engine's update, wall and CPU seconds inside ``process``), or None if it
        was skipped."""
        frame = msg.header.frame_id.strip().lstrip("/")
        t = msg.header.stamp.to_sec()
        if not frame:
            return self._skip("scans_bad_frame", "empty header.frame_id")
        if not math.isfinite(t):
            return self._skip("scans_bad_stamp", f"stamp {t}")
        try:
            mount = self._mount(frame)
        except TfError as exc:
            return self._skip("scans_no_tf", f"frame_id {frame!r} is not connected to {self.frames.base} ({exc})")
        if t < self._last_stamp - CLOCK_EPOCH_BACK_S:
            self._new_clock_epoch(t)
        odom = self._odom_at(t)
        if odom is None:
            return self._skip("scans_no_odom", f"no odometry ({self.frames.odom} -> {self.frames.base}) at t={t:.3f}")
        scan = Scan(np.asarray(msg.ranges, dtype=np.float32), float(msg.angle_min), float(msg.angle_increment),
                    float(msg.range_min), float(msg.range_max), stamp=t, mount=mount, frame_id=frame)
        with self.lock:
            if not self.integrating:  # paused while the scan was queued
                return None
            if self._resumed:  # odometry is trusted across a pause: keep map->odom, skip the jump check
                m2o = self._resume_m2o if self._resume_m2o is not None else self.engine.map_to_odom()
                self.engine.set_initial_pose(compose(m2o, odom))
                self._resumed, self._resume_m2o = False, None
            c0, t0 = time.thread_time(), time.perf_counter()
            upd = self.engine.process(scan, odom, t)
            process_s = time.perf_counter() - t0
            cpu_s = time.thread_time() - c0
            self._note_process_time(1e3 * process_s, 1e3 * cpu_s)
            self._m2o = upd.map_to_odom
            self._last_stamp = max(self._last_stamp, t)
            if upd.map_changed:
                self._map_dirty = True
        self._send_tf(t)
        return upd, process_s, cpu_s

    def _new_clock_epoch(self, t: float) -> None:
        """Scans stamped well before the last one: the clock started again (a simulator restarted without
        its saved state). The TF history is of the old epoch (newer stamps: every lookup at the new times
        fails, "skipped scan: no odometry"), so it is dropped; the next scan re-anchors like after a pause
        (map->odom kept, the robot placed by today's odometry) instead of being read as an odometry jump."""
        log.warning("scan stamped %.2f s, %.2f s before the last one: clock went back (simulator restarted?); "
                    "TF history dropped, re-anchoring on the next scan", t, self._last_stamp - t)
        self.tf.clear(keep_static=True)
        self._odom = None
        with self.lock:
            self._last_stamp = t
            self._resumed, self._resume_m2o = True, None
        self.counters["clock_epochs"] += 1

    def _note_process_time(self, ms: float, cpu_ms: float) -> None:
        """Per-scan cost in the status: a call near the 100 ms scan period is what fills the queue."""
        self.process_ms_max = max(self.process_ms_max, ms)
        self._process_ms.append(ms)
        self._process_cpu_ms.append(cpu_ms)
        if ms > 100.0:
            self.counters["process_over_100ms"] += 1

    # ---------------------------------------------------------------- outputs
    def _send_tf(self, stamp: float) -> None:
        x, y, th = (float(v) for v in self._m2o)
        self._tf_out.send(self.frames.map, self.frames.odom, x, y, th, stamp)
        if self._on_tf is not None:
            self._on_tf((x, y, th), stamp)
        self._last_tf_wall = time.monotonic()
        self.counters["tf_sent"] += 1

    def _has_map(self) -> bool:
        return self.engine.mode == "localization" or self.engine.graph.n_nodes > 0

    def _publish_loop(self) -> None:
        while not self._stop.wait(self._tf_period / 2):
            try:
                now = self.clock.now()
                stamp = max(now, self._last_stamp)
                if time.monotonic() - self._last_tf_wall >= self._tf_period and (stamp > 0 or not self.use_sim_time):
                    self._send_tf(stamp)
                self._maybe_publish_map(now)
            except Exception as exc:  # DDS closing under us at shutdown, or a bug: keep the thread alive
                if self._stop.is_set():
                    return
                self._warn("publisher", f"publisher iteration failed: {exc}")

    def _maybe_publish_map(self, now: float, force: bool = False) -> None:
        if not self._map_dirty:
            return
        wall = time.monotonic()
        if not force and now - self._map_clock < self._map_period and wall - self._map_wall < self._map_period \
                and now >= self._map_clock:
            return
        with self.lock:
            if not self._map_dirty:  # the other thread published it meanwhile
                return
            grid = self.engine.map()
            self._map_dirty = False
            self._publishing = True
        try:
            self._map_pub.publish(grid_to_msg(grid, max(now, self._last_stamp), self.frames.map))
        finally:
            self._publishing = False
        self._map_clock, self._map_wall = now, wall
        self.counters["maps_published"] += 1
        if self.counters["maps_published"] == 1:  # numba after the first map: nav2 waits for it during boot
            kernels.load_in_background()
        if self._on_map is not None:
            self._on_map(grid)

    # ---------------------------------------------------------------- crash autosave
    def _version(self) -> tuple[int, int, int]:
        """Changes when the session has new data: another engine, a node, or an edge (loop closure)."""
        g = self.engine.graph
        return (id(self.engine), g.n_nodes, len(g.edge_ij))

    def autosave_now(self) -> bool:
        """Write the session if it has new data since the last write; True when written."""
        with self.lock:
            if self.engine.mode != "mapping" or self.engine.graph.n_nodes == 0:
                return False
            version = self._version()
            if version == self._saved_version:
                return False
            session = self.engine.session()  # a snapshot: written outside the lock
        assert self._autosave is not None
        self._autosave(session)
        self._saved_version = version
        self.counters["autosaves"] += 1
        return True

    def _autosave_loop(self) -> None:
        while not self._stop.wait(self._autosave_period):
            try:
                self.autosave_now()
            except Exception as exc:  # a full disk must not stop mapping
                if self._stop.is_set():
                    return
                self._warn("autosave", f"autosave failed: {exc}")

    # ---------------------------------------------------------------- control (RPC / lifecycle threads)
    def set_integrating(self, on: bool) -> None:
        with self.lock:
            if on and not self.integrating and self.engine.stats.scans_received:
                self._resumed = True
            self.integrating = on
        if not on:
            self.counters["scans_paused"] += self._queue.clear()
            # the changes made before the pause go out now, so nothing is published while paused
            try:
                self._maybe_publish_map(self.clock.now(), force=True)
            except Exception as exc:  # DDS closing at shutdown: the pause itself must still happen
                self._warn("publisher", f"map publish at pause failed: {exc}")

    def replace_engine(self, engine: SlamEngine, map_id: str = "") -> None:
        """Swap in a freshly loaded engine (load_map): the map is republished at once."""
        with self.lock:
            self.engine = engine
            self.map_id = map_id
            self._resumed, self._resume_m2o = False, None  # the loaded engine has its own start pose
            self._m2o = engine.map_to_odom()
            self._map_dirty = True
            self._map_clock = self._map_wall = -math.inf
        if self._on_change is not None:
            self._on_change()

    def map_changed(self) -> None:
        """Force a /map publication (after reset_map / switch_mode), bypassing the rate cap."""
        with self.lock:
            self._m2o = self.engine.map_to_odom()
            self._map_dirty = True
            self._map_clock = self._map_wall = -math.inf
        if self._on_change is not None:
            self._on_change()

    def set_pose(self, pose: tuple[float, float, float]) -> None:
        """A pose estimate (map frame) applied at the next scan; it wins over the resume re-anchoring."""
        with self.lock:
            self.engine.set_initial_pose(pose)
            self._resumed, self._resume_m2o = False, None

    def robot_pose(self) -> tuple[float, float, float]:
        """Live base pose in map: map->odom (last estimate) composed with the latest odom->base."""
        with self.lock:
            m2o, pose = self.engine.map_to_odom(), self.engine.pose()
        try:
            o2b = self.tf.lookup_pose2d(self.frames.odom, self.frames.base)
        except TfError:
            return (float(pose[0]), float(pose[1]), float(pose[2]))
        p = compose(m2o, o2b)
        return (float(p[0]), float(p[1]), float(p[2]))

    def stats(self) -> dict[str, Any]:
        with self.lock:
            engine = self.engine.stats.to_dict()
            mode = self.engine.mode
            nodes = self.engine.graph.n_nodes
            recent = np.asarray(self._process_ms, dtype=float)
            recent_cpu = np.asarray(self._process_cpu_ms, dtype=float)
        pct = {f"process{kind}_ms_p{q}": round(float(np.percentile(v, q)), 1) if v.size else None
               for kind, v in (("", recent), ("_cpu", recent_cpu)) for q in (50, 99)}
        return {"mode": mode, "integrating": self.integrating, **dict(self.counters),
                "process_ms_max": round(self.process_ms_max, 1), **pct, "process_ms_window": int(recent.size),
                "queue_size": self._queue.size, "queue_depth": len(self._queue),
                "queue_high_water": self._queue.high_water, "nodes": nodes, "engine": engine,
                "idle": self.idle()}

    def idle(self) -> bool:
        """Every scan received so far has been dealt with and the map it made is on /map: none queued or in
        progress, no map change waiting for (or in) its publication. Why: whoever feeds SLAM a recording (a
        replay) can wait for this instead of a fixed time before it reads what SLAM made of it."""
        if self._queue.pending():   # first: a scan finishes (and dirties the map) before it stops being pending
            return False
        with self.lock:
            return not self._map_dirty and not self._publishing

    def close(self, reason: str = "") -> None:
        self._stop.set()
        self._queue.wake()
        for th in self._threads:
            th.join(5.0)
        for item in (*self._subs, self.tf, self.clock, self._tf_out):
            try:
                item.close()
            except Exception:  # closing must not stop the teardown of the rest
                log.debug("closing %s failed", type(item).__name__, exc_info=True)
        self._subs = []

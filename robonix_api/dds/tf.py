"""TF: a transform buffer fed by /tf and /tf_static (or directly), and broadcasters.

Semantics follow tf2: ``lookup_transform(target, source, t)`` is the pose of ``source`` in ``target``
(it maps points from source into target). ``t`` None/0 means the latest time all links on the path have
in common. Between stamps: linear translation, slerp rotation. Static links hold for every time.
"""

from __future__ import annotations

import bisect
import math
import threading
import time as _time
from dataclasses import dataclass

from robonix_api.dds.messages import Header, Quaternion, TFMessage, Time, Transform, TransformStamped, Vector3
from robonix_common.geometry import quat_to_yaw, yaw_to_quat


class TfError(Exception):
    """Base of all TF lookup failures."""


class FrameNotFoundError(TfError, LookupError):
    """A frame the buffer has never heard of (message lists the known frames)."""


class ConnectivityError(TfError):
    """Both frames are known but lie in different trees."""


class ExtrapolationError(TfError):
    """The requested time is outside the buffered range of some link (message gives both)."""


@dataclass(frozen=True)
class Transform3:
    """Rigid transform: translation (x, y, z) and unit quaternion (x, y, z, w)."""

    translation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
    stamp: float = 0.0

    def __mul__(self, other: Transform3) -> Transform3:
        """self ∘ other: apply ``other`` first, then ``self``."""
        t = _rotate(self.rotation, other.translation)
        return Transform3((self.translation[0] + t[0], self.translation[1] + t[1], self.translation[2] + t[2]),
                          _qmul(self.rotation, other.rotation), min(self.stamp, other.stamp))

    def inverse(self) -> Transform3:
        """The transform the other way round (child to parent), same stamp."""
        qi = (-self.rotation[0], -self.rotation[1], -self.rotation[2], self.rotation[3])
        t = _rotate(qi, self.translation)
        return Transform3((-t[0], -t[1], -t[2]), qi, self.stamp)

    def to_pose2d(self) -> tuple[float, float, float]:
        """The planar part: x, y and yaw."""
        return self.translation[0], self.translation[1], quat_to_yaw(*self.rotation)

    def to_msg(self) -> Transform:
        """As a ROS Transform message."""
        return Transform(translation=Vector3(*self.translation), rotation=Quaternion(*self.rotation))


def _qmul(a: tuple[float, ...], b: tuple[float, ...]) -> tuple[float, float, float, float]:
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz)


def _rotate(q: tuple[float, ...], v: tuple[float, ...]) -> tuple[float, float, float]:
    r = _qmul(_qmul(q, (v[0], v[1], v[2], 0.0)), (-q[0], -q[1], -q[2], q[3]))
    return r[0], r[1], r[2]


def _slerp(a: tuple[float, ...], b: tuple[float, ...], u: float) -> tuple[float, float, float, float]:
    dot = sum(x * y for x, y in zip(a, b, strict=True))
    if dot < 0.0:
        b, dot = tuple(-x for x in b), -dot
    if dot > 0.9995:
        r = [x + u * (y - x) for x, y in zip(a, b, strict=True)]
    else:
        th = math.acos(dot)
        s0, s1 = math.sin((1 - u) * th) / math.sin(th), math.sin(u * th) / math.sin(th)
        r = [s0 * x + s1 * y for x, y in zip(a, b, strict=True)]
    n = math.sqrt(sum(x * x for x in r))
    return r[0] / n, r[1] / n, r[2] / n, r[3] / n


def stamp_to_sec(stamp: float | Time | None) -> float:
    """A stamp (seconds, Time or None = latest) as float seconds, 0.0 for None."""
    if stamp is None:
        return 0.0
    return stamp.to_sec() if isinstance(stamp, Time) else float(stamp)


def _norm_frame(f: str) -> str:
    return f.strip().lstrip("/")


class _Link:
    """History of one child frame's transform to its parent."""

    def __init__(self, parent: str, static: bool) -> None:
        self.parent, self.static = parent, static
        self.times: list[float] = []
        self.values: list[Transform3] = []

    def insert(self, t: float, tf: Transform3, cache_s: float) -> None:
        if self.static:
            self.times, self.values = [t], [tf]
            return
        i = bisect.bisect_left(self.times, t)
        if i < len(self.times) and self.times[i] == t:
            self.values[i] = tf
        else:
            self.times.insert(i, t)
            self.values.insert(i, tf)
        cut = bisect.bisect_left(self.times, self.times[-1] - cache_s)
        if cut:
            del self.times[:cut], self.values[:cut]

    def at(self, t: float, child: str) -> Transform3:
        if self.static:
            return self.values[0]
        lo, hi = self.times[0], self.times[-1]
        if t < lo - 1e-9 or t > hi + 1e-9:
            raise ExtrapolationError(
                f"lookup of {self.parent} -> {child} at t={t:.6f} would extrapolate: "
                f"buffered range is [{lo:.6f}, {hi:.6f}] ({'past' if t < lo else 'future'} by "
                f"{(lo - t) if t < lo else (t - hi):.6f} s)")
        i = bisect.bisect_left(self.times, t)
        if i < len(self.times) and abs(self.times[i] - t) <= 1e-9 or len(self.times) == 1:
            return self.values[min(i, len(self.times) - 1)]
        if i == 0:
            return self.values[0]
        if i >= len(self.times):
            return self.values[-1]
        t0, t1 = self.times[i - 1], self.times[i]
        a, b = self.values[i - 1], self.values[i]
        u = (t - t0) / (t1 - t0)
        tr = tuple(x + u * (y - x) for x, y in zip(a.translation, b.translation, strict=True))
        return Transform3(tr, _slerp(a.rotation, b.rotation, u), t)  # type: ignore[arg-type]


class TfBuffer:
    """Buffered transform tree; with a node, fed from /tf (reliable, depth 100) and /tf_static (latched).

    /tf has one writer per broadcasting process (SLAM's map→odom, the chassis' odom→base_link), so the
    buffer remembers which writer last sent each dynamic link: when that writer loses DDS liveliness
    (its process died or stalled), ``lost_links()`` names the link at once, long before its stamp is
    old enough to call it stale.
    """

    def __init__(self, node: object | None = None, cache_s: float = 10.0) -> None:
        self.cache_s = float(cache_s)
        self._links: dict[str, _Link] = {}
        self._lock = threading.Lock()
        self._changed = threading.Condition(self._lock)
        self._writer_of: dict[str, int] = {}   # dynamic child frame -> publication handle of its last writer
        self._dead_writers: set[int] = set()
        self._subs = []
        if node is not None:
            self._subs = [
                node.create_subscription("/tf", TFMessage, lambda m: self._on_msg(m, False), "reliable", 100,
                                         on_liveliness=self._on_liveliness),
                # Depth 100 like tf2's static listener: each static publisher's latched sample must survive.
                node.create_subscription("/tf_static", TFMessage, lambda m: self._on_msg(m, True), "latched", 100),
            ]

    def _on_msg(self, msg: TFMessage, static: bool) -> None:
        handle = getattr(getattr(msg, "sample_info", None), "publication_handle", 0)
        for ts in msg.transforms:
            self.set_transform(ts, static=static)
            if not static and handle:
                with self._lock:
                    self._writer_of[_norm_frame(ts.child_frame_id)] = handle
        if handle and not static:
            with self._lock:
                self._dead_writers.discard(handle)

    def _on_liveliness(self, handle: int, alive: bool) -> None:
        with self._lock:
            if alive:
                self._dead_writers.discard(handle)
            else:
                self._dead_writers.add(handle)
            self._changed.notify_all()

    def lost_links(self) -> list[tuple[str, str]]:
        """(parent, child) of each dynamic link whose last /tf writer lost liveliness (died or stalled)."""
        with self._lock:
            return sorted((self._links[c].parent, c) for c, h in self._writer_of.items()
                          if h in self._dead_writers and c in self._links)

    def link_lost(self, child: str) -> bool:
        """True when the writer that last sent ``child``'s transform lost liveliness."""
        with self._lock:
            h = self._writer_of.get(_norm_frame(child))
            return h is not None and h in self._dead_writers

    # --- feeding ----------------------------------------------------------------------------------
    def set_transform(self, ts: TransformStamped, authority: str = "", static: bool = False) -> None:
        """Insert one transform (tf2's setTransform); also the way to feed TF without DDS."""
        parent, child = _norm_frame(ts.header.frame_id), _norm_frame(ts.child_frame_id)
        if not parent or not child or parent == child:
            raise ValueError(f"bad transform {parent!r} -> {child!r}: frames must be non-empty and differ")
        tr, q = ts.transform.translation, ts.transform.rotation
        n = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
        if not math.isfinite(n) or n < 1e-9:
            raise ValueError(f"transform {parent} -> {child}: invalid quaternion {q}")
        t = stamp_to_sec(ts.header.stamp)
        value = Transform3((tr.x, tr.y, tr.z), (q.x / n, q.y / n, q.z / n, q.w / n), t)
        with self._lock:
            link = self._links.get(child)
            if link is None or link.parent != parent or link.static != static:
                link = self._links[child] = _Link(parent, static)
            link.insert(t, value, self.cache_s)
            self._changed.notify_all()

    def set_pose2d(self, parent: str, child: str, x: float, y: float, yaw: float, stamp: float | Time = 0.0,
                   static: bool = False) -> None:
        """Store a planar transform parent -> child (as ``set_transform`` does with a message)."""
        self.set_transform(make_transform(parent, child, x, y, yaw, stamp), static=static)

    def clear(self, keep_static: bool = False) -> None:
        """Forget every stored transform (after a time jump or a reset); ``keep_static`` keeps the static
        ones (mounts: sent once, transient-local, valid in any clock epoch)."""
        with self._lock:
            if keep_static:
                self._links = {k: v for k, v in self._links.items() if v.static}
            else:
                self._links.clear()

    def frames(self) -> list[str]:
        """Every frame the buffer knows, sorted."""
        with self._lock:
            return sorted(set(self._links) | {lk.parent for lk in self._links.values()})

    # --- lookups ----------------------------------------------------------------------------------
    def _chain(self, frame: str) -> list[str]:
        chain = [frame]
        while chain[-1] in self._links:
            chain.append(self._links[chain[-1]].parent)
            if len(chain) > 1000:
                raise TfError(f"TF loop detected above {frame}")
        return chain

    def _known(self, frame: str) -> None:
        if frame not in self._links and all(lk.parent != frame for lk in self._links.values()):
            known = sorted(set(self._links) | {lk.parent for lk in self._links.values()})
            raise FrameNotFoundError(f"frame {frame!r} does not exist; known frames: {known or 'none'}")

    def lookup_transform(self, target: str, source: str, time: float | Time | None = None) -> Transform3:
        """Pose of ``source`` in ``target`` at ``time`` (None/0: latest common time)."""
        target, source = _norm_frame(target), _norm_frame(source)
        t = stamp_to_sec(time)
        with self._lock:
            self._known(target)
            self._known(source)
            if target == source:
                return Transform3(stamp=t)
            up_s, up_t = self._chain(source), self._chain(target)
            common = next((f for f in up_s if f in set(up_t)), None)
            if common is None:
                raise ConnectivityError(f"frames {target!r} and {source!r} are not connected: "
                                        f"{source} has root {up_s[-1]!r}, {target} has root {up_t[-1]!r}")
            path_s = up_s[:up_s.index(common)]  # children whose links lead source -> common
            path_t = up_t[:up_t.index(common)]
            links = [(c, self._links[c]) for c in path_s + path_t]
            if t == 0.0:
                dyn = [lk.times[-1] for _, lk in links if not lk.static]
                t = min(dyn) if dyn else 0.0
            tf_common_source = Transform3(stamp=t)
            for c in reversed(path_s):
                tf_common_source = tf_common_source * self._links[c].at(t, c)
            tf_common_target = Transform3(stamp=t)
            for c in reversed(path_t):
                tf_common_target = tf_common_target * self._links[c].at(t, c)
        out = tf_common_target.inverse() * tf_common_source
        return Transform3(out.translation, out.rotation, t)

    def lookup_pose2d(self, target: str, source: str, time: float | Time | None = None) -> tuple[float, float, float]:
        """Planar (x, y, yaw) of ``source`` in ``target``."""
        return self.lookup_transform(target, source, time).to_pose2d()

    lookup = lookup_pose2d

    def can_transform(self, target: str, source: str, time: float | Time | None = None) -> bool:
        """Whether ``lookup_transform(target, source, time)`` would succeed now."""
        try:
            self.lookup_transform(target, source, time)
            return True
        except TfError:
            return False

    def wait_for_transform(self, target: str, source: str, time: float | Time | None = None,
                           timeout_s: float = 1.0) -> bool:
        """Block until ``can_transform`` (wall-clock timeout)."""
        deadline = _time.monotonic() + timeout_s
        while not self.can_transform(target, source, time):
            left = deadline - _time.monotonic()
            if left <= 0:
                return False
            with self._changed:
                self._changed.wait(min(left, 0.05))
        return True

    def close(self) -> None:
        """Stop listening to /tf and /tf_static."""
        for s in self._subs:
            s.close()
        self._subs = []


def make_transform(parent: str, child: str, x: float, y: float, yaw: float,
                   stamp: float | Time = 0.0, z: float = 0.0) -> TransformStamped:
    """Planar TransformStamped parent -> child."""
    qx, qy, qz, qw = yaw_to_quat(yaw)
    st = stamp if isinstance(stamp, Time) else Time.from_sec(float(stamp))
    return TransformStamped(header=Header(stamp=st, frame_id=parent), child_frame_id=child,
                            transform=Transform(translation=Vector3(float(x), float(y), float(z)),
                                                rotation=Quaternion(qx, qy, qz, qw)))


class TfBroadcaster:
    """Publishes on /tf with tf2_ros's dynamic broadcaster QoS (reliable, volatile, depth 100)."""

    topic, qos, depth = "/tf", "reliable", 100

    def __init__(self, node: object) -> None:
        self._pub = node.create_publisher(self.topic, TFMessage, self.qos, self.depth)

    def send(self, parent: str, child: str, x: float, y: float, yaw: float, stamp: float | Time = 0.0) -> None:
        """Publish one planar transform parent -> child."""
        self.send_transform([make_transform(parent, child, x, y, yaw, stamp)])

    def send_transform(self, transforms: TransformStamped | list[TransformStamped]) -> None:
        """Publish one or more stamped transforms in one TFMessage."""
        ts = [transforms] if isinstance(transforms, TransformStamped) else list(transforms)
        self._pub.publish(TFMessage(transforms=ts))

    def close(self) -> None:
        """Stop publishing."""
        self._pub.close()


class StaticTfBroadcaster(TfBroadcaster):
    """/tf_static, latched (depth 1): like tf2_ros it re-sends every static transform it was given."""

    topic, qos, depth = "/tf_static", "latched", 1

    def __init__(self, node: object) -> None:
        super().__init__(node)
        self._all: dict[str, TransformStamped] = {}

    def send_transform(self, transforms: TransformStamped | list[TransformStamped]) -> None:
        """Add or replace these static transforms and republish all of them (latched, like tf2's static broadcaster)."""
        ts = [transforms] if isinstance(transforms, TransformStamped) else list(transforms)
        for t in ts:
            self._all[_norm_frame(t.child_frame_id)] = t
        self._pub.publish(TFMessage(transforms=list(self._all.values())))

"""ROS 2 message names and ``ros2msg`` schema text for our DDS message types, plus the topic table that
recording and replay share.

Recordings must be readable by Foxglove and ``ros2 bag``, which need the ``.msg`` definition of every
channel (``ros2msg`` encoding: the type's fields, then each nested type after a ``MSG:`` separator). The
definitions are generated from the IDL structs in ``robonix_api.dds.messages``, the same classes that
serialise the wire bytes, so schema and payload cannot drift apart.
"""

from __future__ import annotations

import typing
from dataclasses import dataclass
from typing import Any

from robonix_api.dds import messages as m

SEPARATOR = "=" * 80

# IDL primitive annotation -> ROS 2 .msg primitive
_PRIMS = {"int8": "int8", "uint8": "uint8", "int16": "int16", "uint16": "uint16", "int32": "int32",
          "uint32": "uint32", "int64": "int64", "uint64": "uint64", "float32": "float32", "float64": "float64"}


def ros_name(cls: type) -> str:
    """``nav_msgs::msg::dds_::Odometry_`` -> ``nav_msgs/msg/Odometry`` (rosbag2's type name)."""
    pkg, _msg, _dds, typ = cls.__idl_typename__.split("::")
    return f"{pkg}/msg/{typ.rstrip('_')}"


def _short(cls: type) -> str:
    """The name nested types use inside a .msg (``std_msgs/Header``)."""
    pkg, _, typ = ros_name(cls).split("/")
    return f"{pkg}/{typ}"


def _field_type(hint: Any, deps: list[type]) -> str:
    meta = getattr(hint, "__metadata__", None)
    if meta:
        holder = meta[0]
        if isinstance(holder, str):
            return _PRIMS[holder]
        sub = _field_type(holder.subtype, deps)
        length = getattr(holder, "length", None)
        return f"{sub}[{length}]" if length is not None else f"{sub}[]"
    if hint is str:
        return "string"
    if hint is bool:
        return "bool"
    if isinstance(hint, type) and hasattr(hint, "__idl_typename__"):
        if hint not in deps:
            deps.append(hint)
        return _short(hint)
    raise TypeError(f"no ROS 2 .msg equivalent for field type {hint!r}")


def _fields(cls: type, deps: list[type]) -> str:
    hints = typing.get_type_hints(cls, include_extras=True)
    return "\n".join(f"{_field_type(h, deps)} {name}" for name, h in hints.items())


def schema_text(cls: type) -> str:
    """The full ``ros2msg`` definition: the type's fields, then every nested type once (depth first)."""
    deps: list[type] = []
    parts = [_fields(cls, deps)]
    done: set[type] = set()
    while len(done) < len(deps):
        dep = next(d for d in deps if d not in done)
        done.add(dep)
        parts.append(f"{SEPARATOR}\nMSG: {_short(dep)}\n{_fields(dep, deps)}")
    return "\n".join(parts) + "\n"


TYPES: dict[str, type] = {ros_name(t): t for t in m.ALL_TYPES}


def type_by_name(name: str) -> type | None:
    """Our class for a ROS 2 type name in any common spelling (``nav_msgs/msg/Odometry``,
    ``nav_msgs/Odometry``)."""
    pkg, _, typ = name.strip().partition("/")
    return TYPES.get(f"{pkg}/msg/{typ.rpartition('/')[2]}")


@dataclass(frozen=True)
class TopicSpec:
    """A topic we know how to subscribe to or publish: its type and the QoS its usual writer offers."""

    topic: str
    msg_type: type
    qos: str  # robonix_api.dds.qos preset: reliable | best_effort | latched


DEFAULT_TOPICS: tuple[TopicSpec, ...] = (
    TopicSpec("/scan", m.LaserScan, "best_effort"),
    TopicSpec("/odom", m.Odometry, "reliable"),
    TopicSpec("/tf", m.TFMessage, "reliable"),
    TopicSpec("/tf_static", m.TFMessage, "latched"),
    TopicSpec("/map", m.OccupancyGrid, "latched"),
    TopicSpec("/plan", m.Path, "reliable"),
    TopicSpec("/cmd_vel", m.Twist, "reliable"),
    TopicSpec("/clock", m.Clock, "best_effort"),
)
KNOWN = {s.topic: s for s in DEFAULT_TOPICS} | {
    "/ground_truth/odom": TopicSpec("/ground_truth/odom", m.Odometry, "reliable"),
}


class TopicError(ValueError):
    """A topic argument we cannot serve; str() is one line naming it."""


def parse_topic(arg: str) -> TopicSpec:
    """``/scan`` (a known topic) or ``/name:pkg/Type[:qos]`` for any other topic of a type we have."""
    name, _, rest = arg.partition(":")
    name = "/" + name.strip().lstrip("/")
    if name == "/":
        raise TopicError(f"topic {arg!r}: empty name")
    typ, _, qos = rest.partition(":")
    if not typ:
        if name not in KNOWN:
            raise TopicError(f"topic {name}: unknown type; give it as {name}:pkg/Type (e.g. {name}:nav_msgs/Odometry)")
        return KNOWN[name]
    cls = type_by_name(typ)
    if cls is None:
        raise TopicError(f"topic {name}: type {typ!r} is not one of {', '.join(sorted(TYPES))}")
    qos = qos or (KNOWN[name].qos if name in KNOWN else "reliable")
    if qos not in ("reliable", "best_effort", "latched"):
        raise TopicError(f"topic {name}: qos {qos!r} must be reliable, best_effort or latched")
    return TopicSpec(name, cls, qos)

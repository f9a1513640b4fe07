"""QoS presets under robonix's names, mapped to the ROS 2 profiles they stand for.

Every preset also pins the data representation to XCDR1, which is what rmw_cyclonedds offers and
accepts for ROS 2's ``@final`` types; a reader asking for XCDR2 would never match a ROS 2 writer.
"""

from __future__ import annotations

import math
import os

from cyclonedds.core import Policy
from cyclonedds.qos import Qos
from cyclonedds.util import duration

# Cyclone's own default for reliable writers: how long write() may block on a full history.
MAX_BLOCKING = duration(milliseconds=100)

# name -> (reliable, transient_local, default depth)
_PRESETS: dict[str, tuple[bool, bool, int]] = {
    "best_effort": (False, False, 10),
    "reliable": (True, False, 10),
    "latched": (True, True, 1),
    "transient_local": (True, True, 1),  # alias of latched (robonix maps it differently; this is ROS's meaning)
    "sensor_data": (False, False, 5),  # rmw_qos_profile_sensor_data
    "clock": (False, False, 1),  # rclcpp::ClockQoS = sensor_data with keep-last 1
}
QOS_NAMES: tuple[str, ...] = tuple(_PRESETS)

XCDR1 = Policy.DataRepresentation(use_cdrv0_representation=True)

LIVELINESS_ENV = "ROBONIX_DDS_LIVELINESS_S"
DEFAULT_LIVELINESS_S = 0.5


def liveliness_lease_s(raw: str | None = None) -> float:
    """Writers' automatic-liveliness lease in seconds (``ROBONIX_DDS_LIVELINESS_S``, default 0.5).

    Readers learn that a writer's process died or stalled (SIGKILL, SIGSTOP) within about this lease,
    from the data plane alone. ``inf`` (or ``off``) keeps DDS's infinite lease. A bad value raises
    ValueError naming the variable, so a typo in a deploy's ``env:`` fails at start, not silently.
    """
    text = os.environ.get(LIVELINESS_ENV, "") if raw is None else raw
    text = text.strip().lower()
    if not text:
        return DEFAULT_LIVELINESS_S
    if text in ("inf", "infinite", "off"):
        return math.inf
    try:
        v = float(text)
    except ValueError:
        raise ValueError(f"{LIVELINESS_ENV}: expected seconds > 0 (or 'inf'), got {text!r}") from None
    if not v > 0.0 or math.isnan(v):
        raise ValueError(f"{LIVELINESS_ENV}: expected seconds > 0 (or 'inf'), got {text!r}")
    if math.isfinite(v) and v < 0.05:
        raise ValueError(f"{LIVELINESS_ENV}: {v:g} s is below the 0.05 s minimum (loaded machines would "
                         "report live writers as lost)")
    return v


def writer_qos(qos: Qos, lease_s: float | None = None) -> Qos:
    """A writer's QoS with automatic liveliness at the configured lease.

    Offering a finite lease stays matchable by every reader that asks for less or equal strictness:
    ROS 2 readers request AUTOMATIC with an infinite lease (its default), and so do ours, so a ROS 2
    peer still matches while our readers get LIVELINESS_CHANGED when the writer stops asserting.
    A QoS that already carries a Liveliness policy is left as given.
    """
    if qos[Policy.Liveliness.Automatic] is not None or qos[Policy.Liveliness.ManualByTopic] is not None \
            or qos[Policy.Liveliness.ManualByParticipant] is not None:
        return qos
    lease = liveliness_lease_s() if lease_s is None else lease_s
    if not math.isfinite(lease):
        return qos
    return Qos(Policy.Liveliness.Automatic(duration(seconds=lease)), base=qos)


def qos_profile(name: str, depth: int | None = None) -> Qos:
    """A preset by name; ``depth`` overrides the KEEP_LAST depth."""
    try:
        reliable, latched, default_depth = _PRESETS[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown QoS preset {name!r}; valid: {', '.join(QOS_NAMES)}") from None
    d = default_depth if depth is None else int(depth)
    if d < 1:
        raise ValueError(f"QoS depth must be >= 1, got {depth}")
    return Qos(
        Policy.Reliability.Reliable(MAX_BLOCKING) if reliable else Policy.Reliability.BestEffort,
        Policy.Durability.TransientLocal if latched else Policy.Durability.Volatile,
        Policy.History.KeepLast(d),
        XCDR1,
    )


def resolve_qos(qos: str | Qos, depth: int | None = None) -> Qos:
    """Accept a preset name or a ready Qos; a custom Qos gets XCDR1 and the depth added if missing."""
    if isinstance(qos, str):
        return qos_profile(qos, depth)
    if not isinstance(qos, Qos):
        raise TypeError(f"qos must be a preset name ({', '.join(QOS_NAMES)}) or a cyclonedds Qos, got {qos!r}")
    extra = []
    if qos[Policy.DataRepresentation] is None:
        extra.append(XCDR1)
    if depth is not None:
        extra.append(Policy.History.KeepLast(int(depth)))
    return Qos(*extra, base=qos) if extra else qos


def describe(qos: Qos) -> dict[str, object]:
    """Plain summary (reliability, durability, depth) for logs and the atlas."""
    rel = qos[Policy.Reliability.BestEffort]
    dur = qos[Policy.Durability.Volatile]
    hist = qos[Policy.History.KeepAll]
    live = qos[Policy.Liveliness.Automatic]
    lease = getattr(live, "lease_duration", None)
    out: dict[str, object] = {
        "reliability": "reliable" if isinstance(rel, Policy.Reliability.Reliable) else "best_effort",
        "durability": "transient_local" if dur is Policy.Durability.TransientLocal else "volatile",
        "depth": getattr(hist, "depth", None),
    }
    if lease is not None and lease < 2**62:
        out["liveliness_lease_s"] = lease / 1e9
    return out

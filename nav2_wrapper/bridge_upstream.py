"""Resolve what navigation consumes (map, odom, scan) and where it commands (twist_in) through the atlas.

find_capability by contract → connect_capability → endpoint (topic) + QoS, channel closed right after,
as robonix's navigation package does. ``topic_remap`` skips the lookup for a role; ``provider_ids``
pins a provider. A required role with no provider raises ``MissingUpstream`` (→ ``Deferred``).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

from .bridge_config import BridgeConfig

log = logging.getLogger("nav2_wrapper.upstream")

MAP = "robonix/service/map/occupancy_grid"
ODOM = "robonix/primitive/chassis/odom"
SCAN = "robonix/primitive/lidar/lidar"
TWIST_IN = "robonix/primitive/chassis/twist_in"
ROLES: dict[str, tuple[str, bool, str]] = {  # role -> (contract, required, default QoS)
    "map": (MAP, True, "transient_local"),
    "odom": (ODOM, True, "reliable"),
    "scan": (SCAN, False, "best_effort"),
}
DEFAULT_CMD_VEL = "/cmd_vel"


class MissingUpstream(LookupError):
    """A required contract has no live provider on the atlas (the message is the Deferred reason)."""


@dataclass(frozen=True)
class Binding:
    """One resolved input/output: topic, the QoS name to use, and where it came from."""

    role: str
    topic: str
    qos: str
    provider_id: str = ""   # "" when given by topic_remap / velocity_output_topic / default
    contract_id: str = ""
    source: str = "atlas"   # atlas | topic_remap | config | default


def reader_qos(declared: str, default: str) -> str:
    """QoS preset for a reader matching a provider's declared profile.

    "transient_local"/"latched" must stay TRANSIENT_LOCAL so a late joiner still gets the last map;
    a TRANSIENT_LOCAL reader would not match a VOLATILE writer, so "reliable" stays volatile.
    """
    q = (declared or "").strip().lower()
    if q in ("transient_local", "latched"):
        return "latched"
    if q in ("reliable", "best_effort"):
        return q
    return default if default != "transient_local" else "latched"


def _pick(atlas: Any, contract: str, provider: str) -> Any | None:
    caps = atlas.find_capability(contract_id=contract, transport="ros2", provider_id=provider or None)
    if not caps:
        return None
    caps = sorted(caps, key=lambda c: c.provider_id)
    if len(caps) > 1:
        log.warning("%s is offered by %s; using %s (pin one with provider_ids)", contract,
                    ", ".join(c.provider_id for c in caps), caps[0].provider_id)
    return caps[0]


def _connect(atlas: Any, consumer: str, role: str, contract: str, cap: Any, default_qos: str) -> Binding:
    ch = atlas.connect_capability(consumer_id=consumer, provider_id=cap.provider_id, contract_id=contract,
                                  transport="ros2")
    try:
        declared = getattr(ch.params, "qos_profile", "") if ch.params is not None else ""
        return Binding(role, ch.endpoint, reader_qos(declared, default_qos), cap.provider_id, contract)
    finally:
        ch.close()


def resolve(atlas: Any, consumer: str, cfg: BridgeConfig) -> dict[str, Binding]:
    """map, odom, (scan), cmd_vel bindings; MissingUpstream for the first required role that is absent."""
    out: dict[str, Binding] = {}
    for role, (contract, required, default_qos) in ROLES.items():
        remap = getattr(cfg.topic_remap, role)
        if remap:
            out[role] = Binding(role, remap, reader_qos("", default_qos), contract_id=contract, source="topic_remap")
            continue
        pin = getattr(cfg.provider_ids, role)
        cap = _pick(atlas, contract, pin)
        if cap is None:
            if required:
                who = f"provider {pin!r} is not on the atlas" if pin else "no provider on the atlas"
                raise MissingUpstream(f"waiting for {contract} ({who})")
            log.info("optional %s not on the atlas: the obstacle layer has no %s source", contract, role)
            continue
        out[role] = _connect(atlas, consumer, role, contract, cap, default_qos)
    out["cmd_vel"] = _cmd_vel(atlas, consumer, cfg)
    return out


def _cmd_vel(atlas: Any, consumer: str, cfg: BridgeConfig) -> Binding:
    if cfg.velocity_output_topic:
        return Binding("cmd_vel", cfg.velocity_output_topic, "reliable", source="config")
    cap = _pick(atlas, TWIST_IN, cfg.provider_ids.twist_in)
    if cap is None:
        log.info("%s not on the atlas; commanding %s", TWIST_IN, DEFAULT_CMD_VEL)
        return Binding("cmd_vel", DEFAULT_CMD_VEL, "reliable", source="default")
    b = _connect(atlas, consumer, "cmd_vel", TWIST_IN, cap, "reliable")
    return Binding("cmd_vel", b.topic, "reliable", b.provider_id, TWIST_IN)


def still_there(atlas: Any, b: Binding) -> bool:
    """False once the provider a binding came from is gone (TERMINATED / evicted) from the atlas."""
    if b.source != "atlas" or not b.provider_id:
        return True
    return bool(atlas.find_capability(contract_id=b.contract_id, transport="ros2", provider_id=b.provider_id))

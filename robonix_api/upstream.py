"""Resolve a consumed topic by contract on the atlas: the one way every provider finds its inputs.

find_capability (ROS 2 transport; ``provider_ids`` pins one) → connect_capability → endpoint (topic) and
the declared QoS → the channel is closed right away, as robonix's packages do. ``topic_remap`` skips the
lookup for a role (e.g. a real robot whose drivers are not on our atlas). A required role with no
provider raises :class:`MissingUpstream`, whose message is the ``Deferred`` reason.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

log = logging.getLogger("robonix_api.upstream")


class MissingUpstream(LookupError):
    """A required contract has no live provider on the atlas (the message is the Deferred reason)."""


@dataclass(frozen=True)
class Binding:
    """One resolved topic: where to read (or write) it, the QoS preset to use, and where it came from."""

    role: str
    topic: str
    qos: str
    provider_id: str = ""   # "" when given by topic_remap / config / a default
    contract_id: str = ""
    source: str = "atlas"   # atlas | topic_remap | config | default


def reader_qos(declared: str, default: str) -> str:
    """QoS preset for a reader that must match what the provider declared.

    "transient_local"/"latched" stay TRANSIENT_LOCAL so a late joiner still gets the last sample; a
    TRANSIENT_LOCAL reader would not match a VOLATILE writer, so "reliable" stays volatile.
    """
    q = (declared or "").strip().lower()
    if q in ("transient_local", "latched"):
        return "latched"
    if q in ("reliable", "best_effort", "sensor_data"):
        return q
    return "latched" if default == "transient_local" else default


def resolve_topic(atlas: Any, consumer: str, role: str, contract: str, *, default_qos: str,
                  remap: str = "", pin: str = "", required: bool = True) -> Binding | None:
    """The binding for one role; None for an absent optional role, MissingUpstream for a required one."""
    if remap:
        return Binding(role, remap, reader_qos("", default_qos), contract_id=contract, source="topic_remap")
    caps = sorted(atlas.find_capability(contract_id=contract, transport="ros2", provider_id=pin or None),
                  key=lambda c: c.provider_id)
    if not caps:
        if required:
            who = f"provider {pin!r} is not on the atlas" if pin else "no provider on the atlas"
            raise MissingUpstream(f"waiting for {contract} ({who})")
        return None
    if len(caps) > 1:
        log.warning("%s is offered by %s; using %s (pin one with provider_ids.%s)", contract,
                    ", ".join(c.provider_id for c in caps), caps[0].provider_id, role)
    with atlas.connect_capability(consumer_id=consumer, provider_id=caps[0].provider_id, contract_id=contract,
                                  transport="ros2") as ch:
        declared = getattr(ch.params, "qos_profile", "") if ch.params is not None else ""
        return Binding(role, ch.endpoint, reader_qos(declared, default_qos), caps[0].provider_id, contract)


def still_there(atlas: Any, b: Binding) -> bool:
    """False once the provider a binding came from is gone (TERMINATED / evicted) from the atlas."""
    if b.source != "atlas" or not b.provider_id:
        return True
    return bool(atlas.find_capability(contract_id=b.contract_id, transport="ros2", provider_id=b.provider_id))

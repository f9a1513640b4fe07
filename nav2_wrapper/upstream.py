"""What navigation consumes (map, odom, scan) and where it commands (twist_in), resolved through the atlas
with the SDK's contract lookup (``robonix_api.upstream``). ``velocity_output_topic`` overrides the
command output; without it and without a twist_in provider, navigation commands ``/cmd_vel``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Any

from robonix_api.types import LifecycleState
from robonix_api.upstream import Binding, MissingUpstream, resolve_topic, still_there

from .config import ProviderConfig

__all__ = ["Binding", "MissingUpstream", "UpstreamWatch", "resolve", "still_there"]

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


def resolve(atlas: Any, consumer: str, cfg: ProviderConfig) -> dict[str, Binding]:
    """map, odom, (scan), cmd_vel bindings; MissingUpstream for the first required role that is absent."""
    out: dict[str, Binding] = {}
    for role, (contract, required, default_qos) in ROLES.items():
        b = resolve_topic(atlas, consumer, role, contract, default_qos=default_qos, required=required,
                          remap=getattr(cfg.topic_remap, role), pin=getattr(cfg.provider_ids, role))
        if b is None:
            log.info("optional %s not on the atlas: the obstacle layer has no %s source", contract, role)
            continue
        out[role] = b
    out["cmd_vel"] = _cmd_vel(atlas, consumer, cfg)
    return out


def _cmd_vel(atlas: Any, consumer: str, cfg: ProviderConfig) -> Binding:
    if cfg.velocity_output_topic:
        return Binding("cmd_vel", cfg.velocity_output_topic, "reliable", source="config")
    b = resolve_topic(atlas, consumer, "twist_in", TWIST_IN, default_qos="reliable",
                      pin=cfg.provider_ids.twist_in, required=False)
    if b is None:
        log.info("%s not on the atlas; commanding %s", TWIST_IN, DEFAULT_CMD_VEL)
        return Binding("cmd_vel", DEFAULT_CMD_VEL, "reliable", source="default")
    return Binding("cmd_vel", b.topic, "reliable", b.provider_id, TWIST_IN)


@dataclass
class UpstreamWatch:
    """The atlas' view of the providers navigation reads from, polled by the loop's watch thread.

    ``poll()`` -> ({role: why} for providers the atlas reports TERMINATED, {role: Binding} for roles
    whose provider registered anew and now declares another topic or QoS). A provider the atlas does
    not list at all is neither: right after an atlas restart nobody is registered yet, and providers
    re-register on their next heartbeat, so absence alone must never fail a goal; DDS liveliness
    tells whether the data still flows.
    """

    atlas: Any
    consumer: str
    bindings: dict[str, Binding]
    _registration: dict[str, str] = field(default_factory=dict)

    def poll(self) -> tuple[dict[str, str], dict[str, Binding]]:
        terminated: dict[str, str] = {}
        rebinds: dict[str, Binding] = {}
        watched = {**ROLES, "cmd_vel": (TWIST_IN, False, "reliable")}
        for role, (contract, _required, default_qos) in watched.items():
            b = self.bindings.get(role)
            if b is None or b.source != "atlas" or not b.provider_id:
                continue
            found = self.atlas.query(id=b.provider_id)
            if not found:
                continue  # not (yet) registered on this atlas: judge by the data plane
            p = found[0]
            if p.state == LifecycleState.TERMINATED:
                terminated[role] = f"the atlas reports {b.provider_id} TERMINATED"
                continue
            seen = self._registration.get(role)
            self._registration[role] = p.registration_id
            if seen is None or seen == p.registration_id:
                continue
            nb = resolve_topic(self.atlas, self.consumer, role, contract, default_qos=default_qos,
                               pin=b.provider_id, required=False)
            if nb is not None and role == "cmd_vel":
                nb = Binding("cmd_vel", nb.topic, "reliable", nb.provider_id, TWIST_IN)
            if nb is not None and (nb.topic, nb.qos) != (b.topic, b.qos):
                log.info("%s: provider %s registered anew with %s (was %s)", role, b.provider_id, nb.topic,
                         b.topic)
                rebinds[role] = nb
        return terminated, rebinds

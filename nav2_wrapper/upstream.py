"""What navigation consumes (map, odom, scan) and where it commands (twist_in), resolved through the atlas
with the SDK's contract lookup (``robonix_api.upstream``). ``velocity_output_topic`` overrides the
command output; without it and without a twist_in provider, navigation commands ``/cmd_vel``.
"""

from __future__ import annotations

import logging
from typing import Any

from robonix_api.upstream import Binding, MissingUpstream, resolve_topic, still_there

from .config import ProviderConfig

__all__ = ["Binding", "MissingUpstream", "resolve", "still_there"]

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

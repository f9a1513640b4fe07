"""robonix-api's ``robonix_api.atlas_types``: the atlas dataclasses and enums, and the proto converters
under robonix-api's names. The types themselves live in :mod:`robonix_api.types` (shared with the atlas
server); COMPAT.md lists where they differ from robonix-api's (they are a superset).
"""

from __future__ import annotations

from typing import Any

from robonix_api.types import (
    Capability,
    CapabilityProvider,
    Channel,
    ContractDescriptor,
    FieldSpec,
    GrpcParams,
    Kind,
    LifecycleState,
    McpParams,
    Ros2Params,
    Transport,
    TransportParams,
    params_from_pb,
)


def from_pb_field_spec(pb_f: Any) -> FieldSpec:
    """robonix-api's converter name for :meth:`FieldSpec.from_pb`."""
    return FieldSpec.from_pb(pb_f)


def from_pb_params(transport: Transport | int | str, pb_params: Any) -> TransportParams | None:
    """The params branch matching ``transport`` (None when that branch is not set)."""
    if pb_params is None:
        return None
    params = params_from_pb(pb_params)
    return params if params is not None and params.transport == Transport.parse(transport) else None


def from_pb_capability(pb_cap: Any) -> Capability:
    """robonix-api's converter name for :meth:`Capability.from_pb`."""
    return Capability.from_pb(pb_cap)


def from_pb_provider(pb_rec: Any) -> CapabilityProvider:
    """robonix-api's converter name for :meth:`CapabilityProvider.from_pb`."""
    return CapabilityProvider.from_pb(pb_rec)


def from_pb_contract(pb_c: Any) -> ContractDescriptor:
    """robonix-api's converter name for :meth:`ContractDescriptor.from_pb`."""
    return ContractDescriptor.from_pb(pb_c)


__all__ = [
    "Capability", "CapabilityProvider", "Channel", "ContractDescriptor", "FieldSpec", "GrpcParams", "Kind",
    "LifecycleState", "McpParams", "Ros2Params", "Transport", "from_pb_capability", "from_pb_contract",
    "from_pb_field_spec", "from_pb_params", "from_pb_provider",
]

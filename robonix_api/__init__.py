"""robonix_api: the SDK every provider uses (robonix names).

``ATLAS`` (the default atlas client) is resolved lazily so importing the SDK opens no connection.
"""

from __future__ import annotations

from typing import Any

from robonix_api.grpc_contracts import StatusError
from robonix_api.provider import Primitive, Service, Skill
from robonix_api.result import Deferred, Err, Ok, Result
from robonix_api.types import (
    Capability,
    CapabilityProvider,
    Channel,
    ContractDescriptor,
    GrpcParams,
    Kind,
    LifecycleState,
    McpParams,
    Ros2Params,
    Transport,
)

__all__ = [
    "ATLAS",
    "Capability",
    "CapabilityProvider",
    "Channel",
    "ContractDescriptor",
    "Deferred",
    "Err",
    "GrpcParams",
    "Kind",
    "LifecycleState",
    "McpParams",
    "Ok",
    "Primitive",
    "Result",
    "Ros2Params",
    "Service",
    "Skill",
    "StatusError",
    "Transport",
]


def __getattr__(name: str) -> Any:
    if name == "ATLAS":
        from robonix_api.atlas_client import ATLAS

        return ATLAS
    raise AttributeError(f"module 'robonix_api' has no attribute {name!r}")

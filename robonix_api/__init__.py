"""robonix_api: the SDK every provider uses; an API superset of robonix-api 0.1.0rc1 (see COMPAT.md).

``ATLAS`` (the default atlas client) is resolved lazily so importing the SDK opens no connection.
Importing the SDK also makes the bundled generated protos importable under their top-level names
(``import map_pb2``), as robonix packages import them (:mod:`robonix_api.proto_alias`).
"""

from __future__ import annotations

import contextlib
from typing import Any

from robonix_api import (
    forksafe,  # noqa: F401  (before anything imports grpc)
    proto_alias,
)
from robonix_api.grpc_contracts import StatusError
from robonix_api.provider import Primitive, Service, Skill
from robonix_api.result import Deferred, Err, Ok, Result
from robonix_api.tool import mcp_contract
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
    "mcp_contract",
]

proto_alias.install()


def _bootstrap_caller_codegen() -> None:
    """As robonix-api does on import: put the importing package's ``rbnx-build/codegen`` outputs on
    ``sys.path`` so its generated modules import at the top of the file (a no-op without them)."""
    from robonix_api import pkg
    from robonix_api.codegen import ensure_proto_gen

    root = pkg.find_pkg_root(pkg.caller_file())
    if root is not None:
        ensure_proto_gen(root)


with contextlib.suppress(OSError):  # an unreadable folder on the way up must not break importing the SDK
    _bootstrap_caller_codegen()
del _bootstrap_caller_codegen


def __getattr__(name: str) -> Any:
    if name == "ATLAS":
        from robonix_api.atlas_client import ATLAS

        return ATLAS
    raise AttributeError(f"module 'robonix_api' has no attribute {name!r}")

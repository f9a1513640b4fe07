"""What an ``@svc.mcp(contract)`` tool looks like to a client: its description, request type and JSON
input schema, computed without the MCP server stack.

Kept apart from :mod:`robonix_api.mcp_server` because importing the official ``mcp`` package costs about
a second of CPU per process; a provider declares its tools on the atlas with these schemas at once and
loads the server stack only when it is needed (see :mod:`robonix_api.mcp_deferred`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from robonix_api.contracts import ContractSpec
from robonix_api.proto_schema import message_class, message_schema
from robonix_api.tool import codegen_input_class, input_schema

MCP_PATH = "/mcp/"  # where every MCP server of ours serves streamable HTTP


@dataclass(frozen=True)
class ToolShape:
    """Description, request class and input schema of one contract served as an MCP tool."""

    description: str
    request_cls: type
    input_schema: dict[str, Any]


def tool_shape(spec: ContractSpec, handler: Callable[..., Any], description: str = "") -> ToolShape:
    """The request type is the contract's request proto, or the handler's annotated input class when that
    is a robonix codegen class (``json_schema``/``from_dict``)."""
    doc = (description or (handler.__doc__ or "")).strip() or spec.description or spec.id
    codegen_cls = codegen_input_class(handler)
    if codegen_cls is not None:
        return ToolShape(doc, codegen_cls, input_schema(codegen_cls))
    if not spec.idl:
        raise TypeError(f"@mcp({spec.id!r}): the contract is not in the catalogue, so the handler's input "
                        "must be annotated with a codegen class (json_schema()/from_dict())")
    req_name, _ = spec.proto_types()
    req_cls = message_class(req_name)
    return ToolShape(doc, req_cls, message_schema(req_cls.DESCRIPTOR))

"""robonix-api's ``robonix_api.tool``: ``mcp_contract`` binds a typed handler to an MCP app as a tool.

The tool name is the last segment of the contract id (what robonix's executor calls). The handler takes
one argument annotated with its input type and annotates its return type. The input type may be a
contract request proto (this SDK's messages) or a robonix codegen class (``json_schema()`` /
``from_dict()``); the tool's input schema comes from that type, and the return value goes back as JSON.

The app is anything with ``add_tool(fn, name=, description=, structured_output=)``: the official
``mcp`` package's ``MCPServer`` (``FastMCP`` before mcp 2). robonix-api needs the separate ``fastmcp``
package for this; here only the official ``mcp`` package is used. Provider handlers declared with
``@svc.provides_mcp`` do not go through here: they are served by :mod:`robonix_api.mcp_server`.
"""

from __future__ import annotations

import inspect
import json
import logging
import weakref
from collections.abc import Callable
from typing import Any, get_type_hints

from google.protobuf import json_format
from google.protobuf.message import Message

log = logging.getLogger(__name__)

_JSON_TYPES: dict[str, Any] = {"string": str, "integer": int, "number": float, "boolean": bool,
                               "array": list, "object": dict}
#: app -> [(contract_id, input schema, description)] registered through mcp_contract
_APP_TOOLS: weakref.WeakKeyDictionary[Any, list[tuple[str, dict[str, Any], str]]] = weakref.WeakKeyDictionary()


def io_types_from_handler(user_fn: Callable[..., Any], *, contract_id: str) -> tuple[type, type | None]:
    """``(input type, output type or None)`` from the handler's annotations; TypeError if it does not
    take exactly one annotated argument or lacks a return annotation."""
    where = f"[mcp_contract:{contract_id}] {getattr(user_fn, '__name__', user_fn)!s}"
    params = [p for p in inspect.signature(user_fn).parameters.values()
              if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY, p.POSITIONAL_ONLY)]
    if len(params) != 1:
        raise TypeError(f"{where} must take exactly one parameter (the input message)")
    hints = get_type_hints(user_fn)
    arg = hints.get(params[0].name)
    if not isinstance(arg, type):
        raise TypeError(f"{where}: parameter {params[0].name!r} must be annotated with the input message type")
    if "return" not in hints:
        raise TypeError(f"{where} must annotate its return type")
    ret = hints["return"]
    if ret is type(None):
        return arg, None
    if not isinstance(ret, type):
        raise TypeError(f"{where}: return annotation must be a message class")
    return arg, ret


def json_prop_to_py_type(prop: dict[str, Any]) -> Any:
    """Python type for a JSON Schema property (``Any`` when the type is unknown)."""
    return _JSON_TYPES.get(prop.get("type", "string"), Any)


def wire_output_for_json(value: Any) -> Any:
    """A handler's return value as JSON data: protos via ``MessageToDict``, codegen classes via
    ``to_dict()``, JSON values as they are."""
    if isinstance(value, Message):
        return json_format.MessageToDict(value, preserving_proto_field_name=True,
                                         always_print_fields_with_no_presence=True)
    to_dict = getattr(value, "to_dict", None)
    return to_dict() if callable(to_dict) else value


def input_schema(input_cls: type) -> dict[str, Any]:
    """JSON Schema of an input type: a proto's from its descriptor, a codegen class's own."""
    if isinstance(input_cls, type) and issubclass(input_cls, Message):
        from robonix_api.proto_schema import message_schema

        return message_schema(input_cls.DESCRIPTOR)
    schema = getattr(input_cls, "json_schema", None)
    if not callable(schema):
        raise TypeError(f"{input_cls.__name__}: not a proto message and has no json_schema()")
    return dict(schema())


def codegen_input_class(handler: Callable[..., Any]) -> type | None:
    """The handler's annotated input class when it is a robonix codegen class (not a proto), else None."""
    try:
        params = [p for p in inspect.signature(handler).parameters.values()
                  if p.kind in (p.POSITIONAL_OR_KEYWORD, p.POSITIONAL_ONLY)]
        hints = get_type_hints(handler) if params else {}
    except (TypeError, ValueError, NameError):
        return None
    cls = hints.get(params[0].name) if params else None
    if (isinstance(cls, type) and not issubclass(cls, Message) and callable(getattr(cls, "json_schema", None))
            and callable(getattr(cls, "from_dict", None))):
        return cls
    return None


def build_input(input_cls: type, arguments: dict[str, Any]) -> Any:
    """A tool's JSON arguments as its request type (a protobuf message or a dataclass with ``from_dict``)."""
    if issubclass(input_cls, Message):
        return json_format.ParseDict(arguments, input_cls())
    return input_cls.from_dict(arguments)  # type: ignore[attr-defined]


def make_shim(user_fn: Callable[..., Any], input_cls: type, out_cls: type | None) -> Callable[..., Any]:
    """An async tool function whose keyword parameters are the input schema's properties (so the MCP
    app derives the same schema), building the input object and returning JSON data."""
    props: dict[str, Any] = input_schema(input_cls).get("properties") or {}

    async def shim(**kwargs: Any) -> Any:
        result = user_fn(build_input(input_cls, {k: v for k, v in kwargs.items() if v is not None}))
        if inspect.isawaitable(result):
            result = await result
        return wire_output_for_json(result)

    def annotation(prop: dict[str, Any]) -> Any:
        py = dict if prop.get("type") == "object" else json_prop_to_py_type(prop)
        return Any if py is Any else py | None

    shim.__signature__ = inspect.Signature(  # type: ignore[attr-defined]
        [inspect.Parameter(k, inspect.Parameter.KEYWORD_ONLY, default=None, annotation=annotation(v))
         for k, v in props.items()], return_annotation=Any)
    shim.__annotations__ = {**{k: annotation(v) for k, v in props.items()}, "return": Any}
    shim.__name__ = getattr(user_fn, "__name__", "tool")
    shim.__qualname__ = getattr(user_fn, "__qualname__", shim.__name__)
    shim.__doc__ = user_fn.__doc__ or ""
    return shim


def mcp_contract(mcp: Any, *, contract_id: str,
                 structured_output: bool | None = None) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Register the decorated handler on ``mcp`` as the tool for ``contract_id``; the handler is
    returned unchanged, tagged with ``_robonix_input_cls``, ``_robonix_output_cls`` and
    ``_robonix_contract_id`` as robonix-api does."""

    def decorator(user_fn: Callable[..., Any]) -> Callable[..., Any]:
        input_cls, output_cls = io_types_from_handler(user_fn, contract_id=contract_id)
        shim = make_shim(user_fn, input_cls, output_cls)
        description = (user_fn.__doc__ or "").strip()
        mcp.add_tool(shim, name=contract_id.rsplit("/", 1)[-1], description=description,
                     structured_output=structured_output)
        user_fn._robonix_input_cls = input_cls  # type: ignore[attr-defined]
        user_fn._robonix_output_cls = output_cls  # type: ignore[attr-defined]
        user_fn._robonix_contract_id = contract_id  # type: ignore[attr-defined]
        _APP_TOOLS.setdefault(mcp, []).append((contract_id, input_schema(input_cls), description))
        return user_fn

    return decorator


def declare_app_tools(provider: Any, app: Any) -> None:
    """Declare every ``mcp_contract`` tool of ``app`` on ``provider`` at its MCP endpoint."""
    for contract_id, schema, description in _APP_TOOLS.get(app, []):
        provider.declare_mcp(contract_id, input_schema_json=json.dumps(schema), description=description)


__all__ = ["build_input", "codegen_input_class", "declare_app_tools", "input_schema", "io_types_from_handler",
           "json_prop_to_py_type", "make_shim", "mcp_contract", "wire_output_for_json"]

"""JSON Schema and message classes from proto descriptors, for MCP tools built on contract types.

An MCP client only sees JSON; deriving the schema from the request message keeps the tool's declared
input in lock-step with what ``json_format.ParseDict`` will accept.
"""

from __future__ import annotations

from typing import Any

from google.protobuf import descriptor_pool, message_factory
from google.protobuf.descriptor import Descriptor, FieldDescriptor
from google.protobuf.message import Message

import robonix_api.proto_gen.robonix_contracts_pb2  # noqa: F401  (loads every contract type into the pool)

_FD = FieldDescriptor
_INTEGER = {_FD.TYPE_INT32, _FD.TYPE_SINT32, _FD.TYPE_SFIXED32, _FD.TYPE_UINT32, _FD.TYPE_FIXED32,
            _FD.TYPE_INT64, _FD.TYPE_SINT64, _FD.TYPE_SFIXED64, _FD.TYPE_UINT64, _FD.TYPE_FIXED64}
_NUMBER = {_FD.TYPE_DOUBLE, _FD.TYPE_FLOAT}
_UNSIGNED = {_FD.TYPE_UINT32, _FD.TYPE_FIXED32, _FD.TYPE_UINT64, _FD.TYPE_FIXED64}
_MAX_DEPTH = 12


def message_class(full_name: str) -> type[Message]:
    """The Python class of a proto message by full name (``google.protobuf.Empty`` included)."""
    if full_name == "google.protobuf.Empty":
        from google.protobuf import empty_pb2

        return empty_pb2.Empty
    desc = descriptor_pool.Default().FindMessageTypeByName(full_name)
    return message_factory.GetMessageClass(desc)


def message_schema(desc: Descriptor, _depth: int = 0) -> dict[str, Any]:
    """JSON Schema (object) of a message: nested messages as objects, repeated fields as arrays."""
    if _depth > _MAX_DEPTH:  # recursive types: stop describing, still an object
        return {"type": "object"}
    props = {f.name: _field_schema(f, _depth) for f in desc.fields}
    return {"type": "object", "properties": props, "additionalProperties": False}


def _field_schema(field: FieldDescriptor, depth: int) -> dict[str, Any]:
    if field.message_type is not None and field.message_type.GetOptions().map_entry:
        value = field.message_type.fields_by_name["value"]
        return {"type": "object", "additionalProperties": _single_schema(value, depth)}
    single = _single_schema(field, depth)
    if field.is_repeated:
        return {"type": "array", "items": single}
    return single


def _single_schema(field: FieldDescriptor, depth: int) -> dict[str, Any]:
    t = field.type
    if t in (_FD.TYPE_MESSAGE, _FD.TYPE_GROUP):
        return message_schema(field.message_type, depth + 1)
    if t == _FD.TYPE_ENUM:
        return {"type": "string", "enum": [v.name for v in field.enum_type.values]}
    if t == _FD.TYPE_BOOL:
        return {"type": "boolean"}
    if t == _FD.TYPE_STRING:
        return {"type": "string"}
    if t == _FD.TYPE_BYTES:
        return {"type": "string", "contentEncoding": "base64"}
    if t in _INTEGER:
        return {"type": "integer", "minimum": 0} if t in _UNSIGNED else {"type": "integer"}
    if t in _NUMBER:
        return {"type": "number"}
    return {}

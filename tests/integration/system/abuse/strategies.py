"""Hypothesis strategies for hostile inputs: any protobuf request message (from its descriptor), JSON
values shaped like a JSON schema (MCP tool arguments) or not, and config_json texts.

Values lean on what broke things before: NaN, +-inf, 1e308, 5e-324, ids with a trailing newline, path
escapes, 65-character and 70 000-character strings, control characters, deep nesting.
"""

from __future__ import annotations

import json
import os
from typing import Any

from google.protobuf.descriptor import Descriptor, FieldDescriptor
from google.protobuf.message import Message
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

SPECIAL_FLOATS = [0.0, -0.0, 1e308, -1e308, 5e-324, 1e6, -1e6, 1e4, float("nan"), float("inf"), float("-inf")]
SPECIAL_STRINGS = ["", " ", "ok\n", "\nok", "a\x00b", "..", "../..", "../../etc", "/etc/passwd", "/", "~", "a/b",
                   ".hidden", "x" * 64, "x" * 65, "é" * 40, "mapping", "localization", "faster", "slower",
                   "normal", "map", "odom", "base_link", "room1", "${HOME}", "$(id)", "%s%s%n", "\u202e", "\ud7ff"]
HUGE_STRINGS = ["y" * 5000, "z" * 70_000]
INT_RANGES = {
    FieldDescriptor.TYPE_INT32: (-2**31, 2**31 - 1), FieldDescriptor.TYPE_SINT32: (-2**31, 2**31 - 1),
    FieldDescriptor.TYPE_SFIXED32: (-2**31, 2**31 - 1), FieldDescriptor.TYPE_ENUM: (-2**31, 2**31 - 1),
    FieldDescriptor.TYPE_INT64: (-2**63, 2**63 - 1), FieldDescriptor.TYPE_SINT64: (-2**63, 2**63 - 1),
    FieldDescriptor.TYPE_SFIXED64: (-2**63, 2**63 - 1),
    FieldDescriptor.TYPE_UINT32: (0, 2**32 - 1), FieldDescriptor.TYPE_FIXED32: (0, 2**32 - 1),
    FieldDescriptor.TYPE_UINT64: (0, 2**64 - 1), FieldDescriptor.TYPE_FIXED64: (0, 2**64 - 1),
}



FULL = os.environ.get("ROBONIX_FUZZ", "") == "full"


def fuzz_settings(full_count: int) -> settings:
    """Derandomized hypothesis settings: ``full_count`` examples with ROBONIX_FUZZ=full (the slow run of
    .ci/run), a fifth of them (at least 5) in the contributor's suite, so both runs try the same first inputs."""
    n = full_count if FULL else max(5, full_count // 5)
    return settings(max_examples=n, deadline=None, derandomize=True, database=None,
                    suppress_health_check=list(HealthCheck))

def hostile_text(extra: list[str] | None = None) -> st.SearchStrategy[str]:
    return st.one_of(st.sampled_from(SPECIAL_STRINGS + (extra or [])), st.text(max_size=40),
                     st.sampled_from(HUGE_STRINGS))


def hostile_float(width: int = 64) -> st.SearchStrategy[float]:
    specials = [v for v in SPECIAL_FLOATS if width == 64 or abs(v) < 3e38 or v != v or abs(v) == float("inf")]
    return st.one_of(st.sampled_from(specials), st.floats(-30, 30, width=width),
                     st.floats(allow_nan=True, allow_infinity=True, width=width))


def _scalar(field: FieldDescriptor, extra_strings: list[str]) -> st.SearchStrategy[Any]:
    t = field.type
    if t == FieldDescriptor.TYPE_DOUBLE:
        return hostile_float(64)
    if t == FieldDescriptor.TYPE_FLOAT:
        return hostile_float(32)
    if t == FieldDescriptor.TYPE_BOOL:
        return st.booleans()
    if t == FieldDescriptor.TYPE_STRING:
        return hostile_text(extra_strings)
    if t == FieldDescriptor.TYPE_BYTES:
        return st.binary(max_size=64)
    if t == FieldDescriptor.TYPE_ENUM:
        known = [v.number for v in field.enum_type.values]
        return st.one_of(st.sampled_from(known), st.integers(-5, 1000))
    lo, hi = INT_RANGES[t]
    return st.one_of(st.integers(-3, 100).filter(lambda v: lo <= v <= hi), st.sampled_from([lo, hi]))


def message_fields(desc: Descriptor, depth: int = 0, extra_strings: list[str] | None = None) -> st.SearchStrategy:
    """A dict of field name -> value for ``desc`` (any subset of fields, nested messages to depth 3)."""
    extra = extra_strings or []
    optional: dict[str, st.SearchStrategy[Any]] = {}
    for field in desc.fields:
        if field.type == FieldDescriptor.TYPE_MESSAGE:
            if depth >= 3 or field.message_type.GetOptions().map_entry:
                continue
            one = message_fields(field.message_type, depth + 1, extra)
        else:
            one = _scalar(field, extra)
        optional[field.name] = st.lists(one, max_size=3) if field.is_repeated else one
    return st.fixed_dictionaries({}, optional=optional)


def fill(msg: Message, values: dict[str, Any]) -> Message:
    """Set ``values`` (from :func:`message_fields`) on ``msg``; returns it."""
    for name, value in values.items():
        field = msg.DESCRIPTOR.fields_by_name[name]
        if field.type == FieldDescriptor.TYPE_MESSAGE:
            if field.is_repeated:
                for item in value:
                    fill(getattr(msg, name).add(), item)
            else:
                fill(getattr(msg, name), value)
                getattr(msg, name).SetInParent()
        elif field.is_repeated:
            getattr(msg, name).extend(value)
        else:
            setattr(msg, name, value)
    return msg


def requests(cls: type[Message], extra_strings: list[str] | None = None) -> st.SearchStrategy[Message]:
    return message_fields(cls.DESCRIPTOR, 0, extra_strings).map(lambda v: fill(cls(), v))


def json_values(max_leaves: int = 12) -> st.SearchStrategy[Any]:
    """Any JSON value (finite numbers only: JSON has no NaN), small but with hostile leaves."""
    leaves = st.one_of(st.none(), st.booleans(), st.integers(-2**70, 2**70), hostile_float().filter(lambda v: v == v
                       and abs(v) != float("inf")), hostile_text())
    return st.recursive(leaves, lambda inner: st.one_of(st.lists(inner, max_size=3),
                                                         st.dictionaries(hostile_text(), inner, max_size=3)),
                        max_leaves=max_leaves)


def schema_value(schema: dict[str, Any], depth: int = 0) -> st.SearchStrategy[Any]:
    """A value for a JSON schema: usually of the declared type (with hostile values), sometimes not."""
    wrong = json_values(4)
    kind = schema.get("type")
    if isinstance(kind, list):
        kind = kind[0] if kind else None
    if kind == "object" or "properties" in schema:
        if depth >= 3:
            return st.just({})
        props = schema.get("properties") or {}
        fields = {k: schema_value(v if isinstance(v, dict) else {}, depth + 1) for k, v in props.items()}
        typed = st.fixed_dictionaries({}, optional=fields)
        extra = st.dictionaries(hostile_text(), json_values(3), max_size=2)
        return st.one_of(typed, typed, typed, st.builds(lambda a, b: {**b, **a}, typed, extra), wrong)
    if kind == "array":
        items = schema.get("items") if isinstance(schema.get("items"), dict) else {}
        return st.one_of(st.lists(schema_value(items, depth + 1), max_size=3), wrong)
    typed_by_kind: dict[str, st.SearchStrategy[Any]] = {
        "number": hostile_float().filter(lambda v: v == v and abs(v) != float("inf")),
        "integer": st.one_of(st.integers(-5, 1000), st.sampled_from([2**31, -2**31 - 1, 2**63, 2**64, -2**64])),
        "string": hostile_text(), "boolean": st.booleans(), "null": st.none(),
    }
    typed = typed_by_kind.get(kind or "", json_values(4))
    if "enum" in schema and isinstance(schema["enum"], list) and schema["enum"]:
        typed = st.one_of(st.sampled_from(schema["enum"]), typed)
    return st.one_of(typed, typed, typed, wrong)


def config_json_texts(keys: list[str]) -> st.SearchStrategy[str]:
    """config_json payloads: objects with real and bogus keys, non-objects, broken and deep JSON, huge."""
    real = st.dictionaries(st.one_of(st.sampled_from(keys), hostile_text()), json_values(6), max_size=4)
    return st.one_of(
        real.map(json.dumps), real.map(json.dumps), json_values(6).map(json.dumps),
        st.sampled_from(["", "{", "}", "[1,", '{"a": }', "null", "NaN", '{"a": NaN}', "\x00", '"str"',
                         "[" * 100_000 + "]" * 100_000, '{"a":' * 40 + "1" + "}" * 40,
                         json.dumps({"x": "y" * (1 << 20)}), "1e999", '{"' + "k" * 70_000 + '": 1}']),
        st.text(max_size=60),
    )

"""One declaration per tunable: a dataclass field carries its default, range and doc.

``param(0.05, ge=0.005, le=1.0, doc="m per cell")`` is a ``dataclasses.field`` whose metadata holds the
range under the names pydantic's ``Field`` uses (``gt``, ``ge``, ``lt``, ``le``, ``description``), so a
config layer that validates files with pydantic enforces the very same range without restating it, and
:func:`check_ranges` enforces it in the core's ``__post_init__`` for configs built in Python.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

_OPS = {"gt": (">", float.__gt__), "ge": (">=", float.__ge__), "lt": ("<", float.__lt__), "le": ("<=", float.__le__)}


class ParamError(ValueError):
    """A value outside its declared range; ``field`` names it, ``reason`` says what is wrong."""

    def __init__(self, field: str, reason: str, prefix: str = "") -> None:
        super().__init__(f"{prefix}{field}: {reason}")
        self.field, self.reason = field, reason


def param(default: Any = dataclasses.MISSING, *, doc: str, gt: float | None = None, ge: float | None = None,
          lt: float | None = None, le: float | None = None) -> Any:
    """A dataclass field with its range and doc as metadata."""
    meta: dict[str, Any] = {"description": doc}
    meta.update({k: v for k, v in (("gt", gt), ("ge", ge), ("lt", lt), ("le", le)) if v is not None})
    return dataclasses.field(default=default, metadata=meta)


def describe_range(meta: Any) -> str:
    """``within [0.005, 1]`` / ``> 0`` / ``in (0, 5]``-style text for a field's declared range ('' if none)."""
    lo = ("gt", meta["gt"]) if "gt" in meta else ("ge", meta["ge"]) if "ge" in meta else None
    hi = ("lt", meta["lt"]) if "lt" in meta else ("le", meta["le"]) if "le" in meta else None
    if lo and hi:
        return f"within {'(' if lo[0] == 'gt' else '['}{lo[1]:g}, {hi[1]:g}{')' if hi[0] == 'lt' else ']'}"
    one = lo or hi
    return f"{_OPS[one[0]][0]} {one[1]:g}" if one else ""


def check_ranges(obj: Any, prefix: str = "") -> None:
    """Raise :class:`ParamError` for the first numeric field outside its declared range (NaN never passes)."""
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        bounds = [(k, f.metadata[k]) for k in _OPS if k in f.metadata]
        if not bounds or isinstance(value, bool) or not isinstance(value, int | float):
            continue
        if math.isnan(value) or not all(_OPS[k][1](float(value), float(b)) for k, b in bounds):
            raise ParamError(f.name, f"must be {describe_range(f.metadata)}, got {value:g}", prefix)


def markdown_table(cls: type) -> str:
    """The parameter reference of a config dataclass: one row per field (default, range, doc)."""
    rows = ["| field | default | range | meaning |", "|---|---|---|---|"]
    for f in dataclasses.fields(cls):
        default = f.default if f.default is not dataclasses.MISSING else "required"
        shown = str(default).lower() if isinstance(default, bool) else f"{default:g}" \
            if isinstance(default, float) else str(default)
        rows.append(f"| `{f.name}` | {shown} | {describe_range(f.metadata)} | {f.metadata.get('description', '')} |")
    return "\n".join(rows) + "\n"


def replace_block(text: str, name: str, body: str) -> str:
    """``text`` with the lines between ``<!-- name:begin -->`` and ``<!-- name:end -->`` replaced by ``body``."""
    begin, end = f"<!-- {name}:begin -->\n", f"<!-- {name}:end -->"
    head, found, rest = text.partition(begin)
    if not found or end not in rest:
        raise ValueError(f"no {begin.strip()} ... {end} block")
    return head + begin + body + end + rest.partition(end)[2]


def render_doc(text: str, blocks: dict[str, type]) -> str:
    """``text`` with each ``<!-- name:begin/end -->`` block replaced by the table of its dataclass."""
    for name, cls in blocks.items():
        text = replace_block(text, name, markdown_table(cls))
    return text

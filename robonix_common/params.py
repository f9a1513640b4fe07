"""One declaration per tunable: a dataclass field carries its default, unit, range and doc.

``param(0.05, "m per cell", ge=0.005, le=1.0)`` is a ``dataclasses.field`` whose metadata holds a
:class:`Spec` and the range under the names pydantic's ``Field`` uses (``gt``, ``ge``, ``lt``, ``le``,
``description``). The navigation params tables validate YAML against the Spec and generate their reference
from it; a config layer that validates files with pydantic enforces the very same range without restating
it; :func:`check_ranges` enforces it in a core's ``__post_init__`` for configs built in Python. Every core
(navigation, SLAM, simulator) declares its parameters with this one helper. Plain Python: cores import it.
"""

from __future__ import annotations

import dataclasses
import math
import typing
from dataclasses import dataclass
from typing import Any

_KEY = "robonix_param"

_OPS = {"gt": (">", float.__gt__), "ge": (">=", float.__ge__), "lt": ("<", float.__lt__), "le": ("<=", float.__le__)}


class ParamError(ValueError):
    """A value outside its declared range; ``field`` names it, ``reason`` says what is wrong."""

    def __init__(self, field: str, reason: str, prefix: str = "") -> None:
        super().__init__(f"{prefix}{field}: {reason}")
        self.field, self.reason = field, reason


@dataclass(frozen=True)
class Spec:
    """What a parameter means and which values it accepts (bounds are inclusive unless ``gt``/``lt``)."""

    doc: str
    unit: str = ""
    gt: float | None = None
    ge: float | None = None
    lt: float | None = None
    le: float | None = None
    choices: tuple[str, ...] = ()

    def violation(self, value: Any) -> str | None:
        """Why ``value`` is out of range (None when it is fine); scalars and each item of a sequence."""
        if isinstance(value, (tuple, list)):
            for item in value:
                why = self.violation(item)
                if why:
                    return why
            return None
        if self.choices and value not in self.choices:
            return f"{value!r} is not one of {', '.join(self.choices)}"
        if not isinstance(value, (int, float)) or isinstance(value, bool):
            return None
        if isinstance(value, float) and not math.isfinite(value):
            return f"must be a finite number, got {value}"
        for bound, ok, op in ((self.gt, lambda b: value > b, ">"), (self.ge, lambda b: value >= b, ">="),
                              (self.lt, lambda b: value < b, "<"), (self.le, lambda b: value <= b, "<=")):
            if bound is not None and not ok(bound):
                return f"must be {op} {bound:g}, got {value:g}"
        return None

    def range_text(self) -> str:
        """The accepted range for people: ``> 0``, ``0 … 252``, ``one of a, b``; empty when unbounded."""
        if self.choices:
            return "one of " + ", ".join(self.choices)
        lo = f"> {self.gt:g}" if self.gt is not None else (f">= {self.ge:g}" if self.ge is not None else "")
        hi = f"< {self.lt:g}" if self.lt is not None else (f"<= {self.le:g}" if self.le is not None else "")
        if self.ge is not None and self.le is not None:
            return f"{self.ge:g} … {self.le:g}"
        return ", ".join(p for p in (lo, hi) if p)


def param(default: Any = dataclasses.MISSING, doc: str = "", *, unit: str = "", gt: float | None = None,
          ge: float | None = None, lt: float | None = None, le: float | None = None,
          choices: tuple[str, ...] = ()) -> Any:
    """A dataclass field that is a tunable parameter: its default and its declaration, written once.

    The metadata holds the :class:`Spec` (what the navigation params tables and references read) and the
    range under pydantic ``Field``'s names (what :func:`check_ranges` and :func:`markdown_table` read)."""
    if not doc:
        raise TypeError("param() needs a doc string: say what the parameter means")
    spec = Spec(doc, unit, gt, ge, lt, le, choices)
    if default is not dataclasses.MISSING:
        why = spec.violation(default)
        if why:
            raise ValueError(f"default {default!r} violates its own declaration: {why}")
    meta: dict[str, Any] = {_KEY: spec, "description": doc}
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


def spec_of(f: dataclasses.Field) -> Spec | None:
    """The declaration of a dataclass field, or None for a field that is not a parameter."""
    return f.metadata.get(_KEY)


def declared(cls: type) -> dict[str, tuple[Any, Any, Spec]]:
    """``{field name: (type, default, spec)}`` for every declared parameter of a config dataclass."""
    hints = typing.get_type_hints(cls)
    out = {}
    for f in dataclasses.fields(cls):
        spec = spec_of(f)
        if spec is not None:
            out[f.name] = (hints[f.name], f.default, spec)
    return out


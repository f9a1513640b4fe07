"""Parameter declarations carried by the core config dataclasses: one place per parameter.

A tunable field is declared with :func:`param` (default, doc, unit, range). The same declaration is what
the params loader validates a YAML profile against, what builds the config, and what the parameter
reference in CAPABILITY.md is generated from, so a default or a range is never written twice.
Plain Python only: the cores stay importable without any file-format or middleware package.
"""

from __future__ import annotations

import dataclasses
import math
import typing
from dataclasses import dataclass, field
from typing import Any

_KEY = "robonix_param"


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


def param(default: Any, doc: str, *, unit: str = "", gt: float | None = None, ge: float | None = None,
          lt: float | None = None, le: float | None = None, choices: tuple[str, ...] = ()) -> Any:
    """A dataclass field that is a tunable parameter: its default and its declaration, written once."""
    spec = Spec(doc, unit, gt, ge, lt, le, choices)
    why = spec.violation(default)
    if why:
        raise ValueError(f"default {default!r} violates its own declaration: {why}")
    return field(default=default, metadata={_KEY: spec})


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


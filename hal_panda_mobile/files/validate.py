"""Validate a dict against a core dataclass and turn pydantic's errors into one ``field: message`` line.

The dataclass is the single declaration: pydantic reads its fields' types and the range/doc metadata
written with :func:`hal_panda_mobile.sim.spec.param`, and runs its ``__post_init__`` cross-field checks.
"""

from __future__ import annotations

import dataclasses
import functools
import re
from typing import Any, Literal, TypeVar

from pydantic import BaseModel, ConfigDict, Field, ValidationError, create_model

from hal_panda_mobile.sim import SimConfigError

T = TypeVar("T")

_MESSAGES = {
    "greater_than": "must be > {gt}",
    "greater_than_equal": "must be >= {ge}",
    "less_than": "must be < {lt}",
    "less_than_equal": "must be <= {le}",
    "missing": "required field is missing",
    "missing_argument": "required field is missing",
    "extra_forbidden": "unknown field",
    "unexpected_keyword_argument": "unknown field",
}
# A core check names the field relative to its object ("size: must be > 0"): join it onto the path.
_RELATIVE = re.compile(r"^([A-Za-z_]\w*): (.*)$", re.S)


def _loc(loc: tuple) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else str(part)
    return out


def format_validation_error(exc: ValidationError, prefix: str = "", *, skip: int = 0) -> str:
    """Pydantic errors -> ``walls[3].thickness: must be > 0; ...`` (short, field-first); ``skip`` drops
    leading path parts (a wrapper model's field)."""
    parts = []
    for err in exc.errors():
        template = _MESSAGES.get(err["type"])
        msg = template.format(**err.get("ctx", {})) if template else err["msg"]
        msg = msg.removeprefix("Value error, ")
        path = _loc(tuple(err["loc"])[skip:])
        rel = _RELATIVE.match(msg) if err["type"] == "value_error" else None
        if rel and path:
            path, msg = f"{path}.{rel.group(1)}", rel.group(2)
        parts.append(f"{path}: {msg}" if path else msg)
    return prefix + "; ".join(parts)


def core_field(cls: type, name: str) -> Any:
    """A pydantic ``Field`` for a config model that reuses a core dataclass field's default, range and doc,
    so a CMD_INIT key that feeds the core is not declared a second time."""
    f = {f.name: f for f in dataclasses.fields(cls)}[name]
    return Field(f.default, **f.metadata)


@functools.cache
def _wrapper(cls: type, extra: str) -> type[BaseModel]:
    return create_model(f"{cls.__name__}File", __config__=ConfigDict(extra=extra), value=(cls, ...))  # type: ignore[call-overload]


def validate(cls: type[T], data: object, source: str, *, extra: Literal["forbid", "ignore"] = "forbid") -> T:
    """``cls`` built from ``data`` (a mapping); SimConfigError ``"<source>: <field>: <message>"`` otherwise.
    ``extra="ignore"`` accepts keys the dataclass does not declare (a file other components share)."""
    if not isinstance(data, dict):
        raise SimConfigError(f"{source}: must be a mapping, got {type(data).__name__}")
    try:
        return _wrapper(cls, extra).model_validate({"value": data}).value  # type: ignore[attr-defined]
    except ValidationError as exc:
        raise SimConfigError(format_validation_error(exc, prefix=f"{source}: ", skip=1)) from None
    except SimConfigError as exc:  # raised by a check pydantic does not wrap (e.g. inside a nested default)
        raise SimConfigError(f"{source}: {exc}") from None

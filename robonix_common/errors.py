"""Bad input named by its field, worded the same way everywhere.

Every config model in the project is validated by pydantic, and every place that reports a bad config
(a provider's ``Err(...)`` from CMD_INIT, ``rbnx validate``, the simulator core, the atlas's
``--config-json``) turns the validation error into ``path: message`` through :func:`format_validation_error`.
The functions are duck-typed on ``exc.errors()`` (a list of dicts with ``loc``, ``msg``, ``type`` and
``ctx``) so this module imports no pydantic and the algorithm cores may use it too.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from typing import Any, Protocol

#: Short, field-first wording for pydantic's most common error types (its own text otherwise).
_TEMPLATES = {
    "greater_than": "must be > {gt}",
    "greater_than_equal": "must be >= {ge}",
    "less_than": "must be < {lt}",
    "less_than_equal": "must be <= {le}",
    "missing": "missing required key",
    "missing_argument": "missing required key",
    "extra_forbidden": "unknown field",
    "unexpected_keyword_argument": "unknown field",
}
#: Prefixes pydantic puts before the text of a ``ValueError`` / ``assert`` raised in a validator.
_PREFIXES = ("Value error, ", "Assertion failed, ")
#: How an empty location (the whole document) is named.
ROOT = "(top level)"
#: A check inside a model that names the field relative to it ("size: must be > 0").
_RELATIVE = re.compile(r"^([A-Za-z_]\w*): (.*)$", re.S)


class HasErrors(Protocol):
    """Anything shaped like pydantic's ``ValidationError``."""

    def errors(self) -> Sequence[Mapping[str, Any]]: ...


def field_path(loc: Iterable[Any], root: str = ROOT) -> str:
    """``('service', 1, 'name')`` -> ``service[1].name``; an empty location -> ``root``."""
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else str(part)
    return out or root


def error_message(err: Mapping[str, Any], *, unknown: str | None = None) -> str:
    """One error's text: a short template for bounds / missing / unknown keys, else pydantic's own
    message without its ``Value error,`` prefix and with a lower-case first letter (it follows a colon).
    ``unknown`` replaces the wording for an unexpected key."""
    kind = err.get("type")
    if kind in ("extra_forbidden", "unexpected_keyword_argument") and unknown is not None:
        return unknown
    template = _TEMPLATES.get(str(kind))
    if template is not None:
        try:
            ctx = {k: (f"{v:g}" if isinstance(v, float) else v) for k, v in (err.get("ctx") or {}).items()}
            return template.format(**ctx)
        except (KeyError, IndexError):
            pass
    msg = str(err.get("msg") or "invalid")
    for prefix in _PREFIXES:
        msg = msg.removeprefix(prefix)
    return msg[:1].lower() + msg[1:]


def field_problems(exc: HasErrors, *, unknown: str | None = None,
                   skip: int = 0) -> list[tuple[tuple[Any, ...], str]]:
    """``(loc, message)`` per error, for callers that sort or merge them with problems of their own.

    ``skip`` drops that many leading location parts (a wrapper model's field). A validator's message that
    names a field relative to its object (``size: must be > 0``) has that field joined onto the location."""
    out = []
    for e in exc.errors():
        loc, msg = tuple(e.get("loc", ()))[skip:], error_message(e, unknown=unknown)
        rel = _RELATIVE.match(msg) if e.get("type") == "value_error" and loc else None
        if rel:
            loc, msg = (*loc, rel.group(1)), rel.group(2)
        out.append((loc, msg))
    return out


def validation_lines(exc: HasErrors, *, unknown: str | None = None, root: str = ROOT, skip: int = 0) -> list[str]:
    """One ``path: message`` line per error (``rbnx validate`` prints these one per line)."""
    return [f"{field_path(loc, root)}: {msg}" for loc, msg in field_problems(exc, unknown=unknown, skip=skip)]


def format_validation_error(exc: HasErrors, prefix: str = "", *, unknown: str | None = None,
                            root: str = ROOT, skip: int = 0) -> str:
    """All errors on one line, ``prefix`` first: ``walls[3].thickness: must be > 0; lidar.rate_hz: ...``."""
    return prefix + "; ".join(validation_lines(exc, unknown=unknown, root=root, skip=skip))


def check_finite(value: float, message: str = "must be a finite number") -> float:
    """``value`` unchanged, or ``ValueError(message)`` for NaN and ±inf (use as a pydantic AfterValidator)."""
    if not math.isfinite(value):
        raise ValueError(message)
    return value


__all__ = ["ROOT", "HasErrors", "check_finite", "error_message", "field_path", "field_problems",
           "format_validation_error", "validation_lines"]

"""One error type for every bad input to the simulator core.

A provider turns it into ``Err(message)`` from CMD_INIT, so the message must name the field at fault.
"""

from __future__ import annotations

from pydantic import ValidationError


class SimConfigError(ValueError):
    """Bad robot description, scene, sim parameter or pose; the message names the field."""


_MESSAGES = {
    "greater_than": "must be > {gt}",
    "greater_than_equal": "must be >= {ge}",
    "less_than": "must be < {lt}",
    "less_than_equal": "must be <= {le}",
    "missing": "required field is missing",
    "extra_forbidden": "unknown field",
}


def _loc(loc: tuple) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else str(part)
    return out or "<root>"


def format_validation_error(exc: ValidationError, prefix: str = "") -> str:
    """Pydantic errors -> ``walls[3].thickness: must be > 0; ...`` (short, field-first)."""
    parts = []
    for err in exc.errors():
        template = _MESSAGES.get(err["type"])
        msg = template.format(**err.get("ctx", {})) if template else err["msg"]
        if msg.startswith("Value error, "):
            msg = msg[len("Value error, "):]
        parts.append(f"{_loc(tuple(err['loc']))}: {msg}")
    return prefix + "; ".join(parts)


def config_error(exc: ValidationError, prefix: str = "") -> SimConfigError:
    return SimConfigError(format_validation_error(exc, prefix))

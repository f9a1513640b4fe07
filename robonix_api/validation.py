"""Bad input named by its field, the same way in every provider.

CMD_INIT configs are pydantic models: :func:`field_errors` turns a ``ValidationError`` into one line,
``path: message; path: message``, for ``Err(...)``. Contract requests are protobuf messages:
:func:`require_finite` answers INVALID_ARGUMENT naming the first non-finite number field.
"""

from __future__ import annotations

import math
from typing import Any

import grpc
from pydantic import ValidationError

from robonix_api.grpc_contracts import StatusError


def field_errors(exc: ValidationError, *, unknown_key: str | None = None) -> str:
    """``a.b: message; c: message``; ``unknown_key`` replaces pydantic's text for an unexpected key."""
    parts = []
    for err in exc.errors():
        loc = ".".join(str(p) for p in err["loc"]) or "config"
        msg = err["msg"].removeprefix("Value error, ")
        if unknown_key is not None and err["type"] == "extra_forbidden":
            msg = unknown_key
        parts.append(f"{loc}: {msg}")
    return "; ".join(parts)


def require_finite(req: Any, *names: str) -> None:
    """StatusError(INVALID_ARGUMENT, "<name>: must be a finite number, got <v>") for NaN or ±inf."""
    for name in names:
        v = getattr(req, name)
        if not math.isfinite(v):
            raise StatusError(grpc.StatusCode.INVALID_ARGUMENT, f"{name}: must be a finite number, got {v}")


__all__ = ["field_errors", "require_finite"]

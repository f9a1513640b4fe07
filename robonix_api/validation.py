"""Bad input named by its field, the same way in every provider.

CMD_INIT configs are pydantic models: :func:`finite` / :data:`Seconds` are their non-NaN float fields,
:func:`field_errors` turns a ``ValidationError`` into one line,
``path: message; path: message``, for ``Err(...)``. Contract requests are protobuf messages:
:func:`require_finite` answers INVALID_ARGUMENT naming the first non-finite number field.
"""

from __future__ import annotations

import math
from typing import Annotated, Any

import grpc
from pydantic import AfterValidator, BaseModel, ConfigDict, ValidationError, create_model

from robonix_api.grpc_contracts import StatusError
from robonix_common.errors import check_finite, format_validation_error


def field_errors(exc: ValidationError, *, unknown_key: str | None = None) -> str:
    """``a.b: message; c: message``; ``unknown_key`` replaces the wording for an unexpected key.

    Kept as the SDK's name for :func:`robonix_common.errors.format_validation_error` (the one formatter).
    """
    return format_validation_error(exc, unknown=unknown_key, root="config")


def finite(message: str = "must be a finite number") -> Any:
    """A float config field type that rejects NaN and ±inf with ``message`` (pair it with ``Field(gt=…)``)."""

    def check(v: float) -> float:
        return check_finite(v, message)

    return Annotated[float, AfterValidator(check)]


#: A duration or period in seconds: finite (bounds come from ``Field``).
Seconds = finite("must be a finite number of seconds")


def per_role(name: str, roles: tuple[str, ...], value_type: Any = str, *, doc: str) -> type[BaseModel]:
    """A config block with one field per input role, default "" (unset), unknown roles rejected.

    Consumers configure their inputs per role the robonix way: ``topic_remap: {scan: /front/scan}``
    (a topic instead of an atlas lookup) and ``provider_ids: {odom: hal_1}`` (pin one provider).
    """
    fields: dict[str, Any] = {role: (value_type, "") for role in roles}
    model = create_model(name, __config__=ConfigDict(extra="forbid", frozen=True), **fields)
    model.__doc__ = doc
    return model


#: Echoed user input in an error is cut to this many characters; a whole status message to ERROR_MAX.
ECHO_MAX = 80
ERROR_MAX = 1024
#: Ids (map, run, obstacle, provider names) and free-text notes are capped at these lengths.
ID_MAX = 64
NOTE_MAX = 4096


def clip(value: Any, limit: int = ECHO_MAX) -> str:
    """``repr(value)`` cut to ``limit`` characters (plus the original length), for echoing input in errors."""
    text = repr(value)
    return text if len(text) <= limit else f"{text[:limit]}... ({len(str(value))} chars)"


def clip_message(text: str, limit: int = ERROR_MAX) -> str:
    """An error message cut to ``limit`` characters, so a status never overruns gRPC's metadata limit."""
    return text if len(text) <= limit else text[: limit - 20] + f"... ({len(text)} chars)"


def require_range(req: Any, name: str, lo: float, hi: float, unit: str = "") -> None:
    """INVALID_ARGUMENT ``name: must be within [lo, hi]`` for a finite number outside that range."""
    v = getattr(req, name)
    if not math.isfinite(v) or not lo <= v <= hi:
        raise StatusError(grpc.StatusCode.INVALID_ARGUMENT,
                          f"{name}: must be a finite number within [{lo:g}, {hi:g}]{unit}, got {v:g}")


def require_len(req: Any, name: str, limit: int = ID_MAX) -> str:
    """The string field ``name``, or INVALID_ARGUMENT when it is longer than ``limit`` characters."""
    v = getattr(req, name)
    if len(v) > limit:
        raise StatusError(grpc.StatusCode.INVALID_ARGUMENT, f"{name}: at most {limit} characters, got {len(v)}")
    return v


def require_finite(req: Any, *names: str) -> None:
    """StatusError(INVALID_ARGUMENT, "<name>: must be a finite number, got <v>") for NaN or ±inf."""
    for name in names:
        v = getattr(req, name)
        if not math.isfinite(v):
            raise StatusError(grpc.StatusCode.INVALID_ARGUMENT, f"{name}: must be a finite number, got {v}")


__all__ = ["ECHO_MAX", "ERROR_MAX", "ID_MAX", "NOTE_MAX", "Seconds", "clip", "clip_message", "field_errors", "finite",
           "per_role", "require_finite", "require_len", "require_range"]

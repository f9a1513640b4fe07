"""Validate a dict against a core dataclass and turn pydantic's errors into one ``field: message`` line.

The dataclass is the single declaration: pydantic reads its fields' types and the range/doc metadata
written with :func:`robonix_common.params.param`, and runs its ``__post_init__`` cross-field checks.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any, Literal, TypeVar

from pydantic import BaseModel, ConfigDict, Field, ValidationError, create_model

from hal_panda_mobile.sim import SimConfigError
from robonix_common.errors import format_validation_error

T = TypeVar("T")
_FIELD_KEYS = ("gt", "ge", "lt", "le", "description")   # what pydantic's Field takes of a param()'s metadata


def core_field(cls: type, name: str) -> Any:
    """A pydantic ``Field`` for a config model that reuses a core dataclass field's default, range and doc,
    so a CMD_INIT key that feeds the core is not declared a second time."""
    f = {f.name: f for f in dataclasses.fields(cls)}[name]
    return Field(f.default, **{k: v for k, v in f.metadata.items() if k in _FIELD_KEYS})


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

"""The simulator's parameters are declared once, with :func:`robonix_common.params.param` (default, range,
doc in the dataclass field). The core checks them with :func:`check_ranges` here (a :class:`SimConfigError`
naming the field); :mod:`hal_panda_mobile.files` validates YAML and CMD_INIT against the same metadata."""

from __future__ import annotations

from typing import Any

from robonix_common.params import ParamError, param
from robonix_common.params import check_ranges as _check

from .errors import SimConfigError

__all__ = ["check_ranges", "param"]


def check_ranges(obj: Any) -> None:
    """:func:`robonix_common.params.check_ranges`, raising the simulator's own error type."""
    try:
        _check(obj)
    except ParamError as exc:
        raise SimConfigError(str(exc)) from None

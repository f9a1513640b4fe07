"""One declaration per simulator parameter: default, range and doc live in the dataclass field.

``param(0.2, ge=0, doc="...")`` is a ``dataclasses.field`` whose metadata carries the range (``gt``,
``ge``, ``lt``, ``le``) and the doc (``description``). The core checks it in ``__post_init__`` with
:func:`check_ranges`, so a config built in Python is held to the same limits; the file/config layer
(:mod:`hal_panda_mobile.files`) validates YAML and CMD_INIT against the very same metadata (pydantic
reads a dataclass field's metadata as its constraints), so no range or default is written twice.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from .errors import SimConfigError

_BOUNDS = (("gt", "must be > {}", lambda v, b: v > b), ("ge", "must be >= {}", lambda v, b: v >= b),
           ("lt", "must be < {}", lambda v, b: v < b), ("le", "must be <= {}", lambda v, b: v <= b))


def param(default: Any = dataclasses.MISSING, *, doc: str, gt: float | None = None, ge: float | None = None,
          lt: float | None = None, le: float | None = None) -> Any:
    """A dataclass field with its range and doc as metadata (the names pydantic's ``Field`` uses)."""
    meta: dict[str, Any] = {"description": doc}
    meta.update({k: v for k, v in (("gt", gt), ("ge", ge), ("lt", lt), ("le", le)) if v is not None})
    return dataclasses.field(default=default, metadata=meta)


def check_ranges(obj: Any) -> None:
    """Raise :class:`SimConfigError` naming the first field outside its declared range (NaN never passes)."""
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        if not isinstance(value, int | float) or isinstance(value, bool):
            continue
        for key, message, ok in _BOUNDS:
            bound = f.metadata.get(key)
            if bound is not None and (math.isnan(value) or not ok(value, bound)):
                raise SimConfigError(f"{f.name}: {message.format(f'{bound:g}')}, got {value}")


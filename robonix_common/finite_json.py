"""Non-finite numbers in JSON that came from outside.

Python's ``json`` (and the MCP stack's parser) accepts ``NaN``, ``Infinity`` and ``1e999`` (which becomes
``inf``); forwarded on, pydantic writes them as ``null`` and protobuf reads ``null`` as 0, so ``{"x": NaN}``
turned into a goal at x = 0. Every JSON boundary (the MCP gateway, the dashboard, a Driver's
``config_json``) checks decoded values with :func:`non_finite_path` and refuses naming the field.
"""

from __future__ import annotations

import math
from typing import Any

#: Deeper structures are refused by their own depth limits first; this only bounds the walk.
MAX_DEPTH = 64


def non_finite_path(value: Any, path: str = "") -> str | None:
    """The path (``x``, ``config.a[2]``) of the first NaN/±inf float in a decoded JSON value, else None."""
    stack: list[tuple[Any, str, int]] = [(value, path, 0)]
    while stack:
        v, p, depth = stack.pop()
        if isinstance(v, float):
            if not math.isfinite(v):
                return p or "(value)"
        elif depth < MAX_DEPTH and isinstance(v, dict):
            stack.extend((item, f"{p}.{k}" if p else str(k), depth + 1) for k, item in reversed(list(v.items())))
        elif depth < MAX_DEPTH and isinstance(v, list | tuple):
            stack.extend((item, f"{p}[{i}]", depth + 1) for i, item in reversed(list(enumerate(v))))
    return None


def non_finite_message(value: Any, path: str = "") -> str | None:
    """``"<field>: must be a finite number (got nan)"`` for the first non-finite float, else None."""
    where = non_finite_path(value, path)
    if where is None:
        return None
    return f"{where}: must be a finite number (NaN, Infinity and overflowing literals such as 1e999 are refused)"


__all__ = ["non_finite_message", "non_finite_path"]

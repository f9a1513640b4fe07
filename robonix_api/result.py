"""Lifecycle handler results: ``Ok()``, ``Err(msg)``, ``Deferred(reason)`` (robonix names).

A handler says explicitly how a command went, so the Driver can answer ``ok/state/error`` exactly and
``rbnx boot`` can tell "failed" (Err) from "not yet, retry later" (Deferred).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Ok:
    """The command succeeded; the provider moves to the command's target state."""

    def __bool__(self) -> bool:
        return True


@dataclass(frozen=True)
class Err:
    """The command failed; the provider goes to ERROR and ``message`` is reported as the Driver error.

    ``message`` is robonix-api's field name; ``msg`` (this SDK's earlier name) stays as an alias, both as
    a read-only attribute and as a constructor keyword (``Err(msg="...")``).
    """

    message: str = ""

    def __init__(self, message: str = "", *, msg: str | None = None) -> None:
        object.__setattr__(self, "message", message if msg is None else msg)

    @property
    def msg(self) -> str:
        """robonix-api's name for ``message``."""
        return self.message

    def __bool__(self) -> bool:
        return False


@dataclass(frozen=True)
class Deferred:
    """Not possible yet (e.g. a required input is not registered); state unchanged, retry later."""

    reason: str = ""

    def __bool__(self) -> bool:
        return False


Result = Ok | Err | Deferred

__all__ = ["Deferred", "Err", "Ok", "Result"]

"""One module per `rbnx` command. Each owns its argparse setup and its work:

- ``register(subparsers)`` adds the command's parser (and aliases) and sets ``run`` as its default;
- ``run(args) -> int`` does the work and returns the exit code (0 ok, 1 runtime failure, 2 bad input).

:mod:`rbnx.cli` only assembles them in :data:`COMMANDS` order (the order ``rbnx --help`` lists them) and
maps errors to exit codes. Shared helpers live in :mod:`rbnx.commands.common` and
:mod:`rbnx.commands.atlas_view`.
"""

from __future__ import annotations

import importlib
from typing import Any

#: Command modules in the order `rbnx --help` lists them.
COMMANDS: tuple[str, ...] = (
    "boot", "shutdown", "build", "start", "validate", "caps", "contracts", "describe", "tools", "channels",
    "inspect", "logs", "map_card", "lifecycle", "token", "demo", "navigate", "nav_status", "cancel", "record",
    "replay", "convert_carmen", "dashboard", "init",
)


def register_all(sub: Any, only: str | None = None) -> None:
    """Add every command's parser to ``sub`` (an argparse subparsers action); with ``only`` (the command the
    command line names, e.g. ``nav-status``) just that one when it is a module of its own: a command then
    does not pay for importing all the others (``rbnx record`` starts recording ~1.5 s sooner on a busy
    machine). Aliases and unknown names register everything, so argparse lists and errors as before."""
    module = (only or "").replace("-", "_")
    for name in (module,) if module in COMMANDS else COMMANDS:
        importlib.import_module(f"rbnx.commands.{name}").register(sub)

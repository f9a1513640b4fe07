"""Check each deploy entry's ``config`` against the schema its own package declares, before anything starts.

A package says how CMD_INIT validates its config with ``configSchema: module:function`` in its package
manifest (e.g. ``hal_panda_mobile.config:parse_config``). The function is the very one the provider's
CMD_INIT calls: it takes the config dict and raises ``ValueError`` whose message names the field
(``odom_nosie: unknown key``). So ``rbnx validate`` and ``rbnx boot`` refuse a misspelt key in seconds
instead of after the provider has started and answered ``Err``. A package without ``configSchema`` (a
robonix package written elsewhere) is not checked here; its CMD_INIT still is.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any


@contextmanager
def _package_on_path(root: Path) -> Iterator[None]:
    """Let a package that is not installed be imported from its checkout (its root or the folder above)."""
    added = [str(p) for p in (root.parent, root) if str(p) not in sys.path]
    sys.path[:0] = added
    try:
        yield
    finally:
        for p in added:
            if p in sys.path:
                sys.path.remove(p)


def load_schema(spec: str, root: Path) -> Callable[[dict[str, Any]], Any]:
    """The validating function named by ``configSchema``; ImportError/AttributeError when it is missing."""
    module, _, attr = spec.partition(":")
    try:
        mod = importlib.import_module(module)
    except ModuleNotFoundError:
        with _package_on_path(root):
            mod = importlib.import_module(module)
    fn = getattr(mod, attr)
    if not callable(fn):
        raise AttributeError(f"{spec} is not callable")
    return fn


def _message_lines(exc: Exception) -> list[str]:
    """A schema error may list several fields, one per line or separated by ``; ``."""
    text = str(exc).strip() or type(exc).__name__
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    return lines or [text]


def entry_problems(spec: str | None, root: Path, config: dict[str, Any], where: str) -> tuple[list[str], list[str]]:
    """(problems, warnings) of one entry's ``config`` against its package's ``configSchema`` ``spec``;
    each line starts with ``where`` (``<file>: <kind>[i] (<name>).config``)."""
    if not spec:
        return [], []
    try:
        fn = load_schema(spec, root)
    except (ImportError, AttributeError) as exc:
        return [], [f"{where}: not checked: cannot load configSchema {spec!r} ({exc})"]
    try:
        fn(dict(config))
    except ValueError as exc:
        return [f"{where}.{line}" for line in _message_lines(exc)], []
    except Exception as exc:  # a schema bug must not hide behind a traceback; CMD_INIT will say more
        return [], [f"{where}: not checked: {spec} raised {type(exc).__name__}: {exc}"]
    return [], []

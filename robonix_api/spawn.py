"""robonix-api's ``robonix_api.spawn``: ``SpawnRegistry``, children in their own process groups.

The work is done by :class:`robonix_api.procs.ProcessGroups` (also behind ``Primitive.spawn``); this
module gives it robonix-api's names and keywords: ``spawn(argv, *, env, log_path, cwd)`` adds ``env``
to this process's environment and sends output to ``log_path`` (else discards it), and
``shutdown_all(term_grace_s)`` TERMs every group, waits, then KILLs what is left.
"""

from __future__ import annotations

import os
import subprocess
from collections.abc import Sequence
from pathlib import Path
from typing import IO, Any

from robonix_api.procs import ProcessGroups


def open_log(log: str | os.PathLike[str] | None, pkg_root: Path | None) -> IO[bytes] | None:
    """Append-mode file for a child's output: a bare name under ``<pkg_root>/rbnx-build/data/`` (the
    current directory without a package root), a path as given; None for no log."""
    if log is None:
        return None
    path = Path(log)
    if not isinstance(log, Path) and len(path.parts) == 1:
        path = (pkg_root or Path.cwd()) / "rbnx-build" / "data" / path
    path.parent.mkdir(parents=True, exist_ok=True)
    return open(path, "ab", buffering=0)


class SpawnRegistry:
    """Every process spawned through it, torn down together by :meth:`shutdown_all`."""

    def __init__(self) -> None:
        self._groups = ProcessGroups()

    def spawn(self, argv: Sequence[str], *, env: dict[str, str] | None = None, log_path: Path | None = None,
              cwd: Path | None = None) -> subprocess.Popen[Any]:
        """Start ``argv`` in its own process group with ``env`` added to ours, output to ``log_path``."""
        merged = dict(os.environ)
        if env:
            merged.update({k: str(v) for k, v in env.items()})
        out: Any = subprocess.DEVNULL
        fh = None
        if log_path is not None:
            Path(log_path).parent.mkdir(parents=True, exist_ok=True)
            fh = out = open(log_path, "ab", buffering=0)  # noqa: SIM115
        try:
            return self._groups.spawn(list(argv), env=merged, cwd=str(cwd) if cwd else None, stdout=out, stderr=out)
        finally:
            if fh is not None:
                fh.close()

    @property
    def processes(self) -> list[subprocess.Popen[Any]]:
        """The children started and not yet shut down."""
        return self._groups.processes

    def shutdown_all(self, term_grace_s: float = 5.0) -> None:
        """Stop every child's group: SIGTERM, ``term_grace_s`` to exit, then SIGKILL."""
        self._groups.kill_all(grace_s=term_grace_s)


__all__ = ["SpawnRegistry", "open_log"]

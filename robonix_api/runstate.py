"""Crash-continuity state of one provider instance in one deployment.

``rbnx boot`` hands every package ``RBNX_RUN_DIR`` (one folder per running deployment: deploy name + atlas
address) and, on a restart after a crash, ``RBNX_RESTARTS=<n>``. A provider that must go on where its dead
predecessor stopped (the simulator's clock and robot, SLAM's map→odom, navigation's goal) keeps a small
file there, keyed by its instance id, and reads it back only when it is a restart. Why the run dir and not
a shared folder: two deployments on one machine each have their own, so one can never resume the other's
state (issue 37 item 2: two mapping services both named ``mapping`` shared one crash copy).
"""

from __future__ import annotations

import json
import logging
import os
import re
from pathlib import Path
from typing import Any

log = logging.getLogger("robonix_api.runstate")
_UNSAFE = re.compile(r"[^A-Za-z0-9_.-]+")


def restarts() -> int:
    """How often ``rbnx boot`` restarted this process (``RBNX_RESTARTS``; 0 on a first start)."""
    try:
        return max(0, int(os.environ.get("RBNX_RESTARTS", "0") or 0))
    except ValueError:
        return 0


def safe_name(text: str) -> str:
    """``text`` as one file-name component: anything outside [A-Za-z0-9_.-] becomes '_', never '.'/'..'."""
    return _UNSAFE.sub("_", text).strip("_.-") or "x"


def run_dir() -> Path | None:
    """This deployment's run dir (``RBNX_RUN_DIR``), or None when not started by ``rbnx boot``."""
    d = os.environ.get("RBNX_RUN_DIR", "").strip()
    return Path(d) if d else None


def deployment_key() -> str:
    """A file-name-safe id of the running deployment (the run dir's name: deploy name + atlas address);
    "" when not under ``rbnx boot``."""
    d = run_dir()
    return safe_name(d.name) if d is not None else ""


class StateFile:
    """One JSON document ``<run dir>/<instance>-<kind>.json``, written atomically (temp + rename, so a
    SIGKILL mid-write leaves the previous version); a no-op without a run dir."""

    def __init__(self, path: Path | None) -> None:
        self.path = path
        self._warned = False

    @classmethod
    def for_instance(cls, instance_id: str, kind: str) -> StateFile:
        """``<run dir>/<instance>-<kind>.json`` (both parts sanitised); path None outside ``rbnx boot``."""
        d = run_dir()
        return cls(d / f"{safe_name(instance_id)}-{safe_name(kind)}.json" if d is not None else None)

    def write(self, doc: dict[str, Any]) -> None:
        """Replace the document (best effort: a failure is logged once, never raised)."""
        if self.path is None:
            return
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            tmp = self.path.with_name(f".{self.path.name}.tmp{os.getpid()}")
            tmp.write_text(json.dumps(doc))
            os.replace(tmp, self.path)
        except OSError as exc:  # continuity is best effort: never fail the provider over it
            if not self._warned:
                self._warned = True
                log.warning("cannot write %s: %s", self.path, exc)

    def read(self) -> dict[str, Any] | None:
        """The document, or None when there is none or it is unreadable (logged)."""
        if self.path is None or not self.path.is_file():
            return None
        try:
            doc = json.loads(self.path.read_text())
        except (OSError, ValueError) as exc:
            log.warning("ignoring unreadable %s: %s", self.path, exc)
            return None
        return doc if isinstance(doc, dict) else None

    def discard(self) -> None:
        """Remove the document (a fresh start or a clean end: nothing to resume)."""
        if self.path is not None:
            try:
                self.path.unlink(missing_ok=True)
            except OSError as exc:
                log.warning("cannot remove %s: %s", self.path, exc)

"""The boot state file: lets `rbnx shutdown -f deploy.yaml` find the booting rbnx and its children.

One file per deploy path under $RBNX_STATE_DIR, else $XDG_RUNTIME_DIR/rbnx, else /tmp/rbnx-<uid>; a copy
lives in the log directory for post-mortems. PIDs are stored with their /proc start time so a reused
PID is never signalled.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path
from typing import Any


def state_dir() -> Path:
    if os.environ.get("RBNX_STATE_DIR"):
        return Path(os.environ["RBNX_STATE_DIR"])
    if os.environ.get("XDG_RUNTIME_DIR"):
        return Path(os.environ["XDG_RUNTIME_DIR"]) / "rbnx"
    return Path(tempfile.gettempdir()) / f"rbnx-{os.getuid()}"


def state_path(deploy_path: Path) -> Path:
    digest = hashlib.sha1(str(Path(deploy_path).resolve()).encode()).hexdigest()[:12]
    return state_dir() / f"boot-{Path(deploy_path).stem}-{digest}.json"


def write_state(path: Path, data: dict[str, Any], copy_to: Path | None = None) -> None:
    """Atomic write (tmp + rename) so a reader never sees half a file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    text = json.dumps(data, indent=2)
    tmp = path.with_suffix(f".tmp{os.getpid()}")
    tmp.write_text(text)
    os.replace(tmp, path)
    if copy_to is not None:
        try:
            copy_to.write_text(text)
        except OSError:
            pass


def read_state(path: Path) -> dict[str, Any] | None:
    try:
        return json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        return None


def remove_state(path: Path) -> None:
    try:
        path.unlink()
    except FileNotFoundError:
        pass

"""Shared helpers for rbnx tests: run the real CLI, read the state file, check PIDs through /proc."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from support.procs import alive  # noqa: F401  (re-exported for the rbnx tests)

REPO = Path(__file__).resolve().parents[3]
MINIMAL = REPO / "examples" / "minimal"


def rbnx_cmd() -> list[str]:
    exe = Path(sys.executable).parent / "rbnx"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "rbnx.cli"]


def make_env(tmp: Path, **extra: str) -> dict[str, str]:
    """Isolated state dir, fast heartbeats, loopback-only atlas on a port of the OS's choosing."""
    env = dict(os.environ)
    env.update(RBNX_STATE_DIR=str(tmp / "state"), RBNX_ATLAS_LISTEN="127.0.0.1:0",
               ROBONIX_HEARTBEAT_PERIOD_S="1", PYTHONUNBUFFERED="1")
    env.pop("ROBONIX_ATLAS", None)
    env.update(extra)
    return env


def copy_minimal(tmp: Path) -> Path:
    dst = tmp / "minimal"
    shutil.copytree(MINIMAL, dst, ignore=shutil.ignore_patterns("__pycache__", ".rbnx-built"))
    return dst


def run(args: list[str], env: dict[str, str], cwd: Path, timeout: float = 120.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run(rbnx_cmd() + args, env=env, cwd=cwd, capture_output=True, text=True, timeout=timeout)


def group_alive(pgid: int) -> list[int]:
    out = []
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            stat = Path(f"/proc/{name}/stat").read_text()
        except OSError:
            continue
        fields = stat[stat.rfind(")") + 2:].split()
        if fields[0] not in "ZX" and int(fields[2]) == pgid:
            out.append(int(name))
    return out

"""Helpers for the end-to-end tests: the real `rbnx` CLI as a subprocess, PIDs checked through /proc."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

from support.procs import wait_until  # noqa: F401  (re-exported for the e2e tests)

REPO = Path(__file__).resolve().parents[2]
SIM_DEPLOY = REPO / "examples" / "sim" / "deploy.yaml"


def rbnx_cmd() -> list[str]:
    exe = Path(sys.executable).parent / "rbnx"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "rbnx.cli"]


def e2e_env(tmp: Path, **extra: str) -> dict[str, str]:
    """Isolated state dir, an atlas port of the OS's choosing, a DDS domain no other test run uses."""
    from rbnx.demo_boot import pick_domain_id

    env = dict(os.environ, RBNX_STATE_DIR=str(tmp / "state"), RBNX_ATLAS_LISTEN="127.0.0.1:0",
               PYTHONUNBUFFERED="1", ROS_DOMAIN_ID=str(pick_domain_id()))
    for name in ("ROBONIX_ATLAS", "RBNX_INSTANCE_NAME", "RBNX_DEPLOY_MANAGED"):
        env.pop(name, None)
    env.update(extra)
    return env





def _stat(pid: int) -> list[str] | None:
    try:
        data = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return data[data.rfind(")") + 2:].split()


def alive(pid: int, start_ticks: int | None = None) -> bool:
    """Running, not a zombie, and (when given) the same process as recorded — a reused PID is not ours."""
    f = _stat(pid)
    if not f or f[0] in "ZX":
        return False
    return start_ticks is None or int(f[19]) == int(start_ticks)


def recorded_pids(state_file: Path) -> list[tuple[str, int, int | None]]:
    """Every process a boot recorded: itself, the atlas, each entry (and its extra PIDs)."""
    st = json.loads(state_file.read_text())
    out = [("rbnx boot", int(st["pid"]), st.get("start_ticks"))]
    if st.get("atlas_proc"):
        out.append(("atlas", int(st["atlas_proc"]["pid"]), st["atlas_proc"].get("start_ticks")))
    for c in st.get("children") or []:
        out.append((c["name"], int(c["pid"]), c.get("start_ticks")))
        out.extend((c["name"], int(p), t) for p, t in c.get("extra_pids") or [])
    return out

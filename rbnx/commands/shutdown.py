"""`rbnx shutdown`: stop a running boot of a deploy file (ask the boot; else stop what its state file lists)."""

from __future__ import annotations

import argparse
import os
import signal
import sys
import time
from pathlib import Path
from typing import Any

from rbnx.atlas_rpc import CMD, Atlas, AtlasError, Driver, driver_capability
from rbnx.boot.deployment import StateNotFound, locate_state
from rbnx.boot.procs import pid_alive, run_hook, stop_recorded
from rbnx.boot.statefile import read_state, remove_state
from rbnx.commands.common import boot_alive, deploy_arg
from rbnx.models import DEFAULT_DEPLOY, ManifestProblems, load_package


def register(sub: Any) -> None:
    """``shutdown -f DEPLOY``."""
    s = sub.add_parser("shutdown", help="stop a running boot of a deploy file")
    deploy_arg(s)
    s.add_argument("--timeout", type=float, default=180.0, help="how long to wait for the boot to finish")
    s.add_argument("--term-timeout", type=float, default=30.0)
    s.set_defaults(run=run)


def _driver_shutdown(atlas_addr: str | None, name: str) -> None:
    """Best effort CMD_SHUTDOWN for a provider rbnx no longer supervises."""
    if not atlas_addr:
        return
    try:
        with Atlas(atlas_addr, timeout=2.0) as atlas:
            prov = atlas.provider(name)
            cid = driver_capability(prov) if prov else None
            if cid is None:
                return
            endpoint, params = atlas.endpoint(name, cid, 1)
        d = Driver(endpoint, params)
        d.call(CMD.CMD_SHUTDOWN, None, 5.0)
        d.close()
    except AtlasError:
        pass


def _shutdown_orphans(st: dict[str, Any], term_timeout: float) -> None:
    """The boot process is gone (e.g. --exit-after-boot): run the shutdown ladder from the state file."""
    children = list(reversed(st.get("children", [])))
    # Dependents first: reverse of the order entries became ready; never-ready ones before all.
    children.sort(key=lambda c: -(c.get("ready_at") or float("inf")))
    for child in children:
        name = child["name"]
        extra = [tuple(x) for x in child.get("extra_pids", [])]
        if pid_alive(child["pid"], child.get("start_ticks")):
            _driver_shutdown(st.get("atlas"), name)
            deadline = time.monotonic() + 3.0
            while pid_alive(child["pid"], child.get("start_ticks")) and time.monotonic() < deadline:
                time.sleep(0.05)
        try:
            root, pm = load_package(Path(child["manifest"]))
            if pm.stop and pm.stop.strip():
                env = dict(os.environ, RBNX_INSTANCE_NAME=name, RBNX_DEPLOY_MANAGED="1",
                           ROBONIX_ATLAS=st.get("atlas") or "", RBNX_PACKAGE_ROOT=str(root))
                env.update({"RBNX_RUN_DIR": child["run_dir"]} if child.get("run_dir") else {})
                run_hook(f"{name}-stop", pm.stop, root, env, Path(child["log"]), 20.0)
        except (ManifestProblems, KeyError, OSError):
            pass
        how = stop_recorded(child["pid"], child["pgid"], child.get("start_ticks"), extra, term_timeout)
        print(f"{name}: {how}")
    ap = st.get("atlas_proc")
    if ap:
        how = stop_recorded(ap["pid"], ap["pgid"], ap.get("start_ticks"), [], min(term_timeout, 10.0))
        print(f"atlas: {how}")


def run(args: argparse.Namespace) -> int:
    """Ask the running boot to shut down; when it is gone, stop what its state file lists, dependents first."""
    path = Path(args.file or DEFAULT_DEPLOY)
    try:
        spath = locate_state(path, getattr(args, "atlas", None))
    except StateNotFound as exc:
        print(f"rbnx shutdown: {exc}", file=sys.stderr)
        return 1
    st = read_state(spath)
    if st is None:
        print(f"rbnx shutdown: no running boot recorded for {path} ({spath})", file=sys.stderr)
        return 1
    if boot_alive(st):
        pid = int(st["pid"])
        print(f"asking rbnx boot (pid {pid}) to shut down…", flush=True)
        os.kill(pid, signal.SIGTERM)
        deadline = time.monotonic() + args.timeout
        while pid_alive(pid, st.get("start_ticks")):
            if time.monotonic() >= deadline:
                print(f"rbnx shutdown: boot pid {pid} still running after {args.timeout:g}s; "
                      "stopping its children directly", file=sys.stderr)
                os.kill(pid, signal.SIGKILL)
                break
            time.sleep(0.1)
        else:
            print("shut down")
            return 0
    _shutdown_orphans(st, args.term_timeout)
    remove_state(spath)
    return 0

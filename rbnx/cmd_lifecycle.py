"""`rbnx boot` / `start` / `shutdown` / `logs`: the commands that run or stop packages."""

from __future__ import annotations

import argparse
import os
import signal
import sys
import time
from pathlib import Path
from typing import Any

import yaml

from rbnx.atlas_rpc import CMD, Atlas, AtlasError, Driver, driver_capability
from rbnx.boot import BootOptions, Orchestrator, _Signals, run_boot
from rbnx.deployment import StateNotFound, locate_state
from rbnx.models import (
    DEFAULT_DEPLOY,
    ManifestProblems,
    ResolvedEntry,
    load_package,
    manifest_file,
    read_yaml,
)
from rbnx.procs import pid_alive, run_hook, stop_recorded, tail
from rbnx.runner import Timing
from rbnx.statefile import read_state, remove_state, state_path


def default_log_dir() -> Path:
    return Path("rbnx-logs") / time.strftime("%Y%m%d-%H%M%S")


def _boot_alive(st: dict[str, Any]) -> bool:
    return bool(st.get("pid")) and pid_alive(int(st["pid"]), st.get("start_ticks"))


def _recorded_alive(st: dict[str, Any]) -> bool:
    procs = [*(st.get("children") or []), *([st["atlas_proc"]] if st.get("atlas_proc") else [])]
    return any(p.get("pid") and pid_alive(int(p["pid"]), p.get("start_ticks")) for p in procs)


def cmd_boot(args: argparse.Namespace) -> int:
    from rbnx.models import load_deploy

    path = Path(args.file or DEFAULT_DEPLOY)
    deploy = load_deploy(path)  # ManifestProblems -> exit 2 in cli.main, nothing started
    for w in deploy.warnings:
        print(f"warning: {w}", file=sys.stderr)
    st = read_state(state_path(deploy.path, deploy.atlas_listen))
    if st and (_boot_alive(st) or _recorded_alive(st)):
        who = f"rbnx pid {st['pid']}" if _boot_alive(st) else "a previous boot (its processes still run)"
        print(f"rbnx boot: {path} is already booted by {who}, atlas {st.get('atlas')}; "
              f"run `rbnx shutdown -f {path}` first", file=sys.stderr)
        return 1
    opts = BootOptions(log_dir=Path(args.log_dir) if args.log_dir else default_log_dir(),
                       boot_timeout=args.boot_timeout, term_timeout=args.term_timeout,
                       progress=not args.no_progress, verbose=args.verbose, exit_after_boot=args.exit_after_boot,
                       gateway=not getattr(args, "no_gateway", False),
                       parallel=not getattr(args, "serial", False))
    if getattr(args, "dashboard", None) is None:
        return run_boot(deploy, opts)
    from rbnx.dashboard.cli import atlas_of_deploy, check_port, start_background

    if check_port(args.dashboard):
        print(f"rbnx boot: {check_port(args.dashboard)}", file=sys.stderr)
        return 2
    try:  # the atlas address comes from the boot's state file once the atlas is up
        dash = start_background(atlas_of_deploy(deploy.path), args.dashboard)
    except OSError as exc:
        print(f"rbnx boot: dashboard: {exc}", file=sys.stderr)
        return 1
    print(f"dashboard at {dash.url}", flush=True)
    try:
        return run_boot(deploy, opts)
    finally:
        dash.stop()


# ------------------------------------------------------------------------------ shutdown


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


def cmd_shutdown(args: argparse.Namespace) -> int:
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
    if _boot_alive(st):
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


def cmd_logs(args: argparse.Namespace) -> int:
    path = Path(args.file or DEFAULT_DEPLOY)
    try:
        st = read_state(locate_state(path, getattr(args, "atlas", None)))
    except StateNotFound as exc:
        print(f"rbnx logs: {exc}", file=sys.stderr)
        return 1
    if st is None:
        print(f"rbnx logs: no running boot recorded for {path}", file=sys.stderr)
        return 1
    log_dir = Path(st["log_dir"])
    names = [args.name] if args.name else ["atlas", *(c["name"] for c in st.get("children", []))]
    for n in names:
        p = log_dir / f"{n}.log"
        print(f"==> {p} <==")
        for line in tail(p, args.lines):
            print(line)
    return 0


# ------------------------------------------------------------------------------ start


def _parse_sets(items: list[str], config: dict[str, Any]) -> None:
    """`-s a.b=3` sets config['a']['b'] = 3 (values parsed as YAML scalars)."""
    for item in items:
        key, sep, raw = item.partition("=")
        if not sep or not key:
            raise ManifestProblems([f"--set {item!r}: expected KEY=VALUE"])
        try:
            value = yaml.safe_load(raw) if raw else ""
        except yaml.YAMLError:
            value = raw
        node = config
        parts = key.split(".")
        for part in parts[:-1]:
            nxt = node.get(part)
            if not isinstance(nxt, dict):
                nxt = node[part] = {}
            node = nxt
        node[parts[-1]] = value


def cmd_start(args: argparse.Namespace) -> int:
    root, pm = load_package(Path(args.package), args.manifest)
    config: dict[str, Any] = {}
    if args.config:
        data = read_yaml(Path(args.config))
        if data is not None and not isinstance(data, dict):
            raise ManifestProblems([f"{args.config}: config must be a mapping"])
        config = dict(data or {})
    _parse_sets(args.set or [], config)
    atlas_addr = args.endpoint or args.atlas
    with Atlas(atlas_addr) as atlas:
        if not atlas.ping(2.0):
            print(f"rbnx start: atlas not reachable at {atlas_addr}", file=sys.stderr)
            return 1
    name = args.name or pm.package.name
    mpath = manifest_file(root, args.manifest) if Path(args.package).is_dir() else Path(args.package).resolve()
    entry = ResolvedEntry(name, args.kind, 0, root, mpath, pm, config)
    log_dir = Path(args.log_dir) if args.log_dir else default_log_dir()
    log_dir.mkdir(parents=True, exist_ok=True)
    opts = BootOptions(log_dir=log_dir, boot_timeout=args.boot_timeout, term_timeout=args.term_timeout,
                       progress=not args.no_progress, timing=Timing())
    sig = _Signals()
    sig.install()
    orch = Orchestrator([entry], dict(os.environ), atlas_addr, opts, sig.stop)
    try:
        ok = orch.boot(deadline=time.monotonic() + args.boot_timeout)
        r = orch.runners[0]
        if not ok:
            print(f"rbnx start: {name}: {r.failure or r.state} (log {r.log_path})", file=sys.stderr)
            for line in r.log_tail[-8:]:
                print(f"    | {line}", file=sys.stderr)
            return 1
        if sig.stop.is_set():
            return 130
        print(f"{name} is {r.state} (pid {r.proc.pid if r.proc else '-'}, log {r.log_path}); Ctrl-C to stop",
              flush=True)
        while not sig.stop.wait(0.5):
            if r.proc is not None and not r.proc.running():
                print(f"rbnx start: {name} exited with code {r.proc.popen.returncode}", file=sys.stderr)
                return 1
        return 0
    finally:
        orch.shutdown(opts.term_timeout)
        sig.restore()

"""`rbnx boot` (alias `rbnx deploy`): start the atlas and every package of a deploy file, serve until Ctrl-C."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from rbnx.boot.orchestrator import BootOptions, run_boot
from rbnx.boot.statefile import read_state, state_path
from rbnx.commands.common import boot_alive, default_log_dir, deploy_arg, recorded_alive
from rbnx.models import DEFAULT_DEPLOY


def register(sub: Any) -> None:
    """``boot`` and its alias ``deploy``."""
    for name in ("boot", "deploy"):
        b = sub.add_parser(name, help="start atlas and every package of a deploy file" if name == "boot"
                           else "alias of boot")
        deploy_arg(b)
        b.add_argument("--log-dir", help="where <name>.log files go (default ./rbnx-logs/<timestamp>)")
        b.add_argument("-v", "--verbose", action="store_true")
        b.add_argument("--boot-timeout", type=float, default=120.0,
                       help="deadline in seconds for Deferred entries to come up (default 120)")
        b.add_argument("--term-timeout", type=float, default=30.0,
                       help="seconds between SIGTERM and SIGKILL at shutdown (default 30)")
        b.add_argument("--no-progress", action="store_true", help="no live progress view")
        b.add_argument("--exit-after-boot", action="store_true",
                       help="return after boot, leaving packages running (stop with rbnx shutdown)")
        b.add_argument("--no-gateway", action="store_true", help="do not serve the deployment's MCP gateway")
        b.add_argument("--dashboard", type=int, nargs="?", const=8765, metavar="PORT",
                       help="also serve the live dashboard on 127.0.0.1:PORT (default 8765)")
        b.add_argument("--foxglove", type=int, nargs="?", const=8766, metavar="PORT",
                       help="also serve every DDS topic to Foxglove on ws://127.0.0.1:PORT (default 8766)")
        b.add_argument("--serial", action="store_true",
                       help="start entries one at a time instead of all at once")
        b.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """:func:`_run`, with the live Foxglove bridge (``--foxglove``) serving around it."""
    from rbnx.foxglove_live import start_for_cli

    bridge, rc = start_for_cli(getattr(args, "foxglove", None), "rbnx boot")
    if rc:
        return rc
    try:
        return _run(args)
    finally:
        if bridge is not None:
            bridge.stop()


def _run(args: argparse.Namespace) -> int:
    """Validate the deploy file (exit 2, nothing started), refuse a second boot of it (exit 1), then boot and serve."""
    from rbnx.models import load_deploy

    path = Path(args.file or DEFAULT_DEPLOY)
    # ManifestProblems (each entry's config too, against its package's own schema) -> exit 2, nothing started
    deploy = load_deploy(path, check_configs=True)
    for w in deploy.warnings:
        print(f"warning: {w}", file=sys.stderr)
    st = read_state(state_path(deploy.path, deploy.atlas_listen))
    if st and (boot_alive(st) or recorded_alive(st)):
        who = f"rbnx pid {st['pid']}" if boot_alive(st) else "a previous boot (its processes still run)"
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
    from rbnx.dashboard.launch import atlas_of_deploy, check_port, start_background

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

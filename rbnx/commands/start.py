"""`rbnx start`: start one package against an atlas that is already running, and serve until Ctrl-C."""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import Any

from rbnx.atlas_rpc import Atlas
from rbnx.boot.entry import Timing
from rbnx.boot.orchestrator import BootOptions, Orchestrator, _Signals
from rbnx.commands.common import default_log_dir, parse_sets
from rbnx.models import ENTRY_NAME_RE, ManifestProblems, ResolvedEntry, load_package, manifest_file, read_yaml


def register(sub: Any) -> None:
    """``start -p PACKAGE`` with its config options."""
    st = sub.add_parser("start", help="start one package against a running atlas")
    st.add_argument("-p", "--package", required=True, help="package directory or manifest file")
    st.add_argument("--endpoint", help="atlas address (default --atlas)")
    st.add_argument("-c", "--config", help="YAML file with the config passed to CMD_INIT")
    st.add_argument("-s", "--set", action="append", metavar="KEY=VALUE", help="config override (repeatable)")
    st.add_argument("-m", "--manifest", help="target: package_manifest.<target>.yaml")
    st.add_argument("--name", help="instance name (default: package name)")
    st.add_argument("--kind", choices=("primitive", "service", "skill"), default="service")
    st.add_argument("--log-dir")
    st.add_argument("--boot-timeout", type=float, default=120.0)
    st.add_argument("--term-timeout", type=float, default=30.0)
    st.add_argument("--no-progress", action="store_true")
    st.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Start one package against a running atlas, bring it to ACTIVE and keep it until Ctrl-C or it exits."""
    root, pm = load_package(Path(args.package), args.manifest)
    config: dict[str, Any] = {}
    if args.config:
        data = read_yaml(Path(args.config))
        if data is not None and not isinstance(data, dict):
            raise ManifestProblems([f"{args.config}: config must be a mapping"])
        config = dict(data or {})
    parse_sets(args.set or [], config)
    name = args.name or pm.package.name
    if not ENTRY_NAME_RE.fullmatch(name):  # the name becomes <log-dir>/<name>.log and the provider id
        raise ManifestProblems([f"--name: {name[:80]!r} is not a valid instance name (letters, digits, '_', '.', "
                                "'-' (not first), at most 64 characters)"])
    atlas_addr = args.endpoint or args.atlas
    with Atlas(atlas_addr) as atlas:
        if not atlas.ping(2.0):
            print(f"rbnx start: atlas not reachable at {atlas_addr}", file=sys.stderr)
            return 1
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

"""`rbnx build`: run each package's `build:` in its root and stamp it `.rbnx-built`."""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import Any

from rbnx.boot.procs import run_hook
from rbnx.models import DEFAULT_DEPLOY, PackageManifest, load_deploy, load_package

STAMP = ".rbnx-built"


def register(sub: Any) -> None:
    """``build -f DEPLOY`` or ``build -p PACKAGE``."""
    bl = sub.add_parser("build", help="run packages' build: steps")
    g = bl.add_mutually_exclusive_group()
    g.add_argument("-f", "--file", help=f"deploy file (default {DEFAULT_DEPLOY})")
    g.add_argument("-p", "--package", action="append", help="package directory (repeatable)")
    bl.add_argument("-m", "--manifest", help="target: package_manifest.<target>.yaml (with -p)")
    bl.add_argument("--clean", action="store_true", help="set RBNX_BUILD_CLEAN=1")
    bl.add_argument("--timeout", type=float, default=3600.0)
    bl.set_defaults(run=run)


def build_one(root: Path, pm: PackageManifest, env: dict[str, str], clean: bool, timeout: float) -> tuple[bool, str]:
    """Run the build hook; the stamp records when and what was built (robonix tools look for it)."""
    script = (pm.build or "").strip()
    env = dict(env, RBNX_PACKAGE_ROOT=str(root))
    if clean:
        env["RBNX_BUILD_CLEAN"] = "1"
    if script:
        ok, how = run_hook(f"{pm.package.name}-build", script, root, env, None, timeout)
        if not ok:
            return False, how
        result = "built"
    else:
        result = "nothing to build"
    try:
        (root / STAMP).write_text(f"{pm.package.name} {pm.package.version} {time.strftime('%Y-%m-%dT%H:%M:%S')}\n")
    except OSError as exc:
        return False, f"cannot write {STAMP}: {exc}"
    return True, result


def run(args: argparse.Namespace) -> int:
    """Run the ``build:`` step of each package (of ``-p`` dirs or of a deploy file); exit 1 when any failed."""
    jobs: list[tuple[Path, PackageManifest, dict[str, str]]] = []
    if args.package:
        for p in args.package:
            root, pm = load_package(Path(p), args.manifest)
            jobs.append((root, pm, dict(os.environ)))
    else:
        dep = load_deploy(Path(args.file or DEFAULT_DEPLOY))
        seen: set[Path] = set()
        for e in dep.entries:
            if e.manifest_path not in seen:
                seen.add(e.manifest_path)
                jobs.append((e.root, e.manifest, dep.env))
    rows = []
    failed = 0
    for root, pm, env in jobs:
        print(f"==> building {pm.package.name} in {root}", flush=True)
        t0 = time.monotonic()
        ok, how = build_one(root, pm, env, args.clean, args.timeout)
        failed += not ok
        rows.append((pm.package.name, "ok" if ok else "FAILED", how, f"{time.monotonic() - t0:.1f}s", str(root)))
    w = max([7, *(len(r[0]) for r in rows)])
    print(f"\n{'PACKAGE':<{w}}  RESULT  {'DETAIL':<18}  {'TIME':>7}  ROOT")
    for name, res, how, t, root in rows:
        print(f"{name:<{w}}  {res:<6}  {how:<18}  {t:>7}  {root}")
    if failed:
        print(f"{failed} of {len(rows)} builds failed", file=sys.stderr)
        return 1
    return 0

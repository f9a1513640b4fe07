"""`rbnx validate [PATH ...]`: deploy files and package manifests, kind auto-detected."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from rbnx.models import (
    DEFAULT_DEPLOY,
    PACKAGE_MANIFEST,
    ManifestProblems,
    detect_kind,
    load_deploy,
    load_package,
    parse_package,
    read_yaml,
)


def register(sub: Any) -> None:
    """``validate [PATH ...] [-f FILE ...]``."""
    v = sub.add_parser("validate", help="check deploy files (each entry's config too) and package manifests")
    v.add_argument("paths", nargs="*", help=f"files or package dirs (default {DEFAULT_DEPLOY})")
    v.add_argument("-f", "--file", action="append", default=[], dest="files", metavar="FILE",
                   help="deploy file, as for the other commands (repeatable; same as a positional path)")
    v.set_defaults(run=run)


def validate_path(path: Path) -> tuple[list[str], str]:
    """Problems (one line each) and a short OK description for one file or package directory."""
    label = str(path)
    try:
        if path.is_dir():
            root, pm = load_package(path)
            return [], f"package {pm.package.name!r} ({root / PACKAGE_MANIFEST})"
        data = read_yaml(path, label)
        kind = detect_kind(data)
        if kind == "package":
            pm = parse_package(data, label)
            return [], f"package {pm.package.name!r}"
        if kind == "deploy":
            dep = load_deploy(path, label=label, check_configs=True)
            for w in dep.warnings:
                print(f"warning: {w}", file=sys.stderr)
            return [], f"deploy {dep.name!r} with {len(dep.entries)} entries (all packages and configs valid)"
        if data is None:
            return [f"{label}: empty file"], ""
        return [f"{label}: neither a deploy file (primitive/service/skill/system keys) "
                "nor a package manifest (package/start keys)"], ""
    except ManifestProblems as mp:
        return mp.lines, ""


def run(args: argparse.Namespace) -> int:
    """Check each deploy file or package manifest; print one line per problem and exit 2 when there are any."""
    paths = [Path(p) for p in [*args.paths, *getattr(args, "files", [])]]
    if not paths:
        default = Path(DEFAULT_DEPLOY)
        paths = [default if default.exists() else Path(PACKAGE_MANIFEST)]
    problems = 0
    for p in paths:
        lines, ok = validate_path(p)
        for line in lines:
            print(line)
        problems += len(lines)
        if not lines:
            print(f"{p}: ok — {ok}")
    if problems:
        print(f"{problems} problem{'s' if problems != 1 else ''} found", file=sys.stderr)
        return 2
    return 0

"""`rbnx init DIR`: write the shipped example deploys (sim, real_robot, minimal) for a user to edit.

An installed robonix-nav keeps its examples inside site-packages; this copies them out, pointing their
package paths at the installed packages, so `rbnx boot -f DIR/sim/deploy.yaml` works from anywhere.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from robonix_nav_data import resources


def register(sub: Any) -> None:
    """``init [DIR] [--example NAME]``."""
    p = sub.add_parser("init", help="write the example deploy files into DIR to edit (sim, real_robot, minimal)")
    p.add_argument("dir", nargs="?", default="robonix-examples", help="target directory (default ./robonix-examples)")
    p.add_argument("--example", action="append", choices=resources.EXAMPLES,
                   help="only this example (repeatable; default all)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Copy the example deploys into DIR; exit 2 when DIR is a file or an example is already there."""
    dest = Path(args.dir)
    if dest.exists() and not dest.is_dir():
        print(f"rbnx init: {dest} exists and is not a directory", file=sys.stderr)
        return 2
    names = tuple(args.example or resources.EXAMPLES)
    try:
        dest.mkdir(parents=True, exist_ok=True)
        written = resources.copy_examples(dest, names)
    except (FileExistsError, resources.ResourceError) as exc:
        print(f"rbnx init: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"rbnx init: cannot write {dest}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    for deploy in written:
        print(f"wrote {deploy}")
    print(f"next: rbnx boot -f {written[0]}")
    return 0

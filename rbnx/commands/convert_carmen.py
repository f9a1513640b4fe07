"""`rbnx convert-carmen`: a CARMEN .clf laser log as a rosbag2 (see :mod:`rbnx.carmen_bag`)."""

from __future__ import annotations

import argparse
import sys
from typing import Any


def register(sub: Any) -> None:
    r = sub.add_parser("convert-carmen", help="convert a CARMEN .clf(.bz2) laser log to a rosbag2 directory "
                       "(/scan /odom /tf /tf_static) for rbnx replay")
    r.add_argument("log", help="CARMEN log: .clf, .clf.bz2 or .clf.gz")
    r.add_argument("output", help="rosbag2 directory to create")
    r.add_argument("--max-scans", type=int, help="only the first N laser scans")
    r.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from rbnx.carmen_bag import ConvertError, convert_carmen
    from robonix_eval.carmen import CarmenError

    if args.max_scans is not None and args.max_scans < 1:
        print(f"rbnx convert-carmen: --max-scans must be >= 1, got {args.max_scans}", file=sys.stderr)
        return 2
    try:
        n = convert_carmen(args.log, args.output, args.max_scans)
    except (ConvertError, CarmenError) as exc:
        print(f"rbnx convert-carmen: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {n} scans to {args.output}")
    return 0

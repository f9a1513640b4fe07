"""How much of a recording survives a SIGKILL, and how finely its messages are stamped (issue 38).

    ROS_DOMAIN_ID=<the running deploy's> python bench/record_survival.py [--seconds 20] [--topics ...]

Needs a running system on the domain (e.g. ``rbnx boot -f examples/sim/deploy.yaml``). Starts
``rbnx record`` (MCAP), SIGKILLs it ``--seconds`` after launch, reads the file with mcap's non-seeking reader
and prints: seconds of data (first to last log time), how long the recorder took to start (launch to its
"recording" line), what the kill lost (kill time minus the last log time), and the share of consecutive
/odom messages whose log times differ. Then records ``--format rosbag2`` for a few seconds, stops it with
SIGINT and opens the folder with rosbags' AnyReader. Writes bench/results/record_survival.json.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from rbnx.record import read_truncated  # noqa: E402

OUT = ROOT / "bench" / "results" / "record_survival.json"


def _killed_recording(path: Path, seconds: float, topics: list[str]) -> dict[str, Any]:
    t0 = time.time()
    proc = subprocess.Popen([sys.executable, "-m", "rbnx.cli", "record", "-q", "-o", str(path), *topics],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    assert proc.stdout is not None
    proc.stdout.readline()  # "recording ... to ..." once the readers exist
    started = time.time()
    time.sleep(max(0.0, seconds - (started - t0)))
    killed = time.time()
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(10)
    msgs = list(read_truncated(path))
    times = [m.log_time for _s, _c, m in msgs]
    odom = [m.log_time for _s, c, m in msgs if c.topic == "/odom"]
    distinct = sum(b != a for a, b in zip(odom, odom[1:], strict=False)) / max(1, len(odom) - 1)
    return {"seconds_until_kill": round(killed - t0, 2), "startup_s": round(started - t0, 2),
            "file_bytes": path.stat().st_size, "messages": len(msgs),
            "per_topic": dict(Counter(c.topic for _s, c, _m in msgs)),
            "data_s": round((max(times) - min(times)) / 1e9, 2) if times else 0.0,
            "lost_at_kill_s": round(killed - max(times) / 1e9, 2) if times else None,
            "odom_distinct_consecutive_log_times": round(distinct, 4)}


def _rosbag2(folder: Path, seconds: float, topics: list[str]) -> dict[str, Any]:
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    proc = subprocess.Popen([sys.executable, "-m", "rbnx.cli", "record", "-q", "--format", "rosbag2", "-o",
                             str(folder), *topics], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    assert proc.stdout is not None
    proc.stdout.readline()
    time.sleep(seconds)
    proc.send_signal(signal.SIGINT)
    proc.wait(30)
    with AnyReader([folder], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        decoded = sum(1 for c, _t, raw in reader.messages() if reader.deserialize(raw, c.msgtype) is not None)
        return {"files": sorted(p.name for p in folder.iterdir()), "anyreader_messages": reader.message_count,
                "decoded_with_rosbags_types": decoded,
                "topics": {c.topic: c.msgtype for c in reader.connections}}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=float, default=20.0, help="SIGKILL this long after launch (default 20)")
    ap.add_argument("--bag-seconds", type=float, default=5.0, help="length of the rosbag2 recording (default 5)")
    ap.add_argument("--topics", nargs="*", default=[], help="topics (default: rbnx record's defaults)")
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        result = {"sigkill": _killed_recording(Path(tmp) / "run.mcap", args.seconds, args.topics),
                  "rosbag2": _rosbag2(Path(tmp) / "bag", args.bag_seconds, args.topics),
                  "load_average": os.getloadavg()}
    print(json.dumps(result, indent=2))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

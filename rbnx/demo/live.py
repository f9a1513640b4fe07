"""`rbnx demo --record` / `--dashboard`: the demo's run recorded to OUT/run.mcap and shown live.

Kept apart from rbnx.commands.demo so the demo's flow stays readable: ``start`` once the system is up (the robot
has not moved yet, so the recording holds the whole run), ``stop`` in the demo's cleanup. The recording
adds the simulator's ground-truth odometry to the default topics, so a replay can be scored (ATE).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

GROUND_TRUTH_TOPIC = "/ground_truth/odom"


class DemoLive:
    def __init__(self, record: bool, dashboard_port: int | None, out: Path, domain_id: int) -> None:
        self.record_path = out / "run.mcap" if record else None
        self.dashboard_port = dashboard_port
        self.domain_id = domain_id
        self.recorder: Any = None
        self.dashboard: Any = None

    def start(self, atlas: str, summary: dict[str, Any]) -> None:
        if self.record_path is not None:
            from rbnx.record import McapRecorder
            from rbnx.rosmsg import DEFAULT_TOPICS, KNOWN

            topics = (*DEFAULT_TOPICS, KNOWN[GROUND_TRUTH_TOPIC])
            self.recorder = McapRecorder(self.record_path, topics, self.domain_id)
            self.recorder.start()
            summary["recording"] = str(self.record_path)
            print(f"recording to {self.record_path}", flush=True)
        if self.dashboard_port is not None:
            from rbnx.dashboard.launch import start_background

            try:
                self.dashboard = start_background(atlas, self.dashboard_port, self.domain_id)
            except OSError as exc:
                print(f"warning: dashboard not started: {exc}", file=sys.stderr)
                return
            summary["dashboard"] = self.dashboard.url
            print(f"dashboard at {self.dashboard.url}", flush=True)

    def stop(self, summary: dict[str, Any]) -> None:
        if self.dashboard is not None:
            self.dashboard.stop()
            self.dashboard = None
        if self.recorder is not None:
            self.recorder.stop()
            summary["recording_summary"] = self.recorder.summary()
            print(f"recording {self.record_path}: {self.recorder.summary()}", flush=True)
            self.recorder = None

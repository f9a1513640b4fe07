"""`rbnx demo` output: the live progress line, per-goal results, summary.json and the closing table."""

from __future__ import annotations

import json
import os
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, TextIO

from rbnx.demo.goals import Goal, fmt_s


class LiveLine:
    """One updating line on a terminal; on a pipe/file one line per change, at most one a second
    (plus every state change), so CI logs stay readable."""

    def __init__(self, stream: TextIO | None = None, min_interval: float = 1.0) -> None:
        self.stream = stream or sys.stdout
        self.tty = self.stream.isatty()
        self.min_interval = min_interval
        self._width = 0
        self._last = ("", "")
        self._last_t = 0.0

    def update(self, state: str, text: str) -> None:
        if self.tty:
            cols = _columns()
            line = text[: cols - 1]
            self.stream.write("\r" + line.ljust(self._width))
            self._width = len(line)
            self.stream.flush()
            return
        now = time.monotonic()
        if (state, text) == self._last or (state == self._last[0] and now - self._last_t < self.min_interval):
            return
        self._last, self._last_t = (state, text), now
        print(text, file=self.stream, flush=True)

    def done(self, text: str) -> None:
        """Close the goal with its final line (kept on screen)."""
        if self.tty:
            self.stream.write("\r" + text.ljust(self._width) + "\n")
            self._width = 0
            self.stream.flush()
        else:
            print(text, file=self.stream, flush=True)
        self._last = ("", "")


def _columns() -> int:
    try:
        return os.get_terminal_size().columns
    except OSError:
        return 120


@dataclass
class GoalResult:
    index: int
    goal: Goal
    state: str = "PENDING"
    detail: str = ""
    run_id: str = ""
    duration_sim_s: float | None = None
    duration_wall_s: float = 0.0
    path_length_m: float = 0.0
    plan_length_m: float | None = None
    final_pose: tuple[float, float, float] | None = None
    final_error_m: float | None = None
    collisions: list[dict[str, Any]] = field(default_factory=list)
    # nav status changes seen while driving (sim time, state, detail), numbers aside: what navigation was doing
    # (following, blocked, which recovery) when a contact happened; each contact gets the entry then in force
    nav_events: list[dict[str, Any]] = field(default_factory=list)
    # the true footprint's closest approach to the true obstacles while driving (robonix_eval/clearance.py)
    closest: dict[str, float] | None = None
    plan: Any = field(default=None, repr=False, compare=False)  # (N, 2) map-frame route, for map.png only

    @property
    def reached(self) -> bool:
        """Navigation reported the goal reached (contacts aside)."""
        return self.state == "SUCCEEDED"

    @property
    def succeeded(self) -> bool:
        """Reached without touching anything: a contact during the goal fails it, whatever nav reported."""
        return self.reached and not self.collisions

    @property
    def outcome(self) -> str:
        """The state shown to people: nav's state, or CONTACT when it reached the goal by hitting something."""
        return "CONTACT" if self.reached and self.collisions else self.state

    def as_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d.pop("plan")
        g = d.pop("goal")
        d = {"index": d.pop("index"), "name": g["name"],
             "target": {"x": g["x"], "y": g["y"], "yaw": g["yaw"], "frame": "map"}, **d}
        for k in ("duration_sim_s", "duration_wall_s", "path_length_m", "plan_length_m", "final_error_m"):
            if d[k] is not None:
                d[k] = round(d[k], 3)
        if d["final_pose"] is not None:
            d["final_pose"] = {"x": round(d["final_pose"][0], 3), "y": round(d["final_pose"][1], 3),
                               "theta": round(d["final_pose"][2], 3), "frame": "world (ground truth)"}
        d["nav_events"] = [{k: v for k, v in e.items() if k != "kind"} for e in d["nav_events"]]
        d["collision_count"] = len(d["collisions"])
        d["reached"] = self.reached
        d["succeeded"] = self.succeeded
        if self.reached and self.collisions:
            d["failure"] = "contact with " + ", ".join(sorted({str(c.get("other_geom", "?")) for c in self.collisions}))
        return d


def goals_exit_code(results: list[GoalResult], n_planned: int) -> int:
    """0 only when every planned goal ran and succeeded (a goal reached with a contact did not), else 1."""
    return 0 if len(results) == n_planned and all(r.succeeded for r in results) else 1


def write_json(path: Path, data: dict[str, Any]) -> None:
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(data, indent=2) + "\n")
    tmp.replace(path)


def print_table(results: list[GoalResult], n_planned: int, stream: TextIO | None = None) -> None:
    out = stream or sys.stdout
    head = f"{'#':>2}  {'goal':<16} {'target':<14} {'state':<10} {'sim':>8} {'wall':>8} {'path':>7} " \
           f"{'error':>6} {'coll':>4}"
    print(head, file=out)
    print("-" * len(head), file=out)
    for r in results:
        g = r.goal
        err = f"{r.final_error_m:.2f}m" if r.final_error_m is not None else "-"
        print(f"{r.index:>2}  {g.name[:16]:<16} {f'({g.x:.2f}, {g.y:.2f})':<14} {r.outcome:<10} "
              f"{fmt_s(r.duration_sim_s):>8} {fmt_s(r.duration_wall_s):>8} {r.path_length_m:>6.2f}m "
              f"{err:>6} {len(r.collisions):>4}", file=out)
    ok = sum(r.succeeded for r in results)
    hit = sum(r.reached and not r.succeeded for r in results)
    print(f"{ok}/{n_planned} goals succeeded" + (f" ({hit} reached with a contact: failed)" if hit else ""),
          file=out, flush=True)

"""Live boot progress: a compact table redrawn in place on a TTY, one plain line per change otherwise.

Rendering is a pure function of the rows (tested alone); the view only decides when and how to write.
"""

from __future__ import annotations

import shutil
import sys
import threading
import time
from dataclasses import dataclass, field
from typing import TextIO

FINAL_OK = ("active", "inactive")


@dataclass
class Row:
    name: str
    kind: str
    state: str = "pending"
    detail: str = ""
    started: float | None = None
    finished: float | None = None

    def label(self) -> str:
        return f"{self.state}({self.detail})" if self.detail else self.state

    def elapsed(self, now: float) -> float | None:
        if self.started is None:
            return None
        return (self.finished or now) - self.started


def render_table(rows: list[Row], now: float, width: int = 100, title: str = "") -> list[str]:
    """The table as lines: NAME KIND STATE ELAPSED, states truncated to fit `width`."""
    name_w = max([4, *(len(r.name) for r in rows)])
    kind_w = max([4, *(len(r.kind) for r in rows)])
    state_w = max(12, width - name_w - kind_w - 14)
    lines = [title] if title else []
    lines.append(f"{'NAME':<{name_w}}  {'KIND':<{kind_w}}  {'STATE':<{state_w}}  {'TIME':>6}".rstrip())
    for r in rows:
        label = r.label()
        if len(label) > state_w:
            label = label[: state_w - 1] + "…"
        el = r.elapsed(now)
        t = f"{el:5.1f}s" if el is not None else "     -"
        lines.append(f"{r.name:<{name_w}}  {r.kind:<{kind_w}}  {label:<{state_w}}  {t:>6}".rstrip())
    return lines


def plain_line(row: Row, now: float, t0: float) -> str:
    """One line per state change for logs and pipes."""
    return f"[{now - t0:6.1f}s] {row.name} ({row.kind}): {row.label()}"


@dataclass
class ProgressView:
    """Tracks rows and shows changes; `enabled=False` keeps the rows silently (for --no-progress)."""

    rows: list[Row]
    stream: TextIO = field(default_factory=lambda: sys.stdout)
    enabled: bool = True
    tty: bool | None = None
    t0: float = field(default_factory=time.monotonic)
    _drawn: int = 0
    _last_draw: float = 0.0
    _lock: threading.Lock = field(default_factory=threading.Lock)

    def __post_init__(self) -> None:
        if self.tty is None:
            self.tty = bool(getattr(self.stream, "isatty", lambda: False)())

    def row(self, name: str) -> Row:
        return next(r for r in self.rows if r.name == name)

    def set(self, name: str, state: str, detail: str = "") -> None:
        """Change an entry's state; prints a line (or redraws) only when something changed."""
        now = time.monotonic()
        with self._lock:
            r = self.row(name)
            if (r.state, r.detail) == (state, detail):
                return
            if (r.started is None and state != "pending") or state == "stopping":
                r.started = now  # shutdown is timed on its own
            r.state, r.detail = state, detail
            r.finished = now if state in (*FINAL_OK, "failed", "stopped") else None
            if not self.enabled:
                return
            if self.tty:
                self._redraw(now)
            else:
                print(plain_line(r, now, self.t0), file=self.stream, flush=True)

    def tick(self) -> None:
        """Refresh elapsed times on a TTY (cheap; at most 4 redraws a second)."""
        now = time.monotonic()
        if self.enabled and self.tty and now - self._last_draw >= 0.25:
            with self._lock:
                self._redraw(now)

    def finish(self) -> None:
        """Leave the last table on screen; later output goes below it."""
        with self._lock:
            if self.enabled and self.tty:
                self._redraw(time.monotonic())
            self._drawn = 0

    def _redraw(self, now: float) -> None:
        width = shutil.get_terminal_size((100, 20)).columns
        lines = render_table(self.rows, now, width=width - 1)
        out = f"\x1b[{self._drawn}F" if self._drawn else ""
        out += "".join(f"\x1b[2K{line}\n" for line in lines)
        self.stream.write(out)
        self.stream.flush()
        self._drawn = len(lines)
        self._last_draw = now

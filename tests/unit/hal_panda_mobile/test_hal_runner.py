"""The sim loop alone (no DDS): publish schedule in sim time, pacing, hold, and surviving exceptions."""

from __future__ import annotations

import time
from typing import Any

from support.wait import wait_until

from hal_panda_mobile.config import build_sim, parse_config
from hal_panda_mobile.loop import LoopRates, SimLoop
from hal_panda_mobile.outputs import Snapshot


class FakeOutputs:
    def __init__(self, fail_first: int = 0) -> None:
        self.snaps: list[Snapshot] = []
        self.fail_first = fail_first

    def publish(self, snap: Snapshot) -> None:
        if self.fail_first > 0:
            self.fail_first -= 1
            raise RuntimeError("writer hiccup")
        self.snaps.append(snap)

    def of(self, what: str) -> list[float]:
        return [s.t for s in self.snaps if getattr(s, what)]


def make(rtf: float, outputs: Any) -> SimLoop:
    sim = build_sim(parse_config({"scene": "warehouse"}))
    return SimLoop(sim, outputs, LoopRates(odom=50.0, scan=10.0, clock=100.0, ground_truth=10.0, hold=20.0),
                     real_time_factor=rtf)


def test_rates_in_sim_time_and_exceptions_are_survived() -> None:
    out = FakeOutputs(fail_first=3)
    r = make(0.0, out)
    r.start()
    try:
        held = wait_until(lambda: len(out.snaps) >= 2, 30, "held republishing")
        assert held
        assert all(s.t == 0.0 for s in out.snaps)
        r.activate()
        wait_until(lambda: r.sim.time > 3.0, 60, "3 s of sim time")
    finally:
        r.stop()
    assert r.stats.errors == 3
    assert "writer hiccup" in r.stats.last_error
    scans = [t for t in out.of("scan") if t > 0.5]
    odoms = [t for t in out.of("odom") if t > 0.5]
    assert max(abs(b - a - 0.1) for a, b in zip(scans, scans[1:], strict=False)) < 1e-6
    assert max(abs(b - a - 0.02) for a, b in zip(odoms, odoms[1:], strict=False)) < 1e-6


def test_paced_rtf_and_deactivate_holds() -> None:
    out = FakeOutputs()
    r = make(4.0, out)
    r.start()
    try:
        r.activate()
        t0 = time.monotonic()
        wait_until(lambda: r.sim.time >= 2.0, 60, "2 s of sim time")
        assert time.monotonic() - t0 >= 2.0 / 4.0 * 0.9  # never faster than 4x
        assert r.cmd_vel(0.5, 0.0, 0.0)
        r.deactivate()
        assert not r.cmd_vel(0.5, 0.0, 0.0)  # ignored unless active
        wait_until(lambda: r.mode == "held", 60, "hold after braking")
        t, n = r.sim.time, len(out.snaps)
        # held republishes the frozen state (20 Hz here): five more of them prove time passed, not sim time
        wait_until(lambda: len(out.snaps) >= n + 5, 60, "five held republishes")
        assert r.sim.time == t
        assert {s.t for s in out.snaps[n:]} == {t}
        assert max(abs(v) for v in r.sim.ground_truth()[3:]) < 1e-3
    finally:
        r.stop()

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


def lagged(bound: float, wait_max: float = 60.0) -> SimLoop:
    """As fast as possible (rtf 0): without the bound the sim would run far past any command. The wait for a
    follow-up command is long here (60 s) so that a busy machine delaying this test thread cannot end it."""
    sim = build_sim(parse_config({"scene": "warehouse"}))
    return SimLoop(sim, FakeOutputs(), LoopRates(odom=50.0, scan=10.0, clock=100.0, ground_truth=10.0, hold=20.0),
                   real_time_factor=0.0, command_lag_bound_s=bound, command_wait_max_s=wait_max)


CHUNK_S = 0.01  # the loop steps to the next due output: /clock at 100 Hz here


def test_command_lag_bound_holds_sim_time_until_the_next_command() -> None:
    r = lagged(0.15)
    r.start()
    try:
        r.activate()
        wait_until(lambda: r.sim.time > 0.5, 60, "0.5 s of sim time")
        for _ in range(5):  # a controller slower than the sim: each command comes only once the sim waits
            waits = r.stats.cmd_waits
            assert r.cmd_vel(0.3, 0.0, 0.1)
            wait_until(lambda w=waits: r.stats.cmd_waits > w, 60, "the loop waiting for the next command")
        assert r.stats.cmd_wait_timeouts == 0
        # every wait began one chunk or less past the bound, never later: the base never ran out of command
        assert 0.15 <= r.stats.cmd_wait_lag_max_s <= 0.15 + CHUNK_S + 1e-6
        assert r.sim.commanding
    finally:
        r.stop()


def test_a_command_that_is_not_followed_up_stops_being_waited_for() -> None:
    r = lagged(0.15, wait_max=0.4)
    r.start()
    try:
        r.activate()
        wait_until(lambda: r.sim.time > 0.2, 60, "0.2 s of sim time")
        t0 = r.sim.time
        assert r.cmd_vel(0.3, 0.0, 0.0)
        wait_until(lambda: r.stats.cmd_wait_timeouts == 1, 60, "the wait for a follow-up command giving up")
        wait_until(lambda: r.sim.time > t0 + 2.0, 60, "sim time running on")
        assert r.stats.cmd_waits == 1   # the same command is not waited for twice
        assert not r.sim.commanding     # its own 0.5 s timeout ended it
        assert max(abs(v) for v in r.sim.ground_truth()[3:]) < 1e-3
    finally:
        r.stop()


def test_zero_commands_and_bound_zero_never_wait() -> None:
    for bound, cmd in ((0.15, (0.0, 0.0, 0.0)), (0.0, (0.3, 0.0, 0.0))):
        r = lagged(bound)
        r.start()
        try:
            r.activate()
            assert r.cmd_vel(*cmd)
            wait_until(lambda r=r: r.sim.time > 2.0, 60, "2 s of sim time")
            assert r.stats.cmd_waits == 0
        finally:
            r.stop()


def test_deactivate_ends_a_wait_and_brakes() -> None:
    r = lagged(0.15)   # the wait would last 60 s: only the mode change can end it
    r.start()
    try:
        r.activate()
        assert r.cmd_vel(0.3, 0.0, 0.0)
        wait_until(lambda: r.stats.cmd_waits == 1, 60, "the loop waiting for a follow-up command")
        r.deactivate()
        wait_until(lambda: r.mode == "held", 60, "hold after braking")
        assert r.stats.cmd_wait_timeouts == 0
        assert max(abs(v) for v in r.sim.ground_truth()[3:]) < 1e-3
    finally:
        r.stop()

"""Unit tests: result types and the Driver state machine (no network)."""

from __future__ import annotations

import threading

import pytest

from robonix_api import Deferred, Err, Ok
from robonix_api.driver import (
    CMD_ACTIVATE,
    CMD_DEACTIVATE,
    CMD_INIT,
    CMD_SHUTDOWN,
    Lifecycle,
    parse_config_json,
)


def test_result_types() -> None:
    assert Ok() == Ok()
    assert bool(Ok())
    assert Err("x").msg == "x"
    assert not Err("x")
    assert Deferred("later").reason == "later"
    assert not Deferred("later")
    assert Err("a") != Err("b")


def make(**handlers):  # type: ignore[no-untyped-def]
    pushed: list[tuple[str, str]] = []
    lc = Lifecycle(lambda s, d: pushed.append((s, d)))
    lc.handlers.update(handlers)
    return lc, pushed


def test_full_cycle_replies_and_pushes() -> None:
    seen: list[object] = []
    lc, pushed = make(init=lambda cfg: seen.append(cfg) or Ok(), activate=lambda: Ok(),
                      deactivate=lambda: Ok(), shutdown=lambda: Ok())
    r = lc.handle(CMD_INIT, '{"rate": 5}')
    assert (r.ok, r.state, r.error) == (True, "inactive", "")
    assert seen == [{"rate": 5}]
    assert lc.config == {"rate": 5}
    assert lc.handle(CMD_ACTIVATE).state == "active"
    assert lc.handle(CMD_DEACTIVATE).state == "inactive"
    assert lc.handle(CMD_ACTIVATE).state == "active"
    r = lc.handle(CMD_SHUTDOWN)
    assert (r.ok, r.state) == (True, "terminated")
    assert lc.terminated.is_set()
    assert [s for s, _ in pushed] == ["inactive", "active", "inactive", "active", "terminated"]


def test_missing_handlers_are_ok() -> None:
    lc, _ = make()
    assert lc.handle(CMD_INIT, "").state == "inactive"
    assert lc.handle(CMD_ACTIVATE).ok


def test_err_goes_to_error_and_init_can_retry() -> None:
    calls = iter([Err("no lidar"), Ok()])
    lc, pushed = make(init=lambda cfg: next(calls))
    r = lc.handle(CMD_INIT)
    assert (r.ok, r.state, r.error) == (False, "error", "no lidar")
    assert lc.state == "error"
    assert pushed[-1] == ("error", "no lidar")
    r = lc.handle(CMD_ACTIVATE)
    assert not r.ok
    assert "cannot activate" in r.error
    assert lc.handle(CMD_INIT).ok


def test_deferred_keeps_state_and_pushes_reason() -> None:
    lc, pushed = make(init=lambda cfg: Deferred("waiting for robonix/primitive/lidar/lidar"))
    r = lc.handle(CMD_INIT, "{}")
    assert (r.ok, r.state, r.error) == (False, "deferred", "waiting for robonix/primitive/lidar/lidar")
    assert lc.state == "registered"
    assert pushed == [("registered", "waiting for robonix/primitive/lidar/lidar")]


def test_exception_and_bad_return_become_err() -> None:
    def boom(cfg: dict) -> Ok:
        raise RuntimeError("disk full")

    lc, _ = make(init=boom)
    r = lc.handle(CMD_INIT)
    assert not r.ok
    assert r.state == "error"
    assert "disk full" in r.error
    lc, _ = make(init=lambda cfg: True)
    r = lc.handle(CMD_INIT)
    assert not r.ok
    assert r.state == "error"
    assert "TypeError" in r.error
    assert "bool" in r.error


@pytest.mark.parametrize(("text", "expected"),
                         [("", {}), ("  ", {}), ("[1, 2]", {}), ("3", {}), ('{"a": 1}', {"a": 1})])
def test_config_json_lenient(text: str, expected: dict) -> None:
    assert parse_config_json(text) == expected


def test_invalid_config_json_names_the_problem_and_keeps_state() -> None:
    lc, pushed = make()
    with pytest.raises(ValueError, match="config_json: invalid JSON at line 1 column 7"):
        lc.handle(CMD_INIT, '{"a": }')
    with pytest.raises(ValueError, match="config_json: nested too deeply"):
        lc.handle(CMD_INIT, "[" * 100_000 + "]" * 100_000)
    assert lc.state == "registered"
    assert pushed == []


def test_illegal_transitions_and_unknown_command() -> None:
    lc, pushed = make()
    r = lc.handle(CMD_ACTIVATE)
    assert (r.ok, r.state, r.error) == (False, "error", "cannot activate: not initialized (state registered)")
    r = lc.handle(CMD_DEACTIVATE)
    assert not r.ok
    assert "cannot deactivate" in r.error
    assert lc.state == "registered"
    assert pushed == []
    r = lc.handle(7)  # an unknown command moves the provider to ERROR, as robonix's SDK does
    assert not r.ok
    assert r.state == "error"
    assert "command" in r.error
    assert "7" in r.error
    assert lc.state == "error"
    assert pushed == [("error", r.error)]
    lc.handle(CMD_INIT)
    lc.handle(CMD_ACTIVATE)
    assert "deactivate first" in lc.handle(CMD_INIT).error
    assert lc.handle(CMD_ACTIVATE).ok  # repeat is idempotent
    lc.handle(CMD_SHUTDOWN)
    assert lc.handle(CMD_SHUTDOWN).ok  # so is a second shutdown
    assert "terminated" in lc.handle(CMD_INIT).error


def test_shutdown_err_still_terminates_and_signal_cannot_defer() -> None:
    lc, pushed = make(shutdown=lambda: Err("left a mess"))
    r = lc.handle(CMD_SHUTDOWN)
    assert (r.ok, r.state, r.error) == (False, "error", "left a mess")
    assert lc.state == "terminated"
    assert lc.terminated.is_set()
    assert pushed[-1][0] == "terminated"
    lc, _ = make(shutdown=lambda: Deferred("busy"))
    assert lc.handle(CMD_SHUTDOWN).state == "deferred"
    assert lc.state == "registered"
    r = lc.shutdown("signal SIGTERM")
    assert lc.state == "terminated"
    assert "busy" in r.error


def test_commands_are_serialized() -> None:
    release = threading.Event()
    entered = threading.Event()

    def slow_init(cfg: dict) -> Ok:
        entered.set()
        release.wait(30)
        return Ok()

    lc, _ = make(init=slow_init)
    replies: dict[str, object] = {}
    t1 = threading.Thread(target=lambda: replies.setdefault("init", lc.handle(CMD_INIT)))
    t1.start()
    assert entered.wait(30)
    t2 = threading.Thread(target=lambda: replies.setdefault("activate", lc.handle(CMD_ACTIVATE)))
    t2.start()
    t2.join(0.3)
    assert t2.is_alive(), "ACTIVATE must wait for the running INIT"
    release.set()
    t1.join(30)
    t2.join(30)
    assert replies["init"].state == "inactive"  # type: ignore[attr-defined]
    assert replies["activate"].state == "active"  # type: ignore[attr-defined]

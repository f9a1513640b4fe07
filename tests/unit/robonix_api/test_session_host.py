"""The lifecycle glue every provider shares (robonix_api.hosting), driven through the real Driver logic.

No network: a ``Service`` that never runs still owns a real ``Lifecycle``, so CMD_INIT / ACTIVATE /
DEACTIVATE / SHUTDOWN go through the same state machine the gRPC Driver uses.
"""

from __future__ import annotations

import json
import math
from typing import Any

import grpc
import pytest
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from robonix_api import Deferred, Err, Service, StatusError
from robonix_api.driver import CMD_ACTIVATE, CMD_DEACTIVATE, CMD_INIT, CMD_SHUTDOWN
from robonix_api.hosting import Session, SessionHost, serve_contracts
from robonix_api.validation import field_errors, require_finite


class Work:
    def __init__(self, name: str, events: list[str]) -> None:
        self.name, self.events = name, events
        self.active = False

    def close(self, reason: str) -> None:
        self.events.append(f"close {self.name}: {reason}")


class Resource:
    def __init__(self, name: str, events: list[str]) -> None:
        self.name, self.events = name, events

    def close(self) -> None:
        self.events.append(f"close {self.name}")


class Host(SessionHost[dict, Work]):
    """prepare: {"defer": why} -> Deferred, {"bad": why} -> Err; start: {"fail": why} -> Err after owning one."""

    def __init__(self, svc: Service) -> None:
        super().__init__(svc)
        self.events: list[str] = []

    def prepare(self, config: dict[str, Any]) -> dict | Err | Deferred:
        if "defer" in config:
            return Deferred(config["defer"])
        if "bad" in config:
            return Err(config["bad"])
        return config

    def start(self, setup: dict) -> Work | Err:
        name = setup.get("name", "w")
        self.own(Resource(f"{name}.sub", self.events))
        if "fail" in setup:
            return Err(setup["fail"])
        self.own(Resource(f"{name}.pub", self.events))
        return Work(name, self.events)

    def activate(self, work: Work) -> None:
        work.active = True

    def deactivate(self, work: Work) -> None:
        work.active = False


@pytest.fixture
def host() -> Host:
    return Host(Service("hosting_test", "robonix/service/test"))


def drive(h: Host, command: int, cfg: dict | None = None) -> tuple[bool, str, str]:
    r = h.provider.lifecycle.handle(command, json.dumps(cfg) if cfg is not None else "")
    return r.ok, r.state, r.error


def test_init_deferred_then_ok_exposes_the_session(host: Host) -> None:
    assert host.current() is None
    assert host.not_ready == "waiting for CMD_INIT"
    assert drive(host, CMD_INIT, {"defer": "waiting for robonix/x"}) == (False, "deferred", "waiting for robonix/x")
    assert host.current() is None
    assert host.not_ready == "waiting for robonix/x"
    assert drive(host, CMD_INIT, {"name": "a"})[:2] == (True, "inactive")
    s = host.current()
    assert isinstance(s, Session)
    assert s.work.name == "a"
    assert s.setup == {"name": "a"}
    assert host.not_ready == ""
    assert host.events == []


def test_failed_reinit_keeps_the_running_session(host: Host) -> None:
    drive(host, CMD_INIT, {"name": "a"})
    first = host.current()
    assert drive(host, CMD_INIT, {"bad": "rate: must be > 0"}) == (False, "error", "rate: must be > 0")
    assert host.current() is first
    assert host.events == []
    assert drive(host, CMD_INIT, {"defer": "gone"})[1] == "deferred"
    assert host.current() is first
    assert host.events == []


def test_reinit_closes_the_old_session_work_first_then_resources_newest_first(host: Host) -> None:
    drive(host, CMD_INIT, {"name": "a"})
    assert drive(host, CMD_INIT, {"name": "b"})[:2] == (True, "inactive")
    assert host.events == ["close a: re-initialized", "close a.pub", "close a.sub"]
    assert host.current() is not None
    assert host.current().work.name == "b"


def test_start_failure_closes_what_it_owned_and_says_why(host: Host) -> None:
    drive(host, CMD_INIT, {"name": "a"})
    assert drive(host, CMD_INIT, {"name": "b", "fail": "no /map within 5 s"}) == (False, "error", "no /map within 5 s")
    assert host.events == ["close a: re-initialized", "close a.pub", "close a.sub", "close b.sub"]
    assert host.current() is None
    assert host.not_ready == "last CMD_INIT failed: no /map within 5 s"


def test_activate_deactivate_reach_the_work_and_shutdown_closes(host: Host) -> None:
    drive(host, CMD_INIT, {"name": "a"})
    work = host.current().work
    assert drive(host, CMD_ACTIVATE)[:2] == (True, "active")
    assert work.active
    assert drive(host, CMD_DEACTIVATE)[:2] == (True, "inactive")
    assert not work.active
    assert drive(host, CMD_SHUTDOWN)[:2] == (True, "terminated")
    assert host.events == ["close a: shutting down", "close a.pub", "close a.sub"]
    assert host.current() is None
    assert host.not_ready == "shut down"


def test_a_failing_close_does_not_stop_the_rest(host: Host) -> None:
    drive(host, CMD_INIT, {"name": "a"})
    s = host.current()

    def boom(reason: str) -> None:
        raise RuntimeError("writer already gone")

    s.work.close = boom  # type: ignore[method-assign]
    assert drive(host, CMD_SHUTDOWN)[:2] == (True, "terminated")
    assert host.events == ["close a.pub", "close a.sub"]


def test_serve_contracts_binds_grpc_and_mcp_faces() -> None:
    seen: list[tuple[str, str, Any]] = []

    class Recorder:
        def grpc(self, cid: str) -> Any:
            return lambda fn: seen.append(("grpc", cid, fn))

        def mcp(self, cid: str) -> Any:
            return lambda fn: seen.append(("mcp", cid, fn))

    def plain(req: Any) -> Any: ...
    def structured(req: Any) -> Any: ...
    serve_contracts(Recorder(), {"a/x": plain, "a/y": (plain, structured)})
    assert seen == [("grpc", "a/x", plain), ("mcp", "a/x", plain), ("grpc", "a/y", plain), ("mcp", "a/y", structured)]


class _Cfg(BaseModel):
    model_config = ConfigDict(extra="forbid")
    rate_hz: float = Field(1.0, gt=0)


def test_field_errors_name_each_field() -> None:
    with pytest.raises(ValidationError) as exc:
        _Cfg.model_validate({"rate_hz": -1, "ratehz": 2})
    text = field_errors(exc.value)
    assert text.startswith("rate_hz: must be > 0")
    assert "; ratehz: " in text
    assert field_errors(exc.value, unknown_key="unknown key (misspelt?)").endswith("ratehz: unknown key (misspelt?)")


def test_require_finite_names_the_field() -> None:
    class Req:
        x, y = 1.0, math.nan

    require_finite(Req(), "x")
    with pytest.raises(StatusError) as exc:
        require_finite(Req(), "x", "y")
    assert exc.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert "y: must be a finite number" in str(exc.value)

"""Lifecycle control of a deployment's entries: the verbs an agent (or a person) uses to decide what runs.

Every verb drives the provider's own lifecycle Driver, found through the atlas like any consumer
finds it; the atlas is also where the state comes from, so what :meth:`LifecycleControl.list_services`
reports is what the providers pushed, not what rbnx remembers. The verbs mirror ROS 2 managed-node
transitions, mapped onto the robonix Driver:

=============  =========================================================================================
``activate``   CMD_ACTIVATE (INACTIVE → ACTIVE; ACTIVE stays)
``deactivate`` CMD_DEACTIVATE (ACTIVE → INACTIVE: a paused service keeps serving what it has)
``configure``  re-INIT with the entry's config plus a JSON merge patch (RFC 7386: ``null`` deletes a key);
               an ACTIVE entry is deactivated first and re-activated after. The provider validates the
               config; a rejected one leaves the entry in ERROR with the provider's reason, its config
               unchanged here
``cleanup``    (alias ``reset``) re-INIT with the deploy file's config, dropping patches: a fresh session,
               left INACTIVE
``shutdown``   CMD_SHUTDOWN of one entry (its process exits); without an entry, the whole deployment
=============  =========================================================================================

Every failure is a :class:`ControlError` whose message names the entry and the problem; an unknown
entry lists the known ones. With tracing on, each verb is a span whose context reaches the provider's
Driver over gRPC metadata.
"""

from __future__ import annotations

import copy
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from rbnx.atlas_rpc import CMD, STATE_NAMES, Atlas, AtlasError, Driver, DriverReply, driver_capability
from rbnx.boot.backoff import Backoff
from robonix_api import telemetry

DEFERRED_RETRY_S = 60.0  # how long configure/reset retry a Deferred INIT (an input that is briefly away)


class ControlError(RuntimeError):
    """A lifecycle verb failed; ``str()`` is one line naming the entry and the reason."""


@dataclass
class Entry:
    """One deploy entry as the control sees it: its deploy config and the config in force now."""

    name: str
    kind: str
    deploy_config: dict[str, Any]
    autostart: bool = True
    config: dict[str, Any] = field(default_factory=dict)
    reinits: int = 0

    def __post_init__(self) -> None:
        if not self.config:
            self.config = copy.deepcopy(self.deploy_config)


def merge_patch(target: Any, patch: Any) -> Any:
    """RFC 7386 JSON merge patch: objects merge recursively, ``None`` removes a key, anything else replaces."""
    if not isinstance(patch, dict):
        return copy.deepcopy(patch)
    out = dict(target) if isinstance(target, dict) else {}
    for k, v in patch.items():
        if v is None:
            out.pop(k, None)
        else:
            out[k] = merge_patch(out.get(k), v)
    return out


class LifecycleControl:
    """The lifecycle verbs over the entries of one deployment (thread-safe: one verb per entry at a time)."""

    def __init__(self, atlas_addr: str, entries: list[Entry], *, driver_timeout: float = 90.0,
                 restarts: Callable[[str], int] | None = None,
                 shutdown_all: Callable[[], None] | None = None) -> None:
        self.atlas_addr = atlas_addr
        self.entries = {e.name: e for e in entries}
        self.driver_timeout = driver_timeout
        self._restarts = restarts or (lambda _name: 0)
        self._shutdown_all = shutdown_all
        self._locks = {e.name: threading.Lock() for e in entries}

    # ------------------------------------------------------------------ lookups
    def known(self) -> list[str]:
        return list(self.entries)

    def entry(self, name: Any) -> Entry:
        if not isinstance(name, str) or not name.strip():
            raise ControlError(f"entry: required, one of {', '.join(self.known()) or '(none)'}")
        e = self.entries.get(name)
        if e is None:
            raise ControlError(f"unknown entry {name!r}; known: {', '.join(self.known()) or '(none)'}")
        return e

    def _provider(self, atlas: Atlas, name: str) -> Any:
        prov = atlas.provider(name)
        if prov is None:
            raise ControlError(f"{name}: not registered on the atlas at {self.atlas_addr} (not started, or gone)")
        return prov

    def state(self, name: str) -> tuple[str, str]:
        """(state, detail) as the provider last pushed it to the atlas."""
        try:
            with Atlas(self.atlas_addr, timeout=5.0) as atlas:
                prov = atlas.provider(name)
        except AtlasError as exc:
            raise ControlError(str(exc)) from None
        if prov is None:
            return "absent", "not registered on the atlas"
        return STATE_NAMES.get(prov.state, str(prov.state)), prov.state_detail

    # ------------------------------------------------------------------ verbs
    def list_services(self) -> list[dict[str, Any]]:
        """entry, kind, state, detail, autostart, restarts (process restarts), reinits (configure/reset)."""
        try:
            with Atlas(self.atlas_addr, timeout=5.0) as atlas:
                provs = {p.id: p for p in atlas.query()}
        except AtlasError as exc:
            raise ControlError(str(exc)) from None
        out = []
        for e in self.entries.values():
            p = provs.get(e.name)
            out.append({"entry": e.name, "kind": e.kind,
                        "state": STATE_NAMES.get(p.state, str(p.state)) if p is not None else "absent",
                        "detail": p.state_detail if p is not None else "not registered on the atlas",
                        "autostart": e.autostart, "restarts": int(self._restarts(e.name)),
                        "reinits": e.reinits})
        return out

    def activate(self, name: str) -> dict[str, Any]:
        return self._verb("activate", name, lambda e: self._command(e, CMD.CMD_ACTIVATE))

    def deactivate(self, name: str) -> dict[str, Any]:
        return self._verb("deactivate", name, lambda e: self._command(e, CMD.CMD_DEACTIVATE))

    def configure(self, name: str, patch: Any) -> dict[str, Any]:
        if not isinstance(patch, dict):
            raise ControlError(f"config: must be a JSON object (a merge patch of {name}'s config), "
                               f"got {type(patch).__name__}")
        return self._verb("configure", name, lambda e: self._reinit(e, merge_patch(e.config, patch), keep_active=True))

    def reset(self, name: str) -> dict[str, Any]:
        return self._verb("reset", name, lambda e: self._reinit(e, copy.deepcopy(e.deploy_config), keep_active=False))

    cleanup = reset

    def shutdown(self, name: str | None = None) -> dict[str, Any]:
        if name is None or name == "":
            if self._shutdown_all is None:
                raise ControlError("shutdown: name an entry (this control cannot stop the whole deployment)")
            self._shutdown_all()
            return {"entry": "", "state": "shutting down", "detail": "the whole deployment is shutting down"}
        return self._verb("shutdown", name, lambda e: self._command(e, CMD.CMD_SHUTDOWN))

    # ------------------------------------------------------------------ plumbing
    def _verb(self, verb: str, name: str, body: Callable[[Entry], DriverReply]) -> dict[str, Any]:
        e = self.entry(name)
        tracer = telemetry.tracer()
        with self._locks[e.name]:
            if tracer is None:
                reply = body(e)
            else:
                with tracer.start_as_current_span(f"rbnx.lifecycle.{verb}") as span:
                    span.set_attribute("rbnx.entry", e.name)
                    reply = body(e)
                    span.set_attribute("lifecycle.state", reply.state)
        state, detail = self.state(e.name)
        return {"entry": e.name, "verb": verb, "state": state, "detail": detail}

    def _driver(self, e: Entry) -> Driver:
        try:
            with Atlas(self.atlas_addr, timeout=5.0) as atlas:
                prov = self._provider(atlas, e.name)
                cid = driver_capability(prov)
                if cid is None:
                    raise ControlError(f"{e.name}: declares no lifecycle Driver; it cannot be driven")
                endpoint, params = atlas.endpoint(e.name, cid, 1)
        except AtlasError as exc:
            raise ControlError(f"{e.name}: {exc}") from None
        return Driver(endpoint, params)

    def _command(self, e: Entry, cmd: int, config: dict[str, Any] | None = None) -> DriverReply:
        d = self._driver(e)
        try:
            reply = d.call(cmd, config, self.driver_timeout)
        finally:
            d.close()
        if not reply.ok and reply.state != "deferred":
            verb = {CMD.CMD_INIT: "init", CMD.CMD_ACTIVATE: "activate", CMD.CMD_DEACTIVATE: "deactivate",
                    CMD.CMD_SHUTDOWN: "shutdown"}.get(cmd, str(cmd))
            raise ControlError(f"{e.name}: {verb} refused: {reply.error or reply.state} (state {reply.state})")
        return reply

    def _init(self, e: Entry, config: dict[str, Any]) -> DriverReply:
        """CMD_INIT, retrying Deferred (an input briefly away) with backoff for up to DEFERRED_RETRY_S."""
        deadline = time.monotonic() + DEFERRED_RETRY_S
        backoff = Backoff()
        while True:
            reply = self._command(e, CMD.CMD_INIT, config)
            if reply.ok:
                return reply
            if time.monotonic() >= deadline:
                raise ControlError(f"{e.name}: init still deferred after {DEFERRED_RETRY_S:g}s: {reply.error}")
            time.sleep(backoff.next_delay())

    def _reinit(self, e: Entry, config: dict[str, Any], keep_active: bool) -> DriverReply:
        state, _ = self.state(e.name)
        if state == "absent":
            raise ControlError(f"{e.name}: not registered on the atlas at {self.atlas_addr} (not started, or gone)")
        if state == "terminated":
            raise ControlError(f"{e.name}: terminated; it cannot be configured again (boot it again)")
        was_active = state == "active"
        if was_active:
            self._command(e, CMD.CMD_DEACTIVATE)
        reply = self._init(e, config)
        e.config = config
        e.reinits += 1
        if was_active and keep_active:
            reply = self._command(e, CMD.CMD_ACTIVATE)
        return reply

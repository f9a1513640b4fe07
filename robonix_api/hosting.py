"""One shape for every provider: a session built on CMD_INIT, replaced on re-INIT, closed on SHUTDOWN.

Every provider needs the same lifecycle glue around its own work, and getting it subtly different per
package is how bugs hide (a failed re-INIT that kills the running session, a SHUTDOWN that leaks a
thread). :class:`SessionHost` owns that glue once. A provider subclasses it and writes only what is
its own:

``prepare(config) -> setup | Err | Deferred``
    Validate the CMD_INIT config and look up inputs. It must not touch the running session, so a bad
    or premature re-INIT leaves the robot running as it was.
``start(setup) -> work | Err``
    Build the running work (loop threads, subscriptions). The previous session is already closed.
    Resources that are not part of ``work`` are handed to :meth:`SessionHost.own`, and are closed
    with the session (or at once when ``start`` fails).
``activate(work)`` / ``deactivate(work)``
    What ACTIVATE and DEACTIVATE mean for this provider.

The *work* object must offer ``close(reason)``. Contract handlers reach the current
:class:`Session` through :meth:`SessionHost.current` (``None`` before a successful CMD_INIT), and
:attr:`SessionHost.not_ready` says why there is none. :func:`run_provider` is the whole of a
provider's ``__main__``: log setup, build, serve until CMD_SHUTDOWN or SIGTERM/SIGINT (the provider
object owns signal handling and teardown).
"""

from __future__ import annotations

import importlib
import logging
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Generic, Protocol, TypeVar

from robonix_api import telemetry
from robonix_api.logsetup import setup_logging
from robonix_api.result import Deferred, Err, Ok

log = logging.getLogger("robonix_api.hosting")

WAITING = "waiting for CMD_INIT"
IN_PROGRESS = "CMD_INIT in progress"
SHUT_DOWN = "shut down"
#: reasons handed to ``work.close(reason)``
REINIT, SHUTDOWN, INIT_FAILED = "re-initialized", "shutting down", "init failed"


class Work(Protocol):
    """The running work of one session (a loop object): stopped by ``close(reason)``."""

    def close(self, reason: str) -> None:
        """Stop the running work; ``reason`` says why (re-init, shutdown, init failed)."""


C = TypeVar("C")  # what prepare() produced: the validated settings of one CMD_INIT
W = TypeVar("W", bound=Work)  # what start() produced: the running work
T = TypeVar("T")


def _close_quietly(what: str, close: Callable[[], None]) -> None:
    """Closing must never stop the teardown of the rest; a failure is logged with its traceback."""
    try:
        close()
    except Exception:
        log.exception("closing %s failed", what)


@dataclass
class Session(Generic[C, W]):
    """What one successful CMD_INIT built: its settings, its running work and the resources it owns."""

    setup: C
    work: W
    resources: list[Any] = field(default_factory=list)

    def close(self, reason: str) -> None:
        """Stop the work first (it may still publish, e.g. a zero twist), then the resources, newest first."""
        _close_quietly(type(self.work).__name__, lambda: self.work.close(reason))
        for item in reversed(self.resources):
            _close_quietly(type(item).__name__, item.close)
        self.resources = []


class SessionHost(Generic[C, W]):
    """The lifecycle handlers of a provider, bound to it at construction (see the module docstring)."""

    def __init__(self, provider: Any) -> None:
        self.provider = provider
        self.session: Session[C, W] | None = None
        self.not_ready = WAITING
        self._owned: list[Any] = []
        provider.on_init(self._on_init)
        provider.on_activate(self._on_activate)
        provider.on_deactivate(self._on_deactivate)
        provider.on_shutdown(self._on_shutdown)

    # ------------------------------------------------------------------ what a provider writes
    def prepare(self, config: dict[str, Any]) -> C | Err | Deferred:
        """Validate one CMD_INIT config: the settings to start from, ``Err`` naming the field, or ``Deferred``."""
        raise NotImplementedError

    def start(self, setup: C) -> W | Err:
        """Build and start the work of a new session from prepared settings, or ``Err``."""
        raise NotImplementedError

    def activate(self, work: W) -> None:
        """ACTIVATE: default nothing to do."""

    def deactivate(self, work: W) -> None:
        """DEACTIVATE: default nothing to do."""

    # ------------------------------------------------------------------ what handlers use
    def current(self) -> Session[C, W] | None:
        """The session of the last successful CMD_INIT, or None (see ``not_ready`` for why)."""
        return self.session

    def own(self, resource: T) -> T:
        """During ``start``: close ``resource`` (anything with ``close()``) together with this session."""
        self._owned.append(resource)
        return resource

    # ------------------------------------------------------------------ the glue
    def _on_init(self, config: dict[str, Any]) -> Ok | Err | Deferred:
        setup = self.prepare(config)
        if isinstance(setup, Deferred):
            self.not_ready = setup.reason
            log.info("CMD_INIT deferred: %s", setup.reason)
            return setup
        if isinstance(setup, Err):
            return setup
        self._close(REINIT)  # the new config replaces the running session
        self.not_ready = IN_PROGRESS
        self._owned = []
        try:
            work = self.start(setup)
        except BaseException:
            self._drop_owned()
            self.not_ready = WAITING
            raise
        if isinstance(work, Err):
            self._drop_owned()
            self.not_ready = f"last CMD_INIT failed: {work.msg}"
            return work
        self.session = Session(setup, work, self._owned)
        self._owned = []
        self.not_ready = ""
        return Ok()

    def _on_activate(self) -> Ok | Err:
        if self.session is None:
            return Err(f"not initialized: {self.not_ready}")
        self.activate(self.session.work)
        return Ok()

    def _on_deactivate(self) -> Ok:
        if self.session is not None:
            self.deactivate(self.session.work)
        return Ok()

    def _on_shutdown(self) -> Ok:
        self._close(SHUTDOWN)
        self.not_ready = SHUT_DOWN
        return Ok()

    def _close(self, reason: str) -> None:
        if self.session is not None:
            session, self.session = self.session, None
            session.close(reason)

    def _drop_owned(self) -> None:
        for item in reversed(self._owned):
            _close_quietly(type(item).__name__, item.close)
        self._owned = []


Handler = Callable[..., Any]


def serve_contracts(provider: Any, handlers: Mapping[str, Handler | tuple[Handler, Handler]]) -> None:
    """Serve each rpc contract's handler as its gRPC method and as an MCP tool (before ``run()``).

    A ``(grpc_fn, mcp_fn)`` pair gives the tool its own face (e.g. a structured reply for agents).
    """
    for contract_id, fn in handlers.items():
        grpc_fn, mcp_fn = fn if isinstance(fn, tuple) else (fn, fn)
        provider.grpc(contract_id)(grpc_fn)
        provider.mcp(contract_id)(mcp_fn)


def _load(target: str | Callable[[], Any]) -> Callable[[], Any]:
    if callable(target):
        return target
    module, _, attr = target.partition(":")
    return getattr(importlib.import_module(module), attr or "build_provider")


def run_provider(build: str | Callable[[], Any], *, log_env: str) -> int:
    """A provider process: logging from ``$<log_env>``, build, serve until shutdown, exit code 0.

    ``build`` is a factory returning a :class:`SessionHost` (or a bare provider), or its dotted name
    ``"pkg.provider:build_provider"`` so the package is imported after logging is set up.
    """
    setup_logging(log_env)
    built = _load(build)()
    provider = built.provider if isinstance(built, SessionHost) else built
    telemetry.setup(str(getattr(provider, "id", "") or "robonix-provider"))  # no-op unless OTEL_* ask for it
    provider.run()  # blocks until CMD_SHUTDOWN or SIGTERM/SIGINT; tears down cleanly
    telemetry.shutdown()
    return 0


__all__ = ["Session", "SessionHost", "Work", "run_provider", "serve_contracts"]

"""A recording fake atlas for SDK unit tests (imported as ``support.fakes``, so test modules of
different folders never fight over a ``conftest`` module name)."""

from __future__ import annotations

import threading
from typing import Any

import grpc

from robonix_api.types import LifecycleState, Transport


class FakeRpcError(grpc.RpcError):
    def __init__(self, code: grpc.StatusCode, details: str = "") -> None:
        super().__init__(details)
        self._code, self._details = code, details

    def code(self) -> grpc.StatusCode:
        return self._code

    def details(self) -> str:
        return self._details


class FakeAtlas:
    """Records what a provider tells the atlas; ``forget()`` simulates an atlas restart."""

    address = "127.0.0.1:1"

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.registrations: list[dict[str, Any]] = []
        self.declared: dict[tuple[str, str, Transport], dict[str, Any]] = {}
        self.states: list[tuple[str, LifecycleState, str]] = []
        self.heartbeats = 0
        self.known: set[str] = set()
        self.closed = False

    def register(self, kind: Any, id: str, namespace: str, capability_md_path: str = "",
                 capability_md: str = "") -> str:
        with self.lock:
            self.registrations.append(dict(kind=kind, id=id, namespace=namespace,
                                           capability_md_path=capability_md_path, capability_md=capability_md))
            self.known.add(id)
            for key in [k for k in self.declared if k[0] == id]:
                del self.declared[key]
            return id

    def declare_capability(self, provider_id: str, contract_id: str, endpoint: str, transport: Any,
                           params: Any = None, description: str = "") -> str:
        with self.lock:
            key = (provider_id, contract_id, Transport.parse(transport))
            if key in self.declared:
                raise FakeRpcError(grpc.StatusCode.ALREADY_EXISTS, f"duplicate {key}")
            self.declared[key] = dict(endpoint=endpoint, params=params, description=description)
            return endpoint

    def set_state(self, id: str, state: LifecycleState, detail: str = "") -> LifecycleState:
        with self.lock:
            self.states.append((id, state, detail))
        return LifecycleState.REGISTERED

    def heartbeat(self, id: str) -> None:
        with self.lock:
            self.heartbeats += 1
            if id not in self.known:
                raise FakeRpcError(grpc.StatusCode.NOT_FOUND, f"id {id!r} not registered")

    def query(self, **_filters: Any) -> list[Any]:
        """Nothing is ever evicted by the fake, so the provider's own record never reads TERMINATED."""
        return []

    def forget(self) -> None:
        with self.lock:
            self.known.clear()
            self.declared.clear()

    def close(self) -> None:
        self.closed = True

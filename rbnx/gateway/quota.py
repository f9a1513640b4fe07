"""Per-identity MCP session quotas for the gateway, so anonymous clients cannot lock out the token holder.

The MCP SDK caps a server's open sessions as a whole: 100 unauthenticated ``initialize`` calls filled
the gateway and its operator (the deployment token holder) then got HTTP 503. :class:`SessionQuota` sits
in front of the streamable-HTTP app and gives each identity its own quota: callers presenting the
deployment token share ``holder_cap`` sessions, everybody else shares ``anon_cap``. The SDK's global cap
is set to the sum, so memory stays bounded. Without a deployment token there is one identity and the
SDK's cap alone applies.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Collection
from typing import Any

from robonix_api import auth

SESSION_HEADER = b"mcp-session-id"
#: Unauthenticated clients (read-only tools only, when a token is set) share this many sessions;
#: ``ROBONIX_MCP_MAX_ANON_SESSIONS`` overrides.
DEFAULT_ANON_SESSIONS = 16
HOLDER, ANON = "token holder", "unauthenticated"


class SessionQuota:
    """ASGI middleware: a new session (a POST without ``mcp-session-id``) is admitted only while its
    identity has fewer than its cap open (its own sessions still alive in ``live()`` plus those being
    opened); otherwise HTTP 503 saying whose quota is full."""

    def __init__(self, app: Any, live: Callable[[], Collection[str]], *, anon_cap: int, holder_cap: int) -> None:
        self.app = app
        self._live = live
        self.caps = {ANON: anon_cap, HOLDER: holder_cap}
        self._owner: dict[str, str] = {}
        self._opening = {ANON: 0, HOLDER: 0}

    def _identity(self, headers: list[tuple[bytes, bytes]]) -> str | None:
        expected = auth.current_token()
        if not expected:
            return None
        decoded = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in headers}
        return HOLDER if auth.token_matches(expected, auth.token_from_headers(decoded)) else ANON

    def open_sessions(self, identity: str) -> int:
        live = set(self._live())
        for sid in [s for s in self._owner if s not in live]:
            del self._owner[sid]
        return sum(1 for who in self._owner.values() if who == identity) + self._opening[identity]

    async def __call__(self, scope: dict[str, Any], receive: Any, send: Any) -> None:
        headers = scope.get("headers") or []
        if scope.get("type") != "http" or scope.get("method") != "POST" or any(
                k.lower() == SESSION_HEADER for k, _ in headers):
            await self.app(scope, receive, send)
            return
        who = self._identity(headers)
        if who is None:
            await self.app(scope, receive, send)
            return
        if self.open_sessions(who) >= self.caps[who]:
            await _refuse(send, f"too many open MCP sessions for {who} clients ({self.caps[who]}); close one or "
                          "wait for an idle one to expire" + ("" if who == HOLDER else
                                                             " (the deployment token holder has its own quota)"))
            return

        async def tracking_send(message: dict[str, Any]) -> None:
            if message.get("type") == "http.response.start":
                for k, v in message.get("headers") or []:
                    if k.lower() == SESSION_HEADER:
                        self._owner[v.decode("latin-1")] = who
            await send(message)

        self._opening[who] += 1
        try:
            await self.app(scope, receive, tracking_send)
        finally:
            self._opening[who] -= 1


async def _refuse(send: Any, text: str) -> None:
    body = json.dumps({"jsonrpc": "2.0", "id": None, "error": {"code": -32603, "message": text}}).encode()
    await send({"type": "http.response.start", "status": 503,
                "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]})
    await send({"type": "http.response.body", "body": body})


__all__ = ["ANON", "DEFAULT_ANON_SESSIONS", "HOLDER", "SessionQuota"]

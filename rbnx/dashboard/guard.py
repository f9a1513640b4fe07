"""Who may use the dashboard: the browser of the person who ran `rbnx dashboard`, nobody else.

Without this, any web page could drive the robot (a ``text/plain`` POST is a CORS simple request that
needs no preflight), a DNS-rebinding page could read the live map, and any local user could send goals.
So:

* **Host and Origin allow-lists** (DNS rebinding, cross-site pages): the MCP SDK's
  ``TransportSecurityMiddleware``, the check our MCP servers already run, with the loopback names and
  the bound host; an Origin must also carry the dashboard's own port (another local web server on
  another port is another site). A WebSocket handshake is checked the same way.
* **JSON only**: a changing request must say ``Content-Type: application/json`` (not a simple request).
* **An access key** for everything but the static page code: the deployment token when this process
  has one, else a random key per dashboard. `rbnx dashboard` prints ``http://HOST:PORT/?token=KEY``;
  opening it sets an ``HttpOnly; SameSite=Strict`` cookie and redirects to ``/`` (the key leaves the
  address bar). Scripts may send ``Authorization: Bearer KEY`` (or the deployment token) instead.
"""

from __future__ import annotations

import secrets
from http.cookies import SimpleCookie
from typing import Any

from mcp.server.transport_security import TransportSecurityMiddleware, TransportSecuritySettings

from robonix_api import auth

COOKIE = "rbnx_dashboard"
LOOPBACK_NAMES = ("127.0.0.1", "localhost", "[::1]")


def new_key() -> str:
    """The dashboard's access key: the deployment token when set (one secret to hand around), else random."""
    return auth.current_token() or secrets.token_urlsafe(32)


def _names(host: str) -> list[str]:
    names = list(LOOPBACK_NAMES)
    if host not in ("127.0.0.1", "localhost", "::1", "0.0.0.0", "::", ""):  # bound to a LAN address: its name too
        names.append(f"[{host}]" if ":" in host else host)
    return names


class Guard:
    """The checks above for one dashboard listening on ``host:port`` with access ``key``."""

    def __init__(self, host: str, port: int, key: str) -> None:
        self.key = key
        names = _names(host)
        self._transport = TransportSecurityMiddleware(TransportSecuritySettings(
            enable_dns_rebinding_protection=True,
            allowed_hosts=[f"{n}:{port}" for n in names],
            allowed_origins=[f"http://{n}:{port}" for n in names]))

    def authorized_key(self, presented: str | None) -> bool:
        """``presented`` is the key (or this process's deployment token)."""
        deploy = auth.current_token()
        return bool(presented) and (auth.token_matches(self.key, presented)
                                    or bool(deploy and auth.token_matches(deploy, presented)))

    def authorized(self, conn: Any) -> bool:
        """The request (or WebSocket) carries the key: in the cookie, or as a Bearer/robonix-token header."""
        return any(self.authorized_key(p) for p in (conn.cookies.get(COOKIE), auth.token_from_headers(conn.headers)))

    async def refusal(self, conn: Any, *, post: bool = False) -> tuple[int, str] | None:
        """None when ``conn`` may proceed, else (HTTP status, reason): Host/Origin (421/403), content type
        of a POST (400), the key (401)."""
        bad = await self._transport.validate_request(conn, is_post=post)
        if bad is not None:
            return bad.status_code, bytes(bad.body).decode("utf-8", "replace")
        if not self.authorized(conn):
            return 401, ("dashboard access key required: open the URL printed by `rbnx dashboard` "
                         "(.../?token=...), or send Authorization: Bearer <key>")
        return None

    async def host_refusal(self, conn: Any) -> tuple[int, str] | None:
        """Only the Host/Origin checks (for the page code, which holds no secret)."""
        bad = await self._transport.validate_request(conn, is_post=False)
        return None if bad is None else (bad.status_code, bytes(bad.body).decode("utf-8", "replace"))

    def cookie_header(self) -> str:
        """``Set-Cookie`` value handing the key to the browser: HttpOnly (no script reads it), SameSite=Strict
        (no other site's request carries it)."""
        c: SimpleCookie = SimpleCookie()
        c[COOKIE] = self.key
        c[COOKIE]["httponly"] = True
        c[COOKIE]["samesite"] = "Strict"
        c[COOKIE]["path"] = "/"
        return c[COOKIE].OutputString()


__all__ = ["COOKIE", "Guard", "new_key"]

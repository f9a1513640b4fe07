"""The deployment token on rbnx's side: made by ``rbnx boot``, found again by every other command.

``rbnx boot`` draws a fresh random token per deployment, records it in the boot state file (mode 0600,
so only the same user can read it) and hands it to the atlas and every child as ``$ROBONIX_DEPLOY_TOKEN``.
The other commands (``rbnx navigate``, ``rbnx lifecycle``, ``rbnx map-card``, …) look it up in the state
file of the deployment whose atlas they talk to (else they use an exported ``$ROBONIX_DEPLOY_TOKEN``) and
put it into their own environment, where the SDK's clients pick it up; so the README's commands work
unchanged. ``rbnx token`` prints it for agents.
"""

from __future__ import annotations

import os
import secrets
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from rbnx.boot.statefile import read_state, state_dir
from robonix_api.auth import TOKEN_ENV

ALLOWED_HOSTS_ENV = "ROBONIX_ATLAS_ALLOWED_HOSTS"
TOKEN_BYTES = 32  # 256 bits, 43 URL-safe characters


def new_token() -> str:
    return secrets.token_urlsafe(TOKEN_BYTES)


def boot_env(base: Mapping[str, str], token: str, allowed_hosts: list[str] | None = None) -> dict[str, str]:
    """The environment the atlas and the children start with: the token when there is one (and never a
    stale one from the caller's shell when auth is off), the extra allowed endpoint hosts when given."""
    env = dict(base)
    env.pop(TOKEN_ENV, None)
    if token:
        env[TOKEN_ENV] = token
    if allowed_hosts:
        env[ALLOWED_HOSTS_ENV] = ",".join(allowed_hosts)
    return env


def adopt(token: str) -> None:
    """Make ``token`` this process's own (its atlas, Driver, gateway and MCP clients send it); "" clears."""
    if token:
        os.environ[TOKEN_ENV] = token
    else:
        os.environ.pop(TOKEN_ENV, None)


def _same_atlas(a: str, b: str) -> bool:
    def norm(addr: str) -> str:
        host, _, port = addr.strip().rpartition(":")
        host = host.strip("[]").lower()
        if host in ("localhost", "0.0.0.0", "::", "::1", ""):
            host = "127.0.0.1"
        return f"{host}:{port}"

    return bool(a and b) and norm(a) == norm(b)


def token_for_atlas(atlas: str, directory: Path | None = None) -> str:
    """The token recorded by the running boot whose atlas is ``atlas`` ("" when none is recorded)."""
    base = directory or state_dir()
    try:
        files = sorted(base.glob("boot-*.json"), key=lambda p: p.stat().st_mtime, reverse=True)
    except OSError:
        return ""
    for path in files[:64]:
        st = read_state(path) or {}
        if _same_atlas(str(st.get("atlas") or ""), atlas) and st.get("token"):
            return str(st["token"])
    return ""


def token_of_state(state: Mapping[str, Any] | None) -> str:
    return str((state or {}).get("token") or "")


def adopt_for(atlas: str) -> str:
    """Take the token the boot serving ``atlas`` recorded (it wins over a stale exported one); without a
    record keep ``$ROBONIX_DEPLOY_TOKEN`` (an atlas booted elsewhere). Returns the token in effect."""
    token = token_for_atlas(atlas)
    if token:
        adopt(token)
        return token
    return os.environ.get(TOKEN_ENV, "").strip()


__all__ = ["ALLOWED_HOSTS_ENV", "TOKEN_ENV", "adopt", "adopt_for", "boot_env", "new_token", "token_for_atlas",
           "token_of_state"]

"""MCP session limits: defaults and the environment overrides (the limits enforced on a real provider:
tests/integration/system/trust/test_mcp_sessions.py)."""

from __future__ import annotations

import pytest

from robonix_api.mcp_server import DEFAULT_MAX_SESSIONS, DEFAULT_SESSION_IDLE_S, session_limits


def test_session_limits_defaults_and_env(monkeypatch: pytest.MonkeyPatch) -> None:
    assert session_limits() == {"session_idle_timeout": DEFAULT_SESSION_IDLE_S, "max_sessions": DEFAULT_MAX_SESSIONS}
    assert (DEFAULT_SESSION_IDLE_S, DEFAULT_MAX_SESSIONS) == (300.0, 100)
    monkeypatch.setenv("ROBONIX_MCP_SESSION_IDLE_S", "7.5")
    monkeypatch.setenv("ROBONIX_MCP_MAX_SESSIONS", "3")
    assert session_limits() == {"session_idle_timeout": 7.5, "max_sessions": 3}
    for bad in ("0", "-1", "nan", "inf", "lots"):  # a typo never switches a limit off
        monkeypatch.setenv("ROBONIX_MCP_SESSION_IDLE_S", bad)
        monkeypatch.setenv("ROBONIX_MCP_MAX_SESSIONS", bad)
        assert session_limits() == {"session_idle_timeout": DEFAULT_SESSION_IDLE_S,
                                    "max_sessions": DEFAULT_MAX_SESSIONS}

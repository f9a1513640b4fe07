"""The atlas's trust rules without a server: endpoint hosts and the allowlist, the registry's ownership
rule, and how the console script resolves ``auth`` (served over gRPC: tests/integration/system/trust)."""

from __future__ import annotations

import pytest

from atlas.registry import Registry, RegistryError
from atlas.trust import Trust, endpoint_host, parse_allowed_hosts
from robonix_api.types import Kind, LifecycleState


def test_trust_units() -> None:
    assert endpoint_host("http://127.0.0.1:8/mcp/") == "127.0.0.1"
    assert endpoint_host("unix:/run/x.sock") == ""
    assert endpoint_host("[::1]:9") == "::1"
    assert Trust(allowed_hosts=("*",)).endpoint_problem("evil.example.com:443") is None
    assert Trust().endpoint_problem("evil.example.com:443")
    with pytest.raises(ValueError, match="allowed_hosts"):
        parse_allowed_hosts(["good", "bad host"])


def test_registry_ownership_rule() -> None:
    reg = Registry(heartbeat_timeout_ms=0)
    reg.register(Kind.SERVICE, "nav2", "robonix/service/navigation")
    with pytest.raises(RegistryError) as err:
        reg.register(Kind.SERVICE, "nav2", "robonix/service/navigation", may_replace_live=False)
    assert err.value.code == "ALREADY_EXISTS"
    assert err.value.message.startswith("id: ")
    reg.set_state("nav2", LifecycleState.TERMINATED)
    _, reg_id = reg.register_ex(Kind.SERVICE, "nav2", "robonix/service/navigation", may_replace_live=False)
    with pytest.raises(RegistryError) as err:
        reg.heartbeat("nav2", registration_id="an-old-one")
    assert err.value.code == "FAILED_PRECONDITION"
    reg.heartbeat("nav2", registration_id=reg_id)


def test_atlas_console_script_takes_the_token_from_env_and_auth_none_ignores_it() -> None:
    from atlas import settings

    assert settings.resolve({}, '{"auth": "none"}').auth == "none"
    assert settings.resolve({}, None).auth == "token"
    with pytest.raises(ValueError, match="auth"):
        settings.resolve({}, '{"auth": "maybe"}')

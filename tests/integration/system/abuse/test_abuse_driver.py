"""Property-based abuse of every provider's lifecycle Driver: hypothesis sends command numbers (known and
unknown; never SHUTDOWN, which ends a provider by design) with hostile ``config_json`` (real and bogus
keys, hostile values, broken, deep and oversized JSON). Every reply is a Driver response or a clear
INVALID_ARGUMENT, no process dies, and afterwards every provider comes back ACTIVE with its real config."""

from __future__ import annotations

import json
import time
from typing import Any

import grpc
import pytest
from hypothesis import given
from hypothesis import strategies as st

from hal_panda_mobile.config import HalConfig
from nav2_wrapper.config import ProviderConfig as NavConfig
from robonix_api import auth
from robonix_api.proto_gen import lifecycle_pb2
from robonix_api.proto_gen import robonix_contracts_pb2_grpc as rpc
from slam_service.config import ProviderConfig as SlamConfig

from .deployment import CONFIGS, Deployment
from .strategies import config_json_texts, fuzz_settings

pytestmark = pytest.mark.integration
DRIVER = "robonix/lifecycle/driver"
INIT, ACTIVATE, DEACTIVATE = 0, 1, 2
KEYS = {"abuse_hal": list(HalConfig.model_fields), "abuse_mapping": list(SlamConfig.model_fields),
        "abuse_nav": list(NavConfig.model_fields)}
EXAMPLES = fuzz_settings(30)
SLOW: list[str] = []
COMMANDS = st.one_of(st.sampled_from([INIT, INIT, ACTIVATE, DEACTIVATE]),
                     st.integers(0, 2**32 - 1).filter(lambda c: c != 3))


def drive(stub: Any, command: int, config_json: str, with_token: bool = True) -> tuple[Any, str]:
    """(response or None, error details); without the token the Driver must refuse (and nothing else)."""
    try:
        return stub.Driver(lifecycle_pb2.Driver_Request(command=command, config_json=config_json), timeout=120,
                           metadata=auth.metadata() if with_token else None), ""
    except grpc.RpcError as exc:
        expected = grpc.StatusCode.INVALID_ARGUMENT if with_token else grpc.StatusCode.UNAUTHENTICATED
        if exc.code() != expected:  # a refusal must be the right one (pytest.raises cannot express "may raise")
            pytest.fail(f"{exc.code().name}: {(exc.details() or '')[:300]}")
        return None, exc.details() or ""


def fuzz_driver(dep: Deployment, provider: str, stub: Any) -> None:
    @EXAMPLES
    @given(command=COMMANDS, config_json=config_json_texts(KEYS[provider] + [str(dep.bait), "../bait"]),
           with_token=st.sampled_from([True, True, True, False]))
    def run(command: int, config_json: str, with_token: bool) -> None:
        dep.count(f"Driver {provider}")
        t0 = time.monotonic()
        resp, details = drive(stub, command, config_json, with_token)
        took = time.monotonic() - t0
        if took > 2.0:  # a diagnosis aid: which input made a Driver call slow
            SLOW.append(f"{provider} {took:.1f} s: command {command}, config_json {config_json[:120]!r} -> "
                        f"{(resp.state, resp.error[:200]) if resp else details[:200]}")
        if resp is None:
            assert details, details[:300]
            assert len(details) <= 1024, details[:300]
            assert details.startswith("config_json") or not with_token, details[:300]
        else:
            assert resp.state, (resp.state, resp.error[:300])
            assert len(resp.error) <= 1024, (resp.state, resp.error[:300])

    run()


def restore(stub: Any, provider: str, deadline_s: float = 120) -> None:
    """DEACTIVATE, INIT with the deploy's config (retried while Deferred), ACTIVATE."""
    drive(stub, DEACTIVATE, "")
    end = time.monotonic() + deadline_s
    while True:
        resp, details = drive(stub, INIT, json.dumps(CONFIGS[provider]))
        assert resp is not None, details
        if resp.ok or resp.state != "deferred" or time.monotonic() > end:
            break
        time.sleep(0.5)
    assert resp.ok, (provider, resp.state, resp.error)
    assert resp.state == "inactive", (provider, resp.state, resp.error)
    resp, _ = drive(stub, ACTIVATE, "")
    assert resp is not None, (provider, resp)
    assert resp.ok, (provider, resp)
    assert resp.state == "active", (provider, resp)


def test_every_driver_command_and_config(deployment: Deployment) -> None:
    channels = []
    try:
        stubs = {}
        for provider in ("abuse_hal", "abuse_mapping", "abuse_nav"):
            ch = grpc.insecure_channel(deployment.endpoint(provider, DRIVER))
            channels.append(ch)
            stubs[provider] = rpc.RobonixLifecycleDriverStub(ch)
        # upstream first, each restored before the next is fuzzed: navigation's INIT waits (up to its
        # action_wait_s) for the map and TF of a live mapping service
        for provider, stub in stubs.items():
            fuzz_driver(deployment, provider, stub)
            deployment.assert_alive()
            restore(stub, provider)
        print("\n".join(["slow Driver calls:", *SLOW]) if SLOW else "no Driver call took over 2 s")
        deployment.assert_alive()
    finally:
        for ch in channels:
            ch.close()

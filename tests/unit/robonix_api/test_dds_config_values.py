"""The loopback-only DDS config in effect and domain-id validation, without starting DDS (malformed
CYCLONEDDS_URI in a child process: tests/integration/robonix_api/test_dds_config.py)."""

from __future__ import annotations

import pytest

from robonix_api.dds import effective_config
from robonix_api.dds.config import DdsConfigError, resolve_domain_id


def test_effective_config_is_loopback_without_multicast() -> None:
    cfg = effective_config()
    assert cfg["interfaces"] == ["lo"]
    assert cfg["multicast_disabled"]
    assert cfg["allow_multicast"] == "false"
    assert cfg["peers"] == ["127.0.0.1"]
    assert cfg["loopback_only"]


def test_bad_domain_id(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ROS_DOMAIN_ID", "abc")
    with pytest.raises(DdsConfigError, match="ROS_DOMAIN_ID"):
        resolve_domain_id()
    with pytest.raises(DdsConfigError, match="out of range"):
        resolve_domain_id(300)

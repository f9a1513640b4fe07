"""Reader QoS chosen for an upstream topic (robonix_api.upstream); resolution against a real atlas is in
tests/integration/robonix_api/test_upstream_resolution.py."""

from __future__ import annotations

import pytest

from robonix_api.upstream import reader_qos


@pytest.mark.parametrize(("declared", "default", "expect"), [
    ("transient_local", "reliable", "latched"), ("latched", "best_effort", "latched"),
    ("reliable", "best_effort", "reliable"), ("sensor_data", "reliable", "sensor_data"),
    ("", "transient_local", "latched"), ("weird", "best_effort", "best_effort"),
])
def test_reader_qos(declared: str, default: str, expect: str) -> None:
    assert reader_qos(declared, default) == expect

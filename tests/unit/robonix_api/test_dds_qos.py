"""QoS presets (publish-time validation needs a participant:
tests/integration/robonix_api/test_dds_qos_validation.py)."""

from __future__ import annotations

import pytest
from cyclonedds.core import Policy

from robonix_api.dds import (
    QOS_NAMES,
    qos_profile,
)
from robonix_api.dds.qos import describe


@pytest.mark.parametrize(("name", "rel", "dur", "depth"), [
    ("best_effort", "best_effort", "volatile", 10),
    ("reliable", "reliable", "volatile", 10),
    ("latched", "reliable", "transient_local", 1),
    ("transient_local", "reliable", "transient_local", 1),
    ("sensor_data", "best_effort", "volatile", 5),
    ("clock", "best_effort", "volatile", 1),
])
def test_presets(name: str, rel: str, dur: str, depth: int) -> None:
    q = qos_profile(name)
    assert describe(q) == {"reliability": rel, "durability": dur, "depth": depth}
    assert q[Policy.DataRepresentation] == Policy.DataRepresentation(use_cdrv0_representation=True)
    assert describe(qos_profile(name, depth=42))["depth"] == 42


def test_transient_local_is_latched() -> None:
    assert qos_profile("transient_local") == qos_profile("latched")


def test_unknown_preset_lists_valid_names() -> None:
    with pytest.raises(ValueError, match="unknown QoS preset 'durable'") as e:
        qos_profile("durable")
    for n in QOS_NAMES:
        assert n in str(e.value)

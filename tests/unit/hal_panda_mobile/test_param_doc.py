"""hal_panda_mobile/CAPABILITY.md's noise tables are generated from the simulator's dataclasses (one
declaration per parameter); CMD_INIT rejects a value outside the declared range, naming the field."""

from __future__ import annotations

import dataclasses

import pytest

from hal_panda_mobile.config import parse_config
from hal_panda_mobile.param_doc import BLOCKS, CAPABILITY_MD, rendered
from hal_panda_mobile.sim import SimConfigError


def test_capability_md_noise_tables_are_current() -> None:
    text = CAPABILITY_MD.read_text()
    assert rendered(text) == text, "hal_panda_mobile/CAPABILITY.md is stale: run python -m hal_panda_mobile.param_doc"
    for cls in BLOCKS.values():
        for f in dataclasses.fields(cls):
            assert f.metadata.get("description"), f"{cls.__name__}.{f.name} has no doc"
            assert f"| `{f.name}` |" in text


@pytest.mark.parametrize(("raw", "message"), [
    ({"odom_noise": {"v_add_std": -0.1}}, "odom_noise.v_add_std: must be >= 0"),
    ({"lidar_noise": {"dropout_prob": 1.5}}, "lidar_noise.dropout_prob: must be <= 1"),
    ({"odom_noise": {"v_add": 0.1}}, "odom_noise.v_add: unknown field"),
])
def test_cmd_init_checks_the_declared_ranges(raw: dict, message: str) -> None:
    with pytest.raises(SimConfigError, match=f"^{message}"):
        parse_config(raw)

"""The SLAM parameter reference in CAPABILITY.md is generated from SlamConfig's one declaration per field,
and the INIT config is checked against the same ranges."""

from __future__ import annotations

import dataclasses
import re

import pytest

from robonix_common.params import ParamError
from slam_service.config import ConfigError, parse_config
from slam_service.core import SlamConfig
from slam_service.param_doc import CAPABILITY_MD, rendered


def test_capability_md_parameter_table_is_current() -> None:
    text = CAPABILITY_MD.read_text()
    assert rendered(text) == text, "slam_service/CAPABILITY.md is stale: run python -m slam_service.param_doc"


def test_every_numeric_parameter_declares_a_doc_and_the_table_lists_it() -> None:
    text = CAPABILITY_MD.read_text()
    for f in dataclasses.fields(SlamConfig):
        assert f.metadata.get("description"), f"SlamConfig.{f.name} has no doc"
        assert f"| `{f.name}` |" in text


@pytest.mark.parametrize(("field", "value", "message"), [
    ("resolution", 1e-9, "within [0.005, 1]"), ("search_window_xy", 0.0, "within (0, 5]"),
    ("log_odds_miss", 0.1, "< 0"), ("grid_chunk", 4, "within [8, 4096]"),
])
def test_one_range_for_python_and_config(field: str, value: float, message: str) -> None:
    expected = re.escape(f"{field}: must be {message}, got {value:g}")
    with pytest.raises(ParamError, match=rf"^SlamConfig\.{expected}$"):
        SlamConfig(**{field: value})
    with pytest.raises(ConfigError, match=rf"^slam\.{expected}$"):
        parse_config({"slam": {field: value}})

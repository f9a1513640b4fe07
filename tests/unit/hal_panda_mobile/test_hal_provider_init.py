"""Bad HAL configs are refused naming the field (the same list drives the provider process in
tests/integration/hal_panda_mobile/test_hal_provider_init_process.py)."""

from __future__ import annotations

import pytest

from hal_panda_mobile.config import build_sim, parse_config
from hal_panda_mobile.sim import SimConfigError

BAD = [
    ({"scene": "foo"}, "scene: unknown scene 'foo'"),
    ({"scene": {"walls": "not-a-list"}}, "scene: "),
    ({"scene": "apartment", "start": {"x": 2.5, "y": 0.6}}, "start: pose (2.5, 0.6, 0) collides with"),
    ({"rates": {"scan_rate_hz": -1}}, "rates.scan_rate_hz: must be > 0"),
    ({"rates": {"odom_rate_hz": 0}}, "rates.odom_rate_hz: must be > 0"),
    ({"real_time_factor": -2}, "real_time_factor: must be >= 0"),
    ({"topics": {"scan": "bad topic"}}, "topics.scan"),
    ({"odom_noise": "weird"}, "odom_noise: must be 'none', 'realistic'"),
    ({"scene": {"from_map": "/nonexistent/map.yaml"}}, "scene: from_map:"),
    ({"bogus": 1}, "bogus: unknown field"),
]


@pytest.mark.parametrize(("cfg", "needle"), BAD)
def test_config_errors_name_the_field(cfg: dict, needle: str) -> None:
    with pytest.raises(SimConfigError) as exc:
        build_sim(parse_config(cfg))
    assert needle in str(exc.value)

"""The config: blocks of the example deploys are valid for the providers they go to.

rbnx validates deploy structure; this catches drift between an example and a provider's config model
(a renamed key would otherwise only show up as an Err at CMD_INIT).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from hal_panda_mobile.config import parse_config as parse_hal
from nav2_wrapper.config import parse_config as parse_nav
from rbnx.models import load_deploy
from slam_service.config import parse_config as parse_slam

REPO = Path(__file__).resolve().parents[3]
PARSERS = {"hal_panda_mobile": parse_hal, "slam_service": parse_slam, "nav2_wrapper": parse_nav}
EXAMPLES = [REPO / "examples" / "sim" / "deploy.yaml", REPO / "examples" / "real_robot" / "deploy.yaml"]


@pytest.mark.parametrize("deploy", EXAMPLES, ids=lambda p: p.parent.name)
def test_example_entry_configs_parse(deploy: Path) -> None:
    resolved = load_deploy(deploy)
    seen = set()
    for entry in resolved.entries:
        parser = PARSERS[entry.manifest.package.name]
        parser(dict(entry.config or {}))  # raises naming the field on drift
        seen.add(entry.manifest.package.name)
    assert "nav2_wrapper" in seen
    assert "slam_service" in seen

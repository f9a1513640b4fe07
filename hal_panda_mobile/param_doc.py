"""The ``odom_noise`` / ``lidar_noise`` tables of ``hal_panda_mobile/CAPABILITY.md``, generated from the
simulator's dataclasses (``python -m hal_panda_mobile.param_doc`` rewrites them; a test fails when stale)."""

from __future__ import annotations

from pathlib import Path

from hal_panda_mobile.sim import LidarNoise, OdomNoise
from robonix_common.params import render_doc

CAPABILITY_MD = Path(__file__).with_name("CAPABILITY.md")
BLOCKS: dict[str, type] = {"odom-noise": OdomNoise, "lidar-noise": LidarNoise}


def rendered(text: str) -> str:
    """``text`` (CAPABILITY.md) with the generated tables in their blocks."""
    return render_doc(text, BLOCKS)


if __name__ == "__main__":
    CAPABILITY_MD.write_text(rendered(CAPABILITY_MD.read_text()))

"""The ``slam`` parameter table of ``slam_service/CAPABILITY.md``, generated from :class:`SlamConfig`.

``python -m slam_service.param_doc`` rewrites the table in place; ``tests/unit/slam_service/test_param_doc.py`` fails
when the file is stale, so the declaration on the dataclass stays the only one a reader has to trust.
"""

from __future__ import annotations

from pathlib import Path

from robonix_common.params import render_doc
from slam_service.core import SlamConfig

CAPABILITY_MD = Path(__file__).with_name("CAPABILITY.md")
BLOCKS: dict[str, type] = {"slam-parameters": SlamConfig}


def rendered(text: str) -> str:
    """``text`` (CAPABILITY.md) with the generated tables in their blocks."""
    return render_doc(text, BLOCKS)


if __name__ == "__main__":
    CAPABILITY_MD.write_text(rendered(CAPABILITY_MD.read_text()))

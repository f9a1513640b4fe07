"""The ``slam`` parameter table of ``slam_service/CAPABILITY.md``, generated from :class:`SlamConfig`.

``python -m slam_service.param_doc`` rewrites the table in place; ``tests/slam/test_param_doc.py`` fails
when the file is stale, so the declaration on the dataclass stays the only one a reader has to trust.
"""

from __future__ import annotations

import sys
from pathlib import Path

from robonix_common.params import markdown_table, replace_block
from slam_service.core import SlamConfig

CAPABILITY_MD = Path(__file__).with_name("CAPABILITY.md")
BLOCK = "slam-parameters"


def rendered(text: str) -> str:
    """``text`` (CAPABILITY.md) with the generated table in its block."""
    return replace_block(text, BLOCK, markdown_table(SlamConfig))


def main() -> int:
    text = CAPABILITY_MD.read_text()
    new = rendered(text)
    if new != text:
        CAPABILITY_MD.write_text(new)
        print(f"updated {CAPABILITY_MD}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

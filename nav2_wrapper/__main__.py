"""``python -m nav2_wrapper``: the navigation provider (same as ``python -m nav2_wrapper.atlas_bridge``)."""

from __future__ import annotations

import sys

from nav2_wrapper.atlas_bridge import main

if __name__ == "__main__":
    sys.exit(main())

"""``python -m slam_service``: register with the atlas, serve the Driver and map RPCs until shutdown."""

from __future__ import annotations

import logging
import os
import sys


def main() -> int:
    logging.basicConfig(level=os.environ.get("SLAM_LOG_LEVEL", "INFO").upper(),
                        format="%(asctime)s %(levelname)s %(name)s: %(message)s", stream=sys.stderr)
    from slam_service.provider import build_provider

    provider = build_provider()
    provider.svc.run()  # blocks until CMD_SHUTDOWN or SIGTERM/SIGINT; tears down cleanly
    return 0


if __name__ == "__main__":
    sys.exit(main())

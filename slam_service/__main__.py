"""``python -m slam_service``: register with the atlas, serve the Driver and map RPCs until shutdown."""

from __future__ import annotations

import sys


def main() -> int:
    from robonix_api.logsetup import setup_logging

    setup_logging("SLAM_LOG_LEVEL")
    from slam_service.provider import build_provider

    provider = build_provider()
    provider.svc.run()  # blocks until CMD_SHUTDOWN or SIGTERM/SIGINT; tears down cleanly
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""``python -m hal_panda_mobile``: register with the atlas, serve the Driver, run until shutdown."""

from __future__ import annotations

import sys


def main() -> int:
    from robonix_api.logsetup import setup_logging

    setup_logging("HAL_LOG_LEVEL")
    from hal_panda_mobile.provider import build_provider

    hal = build_provider()
    hal.prim.run()  # blocks until CMD_SHUTDOWN or SIGTERM/SIGINT; tears down cleanly
    return 0


if __name__ == "__main__":
    sys.exit(main())

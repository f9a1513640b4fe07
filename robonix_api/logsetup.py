"""One log format for every provider process (stderr, which `rbnx boot` writes to <log-dir>/<name>.log)."""

from __future__ import annotations

import logging
import os
import sys

FORMAT = "%(asctime)s %(levelname)s %(name)s: %(message)s"


def setup_logging(level_env: str, default: str = "INFO") -> None:
    """Configure the root logger; the level comes from ``$<level_env>`` (e.g. HAL_LOG_LEVEL=DEBUG)."""
    logging.basicConfig(level=os.environ.get(level_env, default).upper(), format=FORMAT, stream=sys.stderr)

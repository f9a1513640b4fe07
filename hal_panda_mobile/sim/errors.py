"""One error type for every bad input to the simulator core.

A provider turns it into ``Err(message)`` from CMD_INIT, so the message must name the field at fault.
"""

from __future__ import annotations


class SimConfigError(ValueError):
    """Bad robot description, scene, sim parameter or pose; the message names the field."""

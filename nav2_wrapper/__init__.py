"""robonix navigation service: a pure-Python Nav2-like core (``nav2_wrapper.core``) plus params profiles.

The provider (``nav2_wrapper.provider``, run by ``python -m nav2_wrapper``) wraps the core; the core
itself does no I/O. Layout as in every provider here: ``provider`` (lifecycle), ``handlers`` (contracts),
``config``, ``loop`` (the control loop), plus ``inputs``, ``speed``, ``goals``, ``upstream`` and ``params``.
Params profiles: the core config fields declare each parameter (``robonix_common.params``), ``params_schema``
maps YAML keys to them, ``params`` validates and builds, ``paramdoc`` writes the reference into
CAPABILITY.md; ``robot_io`` reads the robot description (footprint, limits) the core is given.
"""

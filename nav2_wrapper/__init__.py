"""robonix navigation service: a pure-Python Nav2-like core (``nav2_wrapper.core``) plus params profiles.

The provider (``nav2_wrapper.provider``, run by ``python -m nav2_wrapper``) wraps the core; the core
itself does no I/O. Layout as in every provider here: ``provider`` (lifecycle), ``handlers`` (contracts),
``config``, ``loop`` (the control loop), plus ``inputs``, ``speed``, ``goals``, ``upstream`` and ``params``.
"""

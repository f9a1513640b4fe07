"""robonix navigation service: a pure-Python Nav2-like core (``nav2_wrapper.core``) plus params profiles.

The provider (``atlas_bridge``) wraps the core; the core itself does no I/O.
"""

"""The robonix atlas: capability registry server (``atlas.server``), its pure registry logic
(``atlas.registry``) and the contract catalogue (``atlas.catalogue``, TOML files in ``atlas/contracts``)."""

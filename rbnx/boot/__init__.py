"""Booting a deployment: what `rbnx boot` (and `rbnx start`, `rbnx shutdown`) run underneath.

- :mod:`~rbnx.boot.orchestrator`: the atlas, every entry through INIT/ACTIVATE, the gateway, teardown;
- :mod:`~rbnx.boot.entry`: one deploy entry's process and lifecycle (start, Driver calls, stop);
- :mod:`~rbnx.boot.supervise`: restart policies for entries and the atlas;
- :mod:`~rbnx.boot.procs`: process groups (spawn, parent-death signal, the stop ladder);
- :mod:`~rbnx.boot.statefile`, :mod:`~rbnx.boot.deployment`, :mod:`~rbnx.boot.deploytoken`: what a running
  boot records (state file, run dir, token) and how other commands find it;
- :mod:`~rbnx.boot.progress`, :mod:`~rbnx.boot.backoff`: the live progress table and retry back-off.

Kept empty on purpose: ``rbnx token`` or ``rbnx validate`` import one of these without the rest.
"""

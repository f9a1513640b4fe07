"""Find the running boot of one deployment (deploy file + its atlas listen address) for shutdown/logs.

Kept strict on purpose: `rbnx shutdown -f A` must never pick the state of another deployment of the
same file that runs against a different atlas address.
"""

from __future__ import annotations

from pathlib import Path

from rbnx.boot.statefile import find_states, read_state
from rbnx.models import ManifestProblems, load_deploy


class StateNotFound(LookupError):
    """No (or no unique) running boot for the deployment; the message says which and how to pick."""


def deploy_listen(path: Path) -> str:
    """The deploy's atlas listen address as the boot saw it (environment expanded); '' if unreadable."""
    try:
        return load_deploy(path).atlas_listen
    except ManifestProblems:
        return ""


def locate_state(path: Path, atlas: str | None = None) -> Path:
    """The state file of the one running boot of ``path`` with the current environment's listen address.

    Several boots of one file with an OS-picked port (``:0``) are told apart by ``atlas`` (the address
    each boot reports); without it the choice is refused rather than guessed.
    """
    listen = deploy_listen(path)
    states = {p: read_state(p) for p in find_states(path, listen)}
    found = [p for p, st in states.items() if st is not None]
    if len(found) > 1 and atlas:
        found = [p for p in found if (states[p] or {}).get("atlas") == atlas] or found
    if not found:
        where = f" with atlas {listen}" if listen else ""
        raise StateNotFound(f"no running boot recorded for {path}{where}")
    if len(found) > 1:
        addrs = ", ".join(str((states[p] or {}).get("atlas") or "?") for p in found)
        raise StateNotFound(f"{len(found)} boots of {path} run (atlas {addrs}); pick one with --atlas ADDR")
    return found[0]

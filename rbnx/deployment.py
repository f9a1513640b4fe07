"""Find the running boot of one deployment (deploy file + its atlas listen address) for shutdown/logs.

Kept strict on purpose: `rbnx shutdown -f A` must never pick the state of another deployment of the
same file that runs against a different atlas address.
"""

from __future__ import annotations

from pathlib import Path

from rbnx.models import ManifestProblems, load_deploy
from rbnx.statefile import find_states, read_state


class StateNotFound(LookupError):
    """No (or no unique) running boot for the deployment; the message says which and how to pick."""


def deploy_listen(path: Path) -> str:
    """The deploy's atlas listen address as the boot saw it (environment expanded); '' if unreadable."""
    try:
        return load_deploy(path).atlas_listen
    except ManifestProblems:
        return ""


def locate_state(path: Path) -> Path:
    """The state file of the one running boot of ``path`` with the current environment's listen address."""
    listen = deploy_listen(path)
    found = [p for p in find_states(path, listen) if read_state(p) is not None]
    if not found:
        where = f" with atlas {listen}" if listen else ""
        raise StateNotFound(f"no running boot recorded for {path}{where}")
    if len(found) > 1:
        raise StateNotFound(f"{len(found)} boots of {path} with an OS-picked atlas port run; stop them by "
                            "their state file (" + ", ".join(str(p) for p in found) + ") or give each a port")
    return found[0]

"""Provider identity from the environment and the package folder (robonix conventions).

``rbnx boot`` names each instance through ``RBNX_INSTANCE_NAME``; the package's CAPABILITY.md (found
next to its ``package_manifest.yaml``) is sent to the atlas so agents can read what the package does.
"""

from __future__ import annotations

import inspect
import os
from pathlib import Path

MANIFEST = "package_manifest.yaml"
_SDK_DIR = Path(__file__).resolve().parent


def resolve_id(id: str) -> str:
    """``RBNX_INSTANCE_NAME`` overrides ``id``; under ``RBNX_DEPLOY_MANAGED`` it must be non-empty."""
    env = os.environ.get("RBNX_INSTANCE_NAME", "").strip()
    if os.environ.get("RBNX_DEPLOY_MANAGED", "").strip() and not env:
        raise ValueError("RBNX_DEPLOY_MANAGED is set but RBNX_INSTANCE_NAME is empty: "
                         "a deploy-managed provider needs its instance name from rbnx")
    return env or id


def caller_file() -> Path | None:
    """The source file of the first stack frame outside this SDK (the package author's module)."""
    for frame in inspect.stack(context=0)[1:]:
        path = Path(frame.filename)
        if not path.is_file():
            continue
        path = path.resolve()
        if _SDK_DIR not in path.parents:
            return path
    return None


def find_pkg_root(start: Path | None) -> Path | None:
    """Nearest folder at or above ``start`` holding ``package_manifest.yaml``."""
    if start is None:
        return None
    here = start if start.is_dir() else start.parent
    for folder in (here, *here.parents):
        if (folder / MANIFEST).is_file():
            return folder
    return None


def capability_md(pkg_root: Path | None, md_path: str | os.PathLike[str] | None) -> tuple[str, str]:
    """(path, text) of the CAPABILITY.md to send; ("", "") when there is none."""
    if md_path is not None:
        path = Path(md_path)
        if not path.is_absolute() and pkg_root is not None:
            path = pkg_root / path
    elif pkg_root is not None:
        path = pkg_root / "CAPABILITY.md"
    else:
        return "", ""
    try:
        return str(path), path.read_text(encoding="utf-8")
    except OSError:
        if md_path is not None:  # asked for explicitly: say so rather than silently sending nothing
            raise FileNotFoundError(f"md_path: cannot read {path}") from None
        return "", ""

"""`rbnx demo` options that change the simulated robot: a copy of the deploy file with them applied.

The deploy file stays the single description of the system; an option like ``--lidar-noise`` only adds
keys to the simulator primitive's ``config`` in a copy written to the demo's output directory (package
paths made absolute, since they are relative to the file), so the run's own deploy is kept with its logs.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

SECTIONS = ("primitive", "service", "skill")


def sim_entries(raw: dict[str, Any]) -> list[dict[str, Any]]:
    """The primitives that run the simulated HAL (their path names the hal_panda_mobile package)."""
    return [e for e in raw.get("primitive") or [] if isinstance(e, dict)
            and Path(str(e.get("path", ""))).name == "hal_panda_mobile"]


def write_variant(deploy: Path, out_dir: Path, sim_config: dict[str, Any]) -> Path:
    """``deploy`` with ``sim_config`` merged into the simulator's config, written as OUT/deploy.yaml.

    Raises ValueError when the deploy file has no simulator primitive to apply the options to."""
    raw = yaml.safe_load(deploy.read_text()) or {}
    sims = sim_entries(raw)
    if not sims:
        raise ValueError(f"{deploy}: no hal_panda_mobile primitive to apply the simulator options to")
    base = deploy.resolve().parent
    for section in SECTIONS:
        for e in raw.get(section) or []:
            if isinstance(e, dict) and e.get("path") is not None:
                e["path"] = str((base / str(e["path"])).resolve())
    for e in sims:
        e["config"] = {**(e.get("config") or {}), **sim_config}
    out_dir.mkdir(parents=True, exist_ok=True)
    target = out_dir / "deploy.yaml"
    target.write_text(f"# {deploy} with the demo's simulator options applied\n"
                      + yaml.safe_dump(raw, sort_keys=False))
    return target

"""What several commands share: the ``-f`` deploy-file argument, the default log directory, ``-s KEY=VALUE``
config overrides, and whether a recorded boot still runs."""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import yaml

from rbnx.boot.procs import pid_alive
from rbnx.models import DEFAULT_DEPLOY, ManifestProblems


def deploy_arg(sp: argparse.ArgumentParser) -> None:
    """The ``-f/--file`` option of commands that act on one deploy file."""
    sp.add_argument("-f", "--file", default=DEFAULT_DEPLOY, help=f"deploy file (default {DEFAULT_DEPLOY})")


def default_log_dir() -> Path:
    """``./rbnx-logs/<timestamp>``: where a boot's logs go unless ``--log-dir`` says otherwise."""
    return Path("rbnx-logs") / time.strftime("%Y%m%d-%H%M%S")


def boot_alive(st: dict[str, Any]) -> bool:
    """Whether the rbnx process that wrote this state file still runs (same PID and start time)."""
    return bool(st.get("pid")) and pid_alive(int(st["pid"]), st.get("start_ticks"))


def recorded_alive(st: dict[str, Any]) -> bool:
    """Whether any child or the atlas listed in this state file still runs (the boot itself may be gone)."""
    procs = [*(st.get("children") or []), *([st["atlas_proc"]] if st.get("atlas_proc") else [])]
    return any(p.get("pid") and pid_alive(int(p["pid"]), p.get("start_ticks")) for p in procs)


def parse_sets(items: list[str], config: dict[str, Any]) -> None:
    """`-s a.b=3` sets config['a']['b'] = 3 (values parsed as YAML scalars)."""
    for item in items:
        key, sep, raw = item.partition("=")
        if not sep or not key:
            raise ManifestProblems([f"--set {item!r}: expected KEY=VALUE"])
        try:
            value = yaml.safe_load(raw) if raw else ""
        except yaml.YAMLError:
            value = raw
        node = config
        parts = key.split(".")
        for part in parts[:-1]:
            nxt = node.get(part)
            if not isinstance(nxt, dict):
                nxt = node[part] = {}
            node = nxt
        node[parts[-1]] = value

"""rbnx/commands: one module per command, each registering itself; the CLI stays light to import."""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import subprocess
import sys

import rbnx.commands
from rbnx.cli import build_parser
from rbnx.commands import COMMANDS

#: Modules in rbnx/commands that hold shared helpers, not a command.
HELPERS = {"common", "atlas_view"}


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


def test_every_command_module_is_listed_and_has_register_and_run() -> None:
    found = {m.name for m in pkgutil.iter_modules(rbnx.commands.__path__)} - HELPERS
    assert found == set(COMMANDS)
    for name in COMMANDS:
        mod = importlib.import_module(f"rbnx.commands.{name}")
        assert callable(mod.register), name
        assert callable(mod.run), name


def test_each_parser_runs_its_own_module() -> None:
    subs = _subparsers(build_parser())
    # the command name is the module name with "-" for "_"; "deploy" is boot's alias
    assert set(subs) == {n.replace("_", "-") for n in COMMANDS} | {"deploy"}
    for cmd, sp in subs.items():
        module = "boot" if cmd == "deploy" else cmd.replace("-", "_")
        assert sp.get_default("run") is importlib.import_module(f"rbnx.commands.{module}").run, cmd


def test_help_lists_commands_in_registry_order() -> None:
    """`rbnx --help` lists the commands in COMMANDS order (deploy, boot's alias, right after boot)."""
    expected = [n.replace("_", "-") for n in COMMANDS]
    expected.insert(1, "deploy")
    assert list(_subparsers(build_parser())) == expected


def test_cli_import_loads_no_simulator_planner_or_mcp_stack() -> None:
    """`rbnx <cmd>` and `rbnx boot` parse their arguments without MuJoCo, scipy, numba, MCP or DDS."""
    code = ("import sys, rbnx.cli; rbnx.cli.build_parser(); "
            "print(' '.join(m for m in ('mujoco', 'scipy', 'numba', 'mcp', 'cyclonedds', 'starlette') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True)
    assert out.stdout.strip() == ""

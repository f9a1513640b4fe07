"""`$VAR` / `${VAR}` / `${VAR:-default}` expansion for deploy files.

Deploy files are shared between machines, so an undefined variable is reported as a problem (with the
key path) instead of silently becoming an empty string; `$$` is a literal dollar.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

_VAR = re.compile(r"\$(?:\$|\{(?P<braced>[A-Za-z_][A-Za-z0-9_]*)(?::-(?P<default>[^}]*))?\}"
                  r"|(?P<bare>[A-Za-z_][A-Za-z0-9_]*))")


class UndefinedVariable(KeyError):
    """Raised with the variable name when a string refers to an unset variable."""


def expand_str(text: str, env: Mapping[str, str]) -> str:
    """Expand one string; raises UndefinedVariable for an unset variable without a default."""

    def repl(m: re.Match[str]) -> str:
        if m.group(0) == "$$":
            return "$"
        name = m.group("braced") or m.group("bare")
        if name in env:
            return env[name]
        if m.group("default") is not None:
            return m.group("default")
        raise UndefinedVariable(name)

    return _VAR.sub(repl, text)


def expand_tree(value: Any, env: Mapping[str, str], path: str, problems: list[str]) -> Any:
    """Expand every string (not keys) in a YAML tree; each unset variable adds a problem at its path."""
    if isinstance(value, str):
        try:
            return expand_str(value, env)
        except UndefinedVariable as exc:
            problems.append(f"{path}: undefined variable ${exc.args[0]}")
            return value
    if isinstance(value, list):
        return [expand_tree(v, env, f"{path}[{i}]", problems) for i, v in enumerate(value)]
    if isinstance(value, dict):
        return {k: expand_tree(v, env, f"{path}.{k}" if path else str(k), problems) for k, v in value.items()}
    return value


def apply_env_section(section: Mapping[str, Any], base: Mapping[str, str], problems: list[str]) -> dict[str, str]:
    """Build the child environment: `env:` entries in order, each value expanded against what came before."""
    env = dict(base)
    for key, raw in section.items():
        if raw is None:
            raw = ""
        if isinstance(raw, bool):
            raw = "true" if raw else "false"
        if not isinstance(raw, str | int | float):
            problems.append(f"env.{key}: must be a string or number, not {type(raw).__name__}")
            continue
        try:
            env[str(key)] = expand_str(str(raw), env)
        except UndefinedVariable as exc:
            problems.append(f"env.{key}: undefined variable ${exc.args[0]}")
    return env

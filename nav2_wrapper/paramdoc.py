"""Render the params-profile reference in CAPABILITY.md from the parameter tables (never edited by hand).

    python -m nav2_wrapper.paramdoc --write    # rewrite the generated block in nav2_wrapper/CAPABILITY.md
    python -m nav2_wrapper.paramdoc --check    # exit 1 when the block is stale (a test runs this check)
"""

from __future__ import annotations

import argparse
import sys
import typing
from pathlib import Path
from typing import Any

from . import params_schema as ps

CAPABILITY_MD = Path(__file__).with_name("CAPABILITY.md")
BEGIN = "<!-- BEGIN generated parameter reference: python -m nav2_wrapper.paramdoc --write -->"
END = "<!-- END generated parameter reference -->"


def _type_name(tp: Any) -> str:
    origin = typing.get_origin(tp)
    if origin in (list, tuple):
        return f"list of {_type_name(typing.get_args(tp)[0])}"
    args = [a for a in typing.get_args(tp) if a is not type(None)]
    if args:
        return _type_name(args[0])
    return {bool: "bool", int: "int", float: "float", str: "string"}.get(tp, str(tp))


def _optional(tp: Any) -> bool:
    """Whether ``None`` is a valid value of the type (then a None default means "not set", not "required")."""
    return type(None) in typing.get_args(tp)


def _value(v: Any) -> str:
    if v is None:
        return "(required)"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return f'"{v}"' if v == "" or v.strip() != v else v
    return str(v)


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def _section(sec: ps.Section) -> list[str]:
    title = f"### `{sec.title}`"
    if sec.plugins:
        title += " — plugin " + ", ".join(f"`{p}`" for p in sec.plugins)
    lines = [title, ""]
    if sec.doc:
        lines += [sec.doc, ""]
    lines += ["| key | type | default | unit | range | meaning |", "|---|---|---|---|---|---|"]
    for k in sec.keys:
        meaning = k.spec.doc + (f" ({ps.COMPAT_NOTE})" if k.compat else "")
        default = "(unset)" if k.default is None and _optional(k.type) else _value(k.default)
        lines.append(f"| `{k.name}` | {_type_name(k.type)} | `{_cell(default)}` | {k.spec.unit} | "
                     f"{_cell(k.spec.range_text())} | {_cell(meaning)} |")
    return [*lines, ""]


def render() -> str:
    """The generated block, markers included."""
    lines = [BEGIN, "", "## Params profile reference (generated)", "",
             "Every key a params profile may set, per node and plugin section (`ros__parameters` of each node; "
             "a plugin's keys sit under the section name listed in the node's `*_plugins`). A value out of range "
             "is an error naming its key path; a key not listed here is warned about by name and ignored; a key "
             f"marked *{ps.COMPAT_NOTE}* is type-checked and listed in one log line.", ""]
    for sec in ps.SECTIONS:
        lines += _section(sec)
    return "\n".join([*lines, END])


def splice(text: str, block: str) -> str:
    """``text`` with its generated block replaced by ``block`` (appended when there is none yet)."""
    if BEGIN in text and END in text:
        head, rest = text.split(BEGIN, 1)
        tail = rest.split(END, 1)[1]
        return head + block + tail
    return text.rstrip("\n") + "\n\n" + block + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m nav2_wrapper.paramdoc", description=__doc__.split("\n")[0])
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--write", action="store_true", help=f"rewrite the block in {CAPABILITY_MD.name}")
    mode.add_argument("--check", action="store_true", help="exit 1 when the block is stale")
    args = ap.parse_args(argv)
    block = render()
    if not (args.write or args.check):
        print(block)
        return 0
    current = CAPABILITY_MD.read_text()
    wanted = splice(current, block)
    if args.check:
        if wanted != current:
            print(f"{CAPABILITY_MD}: parameter reference is stale; run python -m nav2_wrapper.paramdoc --write",
                  file=sys.stderr)
            return 1
        return 0
    if wanted != current:
        CAPABILITY_MD.write_text(wanted)
    print(f"{CAPABILITY_MD}: parameter reference {'updated' if wanted != current else 'already current'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

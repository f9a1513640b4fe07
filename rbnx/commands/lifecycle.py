"""`rbnx lifecycle`: the gateway's lifecycle verbs for a person at a terminal.

``rbnx lifecycle`` lists the entries of a running boot; ``rbnx lifecycle ENTRY VERB`` runs one verb.
It goes through the boot's MCP gateway when the boot serves one (so a configure patch lands on the
same config the agent sees), else drives the Drivers directly from the deploy file.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
from pathlib import Path
from typing import Any

from rbnx.boot.deployment import StateNotFound, locate_state
from rbnx.boot.statefile import read_state
from rbnx.commands.common import parse_sets
from rbnx.models import DEFAULT_DEPLOY, ManifestProblems, load_deploy

VERBS = ("status", "activate", "deactivate", "configure", "reset", "cleanup", "shutdown")


def register(sub: Any) -> None:
    """``lifecycle [-f DEPLOY] [ENTRY [VERB]]``."""
    lc = sub.add_parser("lifecycle", help="list a running boot's entries, or activate/deactivate/configure/reset one")
    lc.add_argument("-f", "--file", default=DEFAULT_DEPLOY, help=f"deploy file of the running boot "
                                                               f"(default {DEFAULT_DEPLOY})")
    lc.add_argument("entry", nargs="?", help="entry name (omit to list every entry)")
    lc.add_argument("verb", nargs="?", choices=VERBS, help="what to do (default status)")
    lc.add_argument("-s", "--set", action="append", metavar="KEY=VALUE",
                    help="configure: config change (repeatable; dotted keys, YAML values)")
    lc.add_argument("--patch", help="configure: a JSON merge patch of the entry's config")
    lc.add_argument("--json", action="store_true", help="print the result as JSON")
    lc.add_argument("--atlas", help="which boot, when several of the deploy file run (their atlas address)")
    lc.set_defaults(run=run)


def _patch(args: argparse.Namespace) -> dict[str, Any]:
    patch: dict[str, Any] = {}
    if args.patch:
        try:
            patch = json.loads(args.patch)
        except json.JSONDecodeError as exc:
            raise ManifestProblems([f"--patch: invalid JSON: {exc}"]) from None
        if not isinstance(patch, dict):
            raise ManifestProblems(["--patch: must be a JSON object"])
    parse_sets(args.set or [], patch)
    if not patch:
        raise ManifestProblems(["configure: give the change with -s KEY=VALUE or --patch JSON"])
    return patch


def _request(args: argparse.Namespace) -> tuple[str, dict[str, Any]]:
    """(gateway tool, arguments) for the command line; usage problems raise ManifestProblems (exit 2)."""
    if not args.entry:
        if args.verb:
            raise ManifestProblems(["rbnx lifecycle: name an entry before the verb"])
        return "list_services", {}
    verb = args.verb or "status"
    if verb != "configure" and (args.set or args.patch):
        raise ManifestProblems([f"-s/--patch only go with configure, not {verb}"])
    if verb == "status":
        return "list_services", {}
    if verb == "configure":
        return "configure", {"entry": args.entry, "config": _patch(args)}
    return verb, {"entry": args.entry}


async def _via_gateway(url: str, tool: str, arguments: dict[str, Any]) -> tuple[bool, str, Any]:
    from robonix_api.auth import mcp_client

    async with mcp_client(url, read_timeout_seconds=300) as client:
        r = await client.call_tool(tool, arguments)
    text = "".join(getattr(c, "text", "") for c in r.content)
    return not r.is_error, text, r.structured_content


def _direct(st: dict[str, Any], tool: str, arguments: dict[str, Any]) -> tuple[bool, str, Any]:
    from rbnx.gateway import ControlError, Entry, LifecycleControl

    deploy = load_deploy(Path(st["deploy"]))
    control = LifecycleControl(st["atlas"], [Entry(e.name, e.kind, dict(e.config), e.autostart)
                                             for e in deploy.entries])
    try:
        if tool == "list_services":
            data: Any = {"services": control.list_services()}
        elif tool == "configure":
            data = control.configure(arguments["entry"], arguments["config"])
        elif tool in ("reset", "cleanup"):
            data = control.reset(arguments["entry"])
        else:
            data = getattr(control, tool)(arguments["entry"])
    except ControlError as exc:
        return False, f"{tool}: {exc}", None
    return True, json.dumps(data), data


def run(args: argparse.Namespace) -> int:
    """List a running boot's entries or run one verb, through its gateway when it serves one, else directly."""
    path = Path(args.file or DEFAULT_DEPLOY)
    tool, arguments = _request(args)
    try:
        st = read_state(locate_state(path, getattr(args, "atlas", None)))
    except StateNotFound as exc:
        print(f"rbnx lifecycle: {exc}", file=sys.stderr)
        return 1
    if st is None or not st.get("atlas"):
        print(f"rbnx lifecycle: no running boot recorded for {path}", file=sys.stderr)
        return 1
    if st.get("gateway"):
        try:
            ok, text, data = asyncio.run(_via_gateway(st["gateway"], tool, arguments))
        except Exception as exc:  # the gateway went away with its boot
            print(f"rbnx lifecycle: gateway {st['gateway']} not reachable: {type(exc).__name__}: {exc}",
                  file=sys.stderr)
            return 1
    else:
        ok, text, data = _direct(st, tool, arguments)
    if not ok:
        print(f"rbnx lifecycle: {text}", file=sys.stderr)
        return 1
    if args.json:
        print(json.dumps(data, indent=2))
    elif tool == "list_services":
        rows = [s for s in (data or {}).get("services", []) if not args.entry or s["entry"] == args.entry]
        if args.entry and not rows:
            print(f"rbnx lifecycle: unknown entry {args.entry!r}", file=sys.stderr)
            return 1
        for s in rows:
            extra = "" if s.get("autostart", True) else "  (autostart: false)"
            print(f"{s['entry']:<20} {s['kind']:<9} {s['state']:<11} {s.get('detail') or ''}{extra}".rstrip())
    else:
        print(f"{data.get('entry') or 'deployment'}: {data.get('state')}"
              + (f" ({data['detail']})" if data.get("detail") else ""))
    return 0

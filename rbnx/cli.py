"""rbnx command line: argument parsing and error-to-exit-code mapping (user errors never traceback).

Exit codes: 0 ok; 1 runtime failure (atlas unreachable, an entry failed); 2 invalid files or usage;
130 interrupted.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable

from rbnx.atlas_rpc import Atlas, AtlasError, default_atlas
from rbnx.models import DEFAULT_DEPLOY, ManifestProblems


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="rbnx", description="robonix-nav package tool: build, boot, inspect.")
    p.add_argument("--atlas", default=default_atlas(),
                   help="atlas address HOST:PORT (default $ROBONIX_ATLAS or 127.0.0.1:50051)")
    sub = p.add_subparsers(dest="cmd", metavar="COMMAND")
    sub.required = True

    def deploy_arg(sp: argparse.ArgumentParser) -> None:
        sp.add_argument("-f", "--file", default=DEFAULT_DEPLOY, help=f"deploy file (default {DEFAULT_DEPLOY})")

    for name in ("boot", "deploy"):
        b = sub.add_parser(name, help="start atlas and every package of a deploy file" if name == "boot"
                           else "alias of boot")
        deploy_arg(b)
        b.add_argument("--log-dir", help="where <name>.log files go (default ./rbnx-logs/<timestamp>)")
        b.add_argument("-v", "--verbose", action="store_true")
        b.add_argument("--boot-timeout", type=float, default=120.0,
                       help="deadline in seconds for Deferred entries to come up (default 120)")
        b.add_argument("--term-timeout", type=float, default=30.0,
                       help="seconds between SIGTERM and SIGKILL at shutdown (default 30)")
        b.add_argument("--no-progress", action="store_true", help="no live progress view")
        b.add_argument("--exit-after-boot", action="store_true",
                       help="return after boot, leaving packages running (stop with rbnx shutdown)")
        b.add_argument("--no-gateway", action="store_true", help="do not serve the deployment's MCP gateway")
        b.add_argument("--dashboard", type=int, nargs="?", const=8765, metavar="PORT",
                       help="also serve the live dashboard on 127.0.0.1:PORT (default 8765)")
        b.add_argument("--serial", action="store_true",
                       help="start entries one at a time instead of all at once")

    s = sub.add_parser("shutdown", help="stop a running boot of a deploy file")
    deploy_arg(s)
    s.add_argument("--timeout", type=float, default=180.0, help="how long to wait for the boot to finish")
    s.add_argument("--term-timeout", type=float, default=30.0)

    bl = sub.add_parser("build", help="run packages' build: steps")
    g = bl.add_mutually_exclusive_group()
    g.add_argument("-f", "--file", help=f"deploy file (default {DEFAULT_DEPLOY})")
    g.add_argument("-p", "--package", action="append", help="package directory (repeatable)")
    bl.add_argument("-m", "--manifest", help="target: package_manifest.<target>.yaml (with -p)")
    bl.add_argument("--clean", action="store_true", help="set RBNX_BUILD_CLEAN=1")
    bl.add_argument("--timeout", type=float, default=3600.0)

    st = sub.add_parser("start", help="start one package against a running atlas")
    st.add_argument("-p", "--package", required=True, help="package directory or manifest file")
    st.add_argument("--endpoint", help="atlas address (default --atlas)")
    st.add_argument("-c", "--config", help="YAML file with the config passed to CMD_INIT")
    st.add_argument("-s", "--set", action="append", metavar="KEY=VALUE", help="config override (repeatable)")
    st.add_argument("-m", "--manifest", help="target: package_manifest.<target>.yaml")
    st.add_argument("--name", help="instance name (default: package name)")
    st.add_argument("--kind", choices=("primitive", "service", "skill"), default="service")
    st.add_argument("--log-dir")
    st.add_argument("--boot-timeout", type=float, default=120.0)
    st.add_argument("--term-timeout", type=float, default=30.0)
    st.add_argument("--no-progress", action="store_true")

    v = sub.add_parser("validate", help="check deploy files and package manifests")
    v.add_argument("paths", nargs="*", help=f"files or package dirs (default {DEFAULT_DEPLOY})")

    c = sub.add_parser("caps", help="providers and their capabilities")
    c.add_argument("--json", action="store_true")
    c.add_argument("-v", "--verbose", action="store_true", help="endpoints, params, heartbeat age")
    c.add_argument("--kind", choices=("primitive", "service", "skill"))
    c.add_argument("--id", help="only this provider")

    ct = sub.add_parser("contracts", help="the atlas contract catalogue")
    ct.add_argument("--prefix", default="")
    ct.add_argument("--json", action="store_true")

    d = sub.add_parser("describe", help="one provider in detail")
    d.add_argument("--provider", required=True)
    d.add_argument("--json", action="store_true")
    d.add_argument("--check", action="store_true",
                   help="health check: one line, exit 0 only if registered and not TERMINATED/ERROR")

    t = sub.add_parser("tools", help="MCP tools (mcp-transport capabilities)")
    t.add_argument("--json", action="store_true")

    ch = sub.add_parser("channels", help="open channels (from InspectAtlas)")
    ch.add_argument("--json", action="store_true")

    sub.add_parser("inspect", help="InspectAtlas JSON")

    lg = sub.add_parser("logs", help="tail the logs of a running boot")
    deploy_arg(lg)
    lg.add_argument("name", nargs="?", help="entry name (default: all)")
    lg.add_argument("-n", "--lines", type=int, default=20)

    mc = sub.add_parser("map-card", help="write a map provider's dashboard map card as a PNG")
    mc.add_argument("--provider", help="provider id (default: the one live map_card provider)")
    mc.add_argument("-o", "--output", default="map.png", help="PNG path (default map.png)")
    mc.add_argument("--timeout", type=float, default=30.0, help="RPC timeout in seconds")

    from rbnx import cmd_agents, cmd_demo, cmd_init, cmd_nav, cmd_token, record, replay
    from rbnx.dashboard import cli as dashboard_cli
    cmd_agents.add_parser(sub)
    cmd_token.add_parser(sub)
    cmd_demo.add_parser(sub)
    cmd_nav.add_parsers(sub)
    record.add_parser(sub)
    replay.add_parser(sub)
    dashboard_cli.add_parser(sub)
    cmd_init.add_parser(sub)
    return p


def _dispatch(args: argparse.Namespace) -> int:
    from rbnx import cmd_agents, cmd_build, cmd_init, cmd_lifecycle, cmd_map, cmd_query, cmd_validate

    local: dict[str, Callable[[argparse.Namespace], int]] = {
        "boot": cmd_lifecycle.cmd_boot, "deploy": cmd_lifecycle.cmd_boot, "shutdown": cmd_lifecycle.cmd_shutdown,
        "start": cmd_lifecycle.cmd_start, "logs": cmd_lifecycle.cmd_logs, "build": cmd_build.cmd_build,
        "validate": cmd_validate.cmd_validate, "lifecycle": cmd_agents.cmd_lifecycle_verb,
        "init": cmd_init.cmd_init, "token": _cmd_token,
    }
    if args.cmd == "demo":
        from rbnx import cmd_demo
        return cmd_demo.cmd_demo(args)
    from rbnx import cmd_nav, record, replay
    from rbnx.dashboard import cli as dashboard_cli

    local |= {"navigate": cmd_nav.cmd_navigate, "nav-status": cmd_nav.cmd_nav_status, "cancel": cmd_nav.cmd_cancel,
              "record": record.cmd_record, "replay": replay.cmd_replay, "dashboard": dashboard_cli.cmd_dashboard}
    if args.cmd in local:
        return local[args.cmd](args)
    remote = {"caps": cmd_query.cmd_caps, "contracts": cmd_query.cmd_contracts, "describe": cmd_query.cmd_describe,
              "tools": cmd_query.cmd_tools, "channels": cmd_query.cmd_channels, "inspect": cmd_query.cmd_inspect,
              "map-card": cmd_map.cmd_map_card}
    with Atlas(args.atlas) as atlas:
        return remote[args.cmd](args, atlas)


def _cmd_token(args: argparse.Namespace) -> int:
    from rbnx import cmd_token

    return cmd_token.cmd_token(args)


#: Commands that make their own token (boot), need none, or print it.
_NO_TOKEN = frozenset({"boot", "deploy", "demo", "validate", "init", "build", "token"})


def _adopt_token(args: argparse.Namespace) -> None:
    """Take the deployment token of the boot this command talks to (its state file; else an exported
    $ROBONIX_DEPLOY_TOKEN); the SDK's clients then send it."""
    if args.cmd in _NO_TOKEN:
        return
    from rbnx import deploytoken

    token = deploytoken.token_for_atlas(getattr(args, "endpoint", None) or args.atlas)
    if token:
        deploytoken.adopt(token)
        return
    path = getattr(args, "file", None)
    if path and args.cmd in ("shutdown", "lifecycle", "logs", "dashboard"):
        from pathlib import Path

        from rbnx.deployment import StateNotFound, locate_state
        from rbnx.statefile import read_state

        try:
            token = deploytoken.token_of_state(read_state(locate_state(Path(path), args.atlas)))
        except (StateNotFound, OSError, ValueError):
            return  # the command reports a missing boot in its own words
        if token:
            deploytoken.adopt(token)


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        _adopt_token(args)
        return _dispatch(args)
    except ManifestProblems as mp:
        for line in mp.lines:
            print(line, file=sys.stderr)
        return 2
    except AtlasError as exc:
        print(f"rbnx {args.cmd}: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0


if __name__ == "__main__":
    sys.exit(main())

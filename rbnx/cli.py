"""rbnx command line: assembles the commands of :mod:`rbnx.commands` and maps errors to exit codes (user
errors never traceback).

Exit codes: 0 ok; 1 runtime failure (atlas unreachable, an entry failed); 2 invalid files or usage;
130 interrupted.
"""

from __future__ import annotations

import argparse
import sys

from rbnx.atlas_rpc import AtlasError, default_atlas
from rbnx.commands import register_all
from rbnx.models import ManifestProblems


def _command_of(argv: list[str]) -> str | None:
    """The command word of ``argv`` (skipping the global ``--atlas VALUE``), None if there is none."""
    it = iter(argv)
    for a in it:
        if a == "--atlas":
            next(it, None)
        elif not a.startswith("-"):
            return a
    return None


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """The `rbnx` parser: global options, then each command's own (see :mod:`rbnx.commands`); given
    ``argv``, only the command it names is loaded when that is unambiguous."""
    p = argparse.ArgumentParser(prog="rbnx", description="robonix-nav package tool: build, boot, inspect.")
    p.add_argument("--atlas", default=default_atlas(),
                   help="atlas address HOST:PORT (default $ROBONIX_ATLAS or 127.0.0.1:50051)")
    sub = p.add_subparsers(dest="cmd", metavar="COMMAND")
    sub.required = True
    register_all(sub, None if argv is None else _command_of(argv))
    return p


#: Commands that make their own token (boot), need none, or print it.
_NO_TOKEN = frozenset({"boot", "deploy", "demo", "validate", "init", "build", "token"})


def _adopt_token(args: argparse.Namespace) -> None:
    """Take the deployment token of the boot this command talks to (its state file; else an exported
    $ROBONIX_DEPLOY_TOKEN); the SDK's clients then send it."""
    if args.cmd in _NO_TOKEN:
        return
    from rbnx.boot import deploytoken

    token = deploytoken.token_for_atlas(getattr(args, "endpoint", None) or args.atlas)
    if token:
        deploytoken.adopt(token)
        return
    path = getattr(args, "file", None)
    if path and args.cmd in ("shutdown", "lifecycle", "logs", "dashboard"):
        from pathlib import Path

        from rbnx.boot.deployment import StateNotFound, locate_state
        from rbnx.boot.statefile import read_state

        try:
            token = deploytoken.token_of_state(read_state(locate_state(Path(path), args.atlas)))
        except (StateNotFound, OSError, ValueError):
            return  # the command reports a missing boot in its own words
        if token:
            deploytoken.adopt(token)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = build_parser(argv).parse_args(argv)
    try:
        _adopt_token(args)
        return args.run(args)
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

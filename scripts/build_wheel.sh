#!/usr/bin/env bash
# Build the robonix-nav wheel into DIR (default ./dist) from a clean copy of the source tree, so the
# checkout gets no build/ folder and no stale files of an earlier build end up in the wheel.
#   scripts/build_wheel.sh [DIR]      # prints the wheel's path
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="$(mkdir -p "${1:-$root/dist}" && cd "${1:-$root/dist}" && pwd)"
py="${PYTHON:-python3}"
src="$(mktemp -d "${TMPDIR:-/tmp}/robonix-src.XXXXXX")"
# shellcheck disable=SC2064  # expand now: remove this very directory
trap "rm -rf '$src'" EXIT
# Symlinks stay links (robonix_nav_data/ points into the root's folders); setuptools copies their targets.
tar -C "$root" --exclude=./.git --exclude=./.venv --exclude=./venv --exclude=./build --exclude=./dist \
  --exclude='*.egg-info' --exclude=__pycache__ --exclude=./rbnx-demo --exclude=./rbnx-logs -c . | tar -C "$src" -x
rm -f "$out"/robonix_nav-*.whl
# Build isolation: pip installs what pyproject's [build-system] requires (setuptools>=68, wheel) into a
# throw-away environment, so a fresh venv (setuptools without `wheel`, or an old one) builds too.
# Offline with those already installed: RBNX_WHEEL_NO_ISOLATION=1 reuses this interpreter's.
iso=()
[ "${RBNX_WHEEL_NO_ISOLATION:-0}" = 1 ] && iso=(--no-build-isolation)
"$py" -m pip wheel -q --no-deps "${iso[@]}" -w "$out" "$src" >"$src/pip.log" 2>&1 \
  || { tail -30 "$src/pip.log" >&2; exit 1; }
ls "$out"/robonix_nav-*.whl

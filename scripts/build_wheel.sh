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
iso=(--no-build-isolation)  # reuse this interpreter's setuptools when it has one (no index needed)
"$py" -c "import setuptools" 2>/dev/null || iso=()
"$py" -m pip wheel -q --no-deps "${iso[@]}" -w "$out" "$src" >"$src/pip.log" 2>&1 \
  || { tail -30 "$src/pip.log" >&2; exit 1; }
ls "$out"/robonix_nav-*.whl

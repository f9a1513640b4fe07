#!/usr/bin/env bash
# Stop only what start.sh started for this deployment: the PID recorded by start_native.sh (checked
# against its start time, so a reused PID is never signalled), or the named container.
# Never a pattern-based kill of other processes.
set -uo pipefail
# shellcheck disable=SC1091  # common.sh is checked on its own
. "$(dirname "$0")/common.sh"
pidfile="$(rbnx_pidfile)"

if [ -f "$pidfile" ]; then
  read -r pid ticks < "$pidfile" || true
  if [[ "${pid:-}" =~ ^[0-9]+$ ]] && kill -0 "$pid" 2>/dev/null \
     && { [ -z "${ticks:-}" ] || [ "$(rbnx_start_ticks "$pid")" = "$ticks" ]; }; then
    kill -TERM "$pid"
    for _ in $(seq 1 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -0 "$pid" 2>/dev/null && kill -KILL "$pid"
  fi
  rm -f "$pidfile"
  exit 0
fi
engine="$(rbnx_engine)"
if command -v "$engine" >/dev/null 2>&1; then
  "$engine" rm -f "$(rbnx_container_name)" >/dev/null 2>&1 || true
fi
exit 0

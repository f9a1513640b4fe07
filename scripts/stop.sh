#!/usr/bin/env bash
# Stop only what start.sh started: the named container, or the PID recorded by start_native.sh.
# Never a pattern-based kill of other processes.
set -uo pipefail
name="${ROBONIX_NAV2_CONTAINER:-robonix-nav2-${RBNX_INSTANCE_NAME:-nav2}}"
run_dir="${RBNX_RUN_DIR:-${XDG_RUNTIME_DIR:-/tmp}/robonix}"
pidfile="$run_dir/nav2-${RBNX_INSTANCE_NAME:-nav2}.pid"

if [ -f "$pidfile" ]; then
  pid="$(cat "$pidfile")"
  if [[ "$pid" =~ ^[0-9]+$ ]] && kill -0 "$pid" 2>/dev/null; then
    kill -TERM "$pid"
    for _ in $(seq 1 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -0 "$pid" 2>/dev/null && kill -KILL "$pid"
  fi
  rm -f "$pidfile"
  exit 0
fi
if command -v docker >/dev/null 2>&1; then
  docker rm -f "$name" >/dev/null 2>&1 || true
fi
exit 0

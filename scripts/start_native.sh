#!/usr/bin/env bash
# Run the navigation provider on the host: the installed Python package, no ROS install needed.
# Records its PID (with its start time) in this deployment's run dir so stop.sh stops exactly it.
set -euo pipefail
# shellcheck disable=SC1091  # common.sh is checked on its own
. "$(dirname "$0")/common.sh"
pidfile="$(rbnx_pidfile)"
mkdir -p "$(dirname "$pidfile")"
echo "$$ $(rbnx_start_ticks $$)" > "$pidfile"
exec "${PYTHON:-python3}" -m nav2_wrapper.atlas_bridge

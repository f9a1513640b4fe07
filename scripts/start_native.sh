#!/usr/bin/env bash
# Run the navigation provider on the host: the installed Python package, no ROS install needed.
# Records its PID so stop.sh can stop exactly this process.
set -euo pipefail
run_dir="${RBNX_RUN_DIR:-${XDG_RUNTIME_DIR:-/tmp}/robonix}"
mkdir -p "$run_dir"
echo "$$" > "$run_dir/nav2-${RBNX_INSTANCE_NAME:-nav2}.pid"
exec "${PYTHON:-python3}" -m nav2_wrapper.atlas_bridge

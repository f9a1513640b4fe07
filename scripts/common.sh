#!/usr/bin/env bash
# Shared by start.sh, start_native.sh, stop.sh and build.sh (sourced): which container engine, and the
# names that keep two deployments on one host apart (run dir, pidfile, container name).

# podman when installed (scripts/install_engine.sh), else docker; ROBONIX_CONTAINER_ENGINE wins.
rbnx_engine() {
  if [ -n "${ROBONIX_CONTAINER_ENGINE:-}" ]; then echo "$ROBONIX_CONTAINER_ENGINE"
  elif command -v podman >/dev/null 2>&1; then echo podman
  else echo docker; fi
}

# A file-name-safe id of this deployment: deploy name + atlas address (what rbnx keys it by too).
rbnx_deploy_key() {
  local raw="${RBNX_DEPLOY_NAME:-}-${ROBONIX_ATLAS:-}"
  raw="$(printf '%s' "$raw" | sed -E 's/[^A-Za-z0-9_.-]+/_/g; s/^[_.-]+//; s/[_.-]+$//')"
  echo "${raw:-default}"
}

# rbnx boot passes RBNX_RUN_DIR per deployment; run by hand, the atlas address keys it.
rbnx_run_dir() {
  if [ -n "${RBNX_RUN_DIR:-}" ]; then echo "$RBNX_RUN_DIR"
  else echo "${XDG_RUNTIME_DIR:-/tmp/robonix-$(id -u)}/robonix/$(rbnx_deploy_key)"; fi
}

rbnx_pidfile() { echo "$(rbnx_run_dir)/nav2-${RBNX_INSTANCE_NAME:-nav2}.pid"; }

# Instance name plus, under rbnx, the deployment: two deployments never share a container name.
rbnx_container_name() {
  if [ -n "${ROBONIX_NAV2_CONTAINER:-}" ]; then echo "$ROBONIX_NAV2_CONTAINER"; return; fi
  local name="robonix-nav2-${RBNX_INSTANCE_NAME:-nav2}"
  if [ -n "${ROBONIX_ATLAS:-}${RBNX_DEPLOY_NAME:-}" ]; then name="$name-$(rbnx_deploy_key)"; fi
  echo "$name"
}

# Start time of a PID (clock ticks since boot, /proc/<pid>/stat field 22): with the PID it identifies
# the process even after the PID is reused.
rbnx_start_ticks() {
  local stat
  stat="$(cat "/proc/$1/stat" 2>/dev/null)" || return 1
  stat="${stat##*) }"
  # shellcheck disable=SC2086  # split the fields on purpose
  set -- $stat
  echo "${20}"
}

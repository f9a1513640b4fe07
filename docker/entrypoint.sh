#!/usr/bin/env bash
# Container entrypoint: sane defaults for the robonix environment, fail fast on a bad one, then exec.
set -euo pipefail

: "${ROBONIX_ATLAS:=127.0.0.1:50051}"
: "${ROS_DOMAIN_ID:=0}"
: "${CYCLONEDDS_URI:=file:///etc/robonix/cyclonedds.xml}"
export ROBONIX_ATLAS ROS_DOMAIN_ID CYCLONEDDS_URI

if [ -n "${RBNX_DEPLOY_MANAGED:-}" ] && [ -z "${RBNX_INSTANCE_NAME:-}" ]; then
  echo "robonix-entrypoint: RBNX_DEPLOY_MANAGED is set but RBNX_INSTANCE_NAME is empty (forward it with -e)" >&2
  exit 2
fi
if ! [[ "$ROS_DOMAIN_ID" =~ ^[0-9]+$ ]] || [ "$ROS_DOMAIN_ID" -gt 232 ]; then
  echo "robonix-entrypoint: ROS_DOMAIN_ID must be an integer 0..232, got '$ROS_DOMAIN_ID'" >&2
  exit 2
fi
if [[ "$CYCLONEDDS_URI" == file://* ]] && [ ! -r "${CYCLONEDDS_URI#file://}" ]; then
  echo "robonix-entrypoint: CYCLONEDDS_URI points to a missing file: ${CYCLONEDDS_URI#file://}" >&2
  exit 2
fi
if [ "$#" -eq 0 ]; then
  set -- python -m nav2_wrapper.atlas_bridge
fi
exec "$@"

#!/usr/bin/env bash
# Start the navigation provider natively or in the robonix-nav2 container.
# Mode: ROBONIX_NAV2_FORCE=native|docker wins; else native when ROBONIX_NAV2_PLATFORM=jetson_orin; else docker.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
# shellcheck disable=SC1091  # common.sh is checked on its own
. "$root/scripts/common.sh"
force="${ROBONIX_NAV2_FORCE:-}"
case "$force" in
  native|docker) mode="$force" ;;
  "")
    if [ "${ROBONIX_NAV2_PLATFORM:-}" = "jetson_orin" ]; then mode=native; else mode=docker; fi ;;
  *)
    echo "start.sh: ROBONIX_NAV2_FORCE must be 'native' or 'docker', got '$force'" >&2
    exit 2 ;;
esac

if [ "$mode" = "native" ]; then
  exec bash "$root/scripts/start_native.sh"
fi

image="${ROBONIX_NAV2_IMAGE:-robonix-nav2}"
name="$(rbnx_container_name)"
# Forward what the provider needs, including what robonix forgets (instance name, deploy-managed).
fwd=()
for var in RBNX_INSTANCE_NAME RBNX_DEPLOY_MANAGED ROBONIX_ATLAS ROBONIX_PROVIDER_BIND_HOST \
           ROBONIX_ADVERTISE_HOST ROS_DOMAIN_ID RMW_IMPLEMENTATION CYCLONEDDS_URI ROBONIX_HEARTBEAT_PERIOD_S; do
  if [ -n "${!var:-}" ]; then fwd+=(-e "$var=${!var}"); fi
done
# The deployment token: by name only, so the engine copies it from this environment and it never shows in argv.
if [ -n "${ROBONIX_DEPLOY_TOKEN:-}" ]; then fwd+=(-e ROBONIX_DEPLOY_TOKEN); fi
mounts=()
# A file:// CYCLONEDDS_URI must exist inside the container too: mount it read-only at the same path.
if [[ "${CYCLONEDDS_URI:-}" == file://* ]]; then
  cfg="${CYCLONEDDS_URI#file://}"
  mounts+=(-v "$cfg:$cfg:ro")
fi
# The image is built locally (scripts/build_image.sh): never try a registry.
exec "$(rbnx_engine)" run --rm --pull=never --name "$name" --network host --ipc=host "${fwd[@]}" "${mounts[@]}" \
  "$image" python -m nav2_wrapper.atlas_bridge

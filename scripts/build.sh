#!/usr/bin/env bash
# Build the navigation package for a target (robonix convention): RBNX_BUILD_TARGET selects
#   x86-docker (default) | jetson-docker -> the robonix-nav2 image (scripts/build_image.sh: local base
#                                           rootfs + docker/Dockerfile, no registry; arm64 for jetson)
#   jetson-native                        -> check/install the Python package on the host (no ROS needed)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
target="${RBNX_BUILD_TARGET:-x86-docker}"
image="${ROBONIX_NAV2_IMAGE:-robonix-nav2}"
builder="${RBNX_IMAGE_BUILDER:-$root/scripts/build_image.sh}"  # the one recipe for the image (no registry)

case "$target" in
  x86-docker)
    ROBONIX_NAV2_IMAGE="$image" ROBONIX_IMAGE_ARCH=amd64 bash "$builder"
    ;;
  jetson-docker)
    ROBONIX_NAV2_IMAGE="$image" ROBONIX_IMAGE_ARCH=arm64 bash "$builder"
    ;;
  jetson-native)
    py="${PYTHON:-python3}"
    if ! "$py" -c "import nav2_wrapper, robonix_api" 2>/dev/null; then
      if [ "${RBNX_BUILD_CLEAN:-0}" = "1" ] || [ -n "${RBNX_NATIVE_INSTALL:-}" ]; then
        "$py" -m pip install -e "$root"
      else
        echo "build.sh: nav2_wrapper is not importable by $py; run 'pip install -e $root' (or set RBNX_NATIVE_INSTALL=1)" >&2
        exit 1
      fi
    fi
    ;;
  *)
    echo "build.sh: unknown RBNX_BUILD_TARGET '$target' (expected x86-docker, jetson-docker or jetson-native)" >&2
    exit 2
    ;;
esac
touch "$root/.rbnx-built"
echo "build.sh: built target $target"

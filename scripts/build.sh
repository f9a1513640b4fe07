#!/usr/bin/env bash
# Build the navigation package for a target (robonix convention): RBNX_BUILD_TARGET selects
#   x86-docker (default) | jetson-docker -> the robonix-nav2 image from docker/Dockerfile
#   jetson-native                        -> check/install the Python package on the host (no ROS needed)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
target="${RBNX_BUILD_TARGET:-x86-docker}"
image="${ROBONIX_NAV2_IMAGE:-robonix-nav2}"

case "$target" in
  x86-docker)
    docker build -t "$image" -f docker/Dockerfile .
    ;;
  jetson-docker)
    docker build --platform linux/arm64 -t "$image" -f docker/Dockerfile .
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

#!/usr/bin/env bash
# Healthy = this container's provider is registered on the atlas and not TERMINATED/ERROR.
set -euo pipefail
id="${RBNX_INSTANCE_NAME:-nav2}"
exec rbnx --atlas "${ROBONIX_ATLAS:-127.0.0.1:50051}" describe --provider "$id" --check

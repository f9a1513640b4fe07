"""rbnx: the robonix-nav command line (build, boot, start, shutdown, validate, and atlas queries)."""

import os as _os

# rbnx spawns providers (fork + exec with a parent-death preexec) while it holds gRPC channels: gRPC's
# fork handlers must stay off or children abort before exec (see robonix_api/forksafe.py). Set before
# any rbnx module imports grpc; kept here so `import rbnx` stays light.
_os.environ.setdefault("GRPC_ENABLE_FORK_SUPPORT", "false")

"""Keep gRPC's fork handlers out of the way of fork+exec.

A process that holds gRPC channels and starts children with ``subprocess.Popen(preexec_fn=...)`` (which
forces a real fork) lets gRPC's at-fork handlers restart its poller thread in the child; the child's
``close_fds`` then closes that poller's epoll descriptor and the child aborts before ``exec`` with
``epoll_wait error: Bad file descriptor`` (rc -6). Measured with grpcio 1.85: 12 of 300 such spawns
aborted; with fork support off, 0 of 300. Nothing of ours uses gRPC in a forked child without ``exec``,
so fork support is switched off (unless the user set ``GRPC_ENABLE_FORK_SUPPORT`` themselves).
Must run before gRPC initialises: the packages that spawn processes import this first.
"""

from __future__ import annotations

import os

os.environ.setdefault("GRPC_ENABLE_FORK_SUPPORT", "false")

"""Pure-numpy building blocks shared by the algorithm cores and the plumbing: grids, 2-D geometry and
parameter declarations (``params``: default, range and doc on a dataclass field).

Nothing here imports gRPC, DDS, MCP or a file format, so ``nav2_wrapper.core``, ``slam_service.core`` and
``hal_panda_mobile.sim`` can depend on it and still import where those stacks are absent.
"""

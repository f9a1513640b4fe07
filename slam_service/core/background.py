"""Loop-closure optimisation off the scan path.

A full pose-graph solve on a building-sized graph takes up to seconds; done inside ``process()`` it
stalled the scan path (4.1 s on the Intel log). The engine instead hands a snapshot of the graph to a
worker thread and keeps matching scans against the un-optimised chain. The result is applied at a fixed
node count later (the engine waits there if the solve is still running), so the trajectory is a function
of the input alone, whatever the machine's load. Nodes added meanwhile are moved rigidly with the last
snapshot node: their sequential edges are relative, so the chain after it is unchanged in shape.
"""

from __future__ import annotations

import dataclasses
import threading
import time
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from robonix_common.geometry import compose, inverse

from .posegraph import OptimizeResult, PoseGraph


@dataclass
class OptimizeJob:
    """One background solve of a snapshot that ends in loop edge ``edge`` (closing at node ``node``)."""

    graph: PoseGraph  # the snapshot (its own lists and arrays)
    node: int  # the node the loop closed at
    edge: int  # index of the loop edge in the live graph
    iterations: int
    huber: float | None
    max_chi2: float
    result: OptimizeResult | None = None
    seconds: float = 0.0
    chi2: float = float("nan")
    _thread: threading.Thread | None = field(default=None, repr=False)

    @property
    def n_nodes(self) -> int:
        return self.graph.n_nodes

    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="slam-optimize", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        t0 = time.perf_counter()
        self.result = self.graph.optimize(self.iterations, huber=self.huber)
        self.seconds = time.perf_counter() - t0
        self.chi2 = float(self.graph.edge_chi2()[self.edge])

    def wait(self) -> None:
        if self._thread is not None:
            self._thread.join()

    @property
    def accepted(self) -> bool:
        """The new loop edge agrees with the rest of the graph after the solve."""
        return bool(self.chi2 <= self.max_chi2)


def snapshot(graph: PoseGraph) -> PoseGraph:
    """A copy whose lists and arrays the live graph's later appends do not touch."""
    return dataclasses.replace(graph, poses=graph.poses.copy(), edge_ij=list(graph.edge_ij),
                               edge_z=list(graph.edge_z), edge_info=list(graph.edge_info),
                               edge_kind=list(graph.edge_kind))


def merged_poses(live: NDArray, solved: NDArray) -> NDArray[np.float64]:
    """The solved poses for the snapshot's nodes; later nodes moved rigidly with the snapshot's last node."""
    n0 = len(solved)
    out = live.copy()
    out[:n0] = solved
    if len(live) > n0:
        delta = compose(solved[n0 - 1], inverse(live[n0 - 1]))
        for k in range(n0, len(live)):
            out[k] = compose(delta, live[k])
    return out


def remove_edge(graph: PoseGraph, e: int) -> None:
    """Drop edge ``e`` (a loop edge the solve found inconsistent)."""
    for lst in (graph.edge_ij, graph.edge_z, graph.edge_info, graph.edge_kind):
        del lst[e]

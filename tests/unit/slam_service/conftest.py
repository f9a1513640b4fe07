"""Shared, deterministic SLAM fixtures: the apartment drive is recorded once per test session."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from robonix_eval.synthetic import OdomDrift, Recording, World, apartment_world, drive
from slam_service.core import SlamConfig, SlamEngine

DRIFT = OdomDrift(trans_scale=0.03, rot_scale=0.03, rot_bias_per_m=0.02, sigma_xy=0.003, sigma_theta=0.003)


def two_lap_apartment() -> World:
    """The apartment ring driven twice (then into the second room again): a loop worth closing."""
    base = apartment_world()
    ring = base.waypoints[:-3]
    return World(base.name, base.rects, ring * 2 + base.waypoints[-3:])


@dataclass
class MappingRun:
    world: World
    rec: Recording
    engine: SlamEngine
    node_index: list[int]  # recording index of each pose-graph node

    @property
    def ate_inputs(self) -> tuple[np.ndarray, np.ndarray]:
        return self.engine.trajectory(), self.rec.gt[self.node_index]


def run_mapping(world: World, rec: Recording, config: SlamConfig) -> MappingRun:
    eng = SlamEngine(config)
    for scan, odom in zip(rec.scans, rec.odom, strict=True):
        eng.process(scan, odom)
    eng.flush()  # after the last scan: draw the nodes still waiting for their re-render budget
    # by stamp, not by "integrated": lifelong pruning removes old nodes the second lap re-observes
    idx = [int(i) for i in np.searchsorted(rec.stamps, eng.node_stamps() - 1e-9)]
    return MappingRun(world, rec, eng, idx)


@pytest.fixture(scope="session")
def apartment_recording() -> tuple[World, Recording]:
    world = two_lap_apartment()
    return world, drive(world, range_noise=0.03, dropout=0.05, odom_noise=DRIFT, seed=1)


@pytest.fixture(scope="session")
def mapping_with_lc(apartment_recording: tuple[World, Recording]) -> MappingRun:
    return run_mapping(*apartment_recording, SlamConfig(loop_closure=True))


@pytest.fixture(scope="session")
def mapping_without_lc(apartment_recording: tuple[World, Recording]) -> MappingRun:
    # the old behaviour as the baseline: without loop closure, pruning would drop the drifted second lap's
    # nodes (those an older node covers) and flatter the ATE this run is compared on
    return run_mapping(*apartment_recording, SlamConfig(loop_closure=False, prune_nodes=False))

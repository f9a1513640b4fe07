"""The slam_service provider: a robonix ``Service`` around :class:`slam_service.core.SlamEngine`.

From process start: the map RPCs (gRPC + MCP; "not initialized" before INIT) and the declaration of
``robonix/service/map/occupancy_grid`` on /map (transient_local), so consumers can resolve it early.
CMD_INIT validates the config, resolves lidar + odom through the atlas (``Deferred`` until both have a
provider), optionally loads a saved map, and starts the loop *paused*. ACTIVATE integrates scans;
DEACTIVATE pauses (the last map stays latched on /map, map->odom keeps being published); SHUTDOWN
stops the loop and closes DDS. A failed or deferred INIT leaves the previous session untouched.
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass
from typing import Any

from robonix_api import Deferred, Err, Ok, Service
from robonix_api.dds import OccupancyGrid
from robonix_api.upstream import Binding, MissingUpstream, resolve_topic
from slam_service.config import ConfigError, ProviderConfig, load_footprint, parse_config
from slam_service.contracts import MapContracts
from slam_service.core import SlamConfig, SlamEngine
from slam_service.loop import SlamLoop, install_engine_log_filter
from slam_service.maps import MapIdError, MapStore, MapStoreError, check_id

log = logging.getLogger("slam_service")

DEFAULT_ID = "mapping"
NAMESPACE = "robonix/service/map"
OCCUPANCY_GRID = "robonix/service/map/occupancy_grid"
LIDAR = "robonix/primitive/lidar/lidar"
ODOM = "robonix/primitive/chassis/odom"
MAP_TOPIC = "/map"
MAP_QOS = "transient_local"
ROLES: dict[str, tuple[str, str]] = {"scan": (LIDAR, "best_effort"), "odom": (ODOM, "reliable")}


def resolve_inputs(atlas: Any, consumer: str, cfg: ProviderConfig) -> dict[str, Binding]:
    """scan + odom through the SDK's contract lookup (topic_remap wins, provider_ids pins)."""
    out: dict[str, Binding] = {}
    for role, (contract, default_qos) in ROLES.items():
        out[role] = resolve_topic(atlas, consumer, role, contract, default_qos=default_qos,
                                  remap=getattr(cfg.topic_remap, role), pin=getattr(cfg.provider_ids, role))
    return out


@dataclass
class Session:
    """Everything one successful CMD_INIT built."""

    cfg: ProviderConfig
    slam_cfg: SlamConfig
    store: MapStore
    footprint: list[tuple[float, float]]
    loop: SlamLoop

    def load(self, map_id: str, mode: str, initial_pose: tuple[float, float, float] | None) -> None:
        """Load a saved map into a fresh engine and swap it in; on any error the running one is kept."""
        engine = load_engine(self.store, self.slam_cfg, map_id, mode, initial_pose)
        self.loop.replace_engine(engine)
        log.info("loaded map %r in %s mode", map_id, mode)

    def close(self) -> None:
        self.loop.close()


def load_engine(store: MapStore, slam_cfg: SlamConfig, map_id: str, mode: str,
                initial_pose: tuple[float, float, float] | None) -> SlamEngine:
    """MapStoreError (names the file) or ValueError when the map cannot be used."""
    loaded = store.load(map_id, with_session=mode == "mapping")
    engine = SlamEngine(slam_cfg, mode)  # type: ignore[arg-type]
    engine.load(grid=loaded.grid, session=loaded.session, mode=mode, initial_pose=initial_pose)  # type: ignore[arg-type]
    return engine


class SlamProvider:
    """Owns the Service's lifecycle handlers and the current session."""

    def __init__(self, svc: Service) -> None:
        self.svc = svc
        self.session: Session | None = None
        install_engine_log_filter()
        self._map_pub: Any = None
        self.map_topic = svc.declare_ros2_topic(OCCUPANCY_GRID, MAP_TOPIC, qos=MAP_QOS)
        MapContracts(lambda: self.session).register(svc)
        svc.on_init(self.on_init)
        svc.on_activate(self.on_activate)
        svc.on_deactivate(self.on_deactivate)
        svc.on_shutdown(self.on_shutdown)

    def on_init(self, raw: dict[str, Any]) -> Ok | Err | Deferred:
        try:
            cfg, slam_cfg = parse_config(raw)
            footprint = load_footprint(cfg.robot_description)
            if cfg.map_id:
                check_id(cfg.map_id)
        except (ConfigError, MapIdError) as exc:
            return Err(str(exc))
        try:
            bindings = resolve_inputs(self.svc.atlas, self.svc.id, cfg)
        except MissingUpstream as exc:
            log.info("CMD_INIT deferred: %s", exc)
            return Deferred(str(exc))
        store = MapStore(cfg.map_dir)
        if cfg.map_id:
            pose = cfg.initial_pose.as_tuple() if cfg.initial_pose is not None else None
            try:
                engine = load_engine(store, slam_cfg, cfg.map_id, cfg.mode, pose)
            except (MapStoreError, ValueError) as exc:
                return Err(f"map_id: {exc}")
        else:
            engine = SlamEngine(slam_cfg, cfg.mode)
        if self.session is not None:  # re-INIT replaces the running session
            self.session.close()
            self.session = None
        node = self.svc.dds_node()
        if self._map_pub is None:
            self._map_pub = self.svc.create_publisher(OCCUPANCY_GRID, topic=self.map_topic, msg_type=OccupancyGrid,
                                                      qos=MAP_QOS, declare=False)
        loop = SlamLoop(node, bindings, cfg.frames, engine, self._map_pub, use_sim_time=cfg.use_sim_time,
                        map_period_s=cfg.map_publish_period_s, tf_period_s=cfg.tf_period_s, queue_size=cfg.scan_queue)
        self.session = Session(cfg, slam_cfg, store, footprint, loop)
        log.info("initialized: mode %s, scan %s (%s, %s), odom %s (%s, %s), map %s, map_dir %s", cfg.mode,
                 bindings["scan"].topic, bindings["scan"].qos, bindings["scan"].provider_id or bindings["scan"].source,
                 bindings["odom"].topic, bindings["odom"].qos, bindings["odom"].provider_id or bindings["odom"].source,
                 self.map_topic, store.root)
        return Ok()

    def on_activate(self) -> Ok | Err:
        if self.session is None:
            return Err("not initialized")
        self.session.loop.set_integrating(True)
        return Ok()

    def on_deactivate(self) -> Ok:
        if self.session is not None:
            self.session.loop.set_integrating(False)
        return Ok()

    def on_shutdown(self) -> Ok:
        if self.session is not None:
            self.session.close()
            self.session = None
        return Ok()


def build_provider(instance_id: str | None = None) -> SlamProvider:
    """The Service (id from ``RBNX_INSTANCE_NAME``, default ``mapping``) with every handler bound."""
    svc = Service(instance_id or os.environ.get("RBNX_INSTANCE_NAME") or DEFAULT_ID, NAMESPACE)
    return SlamProvider(svc)

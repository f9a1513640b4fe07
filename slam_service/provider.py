"""The slam_service provider: a robonix ``Service`` around :class:`slam_service.core.SlamEngine`.

From process start: the map RPCs (gRPC + MCP; "not initialized" before INIT) and the declaration of
``robonix/service/map/occupancy_grid`` on /map (transient_local), so consumers can resolve it early.
CMD_INIT validates the config, resolves lidar + odom through the atlas (``Deferred`` until both have a
provider), optionally loads a saved map, and starts the loop *paused*. ACTIVATE integrates scans;
DEACTIVATE pauses (the last map stays latched on /map, map->odom keeps being published); SHUTDOWN
stops the loop and closes DDS. A failed or deferred INIT leaves the previous session untouched
(``robonix_api.hosting.SessionHost`` owns that glue).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

from robonix_api import Deferred, Err, Service
from robonix_api.dds import MapLifecycle, OccupancyGrid
from robonix_api.hosting import SessionHost, serve_contracts
from robonix_api.runstate import deployment_key, restarts
from robonix_api.upstream import Binding, MissingUpstream, resolve_topic
from slam_service.config import ConfigError, ProviderConfig, load_footprint, parse_config
from slam_service.continuity import MapToOdomFile
from slam_service.core import SlamConfig, SlamEngine
from slam_service.core.numeric import load_in_background
from slam_service.handlers import MapHandlers
from slam_service.loop import SlamLoop, install_engine_log_filter
from slam_service.maps import (
    Autosave,
    MapDirError,
    MapIdError,
    MapStore,
    MapStoreError,
    check_id,
    load_engine,
    resume_engine,
)
from slam_service.session_io import SessionFileError
from slam_service.telemetry import PAUSED, SHUTDOWN, LifecycleAnnouncer, MapSpans

log = logging.getLogger("slam_service")

DEFAULT_ID = "mapping"
NAMESPACE = "robonix/service/map"
OCCUPANCY_GRID = "robonix/service/map/occupancy_grid"
MAP_LIFECYCLE = "robonix/service/map/lifecycle"
LIFECYCLE_TOPIC = "/map_lifecycle"
LIDAR = "robonix/primitive/lidar/lidar"
ODOM = "robonix/primitive/chassis/odom"
MAP_TOPIC = "/map"
MAP_QOS = "transient_local"
ROLES: dict[str, tuple[str, str]] = {"scan": (LIDAR, "best_effort"), "odom": (ODOM, "reliable")}


@dataclass(frozen=True)
class SlamSetup:
    """What a CMD_INIT resolved before anything running was touched (the handlers read the first four)."""

    cfg: ProviderConfig
    slam: SlamConfig
    store: MapStore
    footprint: list[tuple[float, float]]
    bindings: dict[str, Binding]
    engine: SlamEngine  # the engine the session starts with; the loop owns it (load_map swaps it there)
    autosave: Autosave | None = None  # the crash copy of a mapping session
    resume_map_to_odom: tuple[float, float, float] | None = None  # set when resumed from the crash copy


def resolve_inputs(atlas: Any, consumer: str, cfg: ProviderConfig) -> dict[str, Binding]:
    """scan + odom through the SDK's contract lookup (topic_remap wins, provider_ids pins)."""
    out: dict[str, Binding] = {}
    for role, (contract, default_qos) in ROLES.items():
        out[role] = resolve_topic(atlas, consumer, role, contract, default_qos=default_qos,
                                  remap=getattr(cfg.topic_remap, role), pin=getattr(cfg.provider_ids, role))
    return out


class SlamProvider(SessionHost[SlamSetup, SlamLoop]):
    """The Service's lifecycle: each session is one :class:`SlamLoop` on the inputs INIT resolved."""

    def __init__(self, svc: Service) -> None:
        super().__init__(svc)
        self.svc = svc
        install_engine_log_filter()
        self._map_pub: Any = None  # one /map writer for the process: its latched map outlives sessions
        self._announcer: LifecycleAnnouncer | None = None  # robonix/service/map/lifecycle, same lifetime
        self.map_topic = svc.declare_ros2_topic(OCCUPANCY_GRID, MAP_TOPIC, qos=MAP_QOS)
        self.lifecycle_topic = svc.declare_ros2_topic(MAP_LIFECYCLE, LIFECYCLE_TOPIC, qos=MAP_QOS)
        self._m2o_file = MapToOdomFile.for_instance(svc.id)  # map->odom as last published, for a restart
        serve_contracts(svc, MapHandlers(self.current).table())

    def prepare(self, config: dict[str, Any]) -> SlamSetup | Err | Deferred:
        load_in_background()  # once: scipy loads while we wait for the lidar, not on the first scan
        try:
            cfg, slam_cfg = parse_config(config)
            footprint = load_footprint(cfg.robot_description)
            if cfg.map_id:
                check_id(cfg.map_id)
            store = MapStore(cfg.map_dir)  # MapDirError unless under the maps root; cleans dead saves' staging
        except (ConfigError, MapIdError, MapDirError) as exc:
            return Err(str(exc))
        try:
            bindings = resolve_inputs(self.svc.atlas, self.svc.id, cfg)
        except MissingUpstream as exc:
            return Deferred(str(exc))
        if cfg.map_id:
            pose = cfg.initial_pose.as_tuple() if cfg.initial_pose is not None else None
            try:
                engine = load_engine(store, slam_cfg, cfg.map_id, cfg.mode, pose)
            except (MapStoreError, ValueError) as exc:
                return Err(f"map_id: {exc}")
            return SlamSetup(cfg, slam_cfg, store, footprint, bindings, engine)
        autosave, m2o = self._autosave_for(cfg, store), None
        engine = SlamEngine(slam_cfg, cfg.mode)
        if autosave is not None and restarts() > 0:
            try:
                session = autosave.read()
            except (SessionFileError, OSError, ValueError) as exc:
                log.warning("autosave %s unreadable, starting a new map: %s", autosave.path, exc)
                session = None
            if session is not None:
                engine, m2o = resume_engine(session, slam_cfg)
                published = self._m2o_file.last()  # what navigation drove on up to the crash
                log.info("restart %d: resumed the autosaved session %s (%d nodes); map->odom %s", restarts(),
                         autosave.path, session.graph.n_nodes,
                         "as last published" if published is not None else "at the last autosaved node")
                m2o = published or m2o
        elif autosave is not None:
            autosave.discard()
            self._m2o_file.discard()
        return SlamSetup(cfg, slam_cfg, store, footprint, bindings, engine, autosave, m2o)

    def _autosave_for(self, cfg: ProviderConfig, store: MapStore) -> Autosave | None:
        """A new mapping session gets a crash copy (a session on a saved map_id restarts from that map),
        in the store's resolved folder: under the maps root like every saved map."""
        if cfg.mode != "mapping" or cfg.autosave_period_s <= 0:
            return None
        try:
            return Autosave(store.root, self.svc.id, deployment_key())
        except MapIdError:
            log.warning("no autosave: instance id %r is not a plain file name", self.svc.id)
            return None

    def start(self, setup: SlamSetup) -> SlamLoop:
        cfg, bindings = setup.cfg, setup.bindings
        if self._map_pub is None:
            self._map_pub = self.svc.create_publisher(OCCUPANCY_GRID, topic=self.map_topic, msg_type=OccupancyGrid,
                                                      qos=MAP_QOS, declare=False)
            self._announcer = LifecycleAnnouncer(self.svc.create_publisher(
                MAP_LIFECYCLE, topic=self.lifecycle_topic, msg_type=MapLifecycle, qos=MAP_QOS, declare=False))
        holder: list[SlamLoop] = []
        spans = MapSpans.maybe(frame_id=cfg.frames.map, base_frame=cfg.frames.base, footprint=setup.footprint,
                               robot_pose=lambda: _pose_if_known(holder[0]) if holder else None)
        loop = SlamLoop(self.svc.dds_node(), bindings, cfg.frames, setup.engine, self._map_pub,
                        use_sim_time=cfg.use_sim_time, map_period_s=cfg.map_publish_period_s,
                        tf_period_s=cfg.tf_period_s, queue_size=cfg.scan_queue, map_id=cfg.map_id or "",
                        on_map=spans.on_map if spans is not None else None,
                        on_change=lambda: self._announce(holder[0]) if holder else None,
                        autosave=setup.autosave.write if setup.autosave is not None else None,
                        autosave_period_s=cfg.autosave_period_s, resume_map_to_odom=setup.resume_map_to_odom,
                        on_tf=self._m2o_file.note if setup.autosave is not None else None)
        holder.append(loop)
        self._announce(loop)
        scan, odom = bindings["scan"], bindings["odom"]
        log.info("initialized: mode %s, scan %s (%s, %s), odom %s (%s, %s), map %s, map_dir %s", cfg.mode,
                 scan.topic, scan.qos, scan.provider_id or scan.source, odom.topic, odom.qos,
                 odom.provider_id or odom.source, self.map_topic, setup.store.root)
        return loop

    def activate(self, work: SlamLoop) -> None:
        work.set_integrating(True)
        self._announce(work)

    def deactivate(self, work: SlamLoop) -> None:
        work.set_integrating(False)
        self._announce(work)

    def _announce(self, work: SlamLoop, mode: str = "") -> None:
        """One MapLifecycle message: the SLAM mode while integrating, else ``paused`` (or ``mode``)."""
        if self._announcer is not None:
            self._announcer.announce(work.map_id, mode or (work.engine.mode if work.integrating else PAUSED))

    def _on_shutdown(self) -> Any:
        s = self.current()
        if s is not None:
            self._announce(s.work, SHUTDOWN)
        return super()._on_shutdown()


def _pose_if_known(work: SlamLoop) -> tuple[float, float, float] | None:
    """The robot's map pose once SLAM has seen a scan (or localizes on a loaded map), else None."""
    with work.lock:
        known = work.engine.stats.scans_received > 0 or work.engine.mode == "localization"
    return work.robot_pose() if known else None


def build_provider(instance_id: str | None = None) -> SlamProvider:
    """The Service (id from ``RBNX_INSTANCE_NAME``, default ``mapping``) with every handler bound."""
    return SlamProvider(Service(instance_id or DEFAULT_ID, NAMESPACE))

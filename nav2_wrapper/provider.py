"""The navigation provider: a robonix ``Service`` around the pure-Python navigation core.

``python -m nav2_wrapper`` (alias ``python -m nav2_wrapper.atlas_bridge``). The contract handlers are
live from process start; CMD_INIT resolves map/odom/scan/twist_in through the atlas (``Deferred`` while
a required one is missing), loads the params profile, subscribes, waits for the first map + odom + TF
and starts the control loop. ACTIVATE accepts goals; DEACTIVATE cancels, stops the robot and rejects
goals; SHUTDOWN stops the robot, the threads and the DDS entities (``robonix_api.hosting.SessionHost``
owns that glue).
"""

from __future__ import annotations

import logging
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from nav2_wrapper import warmup_note
from nav2_wrapper.core import Navigator
from nav2_wrapper.params import LoadedParams, ParamsError, load_params
from nav2_wrapper.params_schema import COMPAT_NOTE
from nav2_wrapper.robot_io import RobotDescriptionError, load_robot
from robonix_api import Deferred, Err, Service
from robonix_api.dds import Path as PathMsg
from robonix_api.dds import Twist
from robonix_api.hosting import INIT_FAILED, SessionHost, serve_contracts
from robonix_api.runstate import restarts
from robonix_api.safefile import UnsafeFileError

from .config import ConfigError, ProviderConfig, parse_config
from .handlers import NavHandlers
from .inputs import Inputs
from .journal import GoalJournal
from .loop import NavLoop, Publishers
from .speed import SpeedLimits
from .upstream import Binding, MissingUpstream, UpstreamWatch, resolve

log = logging.getLogger("nav2_wrapper")

DEFAULT_ID = "nav2"
NAMESPACE = "robonix/service/navigation"
PLAN = "robonix/service/navigation/plan"
MD_PATH = Path(__file__).resolve().parent / "CAPABILITY.md"


@dataclass(frozen=True)
class NavSetup:
    """What a CMD_INIT resolved before anything running was touched."""

    cfg: ProviderConfig
    bindings: dict[str, Binding]
    params: LoadedParams


class NavProvider(SessionHost[NavSetup, NavLoop]):
    """The Service's lifecycle: each session is one :class:`NavLoop` on the inputs INIT resolved."""

    def __init__(self, svc: Service) -> None:
        super().__init__(svc)
        self.svc = svc
        self._plan_topic = ""
        self._ros_action: Any = None  # the ROS 2 navigate_to_pose action + /goal_pose (ros_action.py)
        self._journal = GoalJournal.from_env(svc.id)
        serve_contracts(svc, NavHandlers(self._loop, lambda: self.not_ready, self._restarting_run).table())

    def _restarting_run(self) -> str:
        """The run a crashed predecessor was driving, while this restarted process has not taken it up."""
        if restarts() == 0:
            return ""
        g = self._journal.pending()
        return g.run_id if g is not None else ""

    def _loop(self) -> NavLoop | None:
        s = self.current()
        return s.work if s is not None else None

    def prepare(self, config: dict[str, Any]) -> NavSetup | Err | Deferred:
        warmup_note.start(self.svc.push_detail)  # once: kernels load/compile (and say so) while we wait for the map
        try:
            cfg = parse_config(config)
        except ConfigError as exc:
            return Err(f"config: {exc}")
        try:  # before anything else: a Driver call must not make us read /dev/zero or a 20 GB file
            params_text = cfg.params_text()
        except UnsafeFileError as exc:
            return Err(str(exc))
        fp_path = cfg.resolve_path(cfg.robot_description)
        try:
            robot = load_robot(fp_path)
        except RobotDescriptionError as exc:
            return Err(f"robot_description: {exc}")
        try:
            bindings = resolve(self.svc.atlas, self.svc.id, cfg)
        except MissingUpstream as exc:
            return Deferred(str(exc))
        try:
            params = load_params(cfg.params_source, text=params_text, map_topic=bindings["map"].topic,
                                 odom_topic=bindings["odom"].topic,
                                 scan_topic=bindings["scan"].topic if "scan" in bindings else "",
                                 footprint=robot.footprint, limits=robot.limits)
        except ParamsError as exc:
            return Err(f"{'params_file' if cfg.params_file.strip() else 'params_profile'}: {exc}")
        self._report(cfg, bindings, params)
        return NavSetup(cfg, bindings, params)

    def start(self, setup: NavSetup) -> NavLoop | Err:
        cfg, bindings, params = setup.cfg, setup.bindings, setup.params
        node = self.svc.dds_node()
        if not self._plan_topic:
            self._plan_topic = self.svc.declare_ros2_topic(PLAN, "/plan", qos="reliable")
        inputs = Inputs(node, bindings, cfg.frames, cfg.use_sim_time)
        pubs = Publishers(node.create_publisher(bindings["cmd_vel"].topic, Twist, "reliable"),
                          node.create_publisher(self._plan_topic, PathMsg, "reliable"))
        speed = SpeedLimits(cfg.dynamic_speed, params.config.controller.max_vel_x)

        watch = UpstreamWatch(self.svc.atlas, self.svc.id, bindings)
        loop = NavLoop(Navigator(params.config), inputs, pubs, cfg, speed, watch,
                       self._journal)
        deadline = time.monotonic() + cfg.action_wait_s
        while True:
            missing = inputs.missing()
            if cfg.use_sim_time and not inputs.clock.ticked:
                missing.append("no /clock received (use_sim_time is true)")
            if not missing:
                break
            if time.monotonic() > deadline:
                loop.close(INIT_FAILED)
                return Err("; ".join(f"{m} within {cfg.action_wait_s:g} s" for m in missing))
            time.sleep(0.02)  # the first map is on the boot's critical path: notice it promptly
        loop.apply_speed()
        loop.warm_up()
        loop.start()
        if self._ros_action is None:  # one per process, on the provider's node; it reads the current session
            from .ros_action import NavigateToPoseServer

            self._ros_action = NavigateToPoseServer(node, self._loop)
        log.info("initialized: profile %s, map %s, odom %s, scan %s, cmd_vel %s", params.source,
                 *(bindings[r].topic if r in bindings else "-" for r in ("map", "odom", "scan", "cmd_vel")))
        return loop

    def activate(self, work: NavLoop) -> None:
        work.set_accepting(True)

    def deactivate(self, work: NavLoop) -> None:
        work.set_accepting(False, "canceled: navigation deactivated")

    def _report(self, cfg: ProviderConfig, bindings: dict[str, Binding], params: LoadedParams) -> None:
        """Log every params warning (each names its parameter) and every binding with where it came from."""
        for w in params.warnings:
            log.warning("params %s: %s", params.source, w)
        if params.unused:
            log.warning("params %s: %d parameter(s) %s: %s", params.source, len(params.unused), COMPAT_NOTE,
                        ", ".join(params.unused))
        for role, b in bindings.items():
            log.info("%s: %s (qos %s, %s%s)", role, b.topic, b.qos, b.source,
                     f" provider {b.provider_id}" if b.provider_id else "")
            read = params.topics.get(role)
            if read and read != b.topic:
                log.warning("params read %s topic %s but %s resolved %s: subscribing to %s", role, read,
                            b.source, b.topic, b.topic)
        if cfg.topic_remap.scan_cloud:
            log.warning("topic_remap.scan_cloud=%s is ignored: this core has no 3-D observation source",
                        cfg.topic_remap.scan_cloud)
        nc = params.config.navigator
        if nc.global_frame != cfg.frames.map or nc.robot_base_frame != cfg.frames.base:
            log.warning("params frames (%s, %s) differ from config frames (%s, %s): using the config's",
                        nc.global_frame, nc.robot_base_frame, cfg.frames.map, cfg.frames.base)


def build_provider(instance_id: str | None = None) -> NavProvider:
    """The Service (id: RBNX_INSTANCE_NAME, else ROBONIX_CAPABILITY_ID, else ``nav2``) with handlers bound."""
    sid = instance_id or os.environ.get("ROBONIX_CAPABILITY_ID", "").strip() or DEFAULT_ID
    md = MD_PATH if MD_PATH.is_file() else None
    return NavProvider(Service(sid, NAMESPACE, md_path=md))

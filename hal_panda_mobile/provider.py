"""The hal_panda_mobile provider: a robonix ``Primitive`` wrapping the MuJoCo core.

Lifecycle: CMD_INIT validates the config, builds the sim, declares the topics and starts the loop
*held* (sim time frozen, state republished at 1 Hz so frames resolve); CMD_ACTIVATE starts stepping;
CMD_DEACTIVATE brakes the base to rest and holds again; CMD_SHUTDOWN stops the loop and closes DDS.
A failed CMD_INIT leaves the previous session (if any) untouched and the Driver serving
(``robonix_api.hosting.SessionHost`` owns that glue).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

from hal_panda_mobile.config import HalConfig, build_sim, parse_config
from hal_panda_mobile.handlers import SimHandlers
from hal_panda_mobile.loop import LoopRates, SimLoop
from hal_panda_mobile.outputs import FrameNames, Outputs
from hal_panda_mobile.persist import SimContinuity
from hal_panda_mobile.sim import PandaMobileSim, SimConfigError
from robonix_api import Err, Primitive
from robonix_api.dds.messages import LaserScan, Odometry, Twist
from robonix_api.dds.writer_trust import TAG_PREFIX, WriterTrust
from robonix_api.hosting import SessionHost, serve_contracts
from robonix_api.runstate import restarts

log = logging.getLogger("hal_panda_mobile")

DEFAULT_ID = "panda_mobile"
NAMESPACE = "robonix/primitive"  # covers chassis/*, lidar/* and sim/* without a namespace mismatch
ODOM = "robonix/primitive/chassis/odom"
TWIST_IN = "robonix/primitive/chassis/twist_in"
LIDAR = "robonix/primitive/lidar/lidar"
GT_ODOM = "robonix/primitive/sim/ground_truth_odom"
#: contract -> (config topic key, message type, QoS) per DESIGN.md §3
TOPIC_CONTRACTS: dict[str, tuple[str, type, str]] = {
    ODOM: ("odom", Odometry, "reliable"),
    TWIST_IN: ("cmd_vel", Twist, "reliable"),
    LIDAR: ("scan", LaserScan, "best_effort"),
    GT_ODOM: ("ground_truth", Odometry, "reliable"),
}


@dataclass(frozen=True)
class HalSetup:
    """What a CMD_INIT resolved before anything running was touched."""

    cfg: HalConfig
    sim: PandaMobileSim


class HalProvider(SessionHost[HalSetup, SimLoop]):
    """The Primitive's lifecycle: each session is one :class:`SimLoop` (plus its /cmd_vel subscription)."""

    def __init__(self, prim: Primitive) -> None:
        super().__init__(prim)
        self.prim = prim
        self._topics: dict[str, str] = {}  # contract -> topic the atlas settled on (declared once)
        self._requested: dict[str, str] = {}  # contract -> topic the config asked for
        self._sessions = 0  # only the first session of a restarted process resumes the crashed run
        serve_contracts(prim, SimHandlers(self.current).table())

    def prepare(self, config: dict[str, Any]) -> HalSetup | Err:
        try:
            cfg = parse_config(config)
            self._check_topics(cfg)
            sim = build_sim(cfg)
        except SimConfigError as exc:
            return Err(str(exc))
        for w in sim.warnings:
            log.warning("%s", w)
        return HalSetup(cfg, sim)

    def start(self, setup: HalSetup) -> SimLoop:
        cfg, sim = setup.cfg, setup.sim
        robot, prim = sim.robot, self.prim
        continuity = SimContinuity.for_instance(prim.id, cfg.model_dump(mode="json"))
        log.info("%s", continuity.resume_into(sim, allowed=restarts() > 0 and self._sessions == 0))
        self._sessions += 1
        frames = FrameNames(odom=cfg.frames.odom or robot.odom_frame,
                            base_link=cfg.frames.base_link or robot.base_frame,
                            laser=cfg.frames.laser or robot.lidar.frame, world=cfg.frames.world)
        pubs = {}
        for cid in (ODOM, LIDAR) + ((GT_ODOM,) if cfg.publish_ground_truth else ()):
            _, msg_type, qos = TOPIC_CONTRACTS[cid]
            pubs[cid] = prim.create_publisher(cid, topic=self._topic(cid, cfg), msg_type=msg_type, qos=qos,
                                              declare=False)
        scan_hz = robot.lidar.rate_hz
        outputs = Outputs(prim.dds_node(), frames, odom_pub=pubs[ODOM], scan_pub=pubs[LIDAR],
                          gt_pub=pubs.get(GT_ODOM), publish_clock=cfg.publish_clock, scan_period=1.0 / scan_hz,
                          noisy_odom=not cfg.noise().is_zero)
        rates = LoopRates(odom=cfg.rates.odom_rate_hz, scan=scan_hz,
                          clock=cfg.rates.clock_rate_hz if cfg.publish_clock else None,
                          ground_truth=cfg.rates.ground_truth_rate_hz if cfg.publish_ground_truth else None,
                          hold=cfg.rates.hold_rate_hz)
        loop = SimLoop(sim, outputs, rates, real_time_factor=cfg.real_time_factor, use_sim_time=cfg.use_sim_time,
                       command_lag_bound_s=cfg.command_lag_bound_s, continuity=continuity)
        outputs.publish_static(robot.lidar.mount, sim.time if cfg.use_sim_time else 0.0)

        trust = self._writer_trust(cfg)

        def on_twist(msg: Twist) -> None:
            if trust is not None and not trust.allowed(getattr(getattr(msg, "sample_info", None),
                                                               "publication_handle", None)):
                loop.stats.extra["cmd_vel_refused"] = loop.stats.extra.get("cmd_vel_refused", 0) + 1
                if loop.stats.extra["cmd_vel_refused"] in (1, 10, 100, 1000):
                    log.warning("/cmd_vel from a writer outside the deployment refused (%d so far; "
                                "cmd_vel_writers: deployment)", loop.stats.extra["cmd_vel_refused"])
                return
            loop.cmd_vel(float(msg.linear.x), float(msg.linear.y), float(msg.angular.z),
                         vz=float(msg.linear.z), wx=float(msg.angular.x), wy=float(msg.angular.y))

        self.own(prim.create_subscription(TWIST_IN, topic=self._topic(TWIST_IN, cfg), msg_type=Twist,
                                          callback=on_twist, qos="reliable"))
        loop.start()
        log.info("initialized: scene %s, start %s, rtf %s", sim.scene.name, sim.scene.start,
                 cfg.real_time_factor or "max")
        return loop

    def activate(self, work: SimLoop) -> None:
        work.activate()

    def deactivate(self, work: SimLoop) -> None:
        work.deactivate()

    def _writer_trust(self, cfg: HalConfig) -> WriterTrust | None:
        """The /cmd_vel writer check of ``cmd_vel_writers`` (None: every writer may command the base)."""
        mode = cfg.cmd_vel_writers
        if mode == "any":
            return None
        trust = WriterTrust.for_deployment(self.prim.dds_node().participant)
        if trust is None and mode == "deployment":
            log.warning("cmd_vel_writers: deployment, but no deployment token (ROBONIX_DEPLOY_TOKEN) is set: "
                        "no writer can be told apart, every /cmd_vel is refused")
            return WriterTrust(self.prim.dds_node().participant, TAG_PREFIX + b"(no token: matches no writer)")
        log.info("/cmd_vel accepted from %s", "the deployment's writers only" if trust else "any writer")
        return trust

    # ------------------------------------------------------------------ topics
    def _check_topics(self, cfg: HalConfig) -> None:
        """A topic declared to the atlas cannot be moved (the atlas has no undeclare): say so by field."""
        for cid, (key, _, _) in TOPIC_CONTRACTS.items():
            want = getattr(cfg.topics, key)
            have = self._requested.get(cid)
            if have is not None and have != want:
                raise SimConfigError(f"topics.{key}: {want!r} differs from {have!r} declared by an earlier "
                                     "CMD_INIT; restart the provider to change topics")

    def _topic(self, cid: str, cfg: HalConfig) -> str:
        key, _, qos = TOPIC_CONTRACTS[cid]
        if cid not in self._topics:
            requested = getattr(cfg.topics, key)
            self._topics[cid] = self.prim.declare_ros2_topic(cid, requested, qos=qos)
            self._requested[cid] = requested
            if self._topics[cid] != requested:
                log.warning("atlas moved %s from %s to %s", cid, requested, self._topics[cid])
        return self._topics[cid]


def build_provider(instance_id: str | None = None) -> HalProvider:
    """The Primitive (id from ``RBNX_INSTANCE_NAME``, default ``panda_mobile``) with every handler bound."""
    return HalProvider(Primitive(instance_id or DEFAULT_ID, NAMESPACE))

"""MJCF generated from the robot description and the scene's prisms (no hand-written XML to drift).

Model layout and why:
* floor: a plane that collides with nothing (the base has no z DOF, so floor contacts would only cost
  time and pollute collision events), geom group 1 so the lidar skips it;
* obstacles: static world geoms, group 0 (the only group the lidar sees), named ``obs/<name>``;
* base: body at the floor with slide x, slide y (world axes) then a yaw hinge, so qpos = (x, y, yaw);
  a box covering the footprint (group 3, never seen by the lidar);
* actuators: velocity servos acting at a site on the base, with gears in the *body* frame for x/y, so
  a body-frame twist is the control directly and the sim can run many steps per Python call. Their
  force limits are mass x max acceleration: the acceleration limit is physical, and a wall, being a
  hard contact, always wins against the push.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from xml.sax.saxutils import quoteattr

from .robot import RobotDescription
from .scene import Obstacle
from .shapes import Rect

ROBOT_GEOM = "robot/base"
BASE_BODY = "base"
LIDAR_SITE = "lidar"
FLOOR_GEOM = "floor"
OBSTACLE_PREFIX = "obs/"
BASE_CLEARANCE = 0.01  # m between floor and the bottom of the collision box
SERVO_TIME_CONSTANT = 0.005  # s: velocity servo bandwidth (kv = inertia / tau)


def base_inertia(robot: RobotDescription) -> tuple[float, float]:
    """(mass, yaw inertia) of the base as a solid box over the footprint's bounding box."""
    _, _, sx, sy = robot.footprint_box
    m = robot.body.mass
    return m, m * (sx * sx + sy * sy) / 12.0


def _f(*vals: float) -> str:
    return " ".join(f"{v:.9g}" for v in vals)


def _obstacle_xml(ob: Obstacle) -> str:
    s = ob.shape
    name = quoteattr(OBSTACLE_PREFIX + ob.name)
    if isinstance(s, Rect):
        return (f'<geom name={name} type="box" pos="{_f(s.cx, s.cy, ob.height / 2)}" '
                f'size="{_f(s.sx / 2, s.sy / 2, ob.height / 2)}" euler="0 0 {s.yaw:.12g}" class="obstacle"/>')
    return (f'<geom name={name} type="cylinder" pos="{_f(s.cx, s.cy, ob.height / 2)}" '
            f'size="{_f(s.r, ob.height / 2)}" class="obstacle"/>')


def build_mjcf(robot: RobotDescription, obstacles: Sequence[Obstacle], bounds: Sequence[float],
               timestep: float = 0.002) -> str:
    xmin, ymin, xmax, ymax = bounds
    fx, fy = (xmin + xmax) / 2, (ymin + ymax) / 2
    fsx, fsy = (xmax - xmin) / 2 + 5.0, (ymax - ymin) / 2 + 5.0
    cx, cy, sx, sy = robot.footprint_box
    h = robot.body.height
    mass, izz = base_inertia(robot)
    lim = robot.limits
    mx, my, mz, myaw = robot.lidar.mount
    kv_lin, kv_yaw = mass / SERVO_TIME_CONSTANT, izz / SERVO_TIME_CONSTANT
    obstacles_xml = "\n    ".join(_obstacle_xml(ob) for ob in obstacles)
    return f"""<mujoco model={quoteattr(robot.name)}>
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{timestep:.9g}" integrator="implicitfast" cone="pyramidal"/>
  <default>
    <default class="obstacle">
      <geom contype="1" conaffinity="1" group="0" friction="0.4 0.005 0.0001" solref="0.01 1" rgba=".7 .7 .7 1"/>
    </default>
  </default>
  <worldbody>
    <light pos="{_f(fx, fy, 10)}" dir="0 0 -1"/>
    <geom name="{FLOOR_GEOM}" type="plane" pos="{_f(fx, fy, 0)}" size="{_f(fsx, fsy, 0.1)}"
          contype="0" conaffinity="0" group="1" rgba=".9 .9 .85 1"/>
    {obstacles_xml}
    <body name="{BASE_BODY}" pos="0 0 0">
      <joint name="base_x" type="slide" axis="1 0 0" damping="0"/>
      <joint name="base_y" type="slide" axis="0 1 0" damping="0"/>
      <joint name="base_yaw" type="hinge" axis="0 0 1" damping="0"/>
      <inertial pos="0 0 {BASE_CLEARANCE + h / 2:.9g}" mass="{mass:.9g}" diaginertia="{_f(izz, izz, izz)}"/>
      <geom name="{ROBOT_GEOM}" type="box" pos="{_f(cx, cy, BASE_CLEARANCE + h / 2)}"
            size="{_f(sx / 2, sy / 2, h / 2)}" contype="1" conaffinity="1" group="3" mass="0"
            friction="0.4 0.005 0.0001" solref="0.01 1" rgba=".2 .4 .8 1"/>
      <site name="drive" pos="0 0 0"/>
      <site name="{LIDAR_SITE}" pos="{_f(mx, my, mz)}" euler="0 0 {myaw:.12g}"/>
    </body>
  </worldbody>
  <actuator>
    <velocity name="drive_vx" site="drive" gear="1 0 0 0 0 0" kv="{kv_lin:.9g}"
              forcelimited="true" forcerange="{_f(-mass * lim.max_ax, mass * lim.max_ax)}"/>
    <velocity name="drive_vy" site="drive" gear="0 1 0 0 0 0" kv="{kv_lin:.9g}"
              forcelimited="true" forcerange="{_f(-mass * lim.max_ay, mass * lim.max_ay)}"/>
    <velocity name="drive_wz" joint="base_yaw" kv="{kv_yaw:.9g}"
              forcelimited="true" forcerange="{_f(-izz * lim.max_aw, izz * lim.max_aw)}"/>
  </actuator>
</mujoco>
"""


def yaw_of(xmat: Sequence[float]) -> float:
    """Heading from a body's world rotation matrix (row-major 3x3), never from a joint value."""
    return math.atan2(xmat[3], xmat[0])

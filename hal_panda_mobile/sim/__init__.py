"""Simulation core of hal_panda_mobile: MuJoCo base + 2-D lidar + scenes, no middleware and no file formats.

It takes plain dataclasses (:class:`RobotDescription`, :class:`Scene`, :class:`SimParams`); reading them
from YAML is :mod:`hal_panda_mobile.files`.
"""

from .engine import CmdStatus, CollisionEvent, LidarNoise, PandaMobileSim, SimParams
from .errors import SimConfigError
from .lidar import ScanResult
from .odometry import OdomNoise, OdomState
from .robot import BodySpec, KinematicsSpec, LidarSpec, LimitsSpec, RobotDescription
from .scene import Box, Cylinder, Obstacle, Scene, Wall, check_start, first_collision
from .worldgen import random_scene, scene_from_grid

__all__ = [
    "BodySpec", "Box", "CmdStatus", "CollisionEvent", "Cylinder", "KinematicsSpec", "LidarNoise", "LidarSpec",
    "LimitsSpec", "Obstacle", "OdomNoise", "OdomState", "PandaMobileSim", "RobotDescription", "ScanResult", "Scene",
    "SimConfigError", "SimParams", "Wall", "check_start", "first_collision", "random_scene", "scene_from_grid",
]

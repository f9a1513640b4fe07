"""Simulation core of hal_panda_mobile: MuJoCo base + 2-D lidar + scenes, no middleware."""

from .engine import CmdStatus, CollisionEvent, LidarNoise, PandaMobileSim, SimParams
from .errors import SimConfigError
from .lidar import ScanResult
from .odometry import OdomNoise, OdomState
from .robot import RobotDescription, load_robot_description
from .scene import Scene, available_scenes, load_scene
from .worldgen import random_scene, scene_from_map

__all__ = [
    "CmdStatus", "CollisionEvent", "LidarNoise", "OdomNoise", "OdomState", "PandaMobileSim", "RobotDescription",
    "ScanResult", "Scene", "SimConfigError", "SimParams", "available_scenes", "load_robot_description",
    "load_scene", "random_scene", "scene_from_map",
]

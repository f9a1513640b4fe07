"""SLAM core: numpy/scipy only, no middleware. See :class:`SlamEngine` for the entry point."""

from .engine import SlamEngine
from .lookup import LookupGrid
from .matcher import MatchResult, match_scan
from .metrics import align_se2, ate_rmse, occupied_iou
from .occupancy import OccupancyGrid
from .posegraph import PoseGraph
from .preprocess import PreparedScan, ScanError, prepare_scan
from .render import render_map_png
from .session import SessionData, SessionFileError, SessionSaveError, load_session, save_session
from .types import Scan, SlamConfig, SlamStats, Update

__all__ = [
    "LookupGrid", "MatchResult", "OccupancyGrid", "PoseGraph", "PreparedScan", "Scan", "ScanError",
    "SessionData", "SessionFileError", "SessionSaveError", "SlamConfig", "SlamEngine", "SlamStats", "Update",
    "align_se2", "ate_rmse", "load_session", "match_scan", "occupied_iou", "prepare_scan", "render_map_png",
    "save_session",
]

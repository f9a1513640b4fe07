"""SLAM core: numpy/scipy only, no middleware and no file formats. See :class:`SlamEngine` for the entry point.

Session files are :mod:`slam_service.session_io`; the PNG map card is :mod:`slam_service.render`.
"""

from robonix_common import jit_setup  # noqa: F401  (first: numba's cache dir, before any kernel)
from robonix_common.scan import Scan

from .engine import SlamEngine
from .lookup import LookupGrid
from .matcher import MatchResult, match_scan
from .metrics import align_se2, ate_rmse, occupied_iou
from .occupancy import LogOddsGrid
from .posegraph import PoseGraph
from .preprocess import PreparedScan, ScanError, prepare_scan
from .session import SessionData
from .types import SlamConfig, SlamStats, Update

__all__ = [
    "LogOddsGrid", "LookupGrid", "MatchResult", "PoseGraph", "PreparedScan", "Scan", "ScanError", "SessionData",
    "SlamConfig", "SlamEngine", "SlamStats", "Update", "align_se2", "ate_rmse", "match_scan", "occupied_iou",
    "prepare_scan",
]

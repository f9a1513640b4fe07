"""robonix SLAM service: online 2D mapping + localization.

The numpy/scipy core lives in :mod:`slam_service.core`; the provider process (atlas, DDS, gRPC, MCP)
wraps it and is kept out of this package's import path so the core can be used and tested alone.
"""

"""``python -m slam_service``: register with the atlas, serve the Driver and map RPCs until shutdown."""

from robonix_api.hosting import run_provider

if __name__ == "__main__":
    raise SystemExit(run_provider("slam_service.provider:build_provider", log_env="SLAM_LOG_LEVEL"))

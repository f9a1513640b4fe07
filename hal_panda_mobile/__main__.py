"""``python -m hal_panda_mobile``: register with the atlas, serve the Driver, run until shutdown."""

from robonix_api.hosting import run_provider

if __name__ == "__main__":
    raise SystemExit(run_provider("hal_panda_mobile.provider:build_provider", log_env="HAL_LOG_LEVEL"))

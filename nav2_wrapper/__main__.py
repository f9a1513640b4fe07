"""``python -m nav2_wrapper``: the navigation provider (``python -m nav2_wrapper.atlas_bridge`` is an alias)."""

from robonix_api.hosting import run_provider

if __name__ == "__main__":
    raise SystemExit(run_provider("nav2_wrapper.provider:build_provider", log_env="NAV_LOG_LEVEL"))

"""Alias of ``python -m nav2_wrapper`` under the name robonix's nav2_wrapper seed and our scripts use."""

import runpy

if __name__ == "__main__":
    runpy.run_module("nav2_wrapper", run_name="__main__", alter_sys=True)

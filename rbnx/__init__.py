"""rbnx: the robonix-nav command line (build, boot, start, shutdown, validate, and atlas queries)."""

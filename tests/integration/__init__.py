"""Integration tests, one directory per package (``system/`` for whole deployments): real atlas, providers,
DDS, MuJoCo in a child process, gRPC, MCP, browser, container. Marked ``integration`` by tests/conftest.py."""

"""Helpers shared by the integration-test directories (and bench/nav_latency_bench.py).

Imported as top-level ``support`` from the tests (tests/ is on sys.path, see tests/conftest.py) and as
``tests.support`` from the bench scripts (the repository root on sys.path). Nothing here is collected.
"""

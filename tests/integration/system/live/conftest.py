"""Live-system tests (real boot, browser): fixtures are in the test module."""

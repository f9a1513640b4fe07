"""Recording, replay and dashboard tests share the suite-wide DDS isolation of tests/conftest.py."""

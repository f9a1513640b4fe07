"""Gateway tests: an in-process atlas (support.fixtures) and providers in threads or real processes."""

from support.fixtures import atlas

__all__ = ["atlas"]

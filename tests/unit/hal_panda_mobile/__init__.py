"""Tests of the hal_panda_mobile simulation core."""

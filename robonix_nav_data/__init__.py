"""Data-only package: the repository root's non-Python files, shipped inside the wheel.

The entries here are symlinks into the repository root (config/, examples/, scripts/, docker/, the
navigation package's manifests, constraints.txt); building a wheel copies their contents, so an
installed robonix-nav carries them too. Do not import from here: use ``robonix_api.resources``.
"""

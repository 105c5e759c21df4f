"""The versions that a saved run, agent or report records, so results can be traced.

>>> sorted(package_versions())
['numpy', 'pokerirl', 'pyarrow', 'python', 'rlcard', 'scipy', 'torch']
"""

from __future__ import annotations

import platform
from importlib import metadata

PACKAGES = ("pokerirl", "numpy", "pyarrow", "scipy", "torch", "rlcard")


def package_versions() -> dict[str, str | None]:
    """Python's version and each of :data:`PACKAGES`' (None where one is not installed)."""
    versions: dict[str, str | None] = {"python": platform.python_version()}
    for package in PACKAGES:
        try:
            versions[package] = metadata.version(package)
        except metadata.PackageNotFoundError:
            versions[package] = None
    return versions

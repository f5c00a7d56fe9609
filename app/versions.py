"""``--version``: this program's version, and the versions of what it runs on.

Read from the installed packages' metadata (:mod:`importlib.metadata`), so nothing heavy is
imported to answer (importing numba alone costs about 0.3 s). Run from a checkout that was
never installed, the program's own version comes from ``pyproject.toml`` beside ``app/``.
"""

from __future__ import annotations

import platform
import sys
from importlib import metadata
from pathlib import Path

NAME = "fvd-viewer"
KEY_PACKAGES = ("numpy", "numba", "moderngl", "imgui-bundle")
PYPROJECT = Path(__file__).resolve().parent.parent / "pyproject.toml"


def own_version() -> str:
    """The installed distribution's version, else pyproject's, else ``unknown``."""
    try:
        return metadata.version(NAME)
    except metadata.PackageNotFoundError:
        pass
    try:
        import tomllib
        with open(PYPROJECT, "rb") as file:
            return str(tomllib.load(file)["project"]["version"])
    except (OSError, ValueError, KeyError, TypeError):
        return "unknown"


def package_version(name: str) -> str:
    """``numba 0.61.2``, or ``numba not installed``."""
    try:
        return f"{name} {metadata.version(name)}"
    except metadata.PackageNotFoundError:
        return f"{name} not installed"


def version_text() -> str:
    """Two lines: ``fvd-viewer 0.1.0``, then Python's and the key packages' versions."""
    python = (f"Python {platform.python_version()} ({platform.python_implementation()}, "
              f"{sys.platform} {platform.machine()})")
    return f"{NAME} {own_version()}\n" + ", ".join([python, *map(package_version, KEY_PACKAGES)])

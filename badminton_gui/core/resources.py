"""The files shipped with the package: parameter presets, candidate classifiers, icons.

Why this file exists: they live in the repository's top-level ``resources/`` folder, which the
build maps into the package ``badminton_gui.resources`` (pyproject.toml), so a wheel installed
anywhere carries them. Everything that reads a shipped file asks here, through the import
system, instead of guessing a path relative to the source tree; a plain checkout
that was never installed (``PYTHONPATH=.``) falls back to the repository folder.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

_PACKAGE = "badminton_gui.resources"


def resources_dir() -> Path:
    """The folder holding the shipped resources (``presets/``, ``*.json`` classifiers, ``icons/``)."""
    # resources/ holds no __init__.py, so it is a namespace package: its spec lists its folder
    # (importlib.resources.files would hand back a MultiplexedPath, which is no Path).
    try:
        spec = importlib.util.find_spec(_PACKAGE)
    except ModuleNotFoundError:
        spec = None
    for location in (spec.submodule_search_locations or []) if spec is not None else []:
        if Path(location).is_dir():
            return Path(location)
    return Path(__file__).resolve().parents[2] / "resources"


def resource_path(*parts: str) -> Path:
    """A shipped file's path, e.g. ``resource_path("presets", "default.json")``; it may not exist."""
    return resources_dir().joinpath(*parts)

"""Parameter presets: one readable JSON file per kind of set-up, shipped in ``resources/presets/``.

Why this file exists: the operator picks a set-up (two fixed high-speed cameras, a broadcast
camera) rather than tuning thirty thresholds; the CLI (`--preset`), the GUI and `presets` list
read the same files. A preset may be partial: unspecified values keep their defaults.
"""

from __future__ import annotations

import json
from pathlib import Path

from ..core.params import ParamError, TrackerParams
from ..core.resources import resource_path

DEFAULT_PRESET = "default"


def presets_dir() -> Path:
    """The folder of the shipped presets (inside the installed package)."""
    return resource_path("presets")


def list_presets() -> dict[str, str]:
    """Preset name → its one-line description."""
    out = {}
    for path in sorted(presets_dir().glob("*.json")):
        try:
            description = json.loads(path.read_text(encoding="utf-8")).get("_description", "")
        except (OSError, json.JSONDecodeError):
            description = "(unreadable)"
        out[path.stem] = description
    return out


def preset_path(name_or_path: str) -> Path:
    candidate = Path(name_or_path)
    if candidate.suffix == ".json" and candidate.is_file():
        return candidate
    path = presets_dir() / f"{name_or_path}.json"
    if not path.is_file():
        known = ", ".join(list_presets()) or "none"
        raise ParamError(f"no preset {name_or_path!r} (known presets: {known}; or give a .json path)")
    return path


def load_preset(name_or_path: str | None = None) -> TrackerParams:
    return TrackerParams.load(preset_path(name_or_path or DEFAULT_PRESET))

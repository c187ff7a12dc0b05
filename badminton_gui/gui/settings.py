"""Where the application remembers the last source, rig and parameters (QSettings).

Why this file exists: one place decides which settings store is used, so tests can point it at
a temporary file with ``BADMINTON_GUI_SETTINGS=/tmp/x.ini`` and never touch the user's settings.
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass, replace

from PySide6.QtCore import QSettings

from ..core.params import ParamError, TrackerParams

SETTINGS_ENV = "BADMINTON_GUI_SETTINGS"
ORGANISATION = "badminton-gui"
APPLICATION = "badminton-gui"


def open_settings() -> QSettings:
    """The settings store: an INI file named by $BADMINTON_GUI_SETTINGS, else the user's."""
    path = os.environ.get(SETTINGS_ENV)
    if path:
        return QSettings(path, QSettings.Format.IniFormat)
    return QSettings(QSettings.Format.IniFormat, QSettings.Scope.UserScope, ORGANISATION, APPLICATION)


@dataclass(frozen=True)
class SourceSpec:
    """What to open: the demo court, a video pair with its rig, or two cameras with their rig."""

    kind: str = "demo"                 # "demo" / "video" / "single" (one camera's video) / "cameras"
    left: str = ""                     # video path or camera index / URL
    right: str = ""
    calib: str = ""                    # rig file; optional for the demo (it knows its own rig)
    left_times: str = ""               # optional timestamp CSVs of a video pair
    right_times: str = ""
    realtime: bool = True              # pace file / demo sources to their fps
    video_times: bool = False          # pair a video pair by the files' own frame timestamps
    left_labels: str = ""              # optional label CSVs (Frame,Visibility,X,Y): live score
    right_labels: str = ""

    @property
    def swappable(self) -> bool:
        """A two-camera source whose cameras can be given the other way round."""
        return self.kind in ("video", "cameras")

    def swapped(self) -> "SourceSpec":
        """The same source with the left and right cameras exchanged (their timestamps and labels
        with them): a rack cabled the other way round, or two videos picked in the wrong fields."""
        return replace(self, left=self.right, right=self.left, left_times=self.right_times,
                       right_times=self.left_times, left_labels=self.right_labels,
                       right_labels=self.left_labels)

    def describe(self) -> str:
        if self.kind == "demo":
            return "Demo court"
        if self.kind == "video":
            return f"Videos {os.path.basename(self.left)} + {os.path.basename(self.right)}"
        if self.kind == "single":
            return f"Video {os.path.basename(self.left)} (one camera)"
        return f"Cameras {self.left} + {self.right}"


def load_source_spec(settings: QSettings) -> SourceSpec:
    raw = settings.value("source/spec", "")
    if not raw:
        return SourceSpec()
    try:
        data = json.loads(str(raw))
        return SourceSpec(**{k: v for k, v in data.items() if k in SourceSpec.__dataclass_fields__})
    except (TypeError, ValueError):
        return SourceSpec()


def save_source_spec(settings: QSettings, spec: SourceSpec) -> None:
    settings.setValue("source/spec", json.dumps(asdict(spec)))


def load_params(settings: QSettings) -> TrackerParams | None:
    """The parameters of the last session, or None when absent or no longer valid."""
    raw = settings.value("tracker/params", "")
    if not raw:
        return None
    try:
        return TrackerParams.from_dict(json.loads(str(raw)))
    except (ValueError, ParamError, TypeError):
        return None


def save_params(settings: QSettings, params: TrackerParams) -> None:
    settings.setValue("tracker/params", json.dumps(params.to_dict()))


# ---- the folder each kind of file dialog opens in ----------------------------------------
# One key per kind of file, so the rig dialog does not open where the last video was.
FILE_KINDS = ("videos", "rigs", "presets", "tracks", "labels", "images")


def _default_folder(kind: str) -> str:
    from pathlib import Path
    if kind == "rigs":
        from ..io.app_dirs import rig_dir
        return str(rig_dir())
    return str(Path.home())


def dialog_folder(settings: QSettings, kind: str, first_time: str | None = None) -> str:
    """The folder a file dialog for ``kind`` (one of FILE_KINDS) opens in: the one last used for
    that kind, while it exists; else ``first_time`` if given, else the rigs' folder for rigs and
    the home folder otherwise."""
    if kind not in FILE_KINDS:
        raise ValueError(f"unknown kind of file {kind!r}")
    folder = str(settings.value(f"folders/{kind}", "") or "")
    if folder and os.path.isdir(folder):
        return folder
    return first_time if first_time is not None else _default_folder(kind)


def remember_dialog_folder(settings: QSettings, kind: str, chosen: str) -> None:
    """Remember the folder of ``chosen`` (a file or folder the user picked) for ``kind``."""
    if kind not in FILE_KINDS:
        raise ValueError(f"unknown kind of file {kind!r}")
    if not chosen:
        return
    folder = chosen if os.path.isdir(chosen) else os.path.dirname(os.path.abspath(chosen))
    settings.setValue(f"folders/{kind}", folder)


# ---- the preset the parameters come from ------------------------------------------------
def load_preset_in_use(settings: QSettings) -> str:
    """The preset (a shipped name, or a .json path) the parameters were last set from."""
    return str(settings.value("tracker/preset", "") or "default")


def save_preset_in_use(settings: QSettings, name_or_path: str) -> None:
    settings.setValue("tracker/preset", name_or_path)

"""Where the program keeps what outlives a run: logs, and the rigs the wizard saves.

Why this file exists: the CLI, the GUI's About box, its error banners and the log set-up must
all name the same folders, on Linux, macOS and Windows, also when the package is installed from
a wheel (where no repository ``calibration/`` folder exists). Tests point everything at a
temporary folder with ``BADMINTON_GUI_STATE_DIR`` so they never write into the user's home.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

APP_NAME = "badminton-gui"
STATE_DIR_ENV = "BADMINTON_GUI_STATE_DIR"


def state_dir() -> Path:
    """The per-user folder for this program's state (logs live below it); not created here.

    ``$BADMINTON_GUI_STATE_DIR`` wins; else the platform's convention: ``$XDG_STATE_HOME`` or
    ``~/.local/state`` on Linux, ``~/Library/Application Support`` on macOS, ``%LOCALAPPDATA%``
    on Windows.
    """
    override = os.environ.get(STATE_DIR_ENV)
    if override:
        return Path(override).expanduser()
    home = Path.home()
    if sys.platform.startswith("win"):
        base = Path(os.environ.get("LOCALAPPDATA") or home / "AppData" / "Local")
    elif sys.platform == "darwin":
        base = home / "Library" / "Application Support"
    else:
        base = Path(os.environ.get("XDG_STATE_HOME") or home / ".local" / "state")
    return base / APP_NAME


def log_dir() -> Path:
    """The folder of the rotating log file (``badminton-gui.log``); not created here."""
    return state_dir() / "logs"


def user_rig_dir() -> Path:
    """Where the calibration wizard saves rigs when the program is not run from a checkout."""
    return state_dir() / "rigs"


def repository_root() -> Path | None:
    """The checkout this package runs from (it has ``pyproject.toml`` and ``calibration/``), else None."""
    root = Path(__file__).resolve().parents[2]
    if (root / "pyproject.toml").is_file() and (root / "calibration").is_dir():
        return root
    return None


def rig_dir() -> Path:
    """The rigs' folder: the checkout's ``calibration/`` when run from one, else :func:`user_rig_dir`."""
    root = repository_root()
    return root / "calibration" if root is not None else user_rig_dir()

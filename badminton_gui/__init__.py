"""Courtside stereo-vision shuttlecock tracker for badminton robots.

The public, Qt-free entry points::

    from badminton_gui import StereoTracker, StereoRig
    tracker = StereoTracker(StereoRig.load("calibration/rig.yaml"))
    result = tracker.process(left_bgr, right_bgr, timestamp)
"""

from .core.params import TrackerParams
from .core.rig import RigError, StereoRig
from .core.tracker import StereoTracker
from .core.types import CameraResult, Candidate, StereoFrame, TrackResult

__all__ = ["StereoTracker", "StereoRig", "RigError", "TrackerParams", "TrackResult",
           "CameraResult", "Candidate", "StereoFrame"]


def _version() -> str:
    """The version has one source, pyproject.toml: read from the installed package's metadata,
    or from pyproject.toml itself when this checkout was never installed."""
    from importlib.metadata import PackageNotFoundError, version
    try:
        return version("badminton-gui")
    except PackageNotFoundError:
        import tomllib
        from pathlib import Path
        try:
            with open(Path(__file__).resolve().parents[1] / "pyproject.toml", "rb") as fh:
                return str(tomllib.load(fh)["project"]["version"])
        except (OSError, KeyError, tomllib.TOMLDecodeError):
            return "unknown"


__version__ = _version()

"""Courtside stereo-vision shuttlecock tracker for badminton robots.

The public, Qt-free entry points::

    from badminton_gui import StereoTracker, StereoRig
    tracker = StereoTracker(StereoRig.load("calibration/rig.yaml"))
    result = tracker.process(left_bgr, right_bgr, timestamp)

Input the tracker cannot use (a rig that cannot be right, a frame of the wrong type or size, a
timestamp that is not finite or goes back) raises ``TrackerInputError`` (a ``ValueError``; the
rig's ``RigError`` is one) with a sentence that says what to change.
"""

from .core.errors import TrackerInputError
from .core.params import TrackerParams
from .core.rig import RigError, StereoRig
from .core.tracker import StereoTracker
from .core.types import CameraResult, Candidate, StereoFrame, TrackResult

__all__ = ["StereoTracker", "StereoRig", "RigError", "TrackerInputError", "TrackerParams", "TrackResult",
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

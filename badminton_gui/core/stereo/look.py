"""Each camera's own image path, and the stereo look along it.

Why this file exists: before the 3D flight is known (the first frames after a hit) a small or
dim shuttle may give no blob that passes the contour filters in one camera while the other
follows it; where this camera's own image path continues, on the other detection's epipolar
line, a white spot is that shuttle (``stereo.stereo_look``). The same image path tells when the
shuttle has run out of the image (``stereo.exit_by_path``).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable

import numpy as np

from ..guided import find_spot
from ..params import TrackerParams
from ..rig import StereoRig
from ..step import Step
from ..types import Candidate
from .epipolar import EpipolarGate

# s: how old this camera's last report may be for its image path to be followed (three frames
# at 120 fps).
STEREO_LOOK_AGE = 0.03
# px² at 1280 px width: the largest spot the stereo look takes (a shuttle near the rig is
# ~10 px across; a player's white shirt is larger).
STEREO_LOOK_MAX_AREA = 150.0


class ImagePaths:
    """Per camera, its last two measured reports: (t, x, y, image velocity or None)."""

    def __init__(self) -> None:
        self._reports: tuple[deque, deque] = (deque(maxlen=2), deque(maxlen=2))

    def note(self, cam: int, t: float, x: float, y: float,
             velocity: tuple[float, float] | None) -> None:
        """Camera ``cam`` reported a measured detection at (x, y) at ``t``."""
        self._reports[cam].append((t, x, y, velocity))

    def last(self, cam: int) -> tuple[float, float, float, tuple[float, float] | None] | None:
        """Camera ``cam``'s last noted report, or None."""
        reports = self._reports[cam]
        return reports[-1] if reports else None

    def point(self, cam: int, t: float) -> tuple[float, float] | None:
        """Where this camera's own image path puts the shuttle at ``t``: its last report before
        ``t`` (within ``STEREO_LOOK_AGE`` s) moved on by its track's image velocity, or by the
        step from the report before; None without such reports."""
        hist = [r for r in self._reports[cam] if r[0] < t]
        if not hist:
            return None
        t2, x2, y2, vel = hist[-1]
        if t - t2 > STEREO_LOOK_AGE:
            return None
        if vel is None:
            if len(hist) < 2:
                return None
            t1, x1, y1, _ = hist[-2]
            if not (0.0 < t2 - t1 <= STEREO_LOOK_AGE):
                return None
            vel = ((x2 - x1) / (t2 - t1), (y2 - y1) / (t2 - t1))
        return x2 + vel[0] * (t - t2), y2 + vel[1] * (t - t2)

    def leaves(self, cam: int, frame: np.ndarray, t: float) -> bool:
        """This camera's own image path has left the image by now (``stereo.exit_by_path``)."""
        path = self.point(cam, t)
        if path is None:
            return False
        h, w = frame.shape[:2]
        return not (0 <= path[0] < w and 0 <= path[1] < h)


def stereo_look(rig: StereoRig, params: TrackerParams, gate: EpipolarGate, paths: ImagePaths,
                camera: int, frame: np.ndarray, previous: np.ndarray | None, other: Candidate,
                t: float) -> Candidate | None:
    """A white spot where this camera's own image path continues, on the epipolar line of the
    other camera's detection (``stereo.stereo_look``), or None.

    This camera's last report (within ``STEREO_LOOK_AGE`` s), moved on by its track's image
    velocity (or the step from the report before), says where to look
    (``stereo.stereo_look_radius``); the spot must lie within the vouch's epipolar gate of the
    other detection's epipolar line. ``previous``: this camera's last image.
    """
    sp = params.stereo
    path = paths.point(camera, t)
    if path is None:
        return None
    u, v = path
    h, w = frame.shape[:2]
    if not (0 <= u < w and 0 <= v < h):
        return None
    scale = w / 1280.0
    spot = find_spot(frame, u, v, sp.stereo_look_radius * scale, sp.guided_min_contrast,
                     STEREO_LOOK_MAX_AREA * scale * scale, previous)
    if spot is None:
        return None
    x, y, contrast, area = spot
    pair = ([[other.x, other.y]], [[x, y]]) if camera == 1 else ([[x, y]], [[other.x, other.y]])
    if float(rig.epipolar_errors(*pair)[0, 0]) > gate.vouch_tolerance():
        return None
    return Candidate(x=x, y=y, length=float("nan"), short_side=float("nan"), whiteness=contrast,
                     area=area, motion=math.hypot(x - u, y - v), score=0.0)


def look_on_epipolar_lines(step: Step, rig: StereoRig, params: TrackerParams, gate: EpipolarGate,
                           paths: ImagePaths, previous: list[np.ndarray | None],
                           pair_point: Callable[[Candidate | None, Candidate | None], tuple]) -> None:
    """The stage: neither the pair nor the flight found the shuttle in one camera, the other has a
    sure detection (``stereo.stereo_look_min_score``): look where this camera's own image path
    continues on that detection's epipolar line; a spot found makes the pair (``pair_point``).
    ``previous``: each camera's last image."""
    sp = params.stereo
    if not sp.stereo_look or step.point is not None:
        return
    for cam in (0, 1):
        own, other = step.dets[cam], step.dets[1 - cam]
        if ((own is None or own.predicted) and other is not None
                and not other.predicted and other.score >= sp.stereo_look_min_score):
            found = stereo_look(rig, params, gate, paths, cam, step.frames[cam], previous[cam], other, step.t)
            if found is not None:
                step.add(cam, found)
                step.fired("stereo_look", cam)
                step.point, step.epi = pair_point(step.dets[0], step.dets[1])
                return

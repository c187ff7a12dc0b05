"""The cork correction: the triangulated blob point moved forward along the flight to the cork.

Why this file exists: each camera measures the centroid of the blob's bright part, which lies
behind the cork because the skirt trails it 4–7 cm. The bias is the same 3D offset in both views
(a shift along the flight, not a disparity error), so it is removed in 3D, after triangulation,
with a variance that tells the flight filter how sure the correction's direction is.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..detector import CameraDetector
from ..params import TrackerParams
from ..rig import StereoRig
from ..types import Candidate

# Time step (s) over which the tracklets' image velocities are followed back to find the
# flight direction for the cork correction: long enough to resolve the direction, short
# enough that the image path is still straight.
HEAD_DIRECTION_DT = 0.01
# The cork correction's direction is checked against the 3D step from the previous blob point
# when that point is at most this old (s) and the step at least this many head offsets long
# (shorter steps are mostly the points' noise): see ``CorkCorrection.variance``.
HEAD_CHECK_DT = 0.02
HEAD_CHECK_STEPS = 4.0


class CorkCorrection:
    """Moves pairs' points to the cork; remembers the last blob point to check the direction."""

    def __init__(self, rig: StereoRig, params: TrackerParams,
                 detectors: tuple[CameraDetector, CameraDetector],
                 right_xy: Callable[[Candidate], tuple[float, float]]) -> None:
        self.rig = rig
        self.params = params
        self.detectors = detectors
        self._right_xy = right_xy
        # The last frame's triangulated blob point (left-camera frame) and its time.
        self._last_blob: tuple[float, np.ndarray] | None = None

    def last_blob_point(self) -> np.ndarray | None:
        """The last noted blob point (left-camera frame), or None."""
        return None if self._last_blob is None else self._last_blob[1]

    def note_blob(self, t: float, blob: np.ndarray | None) -> None:
        """This step's triangulated blob point (None: no pair)."""
        self._last_blob = None if blob is None else (t, blob)

    def to_head(self, det_left: Candidate, det_right: Candidate, point: np.ndarray) -> np.ndarray:
        """Move the triangulated blob point forward along the flight to the cork.

        The direction is the triangulation of the two tracklets' image velocities. Without a
        known image velocity in both cameras (the first frames of a tracklet, a shuttle at rest)
        the point is left as measured.
        """
        sp = self.params.stereo
        vl = self.detectors[0].tracklet_velocity(det_left)
        vr = self.detectors[1].tracklet_velocity(det_right)
        if vl is None or vr is None:
            return point
        xr, yr = self._right_xy(det_right)
        back = self.rig.triangulate([[det_left.x - vl[0] * HEAD_DIRECTION_DT,
                                      det_left.y - vl[1] * HEAD_DIRECTION_DT]],
                                    [[xr - vr[0] * HEAD_DIRECTION_DT,
                                      yr - vr[1] * HEAD_DIRECTION_DT]])[0]
        step = point - back
        norm = float(np.linalg.norm(step))
        if norm < sp.head_min_speed * HEAD_DIRECTION_DT:
            return point
        return point + sp.head_offset * step / norm

    def variance(self, timestamp: float, blob: np.ndarray, moved: np.ndarray) -> float:
        """Variance (m², per axis) of the cork correction ``moved`` applied to the blob point.

        The correction follows the tracklets' image velocities, which are smoothed over several
        frames: for the first frames after a hit they still point along the old flight (on the
        demo court the correction was 90° off one frame after a smash and 55° off the next),
        and the first frames of a tracklet get no correction at all. Either way the point is off
        by up to twice ``head_offset`` across the flight, in the directions the stereo pair
        measures best, and a young flight bends to fit it. The 3D step from the last frame's
        blob point shows the real direction when it is long enough to be sure of
        (``HEAD_CHECK_STEPS`` × ``head_offset``): the mismatch between the correction made and
        the one that direction asks for is the variance. Without such a step, an uncorrected
        point gets ``head_offset``² (it may be moving), a corrected one nothing.
        """
        offset = float(self.params.stereo.head_offset)
        last = self._last_blob
        step = None
        if last is not None and 0.0 < timestamp - last[0] <= HEAD_CHECK_DT:
            step = blob - last[1]
            if float(np.linalg.norm(step)) < HEAD_CHECK_STEPS * offset:
                step = None
        if step is None:
            return 0.0 if float(np.linalg.norm(moved)) > 0.0 else offset * offset
        wanted = offset * step / float(np.linalg.norm(step))
        return float(np.sum((moved - wanted) ** 2))

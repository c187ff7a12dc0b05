"""The one-camera tracker: a single view (a TV broadcast) through the same per-camera detector.

Why this file exists: `badminton-track detect` follows the shuttle in one camera's video, and the
GUI must do the same live so an operator can watch and tune the broadcast preset on a TV clip
(issue 5: the broadcast preset is for `detect`, `track` and the GUI). This gives the worker an
object with the stereo tracker's interface — ``process`` returns a :class:`TrackResult` — whose
right camera is empty and which has no 3D point, distance, speed or landing prediction: one view
cannot place the shuttle in space. The readout is the per-camera detector's own choice, frame by
frame (no look-ahead, as the stereo tracker's live readout).
"""

from __future__ import annotations

import time

import numpy as np

from .detector import CameraDetector
from .params import TrackerParams
from .types import CameraResult, FlightInfo, StereoFrame, TrackResult

NO_3D = "one camera: no 3D point"


class MonoTracker:
    """One camera's detector behind the stereo tracker's ``process`` / ``set_params`` / ``close``."""

    trajectory = None          # no 3D flight without a second camera
    rig_epipolar_px = None     # no stereo rig to check
    rig_swapped_px = None

    def __init__(self, params: TrackerParams | None = None) -> None:
        self.params = params or TrackerParams()
        self.detector = CameraDetector(self.params)

    def set_params(self, params: TrackerParams) -> None:
        self.detector.set_params(params)
        self.params = params

    def reset(self) -> None:
        self.detector.reset()

    def close(self) -> None:
        """Nothing to release (the stereo tracker's thread pool has no counterpart here)."""

    def process_frame(self, frame: StereoFrame, keep_masks: bool = True) -> TrackResult:
        """One step of a one-camera source (its frames carry ``right=None``)."""
        return self.process(frame.left, None, frame.t_left, frame.index, frame.index_right, keep_masks)

    def process(self, frame_bgr: np.ndarray, _right: None, timestamp: float, index: int = -1,
                index_right: int = -1, keep_masks: bool = True) -> TrackResult:
        start = time.perf_counter()
        result = self.detector.process(frame_bgr, timestamp, keep_mask=keep_masks)
        h, w = frame_bgr.shape[:2]
        return TrackResult(index=index, timestamp=timestamp, left=result,
                           right=CameraResult(detection=None, image_size=(w, h)),
                           processing_ms=(time.perf_counter() - start) * 1000.0,
                           flight=FlightInfo(withheld_reason=NO_3D))

"""How the two cameras' stages 1–4 run for a pair step: side by side on threads (the default),
or each in a process of its own (``StereoTracker(..., processes=True)``).

Why this file exists: the stereo tracker needs each camera's candidates for a pair before its
stereo stage; where the cameras' detectors run is a choice of execution, not of tracking, and
either choice gives the same results. Threads share the detectors' state with the stereo stage
at no cost but contend for the GIL; processes do not contend but hand each frame over and
answer the stereo stage from a snapshot (``core/camera_process.py``).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np

from .detector import CameraDetector
from .params import TrackerParams
from .types import CameraResult


class ThreadCameras:
    """Both detectors in this process; with ``parallel``, the right camera's image half on a
    pool thread (OpenCV releases the GIL: the two cameras' image work runs on two cores)."""

    def __init__(self, params: TrackerParams, geometry: tuple, parallel: bool = True) -> None:
        self.detectors = (CameraDetector(params, geometry[0]), CameraDetector(params, geometry[1]))
        self._pool = ThreadPoolExecutor(max_workers=2, thread_name_prefix="camera") if parallel else None

    def find_candidates(self, frames: tuple[np.ndarray, np.ndarray], times: tuple[float, float],
                        keep_masks: bool) -> list[CameraResult]:
        """Each camera's candidates. A windowed frame is mostly Python holding the GIL: when both
        cameras process this frame in a window they run faster in turn on this thread than side
        by side; a pair with a whole frame, mostly image work that releases the GIL, runs side by
        side. The windows are chosen first, so a camera's periodic whole frame is never run in
        turn with the other's."""
        left, right = self.detectors
        (left_bgr, right_bgr), (t, t_r) = frames, times
        in_turn = left.plan_window(left_bgr, t) & right.plan_window(right_bgr, t_r)
        if self._pool is not None and not in_turn:
            # Only the image half runs side by side (CameraDetector.segment); the measuring
            # half, many small calls each of which hands the GIL over, runs on this thread,
            # the left camera's while the right camera's image half may still be running.
            fut = self._pool.submit(right.segment, right_bgr, t_r)
            res_left = left.candidates_from(left_bgr, t, left.segment(left_bgr, t), keep_masks)
            return [res_left, right.candidates_from(right_bgr, t_r, fut.result(), keep_masks)]
        return [left.find_candidates(left_bgr, t, keep_masks), right.find_candidates(right_bgr, t_r, keep_masks)]

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None


class ProcessCameras:
    """Each detector in a worker process of its own (``RemoteDetector``): both frames are handed
    over first, then both results taken, so the two cameras run at the same time."""

    def __init__(self, params: TrackerParams, geometry: tuple, start_method: str = "spawn") -> None:
        from .camera_process import RemoteDetector
        self.detectors = (RemoteDetector(params, geometry[0], start_method),
                          RemoteDetector(params, geometry[1], start_method))

    def find_candidates(self, frames: tuple[np.ndarray, np.ndarray], times: tuple[float, float],
                        keep_masks: bool) -> list[CameraResult]:
        for detector, frame, t in zip(self.detectors, frames, times):
            detector.submit(frame, t, keep_masks)
        return [detector.collect() for detector in self.detectors]

    def frame_buffers(self, shapes: tuple[tuple[int, ...], tuple[int, ...]]) -> tuple[np.ndarray, np.ndarray]:
        """Arrays in the workers' shared memory for the next pair's frames (``RemoteDetector.frame_buffer``):
        a pair put there is handed over without a copy."""
        return tuple(detector.frame_buffer(shape) for detector, shape in zip(self.detectors, shapes))

    def worker_cpu(self) -> float:
        """The two workers' CPU seconds so far (as of their last frames)."""
        return sum(detector.worker_cpu for detector in self.detectors)

    def copy_cpu(self) -> float:
        """This process's CPU seconds spent copying the two cameras' frames to the workers."""
        return sum(detector.copy_cpu for detector in self.detectors)

    def close(self) -> None:
        for detector in self.detectors:
            detector.close()

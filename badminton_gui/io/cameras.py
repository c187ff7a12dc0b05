"""Live cameras: two OpenCV devices (indices or URLs) as one stereo source.

Why this file exists: the two cameras must be sampled as close together in time as USB allows:
``grab()`` both first (cheap, latches the frames), then ``retrieve()`` both (decode); each frame
carries the time its driver stamped it with where the driver stamps on our clock (V4L2), so two
cameras without a common trigger are paired at the moments they took their frames. A camera
that cannot open, or stops delivering, raises :class:`SourceError` with one clear sentence that
the GUI shows in its banner.
"""

from __future__ import annotations

import time

import cv2
import numpy as np

from ..core.types import StereoFrame
from .sources import SourceError

# Consecutive failed grabs before a camera counts as gone (a USB hiccup loses one or two).
MAX_FAILED_GRABS = 10
# s: how far a driver's frame time may lie from the moment its grab returned and still be taken
# as the frame's time on the clock ``time.monotonic`` reads (``_frame_time``).
DRIVER_CLOCK_SLACK = 1.0


def _device(spec: int | str) -> int | str:
    """A device index ("0" → 0) or a URL / path as given."""
    if isinstance(spec, str) and spec.strip().isdigit():
        return int(spec)
    return spec


def _backend(cap) -> str:
    """The capture's backend name ('' when OpenCV cannot say)."""
    try:
        return str(cap.getBackendName())
    except cv2.error:
        return ""


def list_cameras(max_index: int = 8) -> list[int]:
    """Indices of the cameras that open on this machine (slow-ish: opens each one)."""
    found = []
    for i in range(max_index):
        cap = cv2.VideoCapture(i)
        try:
            if cap.isOpened():
                found.append(i)
        finally:
            cap.release()
    return found


class CameraPair:
    """Two live cameras (``FrameSource``)."""

    def __init__(self, left: int | str, right: int | str,
                 size: tuple[int, int] | None = None, fps: float | None = None) -> None:
        self._specs = (_device(left), _device(right))
        self._caps: list[cv2.VideoCapture] = []
        for n, spec in enumerate(self._specs):
            cap = cv2.VideoCapture(spec)
            if not cap.isOpened():
                self.close()
                which = "left" if n == 0 else "right"
                raise SourceError(f"the {which} camera ({spec}) cannot be opened: is it plugged in "
                                  f"and not in use by another program?")
            if size is not None:
                cap.set(cv2.CAP_PROP_FRAME_WIDTH, size[0])
                cap.set(cv2.CAP_PROP_FRAME_HEIGHT, size[1])
            if fps is not None:
                cap.set(cv2.CAP_PROP_FPS, fps)
            self._caps.append(cap)
        self.name = f"Cameras {self._specs[0]} + {self._specs[1]}"
        # Linux's V4L2 stamps each frame when the kernel captured it, on the monotonic clock that
        # time.monotonic() reads (OpenCV: CAP_PROP_POS_MSEC): two free-running cameras' frames
        # are then paired at the moments they were taken, not when each grab returned (a grab
        # returns at once with a frame already queued).
        self._driver_clock = [_backend(cap) == "V4L2" for cap in self._caps]
        self._last_time = [float("-inf"), float("-inf")]
        self._index = 0
        self._failed = 0
        self._size: tuple[int, int] | None = None

    @property
    def image_size(self) -> tuple[int, int]:
        if self._size is None:
            w = int(self._caps[0].get(cv2.CAP_PROP_FRAME_WIDTH))
            h = int(self._caps[0].get(cv2.CAP_PROP_FRAME_HEIGHT))
            self._size = (w, h)
        return self._size

    @property
    def fps(self) -> float | None:
        return None

    def read(self) -> StereoFrame | None:
        while True:
            ok_left = self._caps[0].grab()
            t_left = time.monotonic()
            ok_right = self._caps[1].grab()
            t_right = time.monotonic()
            if ok_left and ok_right:
                t_left, t_right = self._frame_time(0, t_left), self._frame_time(1, t_right)
                break
            self._failed += 1
            if self._failed >= MAX_FAILED_GRABS:
                which = "left" if not ok_left else "right"
                spec = self._specs[0 if not ok_left else 1]
                raise SourceError(f"the {which} camera ({spec}) stopped delivering frames: "
                                  f"was it unplugged?")
            time.sleep(0.005)
        self._failed = 0
        ok_l, left = self._caps[0].retrieve()
        ok_r, right = self._caps[1].retrieve()
        if not (ok_l and ok_r):
            raise SourceError("a camera delivered a frame that could not be decoded")
        if left.shape != right.shape:
            raise SourceError(f"the cameras deliver different sizes ({left.shape[1]}×{left.shape[0]} "
                              f"and {right.shape[1]}×{right.shape[0]}): set both to one resolution")
        frame = StereoFrame(np.ascontiguousarray(left), np.ascontiguousarray(right),
                            t_left, t_right, self._index, self._index)
        self._index += 1
        return frame

    def _frame_time(self, cam: int, arrival: float) -> float:
        """The frame's time: its driver's stamp when the driver stamps on our clock (V4L2), it
        lies within ``DRIVER_CLOCK_SLACK`` of the grab and after the camera's last frame; else
        the moment the grab returned."""
        t = arrival
        if self._driver_clock[cam]:
            stamp = float(self._caps[cam].get(cv2.CAP_PROP_POS_MSEC)) / 1000.0
            if stamp > 0 and abs(stamp - arrival) <= DRIVER_CLOCK_SLACK and stamp > self._last_time[cam]:
                t = stamp
        self._last_time[cam] = t
        return t

    def close(self) -> None:
        for cap in self._caps:
            cap.release()
        self._caps = []

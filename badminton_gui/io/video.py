"""Recorded stereo footage: two video files paired by frame index or by per-camera timestamps.

Why this file exists: real rigs do not trigger both cameras together (the NYCU cameras drift by
frames over a rally), so pairing by index is wrong for them; pairing by the nearest timestamp
from each camera's timestamp file is what `track --left-times/--right-times` does (GUIDE §5).
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import cv2
import numpy as np

from ..core.types import StereoFrame
from .sources import OpeningCancelled, SourceError

# How often (frames) ``frame_times`` reports progress and looks whether it should stop: about
# every 0.1 s of decoding at 2048×1536.
_SCAN_REPORT_EVERY = 32


def open_video(path: str | Path) -> cv2.VideoCapture:
    """An opened capture, or a SourceError that says what is wrong with the file."""
    path = Path(path)
    if not path.exists():
        raise SourceError(f"video not found: {path}")
    if path.is_dir():
        raise SourceError(f"{path} is a folder, not a video file")
    cap = cv2.VideoCapture(str(path))
    if not cap.isOpened():
        raise SourceError(f"cannot read {path}: not a video file OpenCV can decode "
                          f"(truncated or unsupported format?)")
    ok, frame = cap.read()
    if not ok or frame is None:
        cap.release()
        raise SourceError(f"cannot read {path}: the file opens but holds no decodable frame "
                          f"(truncated or corrupt?)")
    cap.set(cv2.CAP_PROP_POS_FRAMES, 0)
    return cap


def frame_times(path: str | Path, progress: Callable[[float], None] | None = None,
                should_stop: Callable[[], bool] | None = None) -> np.ndarray:
    """Presentation time (s) of every frame of a video, in decode order, from its container.

    A camera that drops frames writes a video whose frames are not evenly spaced
    (launcher-stereo: 126 of 556 intervals between 1.9 and 90 ms among 8.4 ms ones), so frame i
    is not at i / fps and the other camera's frame i was not taken at the same moment: pairing
    by these times (``VideoPair``'s timestamps) is what such a recording needs when it comes
    without timestamp files. One decoding pass (grab, no colour conversion): ≈ 3 ms a frame at
    2048×1536, so seconds for a long recording: ``progress(fraction)`` is called as it goes
    (fraction of the container's frame count, when it has one) and ``should_stop()`` is asked
    as often; when it says yes the scan ends with ``OpeningCancelled``."""
    cap = open_video(path)
    total = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
    times = []
    try:
        while cap.grab():
            times.append(cap.get(cv2.CAP_PROP_POS_MSEC) / 1000.0)
            if len(times) % _SCAN_REPORT_EVERY == 0:
                if should_stop is not None and should_stop():
                    raise OpeningCancelled(f"reading the frame times of {Path(path).name} was cancelled")
                if progress is not None and total > 0:
                    progress(min(len(times) / total, 1.0))
    finally:
        cap.release()
    out = np.asarray(times, dtype=float)
    if len(out) == 0:
        raise SourceError(f"cannot read {path}: no frame could be decoded")
    if np.any(np.diff(out) <= 0):
        raise SourceError(f"{path}: its frames' timestamps do not increase, so they cannot pair the "
                          f"cameras; give timestamp files or pair by frame index")
    return out


class VideoFile:
    """One camera's video, read sequentially, with its frame count and size."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self._cap = open_video(self.path)
        self.width = int(self._cap.get(cv2.CAP_PROP_FRAME_WIDTH))
        self.height = int(self._cap.get(cv2.CAP_PROP_FRAME_HEIGHT))
        fps = float(self._cap.get(cv2.CAP_PROP_FPS))
        self.fps = fps if fps > 0 else 30.0
        self.frame_count = int(self._cap.get(cv2.CAP_PROP_FRAME_COUNT))
        self.next_index = 0

    def read(self) -> np.ndarray | None:
        ok, frame = self._cap.read()
        if not ok:
            return None
        self.next_index += 1
        return frame

    def seek(self, index: int) -> None:
        """Make ``read`` return decoded frame ``index`` next, exactly.

        OpenCV's own seek (``CAP_PROP_POS_FRAMES``) turns the index into a time at the nominal
        rate, so on a file whose frames are not evenly spaced it lands on another frame
        (launcher-stereo: index i gave decoded frame i + 0 … 17, benchmarks/clips.py). Here a
        seek forward decodes its way there (``grab``: no colour conversion, ≈ 3 ms a frame at
        2048×1536) and a seek back starts again from the first frame, the one place a seek is
        exact on every file."""
        index = max(int(index), 0)
        if index < self.next_index:
            self._cap.set(cv2.CAP_PROP_POS_FRAMES, 0)
            self.next_index = 0
        while self.next_index < index:
            if not self._cap.grab():
                break                     # past the end: the next read says so
            self.next_index += 1

    def close(self) -> None:
        self._cap.release()


class VideoPair:
    """Two video files as a stereo source (``FrameSource``).

    Without timestamps, frame i of the left file pairs with frame i of the right file and
    t = i / fps. With timestamp arrays (seconds, one per frame of each file), every left frame
    is paired with the right frame whose timestamp is nearest, and t = the left timestamp.
    """

    def __init__(self, left: str | Path, right: str | Path,
                 left_times: np.ndarray | None = None, right_times: np.ndarray | None = None,
                 loop: bool = False) -> None:
        self.left_file = VideoFile(left)
        try:
            self.right_file = VideoFile(right)
        except SourceError:
            self.left_file.close()
            raise
        if (self.left_file.width, self.left_file.height) != (self.right_file.width, self.right_file.height):
            size_l = f"{self.left_file.width}×{self.left_file.height}"
            size_r = f"{self.right_file.width}×{self.right_file.height}"
            self.close()
            raise SourceError(f"the two videos differ in size ({size_l} and {size_r}): "
                              f"they are not a stereo pair")
        if (left_times is None) != (right_times is None):
            self.close()
            raise SourceError("give timestamps for both cameras or for neither")
        self.left_times = None if left_times is None else np.asarray(left_times, dtype=float)
        self.right_times = None if right_times is None else np.asarray(right_times, dtype=float)
        self.loop = loop
        self.name = f"Videos {self.left_file.path.name} + {self.right_file.path.name}"
        self._index = 0
        self._right_cache: dict[int, np.ndarray] = {}

    @property
    def image_size(self) -> tuple[int, int]:
        return self.left_file.width, self.left_file.height

    @property
    def fps(self) -> float | None:
        return self.left_file.fps

    @property
    def frame_count(self) -> int:
        return self.left_file.frame_count

    def _right_index_for(self, i: int, t_left: float) -> int:
        if self.right_times is None:
            return i
        j = int(np.searchsorted(self.right_times, t_left))
        if j >= len(self.right_times):
            return len(self.right_times) - 1
        if j > 0 and abs(self.right_times[j - 1] - t_left) <= abs(self.right_times[j] - t_left):
            return j - 1
        return j

    def _right_frame(self, j: int) -> np.ndarray | None:
        if j in self._right_cache:
            return self._right_cache[j]
        if j < self.right_file.next_index - 1 or j > self.right_file.next_index + 2:
            self.right_file.seek(j)  # a jump: skip the frames between without converting them
        frame = None
        while self.right_file.next_index <= j:
            frame = self.right_file.read()
            if frame is None:
                return None
            # Keep the last two decoded right frames: nearest-timestamp pairing may reuse one.
            self._right_cache = {k: v for k, v in self._right_cache.items()
                                 if k >= self.right_file.next_index - 2}
            self._right_cache[self.right_file.next_index - 1] = frame
        return self._right_cache.get(j, frame)

    def read(self) -> StereoFrame | None:
        i = self._index
        if self.left_times is not None and i >= len(self.left_times):
            return self._end()
        left = self.left_file.read()
        if left is None:
            return self._end()
        t = float(self.left_times[i]) if self.left_times is not None else i / self.left_file.fps
        j = self._right_index_for(i, t)
        right = self._right_frame(j)
        if right is None:
            return self._end()
        t_right = float(self.right_times[j]) if self.right_times is not None else j / self.right_file.fps
        self._index += 1
        return StereoFrame(left, right, t, t_right, i, j)

    def _end(self) -> StereoFrame | None:
        if self.loop and self._index > 0:
            self.left_file.seek(0)
            self.right_file.seek(0)
            self._right_cache.clear()
            self._index = 0
            return self.read()
        return None

    def close(self) -> None:
        self.left_file.close()
        self.right_file.close()


class SingleVideo:
    """One camera's video (a TV broadcast, a phone at the court side) as a source of one view.

    Its frames carry ``right=None``: the one-camera tracker (core/mono.py) follows the shuttle in
    2D, as `badminton-track detect` does; there is no 3D without a second camera.
    """

    cameras = 1

    def __init__(self, path: str | Path) -> None:
        self.file = VideoFile(path)
        self.name = f"Video {self.file.path.name} (one camera)"

    @property
    def image_size(self) -> tuple[int, int]:
        return self.file.width, self.file.height

    @property
    def fps(self) -> float | None:
        return self.file.fps

    @property
    def frame_count(self) -> int:
        return self.file.frame_count

    def read(self) -> StereoFrame | None:
        i = self.file.next_index
        frame = self.file.read()
        if frame is None:
            return None
        t = i / self.file.fps
        return StereoFrame(frame, None, t, t, i)

    def close(self) -> None:
        self.file.close()

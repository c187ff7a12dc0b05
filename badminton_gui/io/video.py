"""Recorded stereo footage: two video files paired by frame index or by per-camera timestamps.

Why this file exists: real rigs do not trigger both cameras together (the NYCU cameras drift by
frames over a rally), so pairing by index is wrong for them; pairing by the nearest timestamp
from each camera's timestamp file is what `track --left-times/--right-times` does.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import cv2
import numpy as np

from ..core.types import StereoFrame
from .sources import OpeningCancelled, SourceError

# Why a step's 3D point is withheld (``VideoPair.doubt``; the `track` CSV's last column).
WITHHELD_CLOCK_STALLED = "clock_stalled"
WITHHELD_NO_PARTNER = "no_partner_frame"

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


def pairing_schedule(left_times: np.ndarray, right_times: np.ndarray
                     ) -> list[tuple[int, int, bool, bool]]:
    """The steps that pair two cameras' frames by time: ``(left index, right index, left new,
    right new)``, in time order.

    Each left frame pairs with the right frame of nearest timestamp (ties: the earlier). A right
    frame already paired is not new again; right frames that no left frame chose come, each as
    its own step beside the last left frame, between the pairs they fall between (a right frame
    between the ones nearest to left frames i and i + 1 is taken after t_left[i], so the steps'
    times never go back) and after the last pair. Right frames before the first pair have no left
    frame to stand beside and are left out.
    """
    left_times = np.asarray(left_times, dtype=float)
    right_times = np.asarray(right_times, dtype=float)
    n_right = len(right_times)
    after = np.clip(np.searchsorted(right_times, left_times), 0, n_right - 1)
    before = np.clip(after - 1, 0, None)
    nearest = np.where(np.abs(right_times[before] - left_times) <= np.abs(right_times[after] - left_times),
                       before, after)
    steps: list[tuple[int, int, bool, bool]] = []
    last_j = -1
    for i, j in enumerate(nearest.tolist()):
        if last_j >= 0:
            steps.extend((i - 1, k, False, True) for k in range(last_j + 1, j))
        steps.append((i, j, True, j != last_j))
        last_j = max(last_j, j)
    if last_j >= 0:
        steps.extend((len(left_times) - 1, k, False, True) for k in range(last_j + 1, n_right))
    return steps


class VideoPair:
    """Two video files as a stereo source (``FrameSource``).

    Without timestamps, frame i of the left file pairs with frame i of the right file and
    t = i / fps. With timestamp arrays (seconds, one per frame of each file), every left frame
    is paired with the right frame whose timestamp is nearest, and t = the left timestamp; and
    every frame of each camera is delivered once as new (``StereoFrame.fresh_left`` /
    ``fresh_right``): a right frame that is nearest to two left frames is new in the first pair
    only, and a right frame nearest to none (a camera that dropped frames, or runs longer) comes
    as a step of its own beside the left frame already delivered. On launcher-stereo (free-running
    cameras that drop frames) 54 of 567 right frames were nearest to no left frame and never
    tracked; on the NYCU rallies at most one frame a rally, besides a camera that recorded longer.
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
        # Sentences on what the output may lack (a file cut short, a clock that stalled), for the
        # end of a run: said once, not per frame.
        self.notes: list[str] = []
        self._stalled: tuple[np.ndarray, np.ndarray] | None = None
        self._range: tuple[tuple[float, float], tuple[float, float]] | None = None
        if self.left_times is not None:
            try:
                self._check_clocks()
            except SourceError:
                self.close()
                raise
        self.loop = loop
        self.name = f"Videos {self.left_file.path.name} + {self.right_file.path.name}"
        self._index = 0
        self._right_cache: dict[int, np.ndarray] = {}
        self._schedule = (None if self.left_times is None
                          else pairing_schedule(self.left_times, self.right_times))
        self._last_left: np.ndarray | None = None

    def _check_clocks(self) -> None:
        """Refuse two clocks that cannot pair the cameras; note what pairing by them will lack."""
        times = (self.left_times, self.right_times)
        for name, t, file in zip(("left", "right"), times, (self.left_file, self.right_file)):
            if len(t) == 0 or not np.all(np.isfinite(t)):
                raise SourceError(f"the {name} timestamps are empty or not all finite")
            if np.any(np.diff(t) < 0):
                raise SourceError(f"the {name} timestamps go backwards, so they cannot pair the cameras")
            if file.frame_count > 0 and len(t) < file.frame_count:
                self.notes.append(f"the {name} timestamps time {len(t)} of the {file.frame_count} frames "
                                  f"of {file.path.name}: the {file.frame_count - len(t)} after are not tracked")
        steps = [np.diff(t)[np.diff(t) > 0] for t in times]
        if all(len(d) for d in steps):
            step_l, step_r = (float(np.median(d)) for d in steps)
            ratio = max(step_l, step_r) / min(step_l, step_r)
            if ratio >= 100:
                raise SourceError(
                    f"the left clock's frames are {1000 * step_l:.4g} ms apart and the right clock's "
                    f"{1000 * step_r:.4g} ms (median): {ratio:.0f}× apart, as if one file were in "
                    f"milliseconds; both timestamp files must be in seconds")
        else:
            step_l = step_r = 0.0
        (l0, l1), (r0, r1) = (float(self.left_times[0]), float(self.left_times[-1])), \
                             (float(self.right_times[0]), float(self.right_times[-1]))
        if l1 < r0 or r1 < l0:
            raise SourceError(f"the left clock runs from {l0:g} to {l1:g} s and the right one from "
                              f"{r0:g} to {r1:g} s: they never overlap, so no frames can be paired "
                              f"(do the timestamp files belong to this recording?)")
        # A frame is "beside" the other camera's recording while its time lies within that
        # clock's first and last frame, give or take one and a half of its frame intervals.
        self._range = ((l0 - 1.5 * step_l, l1 + 1.5 * step_l), (r0 - 1.5 * step_r, r1 + 1.5 * step_r))
        # A stalled clock gives several frames one time; none of them can be placed in time, the
        # first of the run included.
        stalled = []
        for t in times:
            same = np.diff(t) == 0
            flags = np.zeros(len(t), dtype=bool)
            flags[1:] |= same
            flags[:-1] |= same
            stalled.append(flags)
        self._stalled = (stalled[0], stalled[1])
        for name, flags in zip(("left", "right"), stalled):
            if flags.any():
                self.notes.append(f"the {name} clock stalled: {int(flags.sum())} of its frames share a "
                                  f"timestamp with a neighbour")

    def doubt(self, index: int, index_right: int) -> str:
        """Why the 3D point of the step pairing left frame ``index`` with right frame
        ``index_right`` would be made up ('' when nothing is known against it): ``clock_stalled``
        (one camera's timestamp does not move), ``no_partner_frame`` (one camera's frame lies
        beyond the other's recording, which ended or had not begun)."""
        if self._stalled is None:
            return ""
        stalled_l, stalled_r = self._stalled
        if (0 <= index < len(stalled_l) and stalled_l[index]) or \
                (0 <= index_right < len(stalled_r) and stalled_r[index_right]):
            return WITHHELD_CLOCK_STALLED
        (l_lo, l_hi), (r_lo, r_hi) = self._range
        if 0 <= index < len(self.left_times) and not r_lo <= self.left_times[index] <= r_hi:
            return WITHHELD_NO_PARTNER
        if 0 <= index_right < len(self.right_times) and not l_lo <= self.right_times[index_right] <= l_hi:
            return WITHHELD_NO_PARTNER
        return ""

    @property
    def image_size(self) -> tuple[int, int]:
        return self.left_file.width, self.left_file.height

    @property
    def fps(self) -> float | None:
        return self.left_file.fps

    @property
    def frame_count(self) -> int:
        """Left frames (what label files and progress count)."""
        return self.left_file.frame_count

    @property
    def step_count(self) -> int:
        """Steps ``read`` delivers: the left frames, plus the right frames paired with none."""
        return self.frame_count if self._schedule is None else len(self._schedule)

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
        if self._schedule is not None:
            return self._read_scheduled()
        i = self._index
        left = self.left_file.read()
        if left is None:
            return self._end(self.left_file, i, other=self.right_file)
        right = self._right_frame(i)
        if right is None:
            return self._end(self.right_file, i, other=self.left_file)
        self._index += 1
        return StereoFrame(left, right, i / self.left_file.fps, i / self.right_file.fps, i, i)

    def _read_scheduled(self) -> StereoFrame | None:
        if self._index >= len(self._schedule):
            return self._end()
        i, j, fresh_left, fresh_right = self._schedule[self._index]
        if fresh_left or self._last_left is None:
            left = self.left_file.read()
            if left is None:
                return self._end(self.left_file, i, other=self.right_file)
            self._last_left = left
        right = self._right_frame(j)
        if right is None:
            return self._end(self.right_file, j, other=self.left_file)
        self._index += 1
        return StereoFrame(self._last_left, right, float(self.left_times[i]), float(self.right_times[j]),
                           i, j, fresh_left, fresh_right)

    def _end(self, ended: VideoFile | None = None, decoded: int = 0,
             other: VideoFile | None = None) -> StereoFrame | None:
        """The source ran out: ``ended`` (a camera's file) gave no frame ``decoded``, before its
        schedule or the other file (``other``) was done — said in :attr:`notes`."""
        if ended is not None and not self.loop:
            self._note_end(ended, decoded, other)
        if self.loop and self._index > 0:
            self.left_file.seek(0)
            self.right_file.seek(0)
            self._right_cache.clear()
            self._last_left = None
            self._index = 0
            return self.read()
        return None

    def _note_end(self, ended: VideoFile, decoded: int, other: VideoFile | None) -> None:
        if any(note.startswith(f"{ended.path.name} ended after ") for note in self.notes):
            return                          # a reader that asks again past the end
        announced = ended.frame_count
        cut = f" of the {announced} its header announces (a truncated file?)" if announced > decoded + 1 else ""
        if self._schedule is not None:
            timed = len(self.left_times if ended is self.left_file else self.right_times)
            if decoded < timed:
                self.notes.append(f"{ended.path.name} ended after {decoded} frames{cut}, before the "
                                  f"{timed} its timestamps time: the steps after were not tracked")
            return
        left_over = (other.frame_count - decoded) if other is not None and other.frame_count else 0
        if cut or left_over > 0:
            rest = (f"; {left_over} frames of {other.path.name} after it were not tracked"
                    if left_over > 0 else "")
            self.notes.append(f"{ended.path.name} ended after {decoded} frames{cut}{rest}")

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

"""Checks on what a caller hands ``StereoTracker.process``: images and timestamps.

Why this file exists: the tracker's stages assume 8-bit BGR images of the rig's size and a clock
that does not run backwards; handed anything else they fail deep inside (a ``cv2.error`` in the
background model, an ``OverflowError`` in the trajectory) or, worse, give 3D points that are
silently wrong. The tracker calls :meth:`InputChecks.check_pair` first, so every such input is
refused once, at the boundary, with a :class:`TrackerInputError` that says what to change.

The rules:

- An image is a non-empty ``numpy`` array of dtype ``uint8``, ``(H, W, 3)`` in BGR order, of
  the rig's calibrated size for the whole run. A grey image, ``(H, W)`` or ``(H, W, 1)``, is
  turned into BGR by repeating its channel (what ``cv2.COLOR_GRAY2BGR`` does); other dtypes
  and channel counts are refused, because no conversion is right for every source (is a
  float image 0–1 or 0–255?).
- A timestamp is a finite real number of seconds, at most ``MAX_TIMESTAMP`` in magnitude
  (Unix time fits), and each camera's clock moves forward from pair to pair within a run
  (``reset`` starts a new run). A pair whose time equals that camera's previous one is refused
  too, alone: the clock stalled, and the trajectory would place the shuttle's new position at
  a time that did not move, metres off where it is. The caller
  skips that pair and goes on (the GUI says so in its banner); the next pair with a later
  time is tracked. Where the clock is known in advance (timestamp files) the file commands
  mark the frames it times instead (``VideoPair.doubt``), and their pairing never hands this
  method a stalled pair.
- The two images differ. Two cameras never give bit-identical pictures (their viewpoints and
  sensor noise differ), so an identical pair is one camera or one file given as both: on a
  toed-in rig its "pairs" triangulate to plausible points metres from the shuttle, silently
  wrong. Such a pair is refused; a uniform pair (two black frames while cameras start) is not.
"""

from __future__ import annotations

import math
import numbers

import cv2
import numpy as np

from .errors import TrackerInputError

# s: the largest timestamp magnitude accepted. Unix time (1.7e9 s) fits; beyond 1e10 s a float64
# second count no longer resolves a 120 fps frame interval to better than a microsecond.
MAX_TIMESTAMP = 1e10

_CAMERAS = ("left", "right")


class InputChecks:
    """The checks of one tracker's run: the rig's frame size and each camera's last time."""

    def __init__(self, image_size: tuple[int, int]) -> None:
        self.image_size = (int(image_size[0]), int(image_size[1]))
        self.reset()

    def reset(self) -> None:
        """A new run: the clocks may start again from any time."""
        self._last_time: list[float | None] = [None, None]

    def check_pair(self, left, right, timestamp, t_right=None) -> tuple[np.ndarray, np.ndarray]:
        """The pair as the tracker wants it (grey turned into BGR), or TrackerInputError.

        ``t_right`` None: the right image has the left one's time. Nothing is remembered
        unless the whole pair passes, so a refused pair leaves the run as it was."""
        images = (self.image(0, left), self.image(1, right))
        if same_picture(*images):
            raise TrackerInputError(
                "the left and right images are identical: both inputs show one camera (the same "
                "camera or video given twice?); a 3D point needs the two cameras' own views")
        t_left = self.timestamp(0, timestamp)
        t_r = t_left if t_right is None else self.timestamp(1, t_right)
        for cam, t in enumerate((t_left, t_r)):
            last = self._last_time[cam]
            if last is not None and t < last:
                raise TrackerInputError(
                    f"the {_CAMERAS[cam]} timestamp {t!r} s is earlier than that camera's previous "
                    f"one ({last!r} s): time must not go back within a run (call reset() when a "
                    f"new recording starts)")
            if last is not None and t == last:
                raise TrackerInputError(
                    f"the {_CAMERAS[cam]} timestamp {t!r} s repeats that camera's previous one: its "
                    f"clock stalled, and this pair's speeds and 3D point would rest on a time that "
                    f"did not move (skip the pair; the next one with a later time is tracked)")
        self._last_time = [t_left, t_r]
        return images

    def image(self, cam: int, img) -> np.ndarray:
        """One camera's image checked (and grey turned into BGR)."""
        name = f"the {_CAMERAS[cam]} frame"
        if not isinstance(img, np.ndarray):
            raise TrackerInputError(f"{name} is a {type(img).__name__}, not a numpy image array")
        if img.size == 0:
            raise TrackerInputError(f"{name} is empty (shape {img.shape})")
        if img.dtype != np.uint8:
            raise TrackerInputError(
                f"{name} has dtype {img.dtype}; the tracker takes 8-bit BGR images (uint8): "
                f"convert it first, e.g. np.clip(img * 255, 0, 255).astype(np.uint8) for a 0–1 float image")
        if img.ndim == 3 and img.shape[2] == 1:
            img = img[:, :, 0]
        if img.ndim == 2:
            img = cv2.cvtColor(np.ascontiguousarray(img), cv2.COLOR_GRAY2BGR)
        elif img.ndim != 3 or img.shape[2] != 3:
            raise TrackerInputError(
                f"{name} has shape {img.shape}; the tracker takes (height, width, 3) BGR images "
                f"or (height, width) grey ones (a BGRA image: cv2.cvtColor(img, cv2.COLOR_BGRA2BGR))")
        height, width = img.shape[:2]
        if (width, height) != self.image_size:
            raise TrackerInputError(
                f"{name} is {width}×{height} but the rig was calibrated for {self.image_size[0]}×"
                f"{self.image_size[1]}: every frame of a run must have the rig's size")
        if not img.flags.c_contiguous:
            img = np.ascontiguousarray(img)
        return img

    def timestamp(self, cam: int, value) -> float:
        """One camera's timestamp as a float, or TrackerInputError."""
        name = f"the {_CAMERAS[cam]} timestamp"
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
            raise TrackerInputError(f"{name} is {value!r}, not a number of seconds")
        t = float(value)
        if not math.isfinite(t):
            raise TrackerInputError(f"{name} is {t!r}: it must be a finite number of seconds")
        if abs(t) > MAX_TIMESTAMP:
            raise TrackerInputError(f"{name} is {t!r} s, beyond ±{MAX_TIMESTAMP:g} s: is it in seconds?")
        return t


def same_picture(left: np.ndarray, right: np.ndarray) -> bool:
    """True when two same-shaped images are identical and not uniform. The middle row is
    compared first: two cameras' images differ there almost always, so the common case costs
    one row's comparison."""
    if left is right:
        return int(left.min()) != int(left.max())
    middle = left.shape[0] // 2
    if not np.array_equal(left[middle], right[middle]) or not np.array_equal(left, right):
        return False
    return int(left.min()) != int(left.max())

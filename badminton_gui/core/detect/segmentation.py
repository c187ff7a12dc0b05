"""Segmentation: a camera frame → the background model's foreground mask and its contours.

Why this file exists: it is the first per-camera stage. The background model
(``core/background.py``) runs on a grey image at a reduced processing scale (``model_scale``,
``ModelGrey``): the image work is most of a frame's cost, and a shuttle a few pixels wide still
shows there. What it hands on, ``Segmented``, is all the candidates stage needs of the image
side. It is nearly all OpenCV on whole images, which releases the GIL, so the stereo tracker
runs the two cameras' segmentation side by side.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np


@dataclasses.dataclass(frozen=True, slots=True)
class Segmented:
    """What ``CameraDetector.segment`` hands to ``candidates_from`` for one frame."""

    gray: np.ndarray                         # the model's grey image (the window's, when windowed)
    mask: np.ndarray                         # foreground mask at the processing scale
    contours: tuple                          # the mask's external contours
    window: tuple[int, int, int, int] | None  # the window (full-resolution x0, y0, x1, y1), or None
    windowed: bool

    def fresh_part(self, mask_scale: float) -> tuple[int, int, int, int]:
        """The part of ``gray`` made this frame, model px (x0, y0, x1, y1): the window, or all."""
        if self.windowed:
            # The window's corners are multiples of ALIGN px: exact model pixels.
            return tuple(int(round(v * mask_scale)) for v in self.window)
        return (0, 0, self.mask.shape[1], self.mask.shape[0])


def model_scale(background, width: int, far_shuttle_px: float | None = None) -> float:
    """The scale the background model runs at for frames ``width`` px wide.

    The processing scale, halved when the frames are wide enough (``coarse_from_width``, the
    coarse preset's fixed rule) or, otherwise, when the farthest shuttle, ``far_shuttle_px``
    long in full-resolution pixels, still spans ``coarse_shuttle_px`` model pixels at the halved
    scale (``CameraDetector.model_scale`` gives it from the camera's view of the court). The
    model must show the shuttle, not the frame: a camera behind the court at 2048 px needs no
    1024 px model, a side camera at 1280 px does. A halved model costs about a quarter of the
    image work, but its mask-based features differ, so the classifier of the coarser scale
    (``classifier.coarse_model``) scores them. Off by default: measured on randomised courts
    behind the baselines (tuning seeds) it lost 3D coverage with either shipped classifier —
    the size rule is ready for a classifier trained at that scale on more than one court.
    """
    scale = float(background.processing_scale)
    if 0 < int(background.coarse_from_width) <= width:
        return scale * 0.5
    limit = float(background.coarse_shuttle_px)
    if int(background.coarse_from_width) == 0 and limit > 0 and far_shuttle_px is not None \
            and far_shuttle_px * scale * 0.5 >= limit:
        return scale * 0.5
    return scale


def external_contours(mask: np.ndarray) -> tuple:
    """The mask's external contours, as OpenCV lists them."""
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    return contours


class ModelGrey:
    """Makes the grey image the background model reads, reusing its buffers frame to frame."""

    def __init__(self) -> None:
        self._small: np.ndarray | None = None   # the frame at the processing scale
        self._gray: np.ndarray | None = None

    def __call__(self, frame_bgr: np.ndarray, scale: float) -> np.ndarray:
        """The grey image the background model reads: the frame at ``scale`` (INTER_AREA).

        Reading the colour frame is most of the cost (9.4 MB at 2048×1536: close to a copy of
        it), so at a quarter scale only every other row is read: OpenCV's 2×2 area fast path
        on the row-strided view (a valid array with twice the row step) averages rows 4k and
        4k + 2 and two columns, the grey image is made there, and an exact 2:1 linear step
        (the mean of pixel pairs) halves it across. Each model pixel is the mean of 8 of its
        16 full-resolution pixels: a shuttle two rows tall or more always shows in it.
        """
        h, w = frame_bgr.shape[:2]
        if scale >= 1.0:
            return cv2.cvtColor(frame_bgr, cv2.COLOR_BGR2GRAY)
        size = (max(1, round(w * scale)), max(1, round(h * scale)))
        quarter = scale == 0.25 and w % 4 == 0 and h % 4 == 0
        first = (w // 2, h // 4) if quarter else size
        if self._small is None or self._small.shape[:2] != (first[1], first[0]):
            # Reused every frame (the grey image is read only within this call).
            self._small = np.empty((first[1], first[0], 3), np.uint8)
            self._gray = np.empty((first[1], first[0]), np.uint8)
        source = frame_bgr[::2] if quarter else frame_bgr
        small = cv2.resize(source, first, dst=self._small, interpolation=cv2.INTER_AREA)
        gray = cv2.cvtColor(small, cv2.COLOR_BGR2GRAY, dst=self._gray)
        if quarter:
            gray = cv2.resize(gray, size, interpolation=cv2.INTER_LINEAR)
        return gray

"""Foreground masks: the paper's Gaussian-mixture background difference, or a frame difference.

Why this file exists: the background model is the first and most expensive step of the chain,
and the one whose parameters an operator tunes most. It works on a grey image at the processing
scale (GUIDE §4: half resolution is the big speed saving; grey input costs little accuracy) and
returns a binary mask at that scale.
"""

from __future__ import annotations

from collections import deque

import cv2
import numpy as np

from .params import BackgroundParams, BinarizeParams


class BackgroundModel:
    """Turns successive grey frames into binary foreground masks (0 / 255)."""

    def __init__(self, background: BackgroundParams, binarize: BinarizeParams) -> None:
        self._bg = background
        self._bin = binarize
        self._mog: cv2.BackgroundSubtractorMOG2 | None = None
        self._previous: deque[np.ndarray] = deque(maxlen=2)
        self._average: np.ndarray | None = None
        self.last_difference: np.ndarray | None = None  # signed difference (bright_diff only)
        self._kernel: np.ndarray | None = None
        self._configure()

    @property
    def params(self) -> tuple[BackgroundParams, BinarizeParams]:
        return self._bg, self._bin

    def set_params(self, background: BackgroundParams, binarize: BinarizeParams) -> None:
        """Apply new parameters; the learnt model survives unless its structure changed."""
        rebuild = (background.method != self._bg.method
                   or background.processing_scale != self._bg.processing_scale)
        self._bg, self._bin = background, binarize
        if rebuild:
            self.reset()
        self._configure()

    def reset(self) -> None:
        self._mog = None
        self._previous.clear()
        self._average = None

    def _configure(self) -> None:
        b = self._bg
        if b.method == "mog2":
            if self._mog is None:
                self._mog = cv2.createBackgroundSubtractorMOG2(
                    history=int(b.history), varThreshold=float(b.var_threshold),
                    detectShadows=bool(b.detect_shadows))
            self._mog.setHistory(int(b.history))
            self._mog.setNMixtures(int(b.n_mixtures))
            self._mog.setVarThreshold(float(b.var_threshold))
            self._mog.setDetectShadows(bool(b.detect_shadows))
        k = int(self._bin.open_kernel)
        self._kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k)) if k >= 2 else None

    def apply(self, gray: np.ndarray) -> np.ndarray:
        """Binary mask (uint8, 0/255) of what moved in this grey frame."""
        if self._bg.method == "mog2":
            raw = self._mog.apply(gray, learningRate=float(self._bg.learning_rate))
            # MOG2 marks foreground 255 and shadows 127: the threshold T drops the shadows.
            _, mask = cv2.threshold(raw, int(self._bin.threshold), 255, cv2.THRESH_BINARY)
        elif self._bg.method == "bright_diff":
            mask = self._brighter_than_average(gray)
        else:
            mask = self._three_frame_difference(gray)
        if self._kernel is not None:
            mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, self._kernel)
        if self._bin.dilate_iterations > 0:
            mask = cv2.dilate(mask, None, iterations=int(self._bin.dilate_iterations))
        return mask

    def is_blind(self, x: float, y: float) -> bool:
        """True when a shuttle at (x, y) (processing-scale px) cannot show in the mask.

        Only the brighter-than-average method has blind spots: pixels whose average is at
        least ``max_background`` (lights, white lines, the net tape) are never foreground, and
        the shake tolerance compares their neighbours with them too.
        """
        avg = self._average
        if self._bg.method != "bright_diff" or avg is None or self._bin.max_background >= 255:
            return False
        h, w = avg.shape
        xi, yi = int(round(x)), int(round(y))
        if not (0 <= xi < w and 0 <= yi < h):
            return False
        k = int(self._bg.shake_tolerance) + 1
        window = avg[max(yi - k, 0):yi + k + 1, max(xi - k, 0):xi + k + 1]
        return bool(window.max() >= float(self._bin.max_background))

    def _brighter_than_average(self, gray: np.ndarray) -> np.ndarray:
        """Pixels brighter than a running average of the scene by more than the threshold.

        The shuttle is white in a dark hall: it is brighter than what lies behind it, while the
        players' dark clothes, hair and shadows are darker, so a *signed* difference keeps the
        shuttle and drops most of the player. The average learns at α everywhere except under
        the foreground (so a slow shuttle is not absorbed at once); flickering lights stay in
        the mask but never travel, which the association step rejects.
        """
        if self._average is None or self._average.shape != gray.shape:
            self._average = gray.astype(np.float32)
            return np.zeros_like(gray)
        current = gray.astype(np.float32)
        # Lights flicker (mains frequency seen by a 119 fps camera) and the hall's exposure
        # drifts: the whole scene brightens or darkens by a common *gain*. Estimated robustly
        # (median ratio on a sparse grid of reasonably lit pixels) and divided out, so a
        # flicker frame does not turn every textured surface into foreground.
        gain = 1.0
        if self._bg.compensate_gain:
            avg_s = self._average[::8, ::8]
            cur_s = current[::8, ::8]
            lit = avg_s > 20
            if np.count_nonzero(lit) > 50:
                gain = float(np.median(cur_s[lit] / avg_s[lit]))
        reference = self._average
        k = int(self._bg.shake_tolerance)
        if k > 0:
            # A camera that shakes by a pixel turns every bright edge (court lines, lights)
            # into foreground; compare with the brightest background pixel nearby instead.
            reference = cv2.dilate(reference, cv2.getStructuringElement(
                cv2.MORPH_RECT, (2 * k + 1, 2 * k + 1)))
        diff = cv2.subtract(current, reference * gain) if gain != 1.0 else cv2.subtract(current, reference)
        if self._bin.max_background < 255:
            # Lights: a shuttle in front of them is invisible anyway, and they flicker.
            diff[self._average >= float(self._bin.max_background)] = 0
        self.last_difference = diff
        _, mask = cv2.threshold(diff, float(self._bin.diff_threshold), 255, cv2.THRESH_BINARY)
        mask = mask.astype(np.uint8)
        alpha = float(self._bg.learning_rate)
        if alpha > 0:
            cv2.accumulateWeighted(gray, self._average, alpha, mask=cv2.bitwise_not(mask))
            # Slow leak under the foreground too, so a change that stays (a light switched on)
            # is absorbed eventually.
            cv2.accumulateWeighted(gray, self._average, alpha * 0.1, mask=mask)
        return mask

    def _three_frame_difference(self, gray: np.ndarray) -> np.ndarray:
        """Pixels that differ from *both* of the two previous frames: the object now, no ghosts."""
        if len(self._previous) < 2 or self._previous[-1].shape != gray.shape:
            self._previous.clear()
            self._previous.append(gray.copy())
            self._previous.append(gray.copy())
            return np.zeros_like(gray)
        t = int(self._bin.diff_threshold)
        d1 = cv2.absdiff(gray, self._previous[-1])
        d2 = cv2.absdiff(gray, self._previous[-2])
        _, m1 = cv2.threshold(d1, t, 255, cv2.THRESH_BINARY)
        _, m2 = cv2.threshold(d2, t, 255, cv2.THRESH_BINARY)
        self._previous.append(gray.copy())
        return cv2.bitwise_and(m1, m2)

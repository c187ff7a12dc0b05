"""Foreground masks: the paper's Gaussian-mixture background difference, or a frame difference.

Why this file exists: the background model is the first and most expensive step of the chain,
and the one whose parameters an operator tunes most. It works on a grey image at the processing
scale (half resolution is the big speed saving; grey input costs little accuracy) and
returns a binary mask at that scale.
"""

from __future__ import annotations

from collections import deque

import cv2
import numpy as np

from .params import BackgroundParams, BinarizeParams


# Inside the box around a held landed shuttle (``BackgroundModel.protect``) a pixel is foreground
# from this fraction of ``binarize.diff_threshold``.
PROTECT_THRESHOLD = 0.5


class BackgroundModel:
    """Turns successive grey frames into binary foreground masks (0 / 255)."""

    def __init__(self, background: BackgroundParams, binarize: BinarizeParams) -> None:
        self._bg = background
        self._bin = binarize
        self._mog: cv2.BackgroundSubtractorMOG2 | None = None
        self._previous: deque[np.ndarray] = deque(maxlen=2)
        self._average: np.ndarray | None = None
        # Brighter-than-average method only: the signed difference of the last frame, and where
        # it counts (255; 0 on lights, where readers must take the difference as 0), or None.
        self.last_difference: np.ndarray | None = None
        self.last_unlit: np.ndarray | None = None
        self._kernel: np.ndarray | None = None
        self._shake_kernel: np.ndarray | None = None
        self._raw_mask: np.ndarray | None = None
        # Windowed tracking: pixels (255) that missed updates, and how many updates they missed,
        # caught up on the next whole frame (``catch_up``); used once.
        self._catch_up: tuple[np.ndarray, int] | None = None
        # Model pixels (x0, y0, x1, y1) thresholded lower in the next update only: around a
        # held landed shuttle (``protect``).
        self._protected: tuple[int, int, int, int] | None = None
        self._configure()

    @property
    def params(self) -> tuple[BackgroundParams, BinarizeParams]:
        return self._bg, self._bin

    @property
    def average(self) -> np.ndarray | None:
        """The brighter-than-average method's running average (model scale), as a read-only
        view; None before its first frame or with another method."""
        if self._average is None:
            return None
        view = self._average.view()
        view.flags.writeable = False
        return view

    def set_params(self, background: BackgroundParams, binarize: BinarizeParams) -> None:
        """Apply new parameters; the learnt model survives unless its structure changed."""
        rebuild = (background.method != self._bg.method
                   or background.processing_scale != self._bg.processing_scale
                   or background.coarse_from_width != self._bg.coarse_from_width)
        self._bg, self._bin = background, binarize
        if rebuild:
            self.reset()
        self._configure()

    def reset(self) -> None:
        self._mog = None
        self._previous.clear()
        self._average = None
        self._protected = None

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
        mask = self._clean(mask)
        if mask is self._raw_mask:
            # The caller keeps the mask (the GUI shows it): never hand out the reused buffer.
            mask = mask.copy()
        return mask

    def _clean(self, mask: np.ndarray) -> np.ndarray:
        """Opening and dilation of a raw mask (``binarize.open_kernel``, ``dilate_iterations``)."""
        if self._kernel is not None:
            mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, self._kernel)
        if self._bin.dilate_iterations > 0:
            mask = cv2.dilate(mask, None, iterations=int(self._bin.dilate_iterations))
        return mask

    def can_window(self, shape: tuple[int, int]) -> bool:
        """True when ``apply_window`` works for a model of this (full) shape: brighter-than-
        average only, and the running average already learnt at that size."""
        return (self._bg.method == "bright_diff" and self._average is not None
                and self._average.shape == tuple(shape))

    def apply_window(self, gray: np.ndarray, x0: int, y0: int) -> np.ndarray:
        """The mask of one window of the model (``gray``: the grey image of model pixels
        ``[y0:y0+h, x0:x0+w]``); only that part of the running average learns (core/window.py).

        The same arithmetic as ``apply`` on those pixels: the shake tolerance's dilation reads
        ``shake_tolerance`` pixels around the window, the flicker gain is estimated on the same
        sparse grid (its points inside the window; a finer grid when the window holds too few)
        and the opening / dilation run inside the window. ``last_difference`` and
        ``last_unlit`` stay full-size buffers, valid inside the window only. A window covering
        the whole model gives what ``apply`` gives (tests/test_window.py).
        """
        avg_full = self._average
        big_h, big_w = avg_full.shape
        h, w = gray.shape
        rows, cols = slice(y0, y0 + h), slice(x0, x0 + w)
        avg = avg_full[rows, cols]
        gain = 1.0
        if self._bg.compensate_gain:
            whole = (h, w) == (big_h, big_w)
            for step in ((8,) if whole else (8, 4, 2)):
                gy, gx = (-y0) % step, (-x0) % step   # the grid of the whole model
                if step > 2 and -(-(h - gy) // step) * -(-(w - gx) // step) <= 50:
                    continue   # too few grid points even if all are lit: the next grid, at once
                avg_s = avg[gy::step, gx::step]
                lit = avg_s > 20
                ratios = gray[gy::step, gx::step][lit] / avg_s[lit]
                if ratios.size > 50:
                    gain = median_float32(ratios)
                    break
        k = int(self._bg.shake_tolerance)
        if k > 0:
            if self._shake_kernel is None or self._shake_kernel.shape[0] != 2 * k + 1:
                self._shake_kernel = cv2.getStructuringElement(cv2.MORPH_RECT, (2 * k + 1, 2 * k + 1))
            ey0, ex0 = max(y0 - k, 0), max(x0 - k, 0)
            grown = cv2.dilate(avg_full[ey0:min(y0 + h + k, big_h), ex0:min(x0 + w + k, big_w)],
                               self._shake_kernel)
            reference = grown[y0 - ey0:y0 - ey0 + h, x0 - ex0:x0 - ex0 + w]
            if gain != 1.0:
                reference = np.multiply(reference, gain, out=reference)
        else:
            reference = np.multiply(avg, gain) if gain != 1.0 else avg
        diff = cv2.subtract(gray, reference, dst=self._difference[rows, cols], dtype=cv2.CV_32F)
        mask = cv2.compare(diff, float(self._bin.diff_threshold), cv2.CMP_GT)
        box = self._take_protected((h, w), x0, y0)
        self._protected_mask(mask, diff, box)
        self.last_difference = self._difference
        self.last_unlit = None
        if self._bin.max_background < 255:
            unlit = cv2.compare(avg, float(self._bin.max_background), cv2.CMP_LT,
                                dst=self._unlit[rows, cols])
            cv2.bitwise_and(mask, unlit, dst=mask)
            self.last_unlit = self._unlit
        alpha = float(self._bg.learning_rate)
        if alpha > 0:
            slow = self._slow_learners(mask, diff, self._dark[rows, cols])
            cv2.accumulateWeighted(gray, avg, alpha, mask=cv2.bitwise_not(slow))
            cv2.accumulateWeighted(gray, avg, alpha * 0.1, mask=slow)
        return self._clean(mask)

    def protect(self, box: tuple[int, int, int, int] | None) -> None:
        """In the next update only, a pixel inside ``box`` (model px x0, y0, x1, y1; None:
        nowhere) is foreground from ``PROTECT_THRESHOLD`` × ``binarize.diff_threshold``.

        The stereo tracker passes the box around a landed shuttle it holds. At a quarter-scale
        model (``coarse``) a lying shuttle is 2–3 px, averaged with the floor around it: its
        difference hovers near the threshold, and when it dims a little (it rolls, a player's
        shadow passes) it drops out of the mask and the hold ends (rally_11-48-00 right 636:
        the difference fell from 20 to 10 against 12, while the average there stayed put).
        A lower threshold where the shuttle is known to lie is hysteresis: it keeps what is
        already followed and starts nothing new. Learning more slowly there changed nothing
        (measured: the same outcomes to the frame).
        """
        self._protected = box

    def _take_protected(self, shape: tuple[int, int], x0: int = 0, y0: int = 0
                        ) -> tuple[slice, slice] | None:
        """The protected box as slices of an image of ``shape`` whose origin is model pixel
        (x0, y0), or None; the box is used up."""
        box, self._protected = self._protected, None
        if box is None:
            return None
        h, w = shape
        bx0, by0 = max(box[0] - x0, 0), max(box[1] - y0, 0)
        bx1, by1 = min(box[2] - x0, w), min(box[3] - y0, h)
        if bx0 >= bx1 or by0 >= by1:
            return None
        return slice(by0, by1), slice(bx0, bx1)

    def _protected_mask(self, mask: np.ndarray, diff: np.ndarray, box: tuple[slice, slice] | None) -> None:
        """Inside the protected box the mask takes the difference from PROTECT_THRESHOLD × the
        threshold (hysteresis: a reported shuttle stays in the mask while it dims a little)."""
        if box is not None:
            t = float(self._bin.diff_threshold) * PROTECT_THRESHOLD
            mask[box] = np.where(diff[box] > t, np.uint8(255), np.uint8(0))

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

    def _slow_learners(self, mask: np.ndarray, diff: np.ndarray, dst: np.ndarray) -> np.ndarray:
        """The pixels (255) whose average learns at α/10: the foreground, and with
        ``background.dark_threshold`` also those darker than the reference by more than it.

        A dark player who stands for a second would otherwise be learnt at α and leave a bright
        ghost of the court behind when he moves (the ghost is foreground, so it learns at α/10
        and lasts ~200 frames). Darker pixels are never foreground here, so the mask is the
        same this frame; only what the average remembers changes. ``diff`` is the frame minus
        the (shake-dilated, gain-corrected) reference, as thresholded for the mask.
        """
        dark = int(self._bg.dark_threshold)
        if dark <= 0:
            return mask
        darker = cv2.compare(diff, -float(dark), cv2.CMP_LT, dst=dst)
        return cv2.bitwise_or(darker, mask, dst=darker)

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
            # Per-frame buffers, reused: at 2048×1536 (a 1024×768 model) every float image
            # pass is 3 MB of memory traffic and a fresh one costs page faults too; this
            # method is memory-bound, so it makes as few full-image float passes as it can.
            # ``last_difference`` and ``last_unlit`` are buffers: valid until the next call
            # (the detector reads them within the same frame).
            self._reference = np.empty_like(self._average)
            self._difference = np.empty_like(self._average)
            self._unlit = np.empty(gray.shape, np.uint8)
            self._raw_mask = np.empty(gray.shape, np.uint8)
            self._still = np.empty(gray.shape, np.uint8)
            self._dark = np.empty(gray.shape, np.uint8)
            return np.zeros_like(gray)
        # Lights flicker (mains frequency seen by a 119 fps camera) and the hall's exposure
        # drifts: the whole scene brightens or darkens by a common *gain*. Estimated robustly
        # (median ratio on a sparse grid of reasonably lit pixels) and divided out, so a
        # flicker frame does not turn every textured surface into foreground.
        gain = 1.0
        if self._bg.compensate_gain:
            avg_s = self._average[::8, ::8]
            lit = avg_s > 20
            # uint8 / float32 divides in float32, as float32 / float32
            ratios = gray[::8, ::8][lit] / avg_s[lit]
            if ratios.size > 50:
                gain = median_float32(ratios)
        reference = self._average
        k = int(self._bg.shake_tolerance)
        if k > 0:
            # A camera that shakes by a pixel turns every bright edge (court lines, lights)
            # into foreground; compare with the brightest background pixel nearby instead.
            if self._shake_kernel is None or self._shake_kernel.shape[0] != 2 * k + 1:
                self._shake_kernel = cv2.getStructuringElement(cv2.MORPH_RECT, (2 * k + 1, 2 * k + 1))
            reference = cv2.dilate(reference, self._shake_kernel, dst=self._reference)
        if gain != 1.0:
            # numpy's float32 × float32(gain), as the classifiers' training data was made.
            reference = np.multiply(reference, gain, out=self._reference)
        # The grey frame is converted to float32 inside the subtraction, block by block.
        diff = cv2.subtract(gray, reference, dst=self._difference, dtype=cv2.CV_32F)
        # diff > threshold as 0 / 255 in one call.
        mask = cv2.compare(diff, float(self._bin.diff_threshold), cv2.CMP_GT, dst=self._raw_mask)
        box = self._take_protected(mask.shape)
        self._protected_mask(mask, diff, box)
        self.last_difference = diff
        self.last_unlit = None
        if self._bin.max_background < 255:
            # Lights: a shuttle in front of them is invisible anyway, and they flicker. They
            # are left out of the mask with a uint8 operation; the float difference keeps its
            # values there (zeroing it would be two more float passes), so readers of
            # ``last_difference`` must count it as 0 where ``last_unlit`` is 0.
            unlit = cv2.compare(self._average, float(self._bin.max_background), cv2.CMP_LT,
                                dst=self._unlit)
            cv2.bitwise_and(mask, unlit, dst=mask)
            self.last_unlit = unlit
        alpha = float(self._bg.learning_rate)
        if alpha > 0:
            slow = self._slow_learners(mask, diff, self._dark)
            cv2.accumulateWeighted(gray, self._average, alpha,
                                   mask=cv2.bitwise_not(slow, dst=self._still))
            # Slow leak under the foreground too, so a change that stays (a light switched on)
            # is absorbed eventually.
            cv2.accumulateWeighted(gray, self._average, alpha * 0.1, mask=slow)
            if self._catch_up is not None and self._catch_up[0].shape == gray.shape:
                self._learn_missed(gray, slow, alpha)
        self._catch_up = None
        return mask

    def _learn_missed(self, gray: np.ndarray, slow: np.ndarray, alpha: float) -> None:
        """``catch_up``: each missed pixel learns what the missed frames would have taught it,
        at the rate it learns at now: the still ones at α, the foreground (``slow``) at α/10.

        A ghost (the court where a player stood) is foreground; caught up at α only where
        still, it faded ``full_every`` × slower outside the windows than on whole frames, and
        beside a landed shuttle merged with it into one blob too long for filter 1.
        """
        missed, frames, changed = self._catch_up
        still = cv2.bitwise_and(self._still, missed)
        if changed is not None:
            cv2.subtract(still, changed, dst=still)
        cv2.accumulateWeighted(gray, self._average, 1.0 - (1.0 - alpha) ** frames, mask=still)
        cv2.accumulateWeighted(gray, self._average, 1.0 - (1.0 - alpha * 0.1) ** frames,
                               mask=cv2.bitwise_and(slow, missed))

    def catch_up(self, missed: np.ndarray, frames: int, changed: np.ndarray | None = None) -> None:
        """The next ``apply`` also teaches the pixels where ``missed`` is 255 what the
        ``frames`` updates they missed would have: an extra rate 1 − (1 − r)^frames, r the
        pixel's own rate in that update (α, or α/10 under the foreground).

        ``changed`` (255): pixels whose grey value changed since the last whole frame, where the
        next frame is no stand-in for the missed ones; those learning at α learn from it alone.
        Under the foreground (α/10) the stand-in errs by little and a ghost must fade.
        """
        alpha = float(self._bg.learning_rate)
        self._catch_up = (missed, int(frames), changed) if frames > 0 and alpha > 0 else None

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


def median_float32(values: np.ndarray) -> float:
    """``float(np.median(values))`` of a non-empty 1-D float32 array without NaN, for less.

    np.median's wrappers cost ~3× its one partition on the few thousand ratios of the gain
    estimate (every frame, GIL held); this is the same partition and the same float32
    arithmetic (the two middle values summed in float32, then halved), so the same value.
    """
    n = values.size
    k = n // 2
    if n % 2:
        return float(np.partition(values, k)[k])
    part = np.partition(values, (k - 1, k))
    return float((part[k - 1] + part[k]) / np.float32(2))

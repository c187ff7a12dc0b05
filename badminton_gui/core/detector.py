"""One camera's shuttle detector: mask → contours → the paper's four filters → association.

Why this file exists: it is the per-camera half of the pipeline (GUIDE §1). It keeps every
candidate with the measurement of each filter and the name of the filter that rejected it, so
the tuning view can show *why* a blob is not the shuttle, and it keeps a small track state so
that it follows the shuttle rather than the last thing that moved.

The chain per frame:
1. grey image at the processing scale → :class:`BackgroundModel` → binary mask;
2. external contours; filter 1 (contour length) and filter 2 (shortest side of the tilted
   rectangle) at the processing scale, converted to full-resolution pixels;
3. for the survivors, a small full-resolution window: filter 3 (whiteness) and a sub-pixel
   position of the head (intensity-weighted centroid of the brightest part of the blob);
4. filter 4 (distance from the position predicted by the track, speed-aware gate);
5. the best surviving candidate by score is the detection.

The tracker may override step 5 with a stereo-consistent choice (``choose`` / ``commit``).
"""

from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np

from .background import BackgroundModel
from .params import TrackerParams
from .types import (REJECT_LENGTH, REJECT_MOTION, REJECT_SCORE, REJECT_SHORT_SIDE,
                    REJECT_WHITENESS, CameraResult, Candidate)

# At most this many blobs per frame get the (more expensive) full-resolution colour check;
# beyond it the largest blobs are dropped first (players, not shuttles).
MAX_COLOUR_CHECKS = 64
# Margin (full-res px) around a blob's box for the sub-pixel refinement window.
REFINE_MARGIN = 3


@dataclasses.dataclass(slots=True)
class _TrackState:
    """Where the shuttle was, how fast it moved in the image, and when."""

    x: float
    y: float
    t: float
    vx: float = 0.0
    vy: float = 0.0
    hits: int = 1

    def predict(self, t: float) -> tuple[float, float]:
        dt = t - self.t
        return self.x + self.vx * dt, self.y + self.vy * dt


class CameraDetector:
    """Finds the shuttle in one camera's frames."""

    def __init__(self, params: TrackerParams | None = None) -> None:
        self.params = params or TrackerParams()
        self._background = BackgroundModel(self.params.background, self.params.binarize)
        self._track: _TrackState | None = None
        self._previous_positions = np.zeros((0, 2))

    # ---- configuration ---------------------------------------------------------------------
    def set_params(self, params: TrackerParams) -> None:
        self.params = params
        self._background.set_params(params.background, params.binarize)

    def reset(self) -> None:
        self._background.reset()
        self._track = None
        self._previous_positions = np.zeros((0, 2))

    @property
    def tracking(self) -> bool:
        return self._track is not None

    # ---- the whole chain for one camera (CLI `detect`) --------------------------------------
    def process(self, frame_bgr: np.ndarray, t: float, keep_mask: bool = True) -> CameraResult:
        result = self.find_candidates(frame_bgr, t, keep_mask)
        chosen = self.choose(result.candidates)
        self.commit(chosen, t, result.candidates)
        return self.finalise(result, chosen)

    # ---- steps, so the stereo tracker can choose with both cameras --------------------------
    def find_candidates(self, frame_bgr: np.ndarray, t: float, keep_mask: bool = True) -> CameraResult:
        """Candidates with filters 1–4 applied (no choice made yet)."""
        p = self.params
        h, w = frame_bgr.shape[:2]
        scale = float(p.background.processing_scale)
        gray_full = None
        if scale < 1.0:
            small = cv2.resize(frame_bgr, (max(1, round(w * scale)), max(1, round(h * scale))),
                               interpolation=cv2.INTER_AREA)
            gray = cv2.cvtColor(small, cv2.COLOR_BGR2GRAY)
        else:
            gray = gray_full = cv2.cvtColor(frame_bgr, cv2.COLOR_BGR2GRAY)
        mask = self._background.apply(gray)
        sx = w / mask.shape[1]
        sy = h / mask.shape[0]
        contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)

        predicted = None
        gate = math.inf
        if self._track is not None:
            if t - self._track.t > p.motion.lost_after:
                self._track = None
            else:
                predicted = self._track.predict(t)
                dt = max(t - self._track.t, 0.0)
                gate = p.motion.base_radius + p.motion.max_image_speed * dt

        geometric: list[tuple[int, float, float, float, tuple[int, int, int, int]]] = []
        candidates: list[Candidate] = []
        s_mean = 0.5 * (sx + sy)
        for contour in contours:
            length = cv2.arcLength(contour, True) * s_mean
            (_cx, _cy), (rw, rh), _angle = cv2.minAreaRect(contour)
            short_side = min(rw, rh) * s_mean
            area = cv2.contourArea(contour) * sx * sy
            bx, by, bw, bh = cv2.boundingRect(contour)
            box = (int(bx * sx), int(by * sy), int(math.ceil(bw * sx)), int(math.ceil(bh * sy)))
            reason = None
            if not (p.contour_length.min_length <= length <= p.contour_length.max_length):
                reason = REJECT_LENGTH
            elif not (p.tilted_rect.min_short_side <= short_side <= p.tilted_rect.max_short_side):
                reason = REJECT_SHORT_SIDE
            if reason is None:
                geometric.append((len(geometric), length, short_side, area, box))
            else:
                cx = (bx + bw / 2) * sx
                cy = (by + bh / 2) * sy
                candidates.append(Candidate(cx, cy, length, short_side, math.nan, area,
                                            math.nan, 0.0, reason))

        if len(geometric) > MAX_COLOUR_CHECKS:
            geometric.sort(key=lambda g: g[3])
            for _, length, short_side, area, box in geometric[MAX_COLOUR_CHECKS:]:
                candidates.append(Candidate(box[0] + box[2] / 2, box[1] + box[3] / 2, length,
                                            short_side, math.nan, area, math.nan, 0.0,
                                            REJECT_LENGTH))
            geometric = geometric[:MAX_COLOUR_CHECKS]

        positions = []
        for _, length, short_side, area, box in geometric:
            x, y, whiteness, saturation = self._measure(frame_bgr, mask, box, sx, sy)
            positions.append((x, y))
            motion = math.nan if predicted is None else math.hypot(x - predicted[0], y - predicted[1])
            reason = None
            if whiteness < p.colour.min_whiteness or saturation > p.colour.max_saturation:
                reason = REJECT_WHITENESS
            elif motion > gate:
                reason = REJECT_MOTION
            elif p.motion.min_displacement > 0 and self._is_stationary(x, y):
                reason = REJECT_MOTION
            score = self._score(whiteness, motion, gate)
            candidates.append(Candidate(x, y, length, short_side, whiteness, area, motion,
                                        score, reason))
        self._previous_positions = np.asarray(positions, dtype=float).reshape(-1, 2)
        return CameraResult(detection=None, candidates=tuple(candidates),
                            mask=mask if keep_mask else None,
                            mask_scale=mask.shape[1] / w, image_size=(w, h))

    def choose(self, candidates: tuple[Candidate, ...]) -> Candidate | None:
        """The best candidate that passed every filter, or None."""
        best = None
        for c in candidates:
            if c.rejected_by is None and (best is None or c.score > best.score):
                best = c
        return best

    def commit(self, detection: Candidate | None, t: float,
               candidates: tuple[Candidate, ...] = ()) -> None:
        """Update the track with this frame's decision."""
        if detection is None:
            return  # the track coasts on its velocity until `lost_after`
        tr = self._track
        if tr is None:
            self._track = _TrackState(detection.x, detection.y, t)
            return
        dt = t - tr.t
        if dt > 1e-6:
            vx = (detection.x - tr.x) / dt
            vy = (detection.y - tr.y) / dt
            # Light smoothing: trust a fresh velocity more once the track is established.
            a = 0.7 if tr.hits >= 2 else 1.0
            tr.vx = a * vx + (1 - a) * tr.vx
            tr.vy = a * vy + (1 - a) * tr.vy
        tr.x, tr.y, tr.t = detection.x, detection.y, t
        tr.hits += 1

    @staticmethod
    def finalise(result: CameraResult, chosen: Candidate | None,
                 losers_reason: str = REJECT_SCORE) -> CameraResult:
        """Mark the chosen candidate, and the other survivors as rejected by ``losers_reason``."""
        cands = []
        for c in result.candidates:
            if c.rejected_by is None and c is not chosen:
                c = dataclasses.replace(c, rejected_by=losers_reason)
            cands.append(c)
        return dataclasses.replace(result, detection=chosen, candidates=tuple(cands))

    # ---- measurements ----------------------------------------------------------------------
    @staticmethod
    def _score(whiteness: float, motion: float, gate: float) -> float:
        score = whiteness / 255.0
        if not math.isnan(motion) and math.isfinite(gate) and gate > 0:
            score += 1.0 - min(motion / gate, 1.0)
        return score

    def _is_stationary(self, x: float, y: float) -> bool:
        prev = self._previous_positions
        if len(prev) == 0:
            return False
        d = np.hypot(prev[:, 0] - x, prev[:, 1] - y)
        return bool(d.min() < self.params.motion.min_displacement)

    @staticmethod
    def _measure(frame: np.ndarray, mask: np.ndarray, box: tuple[int, int, int, int],
                 sx: float, sy: float) -> tuple[float, float, float, float]:
        """(x, y, whiteness, saturation) of a blob from a full-resolution window.

        The position is the intensity-weighted centroid of the blob's brightest part above the
        window's local background (median of the window border), which locates the white cork
        head rather than the middle of head + skirt, to a fraction of a pixel.
        """
        h, w = frame.shape[:2]
        x0 = max(box[0] - REFINE_MARGIN, 0)
        y0 = max(box[1] - REFINE_MARGIN, 0)
        x1 = min(box[0] + box[2] + REFINE_MARGIN, w)
        y1 = min(box[1] + box[3] + REFINE_MARGIN, h)
        crop = frame[y0:y1, x0:x1]
        if crop.size == 0:
            return box[0] + box[2] / 2, box[1] + box[3] / 2, 0.0, 255.0
        # The blob's pixels at full resolution: the mask window, resized.
        mx0, my0 = int(x0 / sx), int(y0 / sy)
        mx1, my1 = max(int(math.ceil(x1 / sx)), mx0 + 1), max(int(math.ceil(y1 / sy)), my0 + 1)
        mcrop = mask[my0:my1, mx0:mx1]
        if mcrop.shape[:2] != crop.shape[:2]:
            mcrop = cv2.resize(mcrop, (crop.shape[1], crop.shape[0]), interpolation=cv2.INTER_NEAREST)
        inside = mcrop > 0
        cmin = crop.min(axis=2)
        cmax = crop.max(axis=2)
        if inside.any():
            whiteness = float(cmin[inside].mean())
            saturation = float((cmax[inside].astype(np.int16) - cmin[inside]).mean())
        else:
            whiteness, saturation = 0.0, 255.0
        gray = crop.astype(np.float32).mean(axis=2)
        border = np.concatenate([gray[0], gray[-1], gray[:, 0], gray[:, -1]])
        background = float(np.median(border))
        excess = gray - background
        peak = float(excess.max())
        if peak <= 0:
            ys, xs = np.nonzero(inside)
            if len(xs) == 0:
                return box[0] + box[2] / 2, box[1] + box[3] / 2, whiteness, saturation
            return x0 + xs.mean(), y0 + ys.mean(), whiteness, saturation
        # Keep the brighter half of the blob: the cork is whiter than the feathers.
        weights = np.clip(excess - 0.5 * peak, 0, None)
        weights *= inside | (excess > 0.5 * peak)
        total = float(weights.sum())
        if total <= 0:
            weights = np.clip(excess, 0, None)
            total = float(weights.sum())
        ys, xs = np.mgrid[0:crop.shape[0], 0:crop.shape[1]]
        # OpenCV's convention: integer coordinates are pixel centres (as projectPoints gives).
        cx = float((weights * xs).sum() / total) + x0
        cy = float((weights * ys).sum() / total) + y0
        return cx, cy, whiteness, saturation

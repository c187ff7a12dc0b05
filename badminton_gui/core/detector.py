"""One camera's shuttle detector: mask → contours → the paper's four filters → association.

Why this file exists: it is the per-camera half of the pipeline (GUIDE §1). It keeps every
candidate with the measurement of each filter and the name of the filter that rejected it, so
the tuning view can show *why* a blob is not the shuttle, and it follows the shuttle over
frames rather than the last thing that moved.

The chain per frame (coarse to fine, GUIDE §4):
1. grey image at the processing scale → :class:`BackgroundModel` → binary mask (default: the
   pixels *brighter* than a running average: a white shuttle in a dark hall; lights ignored);
2. external contours; filter 1 (contour length) and filter 2 (shortest side of the tilted
   rectangle) at the processing scale, converted to full-resolution pixels;
3. the ``association.max_measured`` most promising blobs (near a live tracklet first, then the
   strongest brightening) get a small full-resolution window: filter 3 (whiteness, saturation,
   contrast above the local background), appearance features and a sub-pixel head position;
   the features give each candidate a quality in [0, 1] (the learned classifier of
   ``core/classifier.py``, or a hand-made contrast + size score);
4. filter 4, multi-frame (``core/association.py``): candidates are joined into tracklets with
   a speed-aware gate; only candidates on a confirmed, travelling, smooth tracklet of good
   mean quality pass, scored by the tracklet's merit;
5. the best surviving candidate by score is the detection (the tracker may override this with
   a stereo-consistent choice, ``choose`` / ``commit``);
6. when the followed shuttle leaves no blob because it crosses a spot where the mask is blind
   (a light, a white line: ``binarize.max_background``), its track's prediction stands in for
   up to ``motion.coast_blind`` frames, flagged ``Candidate.predicted`` and never triangulated.

Latency: none (causal); a flight costs its first ``association.min_hits`` frames.
"""

from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np

from .association import TrackletAssociator
from .background import BackgroundModel
from .classifier import load_classifier
from .params import TrackerParams
from .types import (REJECT_LENGTH, REJECT_MOTION, REJECT_SCORE, REJECT_SHORT_SIDE,
                    REJECT_WHITENESS, CameraResult, Candidate)

# At most this many blobs per frame get the (more expensive) full-resolution colour check;
# beyond it the largest blobs are dropped first (players, not shuttles).
MAX_COLOUR_CHECKS = 64
# Margin (full-res px) around a blob's box for the sub-pixel refinement window.
REFINE_MARGIN = 5
_GROW = np.ones((3, 3), np.uint8)
# Appearance features measured in the full-resolution window (order matters: the classifier).
APPEARANCE_NAMES = ("contrast", "background", "log_bright_area", "spill", "whiteness",
                    "saturation", "log_mask_area", "peak_saturation", "window_std")
N_APPEARANCE = len(APPEARANCE_NAMES)
# Shape features from the contour, then the appearance features: the classifier's input.
FEATURE_NAMES = ("log_length", "log_short_side", "log_area", "aspect") + APPEARANCE_NAMES


class CameraDetector:
    """Finds the shuttle in one camera's frames."""

    def __init__(self, params: TrackerParams | None = None) -> None:
        self.params = params or TrackerParams()
        self._background = BackgroundModel(self.params.background, self.params.binarize)
        self._associator = TrackletAssociator(self.params.motion, self.params.association)
        self._tracklet_of: dict[int, int] = {}   # id(candidate) → tracklet ident, this frame
        self.last_features: list = []   # (x, y, features, rejected_by) of the last frame's blobs
        self._classifier = None
        self._load_classifier()
        self._previous_positions = np.zeros((0, 2))

    # ---- configuration ---------------------------------------------------------------------
    def set_params(self, params: TrackerParams) -> None:
        self.params = params
        self._background.set_params(params.background, params.binarize)
        self._associator.set_params(params.motion, params.association)
        self._load_classifier()

    def reset(self) -> None:
        self._background.reset()
        self._associator.reset()
        self._tracklet_of = {}
        self._previous_positions = np.zeros((0, 2))

    @property
    def tracking(self) -> bool:
        return self._associator.selected is not None

    def _load_classifier(self) -> None:
        cp = self.params.classifier
        if not cp.enabled:
            self._classifier = None
        elif self._classifier is None or self._classifier.name != cp.model:
            self._classifier = load_classifier(cp.model)

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

        limit = min(int(p.association.max_measured), MAX_COLOUR_CHECKS)
        if len(geometric) > limit:
            # Cheap ranking at the processing scale: blobs near a live tracklet first, then
            # the strongest brightening; only the best get the full-resolution measurement.
            diff = self._background.last_difference
            live = self._associator.live_predictions(t)
            boxes = np.array([g[4] for g in geometric], dtype=float)
            centre_x = boxes[:, 0] + boxes[:, 2] / 2
            centre_y = boxes[:, 1] + boxes[:, 3] / 2
            if len(live):
                near = (np.hypot(live[None, :, 0] - centre_x[:, None],
                                 live[None, :, 1] - centre_y[:, None])
                        <= live[None, :, 2]).any(axis=1).tolist()
            else:
                near = [False] * len(geometric)
            ranked = []
            for g, is_near in zip(geometric, near):
                box = g[4]
                if diff is not None:
                    bx0, by0 = int(box[0] / sx), int(box[1] / sy)
                    window = (slice(by0, by0 + max(int(box[3] / sy), 1)),
                              slice(bx0, bx0 + max(int(box[2] / sx), 1)))
                    # Brightening, plus plain brightness: a shuttle held still before the
                    # serve fades into the average but stays the brightest thing around.
                    # (cv2.minMaxLoc: the windows' maxima at a fraction of numpy's overhead.)
                    strength = (cv2.minMaxLoc(diff[window])[1]
                                + 0.5 * cv2.minMaxLoc(gray[window])[1])
                else:
                    strength = -g[3]   # MOG2 gives no strength: smaller blobs first
                ranked.append((is_near, strength, g))
            ranked.sort(key=lambda r: (r[0], r[1]), reverse=True)
            for _, _, (_, length, short_side, area, box) in ranked[limit:]:
                candidates.append(Candidate(box[0] + box[2] / 2, box[1] + box[3] / 2, length,
                                            short_side, math.nan, area, math.nan, 0.0,
                                            REJECT_WHITENESS))
            geometric = [r[2] for r in ranked[:limit]]

        # Filter 3 and the appearance features, blob by blob; the classifier then scores all
        # the blobs of the frame in one call (one small matrix product instead of one each).
        measured = []
        features = np.empty((len(geometric), len(FEATURE_NAMES)))
        for row, (_, length, short_side, area, box) in enumerate(geometric):
            x, y, whiteness, saturation, appearance = self._measure(
                frame_bgr, mask, box, sx, sy, p.colour.head_fraction)
            contrast = float(appearance[0])
            reason = None
            if (whiteness < p.colour.min_whiteness or saturation > p.colour.max_saturation
                    or contrast < p.colour.min_contrast):
                reason = REJECT_WHITENESS
            elif p.motion.min_displacement > 0 and self._is_stationary(x, y):
                reason = REJECT_MOTION
            long_side = max(length / 2.0 - short_side, short_side)
            feats = features[row]
            feats[:4] = (math.log1p(length), math.log1p(short_side), math.log1p(area),
                         long_side / max(short_side, 1e-3))
            feats[4:] = appearance
            measured.append([x, y, length, short_side, whiteness, area, 0.0, reason, feats])
        if measured:
            qualities = self._qualities(np.array([m[2] for m in measured]), features[:, 4], features)
            for m, quality in zip(measured, qualities.tolist()):
                m[6] = quality
                if m[7] is None and quality < p.association.min_quality:
                    m[7] = REJECT_SCORE
        self._previous_positions = np.asarray([(m[0], m[1]) for m in measured],
                                              dtype=float).reshape(-1, 2)

        # Filter 4, multi-frame: only candidates on a confirmed, travelling, smooth tracklet
        # pass (the speed-aware gate lives in the associator).
        self.last_features = [(m[0], m[1], m[8], m[7]) for m in measured]
        live = [m for m in measured if m[7] is None]
        positions = np.asarray([(m[0], m[1]) for m in live], dtype=float).reshape(-1, 2)
        qualities = np.asarray([m[6] for m in live], dtype=float)
        ms_x, ms_y = 1.0 / sx, 1.0 / sy
        blind = None
        if p.motion.coast_blind > 0:
            def blind(x: float, y: float) -> bool:
                return self._background.is_blind(x * ms_x, y * ms_y)
        links = self._associator.update(t, positions, qualities, blind)
        self._tracklet_of = {}
        k = 0
        for m in measured:
            x, y, length, short_side, whiteness, area, quality, reason, _ = m
            motion, score, ident = math.nan, quality, None
            if reason is None:
                ident, motion, merit = links[k]
                k += 1
                if merit < 0:
                    reason = REJECT_MOTION
                else:
                    score = merit
            c = Candidate(x, y, length, short_side, whiteness, area, motion, score, reason)
            if ident is not None:
                self._tracklet_of[id(c)] = ident
            candidates.append(c)
        # The followed shuttle crossing a light or a white line leaves no blob: its track's
        # prediction stands in (flagged, never triangulated) until it shows again.
        coast = self._associator.coasting(t, blind)
        if coast is not None:
            tr, merit = coast
            px, py = tr.predict(t)
            c = Candidate(px, py, math.nan, math.nan, math.nan, math.nan, 0.0, merit, None,
                          predicted=True)
            self._tracklet_of[id(c)] = tr.ident
            candidates.append(c)
        return CameraResult(detection=None, candidates=tuple(candidates),
                            mask=mask if keep_mask else None,
                            mask_scale=mask.shape[1] / w, image_size=(w, h))

    def tracklet_hits(self, candidate: Candidate) -> int:
        """Frames the candidate's tracklet has been seen (0 when it is on none)."""
        ident = self._tracklet_of.get(id(candidate))
        for tr in self._associator.tracklets:
            if tr.ident == ident:
                return tr.hits
        return 0

    def tracklet_velocity(self, candidate: Candidate) -> tuple[float, float] | None:
        """Image velocity (px/s) of the candidate's tracklet, or None when not yet known."""
        ident = self._tracklet_of.get(id(candidate))
        for tr in self._associator.tracklets:
            if tr.ident == ident:
                return (tr.vx, tr.vy) if tr.velocity_known else None
        return None

    def choose(self, candidates: tuple[Candidate, ...]) -> Candidate | None:
        """The best candidate that passed every filter, or None."""
        best = None
        for c in candidates:
            if c.rejected_by is None and (best is None or c.score > best.score):
                best = c
        return best

    def commit(self, detection: Candidate | None, t: float,
               candidates: tuple[Candidate, ...] = ()) -> None:
        """Follow the chosen candidate's tracklet (hysteresis in the next frames' choice)."""
        if detection is None:
            return  # the followed tracklet keeps its bonus while it coasts
        self._associator.select(self._tracklet_of.get(id(detection)))

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
    def _qualities(self, lengths: np.ndarray, contrasts: np.ndarray,
                   features: np.ndarray) -> np.ndarray:
        """Shape/contrast scores of lone candidates in [0, 1] (the soft side of filters 1 and 3).

        With the learned classifier enabled this is its probability that each blob is the
        shuttle; otherwise a hand-made blend of contrast and size.
        """
        if self._classifier is not None:
            return self._classifier.probability(features)
        c = self.params.colour
        bright = np.minimum(np.maximum(contrasts - c.min_contrast, 0.0)
                            / max(c.contrast_reference - c.min_contrast, 1.0), 1.0)
        size = np.minimum(lengths / max(self.params.contour_length.min_length * 2.0, 1.0), 1.0)
        return 0.7 * bright + 0.3 * size

    def _is_stationary(self, x: float, y: float) -> bool:
        prev = self._previous_positions
        if len(prev) == 0:
            return False
        d = np.hypot(prev[:, 0] - x, prev[:, 1] - y)
        return bool(d.min() < self.params.motion.min_displacement)

    @staticmethod
    def _measure(frame: np.ndarray, mask: np.ndarray, box: tuple[int, int, int, int],
                 sx: float, sy: float, head_fraction: float = 0.5
                 ) -> tuple[float, float, float, float, np.ndarray]:
        """(x, y, whiteness, saturation, appearance features) of a blob, full-resolution window.

        The position is the intensity-weighted centroid of the blob's brightest part above the
        window's local background (median of the window border), which locates the white cork
        head rather than the middle of head + skirt, to a fraction of a pixel.
        The appearance features (see ``FEATURE_NAMES``) describe how small, bright, isolated
        and white the blob is; the candidate classifier and the hand-made score read them.

        Speed: up to ``association.max_measured`` blobs per frame and camera come here, so
        every step is one OpenCV call on the small window (about a microsecond each) rather
        than a numpy reduction (several microseconds of overhead each, and the GIL held, so
        the two camera threads would queue on it). The values are those of the plain numpy
        formulas that the classifiers were trained on (``tests/test_detector.py`` pins them):
        grey is ``mean(B, G, R)`` in float32, the border median is numpy's, sums and means are
        exact on integer data; only the window's standard deviation and the centroid's sums
        are accumulated in double instead of float32 (relative differences ~1e-7).
        """
        h, w = frame.shape[:2]
        x0 = max(box[0] - REFINE_MARGIN, 0)
        y0 = max(box[1] - REFINE_MARGIN, 0)
        x1 = min(box[0] + box[2] + REFINE_MARGIN, w)
        y1 = min(box[1] + box[3] + REFINE_MARGIN, h)
        if x1 <= x0 or y1 <= y0:
            return (box[0] + box[2] / 2, box[1] + box[3] / 2, 0.0, 255.0,
                    np.zeros(N_APPEARANCE, dtype=np.float32))
        # One contiguous copy of the window: cv2.split of a strided view copies it anyway.
        crop = np.ascontiguousarray(frame[y0:y1, x0:x1])
        ch, cw = crop.shape[:2]
        # The blob's pixels at full resolution: the mask window, resized (0 / 255).
        mx0, my0 = int(x0 / sx), int(y0 / sy)
        mx1, my1 = max(int(math.ceil(x1 / sx)), mx0 + 1), max(int(math.ceil(y1 / sy)), my0 + 1)
        inside = mask[my0:my1, mx0:mx1]
        if inside.shape[:2] != (ch, cw):
            inside = cv2.resize(inside, (cw, ch), interpolation=cv2.INTER_NEAREST)
        blue, green, red = cv2.split(crop)
        cmin = cv2.min(cv2.min(blue, green), red)
        cmax = cv2.max(cv2.max(blue, green), red)
        n_inside = cv2.countNonZero(inside)
        if n_inside:
            whiteness = cv2.mean(cmin, mask=inside)[0]
            saturation = cv2.mean(cv2.subtract(cmax, cmin), mask=inside)[0]
        else:
            whiteness, saturation = 0.0, 255.0
        # mean(B, G, R) in float32: the integer sum is exact, then one float32 division.
        gray = cv2.add(blue, green, dtype=cv2.CV_32F)
        cv2.add(gray, red, dst=gray, dtype=cv2.CV_32F)
        np.divide(gray, 3, out=gray)
        border = np.concatenate([gray[0], gray[-1], gray[:, 0], gray[:, -1]])
        background = _median_float32(border)
        excess = gray - background
        peak = cv2.minMaxLoc(excess)[1]
        half_peak = 0.5 * peak
        n_bright = cv2.countNonZero(cv2.compare(excess, half_peak, cv2.CMP_GT))
        # The border's excess, element for element as the window's (same float32 subtraction).
        spill = float(np.count_nonzero((border - background) > half_peak)) / len(border)
        peak_sat = cv2.minMaxLoc(cmax)[1] - cv2.minMaxLoc(cmin)[1]
        window_std = float(cv2.meanStdDev(gray)[1][0, 0])
        features = np.array((peak, background, math.log1p(n_bright), spill, whiteness, saturation,
                             math.log1p(n_inside), peak_sat, window_std), dtype=np.float32)
        if peak <= 0:
            ys, xs = np.nonzero(inside)
            if len(xs) == 0:
                return box[0] + box[2] / 2, box[1] + box[3] / 2, whiteness, saturation, features
            return x0 + xs.mean(), y0 + ys.mean(), whiteness, saturation, features
        # The position is measured on the blob's own pixels only (its mask, grown by one
        # full-resolution pixel for the blur fringe): a light or a court line inside the
        # window is brighter than the shuttle and used to drag the centroid towards itself.
        blob_peak = 0.0
        if n_inside:
            support = cv2.dilate(inside, _GROW)
            # copyTo into a new array zero-fills outside the mask: excess on the support, else 0.
            blob_excess = cv2.copyTo(excess, support)
            blob_peak = cv2.minMaxLoc(blob_excess)[1]
        if blob_peak <= 0:
            blob_excess = np.maximum(excess, 0)
            blob_peak = peak
        # Keep the part of the blob above ``head_fraction`` of its peak: the cork is whiter
        # than the feathers (0 = the whole blob's intensity centroid).
        weights = blob_excess - head_fraction * blob_peak
        np.maximum(weights, 0, out=weights)
        moments = _raster_moments(weights)
        if moments[0] <= 0:
            moments = _raster_moments(np.maximum(blob_excess, 0))
        # OpenCV's convention: integer coordinates are pixel centres (as projectPoints gives).
        total, sum_x, sum_y = moments
        return sum_x / total + x0, sum_y / total + y0, whiteness, saturation, features


def _median_float32(values: np.ndarray) -> float:
    """``np.median`` of a 1-D float32 array, without its generic machinery (same result)."""
    n = len(values)
    k = n // 2
    if n % 2:
        return float(np.partition(values, k)[k])
    part = np.partition(values, (k - 1, k))
    # np.median averages the two middle values in the array's dtype (float32).
    return float((part[k - 1] + part[k]) / np.float32(2))


def _raster_moments(weights: np.ndarray) -> tuple[float, float, float]:
    """(Σw, Σw·x, Σw·y) of a float32 image, accumulated in double (cv2.moments)."""
    if weights.shape[1] == 2:
        # cv2.moments reads an (N, 2) single-channel float array as N contour points.
        ys, xs = np.mgrid[0:weights.shape[0], 0:weights.shape[1]]
        return float(weights.sum(dtype=np.float64)), float((weights * xs).sum()), float((weights * ys).sum())
    m = cv2.moments(weights)
    return m["m00"], m["m10"], m["m01"]

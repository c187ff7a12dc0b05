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
            ranked = []
            for g in geometric:
                box = g[4]
                cx, cy = box[0] + box[2] / 2, box[1] + box[3] / 2
                if diff is not None:
                    bx0, by0 = int(box[0] / sx), int(box[1] / sy)
                    window = (slice(by0, by0 + max(int(box[3] / sy), 1)),
                              slice(bx0, bx0 + max(int(box[2] / sx), 1)))
                    # Brightening, plus plain brightness: a shuttle held still before the
                    # serve fades into the average but stays the brightest thing around.
                    strength = float(diff[window].max()) + 0.5 * float(gray[window].max())
                else:
                    strength = -g[3]   # MOG2 gives no strength: smaller blobs first
                near = bool(len(live)) and bool(np.any(
                    np.hypot(live[:, 0] - cx, live[:, 1] - cy) <= live[:, 2]))
                ranked.append((near, strength, g))
            ranked.sort(key=lambda r: (r[0], r[1]), reverse=True)
            for _, _, (_, length, short_side, area, box) in ranked[limit:]:
                candidates.append(Candidate(box[0] + box[2] / 2, box[1] + box[3] / 2, length,
                                            short_side, math.nan, area, math.nan, 0.0,
                                            REJECT_WHITENESS))
            geometric = [r[2] for r in ranked[:limit]]

        measured = []
        for _, length, short_side, area, box in geometric:
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
            feats = np.concatenate([[math.log1p(length), math.log1p(short_side), math.log1p(area),
                                     long_side / max(short_side, 1e-3)], appearance])
            quality = self._quality(length, contrast, feats)
            if reason is None and quality < p.association.min_quality:
                reason = REJECT_SCORE
            measured.append([x, y, length, short_side, whiteness, area, quality, reason, feats])
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
    def _quality(self, length: float, contrast: float, features: np.ndarray) -> float:
        """Shape/contrast score of a lone candidate in [0, 1] (the soft side of filters 1 and 3).

        With the learned classifier enabled this is its probability that the blob is the
        shuttle; otherwise a hand-made blend of contrast and size.
        """
        if self._classifier is not None:
            return float(self._classifier.probability(features[None, :])[0])
        c = self.params.colour
        bright = min(max(contrast - c.min_contrast, 0.0) / max(c.contrast_reference - c.min_contrast, 1.0), 1.0)
        size = min(length / max(self.params.contour_length.min_length * 2.0, 1.0), 1.0)
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
        """
        h, w = frame.shape[:2]
        x0 = max(box[0] - REFINE_MARGIN, 0)
        y0 = max(box[1] - REFINE_MARGIN, 0)
        x1 = min(box[0] + box[2] + REFINE_MARGIN, w)
        y1 = min(box[1] + box[3] + REFINE_MARGIN, h)
        crop = frame[y0:y1, x0:x1]
        features = np.zeros(N_APPEARANCE, dtype=np.float32)
        if crop.size == 0:
            return box[0] + box[2] / 2, box[1] + box[3] / 2, 0.0, 255.0, features
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
        bright = excess > 0.5 * peak
        n_bright = int(bright.sum())
        border_bright = np.concatenate([bright[0], bright[-1], bright[:, 0], bright[:, -1]])
        spill = float(border_bright.mean())
        peak_sat = float(cmax.max()) - float(cmin.max())
        features[:] = (peak, background, math.log1p(n_bright), spill, whiteness, saturation,
                       math.log1p(inside.sum()), peak_sat, float(gray.std()))
        if peak <= 0:
            ys, xs = np.nonzero(inside)
            if len(xs) == 0:
                return box[0] + box[2] / 2, box[1] + box[3] / 2, whiteness, saturation, features
            return x0 + xs.mean(), y0 + ys.mean(), whiteness, saturation, features
        # The position is measured on the blob's own pixels only (its mask, grown by one
        # full-resolution pixel for the blur fringe): a light or a court line inside the
        # window is brighter than the shuttle and used to drag the centroid towards itself.
        support = inside
        if support.any():
            support = cv2.dilate(support.astype(np.uint8), _GROW) > 0
        blob_excess = np.where(support, excess, 0.0)
        blob_peak = float(blob_excess.max())
        if blob_peak <= 0:
            blob_excess = np.clip(excess, 0, None)
            blob_peak = peak
        # Keep the part of the blob above ``head_fraction`` of its peak: the cork is whiter
        # than the feathers (0 = the whole blob's intensity centroid).
        weights = np.clip(blob_excess - head_fraction * blob_peak, 0, None)
        total = float(weights.sum())
        if total <= 0:
            weights = np.clip(blob_excess, 0, None)
            total = float(weights.sum())
        ys, xs = np.mgrid[0:crop.shape[0], 0:crop.shape[1]]
        # OpenCV's convention: integer coordinates are pixel centres (as projectPoints gives).
        cx = float((weights * xs).sum() / total) + x0
        cy = float((weights * ys).sum() / total) + y0
        return cx, cy, whiteness, saturation, features

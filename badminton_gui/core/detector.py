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

Speed (issue #7): both cameras run this in two threads, and only OpenCV calls and numpy
operations on large arrays release the GIL, so per-blob and per-contour Python is kept out of
the hot path — contour measurements are gathered in lists and decided for all contours at
once, the ranking's window maxima come from one gather, the measured windows share one canvas
(``measure_blobs``), the classifier scores all blobs in one call. Every value is the one the
plain per-blob code gave (tests/test_detector_fast_paths.py).
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from typing import NamedTuple

import cv2
import numpy as np

from .association import TrackletAssociator
from .background import BackgroundModel
from .classifier import load_classifier
from .detect.measure import (FEATURE_NAMES, GROW, N_APPEARANCE, PATCH_CELLS, PATCH_HALF,  # noqa: F401
                             PATCH_NAMES, REFINE_MARGIN, measure_blobs, patch_features,
                             scaled_boxes, window_maxima)
from .params import TrackerParams
from .window import WindowTracker
from .types import (REJECT_LENGTH, REJECT_MOTION, REJECT_SCORE, REJECT_SHORT_SIDE,
                    REJECT_WHITENESS, CameraResult, Candidate, make_candidate)

# At most this many blobs per frame get the (more expensive) full-resolution colour check;
# beyond it the largest blobs are dropped first (players, not shuttles).
MAX_COLOUR_CHECKS = 64
# px at 1280 px width: the half-size of the box around a held shuttle thresholded lower in the
# next frame (``protect_report``); a shuttle lying on the floor is ≈ 6–10 px long there.
PROTECT_RADIUS = 8.0
# px: a held-back candidate's track must have moved at least this in its last step for the other
# camera to vouch for it (``vouchable``): its smoothed velocity remembers older motion.
VOUCH_MIN_STEP = 1.0
# Frames of a tracklet's blob areas remembered for ``colour.edge_exit``.
EDGE_AREA_FRAMES = 8


class Segmented(NamedTuple):
    """What ``CameraDetector.segment`` hands to ``candidates_from`` for one frame."""

    gray: np.ndarray          # the model's grey image (the window's, when windowed)
    mask: np.ndarray          # foreground mask at the processing scale
    contours: tuple           # the mask's external contours
    window: tuple | None      # the window (full-resolution x0, y0, x1, y1), or None: whole frame
    windowed: bool


class CameraDetector:
    """Finds the shuttle in one camera's frames."""

    def __init__(self, params: TrackerParams | None = None) -> None:
        self.params = params or TrackerParams()
        self._background = BackgroundModel(self.params.background, self.params.binarize)
        self._associator = TrackletAssociator(self.params.motion, self.params.association)
        self._widths: dict[int, deque] = {}      # tracklet ident → its blobs' recent short sides
        self._areas: dict[int, deque] = {}       # tracklet ident → its blobs' recent areas (edge_exit)
        self.last_features: list = []   # (x, y, features, rejected_by) of the last frame's blobs
        # The last frame's measured blobs as the classifier saw them: positions (N, 2) and feature
        # rows (N, F), the patch included when the classifier reads it (core/adaptation.py).
        self.last_scored: tuple[np.ndarray, np.ndarray] = (np.zeros((0, 2)), np.zeros((0, 0)))
        self._classifier = None
        self._load_classifier()
        self._previous_positions = np.zeros((0, 2))
        self._small: np.ndarray | None = None   # the frame at the processing scale (buffer)
        self._gray: np.ndarray | None = None
        self._mask_scale = 0.0   # mask px per full-resolution px (0: no frame yet)
        self._last_mask: np.ndarray | None = None
        self._large_boxes = np.zeros((0, 4), np.int64)   # full-res boxes of blobs too large (filters 1, 2)
        self._window = WindowTracker(self.params)   # windowed tracking (``window.enabled``)
        self._planned: tuple[float, tuple[int, int, int, int] | None] | None = None   # plan_window
        # Set by the stereo tracker while it holds a landed shuttle for this camera: the frame is
        # processed whole, since the window follows the association's track (after a rally, a
        # player walking past) and the lying shuttle outside it would have no candidate.
        self.keep_whole = False
        # The last frame's grey image where it was made (its window, or the whole frame), that
        # part's model-pixel origin and the whole model's shape (split_min_length).
        self._previous_gray: tuple[np.ndarray, int, int, tuple[int, int]] | None = None
        self.last_split = 0   # candidates split off merged blobs in the last frame
        # ``association.exit_margin``: (time the shuttle left the picture, first tracklet ident
        # born after that, {ident: hits} of the tracklets alive then) while it is out, else
        # None; the tracklets that could supply the detection in the last frame.
        self._outside: tuple[float, int, dict[int, int]] | None = None
        self._eligible: set[int] = set()
        self._left_picture = -1   # the tracklet that left the picture this frame (-1: none)

    # ---- configuration ---------------------------------------------------------------------
    def set_params(self, params: TrackerParams) -> None:
        self.params = params
        self._background.set_params(params.background, params.binarize)
        self._associator.set_params(params.motion, params.association)
        self._window.set_params(params)
        self._load_classifier()

    def reset(self) -> None:
        self._background.reset()
        self._window.reset()
        self._planned = None
        self._associator.reset()
        self._widths = {}
        self._areas = {}
        self._previous_gray = None
        self._previous_positions = np.zeros((0, 2))
        self._outside = None
        self._eligible = set()

    @property
    def associator(self) -> TrackletAssociator:
        """This camera's image tracklets (filter 4): a candidate's ``tracklet`` field names one."""
        return self._associator

    @property
    def tracking(self) -> bool:
        return self._associator.selected is not None

    def _load_classifier(self) -> None:
        cp = self.params.classifier
        if not cp.enabled:
            self._classifier = None
        elif self._classifier is None or self._classifier.name != cp.model:
            self._classifier = load_classifier(cp.model)
        # A classifier trained with the patch features reads them after FEATURE_NAMES.
        self._needs_patches = (self._classifier is not None
                               and len(self._classifier.feature_names) > len(FEATURE_NAMES))

    @property
    def classifier(self):
        """The classifier scoring candidates (None: the hand-made score)."""
        return self._classifier

    def use_classifier(self, classifier) -> None:
        """Score candidates with this classifier object instead of the preset's file (until the
        next ``set_params``): a leave-one-clip-out study trains one per left-out clip
        (``benchmarks/train_classifier.py --leave-one-out``) without writing ``resources/``."""
        self._classifier = classifier
        self._needs_patches = (classifier is not None
                               and len(classifier.feature_names) > len(FEATURE_NAMES))

    # ---- the whole chain for one camera (CLI `detect`) --------------------------------------
    def process(self, frame_bgr: np.ndarray, t: float, keep_mask: bool = True) -> CameraResult:
        result = self.find_candidates(frame_bgr, t, keep_mask)
        chosen = self.choose(result.candidates)
        self.commit(chosen, t, result.candidates)
        result, chosen = self.lead_to_head(result, chosen)
        return self.finalise(result, chosen)

    def plan_window(self, frame_bgr: np.ndarray, t: float) -> bool:
        """Choose the coming frame's window now (``find_candidates`` of the same ``t`` then uses
        it): True when the frame will be processed in a window. The stereo tracker asks both
        cameras before it decides whether to run them side by side or in turn."""
        h, w = frame_bgr.shape[:2]
        p = self.params
        window = (self._window.plan(self._associator, t, w, h, model_scale(p.background, w),
                                    self.keep_whole)
                  if p.window.enabled else None)
        self._planned = (t, window)
        return window is not None

    def set_window_phase(self, phase: float) -> None:
        """Where this camera's scheduled whole frames fall in the ``window.full_every`` period
        (``window.stagger``; 0 for the left camera, 0.5 for the right)."""
        self._window.phase = float(phase)

    # ---- steps, so the stereo tracker can choose with both cameras --------------------------
    def find_candidates(self, frame_bgr: np.ndarray, t: float, keep_mask: bool = True) -> CameraResult:
        """Candidates with filters 1–4 applied (no choice made yet)."""
        return self.candidates_from(frame_bgr, t, self.segment(frame_bgr, t), keep_mask)

    def segment(self, frame_bgr: np.ndarray, t: float) -> Segmented:
        """The image half of ``find_candidates``: the background model's mask and its contours,
        in this frame's window or on the whole frame.

        It is nearly all OpenCV on whole images, which releases the GIL, so the stereo tracker
        runs the two cameras' ``segment`` side by side; ``candidates_from`` (many small calls,
        mostly Python) then runs for one camera after the other on one thread. Run side by side,
        the small calls of two threads hand the GIL to each other at every call and each waits
        for it back (the two threads were only 1.1–1.25× one; README Speed).
        """
        p = self.params
        h, w = frame_bgr.shape[:2]
        scale = model_scale(p.background, w)
        # Windowed tracking (core/window.py): only around the followed shuttle's prediction,
        # as chosen by ``plan_window`` for this frame, or now.
        planned, self._planned = self._planned, None
        if planned is not None and planned[0] == t:
            window = planned[1]
        else:
            window = (self._window.plan(self._associator, t, w, h, scale, self.keep_whole)
                      if p.window.enabled else None)
        windowed = None if window is None else self._window.model_mask(frame_bgr, scale, window,
                                                                       self._background)
        if windowed is None:
            if window is not None:
                window = None
                self._window.note(None)
            gray = self._model_grey(frame_bgr, scale)
            self._window.before_whole(self._background)
            mask = self._background.apply(gray)
            contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        else:
            gray, mask, contours = windowed
        return Segmented(gray, mask, contours, window, windowed is not None)

    def candidates_from(self, frame_bgr: np.ndarray, t: float, segmented: Segmented,
                        keep_mask: bool = True) -> CameraResult:
        """The measuring half of ``find_candidates``: filters 1–4 on ``segment``'s contours."""
        p = self.params
        h, w = frame_bgr.shape[:2]
        gray, mask, contours, window = segmented.gray, segmented.mask, segmented.contours, segmented.window
        sx = w / mask.shape[1]
        sy = h / mask.shape[0]
        self._mask_scale = mask.shape[1] / w

        # Filters 1 and 2 (contour length, short side of the tilted rectangle). OpenCV measures
        # each contour; the scaling and the decisions are done for all contours at once.
        candidates: list[Candidate] = []
        s_mean = 0.5 * (sx + sy)
        # (one list per measurement: a row assignment per contour costs as much as a call)
        length_all = np.array([cv2.arcLength(c, True) for c in contours], dtype=float) * s_mean
        short_all = np.array([min(cv2.minAreaRect(c)[1]) for c in contours], dtype=float) * s_mean
        area_all = np.array([cv2.contourArea(c) for c in contours], dtype=float) * sx * sy
        rects = np.array([cv2.boundingRect(c) for c in contours], dtype=float).reshape(-1, 4)
        bx, by, bw, bh = rects[:, 0], rects[:, 1], rects[:, 2], rects[:, 3]
        boxes_all = scaled_boxes(rects, sx, sy)
        length_ok = ((p.contour_length.min_length <= length_all)
                     & (length_all <= p.contour_length.max_length))
        short_ok = ((p.tilted_rect.min_short_side <= short_all)
                    & (short_all <= p.tilted_rect.max_short_side))
        cl = p.contour_length
        if 0 < cl.guided_min_length < cl.min_length and len(contours):
            # Guided exception to filter 1: a short blob where the followed shuttle is predicted.
            followed = self._associator.followed
            if followed is not None and followed.velocity_known:
                px, py = followed.predict(t)
                short = (cl.guided_min_length <= length_all) & (length_all < cl.min_length)
                near = np.hypot((bx + bw / 2) * sx - px, (by + bh / 2) * sy - py) <= cl.guided_radius * w / 1280.0
                length_ok = length_ok | (short & near)
        passed = length_ok & short_ok
        # Blobs too large for a shuttle (a player, a racket and what touches them): a shuttle
        # merged into one cannot be told apart (``is_merged``).
        self._last_mask = mask
        self._large_boxes = boxes_all[(length_all > p.contour_length.max_length)
                                      | (short_all > p.tilted_rect.max_short_side)]
        rejected = np.flatnonzero(~passed)
        if len(rejected):
            reasons = np.where(length_ok[rejected], REJECT_SHORT_SIDE, REJECT_LENGTH).tolist()
            for cx, cy, length, short_side, area, reason in zip(
                    ((bx[rejected] + bw[rejected] / 2) * sx).tolist(),
                    ((by[rejected] + bh[rejected] / 2) * sy).tolist(),
                    length_all[rejected].tolist(), short_all[rejected].tolist(),
                    area_all[rejected].tolist(), reasons):
                candidates.append(make_candidate(cx, cy, length, short_side, math.nan, area,
                                                 math.nan, 0.0, reason))
        kept = np.flatnonzero(passed)
        geometric: list[tuple[int, float, float, float, tuple[int, int, int, int]]] = [
            (k, length, short_side, area, tuple(box)) for k, (length, short_side, area, box) in enumerate(zip(
                length_all[kept].tolist(), short_all[kept].tolist(), area_all[kept].tolist(),
                boxes_all[kept].tolist()))]

        limit = min(int(p.association.max_measured), MAX_COLOUR_CHECKS)
        if len(geometric) > limit:
            # Cheap ranking at the processing scale: blobs near a live tracklet first, then
            # the strongest brightening; only the best get the full-resolution measurement.
            diff = self._background.last_difference
            live = self._associator.live_predictions(t)
            boxes = boxes_all[kept]
            centre_x = boxes[:, 0] + boxes[:, 2] / 2
            centre_y = boxes[:, 1] + boxes[:, 3] / 2
            if len(live):
                near = (np.hypot(live[None, :, 0] - centre_x[:, None],
                                 live[None, :, 1] - centre_y[:, None])
                        <= live[None, :, 2]).any(axis=1)
            else:
                near = np.zeros(len(geometric), dtype=bool)
            if diff is not None:
                # Brightening, plus plain brightness: a shuttle held still before the serve
                # fades into the average but stays the brightest thing around. Each box's
                # window at the processing scale, maxima of all windows in one gather.
                x0 = (boxes[:, 0] / sx).astype(np.int64)
                y0 = (boxes[:, 1] / sy).astype(np.int64)
                win_w = np.minimum(np.maximum((boxes[:, 2] / sx).astype(np.int64), 1), mask.shape[1] - x0)
                win_h = np.minimum(np.maximum((boxes[:, 3] / sy).astype(np.int64), 1), mask.shape[0] - y0)
                diff_max, gray_max = window_maxima((diff, gray), x0, y0, win_w, win_h,
                                                    self._background.last_unlit)
                strength = diff_max.astype(np.float64) + 0.5 * gray_max.astype(np.float64)
            else:
                strength = -area_all[kept]   # MOG2 gives no strength: smaller blobs first
            # Near first, then strongest; ties keep the contour order (a stable sort).
            order = np.lexsort((-strength, ~near)).tolist()
            for i in order[limit:]:
                _, length, short_side, area, box = geometric[i]
                candidates.append(make_candidate(box[0] + box[2] / 2, box[1] + box[3] / 2, length,
                                                 short_side, math.nan, area, math.nan, 0.0,
                                                 REJECT_WHITENESS))
            geometric = [geometric[i] for i in order[:limit]]

        # Filter 3 and the appearance features of all the frame's blobs at once; the
        # classifier then scores them in one call too.
        measured = []
        pos_x, pos_y, whiteness_all, saturation_all, appearance_all = measure_blobs(
            frame_bgr, mask, [g[4] for g in geometric], sx, sy, p.colour.head_fraction)
        if segmented.windowed:
            # The window's corners are multiples of ALIGN px: exact model pixels.
            fresh = tuple(int(round(v * self._mask_scale)) for v in window)
        else:
            fresh = (0, 0, mask.shape[1], mask.shape[0])
        split = self._split_merged(gray, mask, contours, length_all, t, w, sx, sy, fresh)
        self.last_split = len(split[1]) if split is not None else 0
        if split is not None:
            # Parts split off merged blobs, measured on their own pixels (``_split_merged``).
            core_mask, parts = split
            more = measure_blobs(frame_bgr, core_mask, [g[4] for g in parts], sx, sy, p.colour.head_fraction)
            pos_x, pos_y, whiteness_all, saturation_all, appearance_all = (
                np.concatenate([a, b]) for a, b in zip(
                    (pos_x, pos_y, whiteness_all, saturation_all, appearance_all), more))
            geometric = geometric + parts
        features = np.empty((len(geometric), len(FEATURE_NAMES)))
        features[:, 4:] = appearance_all
        for row, ((_, length, short_side, area, _box), x, y, whiteness, saturation, contrast) in enumerate(zip(
                geometric, pos_x.tolist(), pos_y.tolist(), whiteness_all.tolist(),
                saturation_all.tolist(), features[:, 4].tolist())):
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
            measured.append([x, y, length, short_side, whiteness, area, 0.0, reason, feats])
        if measured:
            if self._needs_patches:
                features = np.hstack([features, patch_features(
                    frame_bgr, np.array([m[0] for m in measured]), np.array([m[1] for m in measured]))])
            qualities = self._qualities(np.array([m[2] for m in measured]), features[:, 4], features)
            for m, quality in zip(measured, qualities.tolist()):
                m[6] = quality
                if m[7] is None and quality < p.association.min_quality:
                    m[7] = REJECT_SCORE
        self._previous_positions = np.asarray([(m[0], m[1]) for m in measured],
                                              dtype=float).reshape(-1, 2)
        # The same positions array, no second copy on the per-frame path.
        self.last_scored = (self._previous_positions, features)

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
        self._left_picture = -1
        if p.association.exit_margin > 0:
            links = self._out_of_picture(t, w, h, links)
        width_frames = int(p.colour.head_lead_width_frames)
        edge_exit = p.colour.edge_exit > 0
        k = 0
        # Candidates the association refused, by index, while none passed: ``_accept_lone``.
        lone = p.association.lone_quality < 1.0
        refused: list[int] | None = [] if lone else None
        for m in measured:
            x, y, length, short_side, whiteness, area, quality, reason, _ = m
            motion, score, ident = math.nan, quality, None
            if reason is None:
                ident, motion, merit = links[k]
                k += 1
                if merit < 0:
                    reason = REJECT_MOTION
                    if refused is not None and quality >= p.association.lone_quality:
                        refused.append(len(candidates))
                else:
                    score = merit
                    refused = None
            c = make_candidate(x, y, length, short_side, whiteness, area, motion, score, reason,
                               tracklet=-1 if ident is None else ident)
            if ident is not None:
                if width_frames > 1:
                    widths = self._widths.get(ident)
                    if widths is None or widths.maxlen != width_frames:
                        widths = self._widths[ident] = deque(widths or (), maxlen=width_frames)
                    widths.append(short_side)
                if edge_exit:
                    areas = self._areas.get(ident)
                    if areas is None:
                        areas = self._areas[ident] = deque(maxlen=EDGE_AREA_FRAMES)
                    areas.append(area)
            candidates.append(c)
        if width_frames > 1 and len(self._widths) > 2 * len(self._associator.tracklets) + 16:
            alive = {tr.ident for tr in self._associator.tracklets}
            self._widths = {k: v for k, v in self._widths.items() if k in alive}
        if edge_exit and len(self._areas) > 2 * len(self._associator.tracklets) + 16:
            alive = {tr.ident for tr in self._associator.tracklets}
            self._areas = {k: v for k, v in self._areas.items() if k in alive}
        # The followed shuttle crossing a light or a white line leaves no blob: its track's
        # prediction stands in (flagged, never triangulated) until it shows again.
        coast = self._associator.coasting(t, blind) if self._outside is None else None
        if coast is not None:
            tr, merit = coast
            px, py = tr.predict(t)
            c = Candidate(px, py, math.nan, math.nan, math.nan, math.nan, 0.0, merit, None,
                          predicted=True, tracklet=tr.ident)
            candidates.append(c)
        elif refused and self._outside is None:
            self._accept_lone(candidates, refused)
        return CameraResult(detection=None, candidates=tuple(candidates),
                            mask=mask if keep_mask else None,
                            mask_scale=mask.shape[1] / w, image_size=(w, h),
                            window=None if window is None else tuple(int(v) for v in window),
                            left_picture=self._left_picture)

    def _accept_lone(self, candidates: list, refused: list[int]) -> None:
        """No candidate lies on a confirmed, travelling tracklet: the most shuttle-like one the
        association refused (``refused``: indices into ``candidates``, each of quality ≥
        ``association.lone_quality``) passes after all, scored by its own quality.

        The shuttle held for the serve, or lying after a rally, never travels, and TV labels
        mark it visible; with nothing else to report, a blob the classifier is sure of is more
        often that shuttle than anything (``lone_quality`` in params.py). Not while the shuttle
        is out of the picture (``_out_of_picture`` holds every candidate back then) nor while the
        followed track coasts through a blind spot.
        """
        best = max(refused, key=lambda i: candidates[i].score)
        candidates[best] = dataclasses.replace(candidates[best], rejected_by=None)

    def _out_of_picture(self, t: float, w: int, h: int,
                        links: list[tuple[int, float, float]]) -> list[tuple[int, float, float]]:
        """Hold every report back while the shuttle is out of the picture (``exit_margin``).

        A track that could supply the detection last frame, seen within the margin of the top
        edge while rising and now missing with its prediction above the image, is the shuttle
        leaving the picture (on TV: a clear or a lob; players and rackets cross the other
        edges, not this one). Out there it cannot be seen, so whatever the association offers
        meanwhile (a player in white, a shoe, a logo) is not the shuttle; it can only come back
        across an edge. So until a
        track that has come within ``entry_margin`` of an edge since the exit may supply the
        detection (the shuttle coming back in; its first frames back may be missed, so its
        track can start some way inside; ``_came_in``), or ``exit_timeout`` has passed (a new
        shuttle brought into play), every candidate is held back (``merit`` -1). Any point of a
        track born after the exit counts, not only its first: a young clutter track's wide gate
        (its velocity barely known) can take the returning shuttle's first blob over (1_02_01
        111 with filter 1 at 18 px: a track born at (992, 173) took the shuttle at (847, 6), and
        its first point held it back for 17 frames). The hold starts only while the followed
        track is not seen in the frame.
        """
        a, ap = self._associator, self.params.association
        margin = ap.exit_margin * w / 1280.0
        entry = max(ap.entry_margin, ap.exit_margin) * w / 1280.0
        # The followed track seen in this frame is the shuttle in the picture: another track
        # leaving through the top is clutter (bwf_00001 242 with the speed gate gain at 0.75:
        # a track at the top edge that could have supplied the detection left while the
        # followed shuttle flew on below, and the shuttle was held back for 3 s).
        followed_here = any(tr.ident == a.selected and tr.hit_now for tr in a.tracklets)
        for tr in a.tracklets:
            # Through the top edge only: players, rackets and shoes cross the side and bottom
            # edges of a TV picture, never its top (they stand on the court below it).
            if (not tr.hit_now and tr.misses == 1 and tr.ident in self._eligible and not followed_here
                    and tr.velocity_known and tr.vy < 0 and tr.y + 0.5 < margin):
                if tr.predict(t)[1] < -0.5:
                    # The followed shuttle is the one that left: no clutter keeps the hysteresis.
                    self._outside = (t, a.next_ident, {other.ident: other.hits for other in a.tracklets})
                    a.select(tr.ident)
                    self._left_picture = tr.ident
                    break
        self._eligible = {ident for ident, _, merit in links if merit >= 0}
        if self._outside is None:
            return links
        t_exit, first, hits_then = self._outside
        if t - t_exit > ap.exit_timeout:
            self._outside = None
            return links
        by_id = {tr.ident: tr for tr in a.tracklets}
        out, entered = [], False
        for ident, motion, merit in links:
            tr = by_id.get(ident)
            if merit >= 0 and not (tr is not None and self._came_in(tr, first, hits_then, w, h, entry)):
                merit = -1.0
            entered = entered or merit >= 0
            out.append((ident, motion, merit))
        if entered:
            self._outside = None
        return out

    @staticmethod
    def _came_in(tr, first: int, hits_then: dict[int, int], w: int, h: int, entry: float) -> bool:
        """Has tracklet ``tr`` been within ``entry`` px of an edge since the shuttle left?

        A track born after the exit (ident ≥ ``first``): any of its points. An older one: only
        the points it gained since (its hits then, ``hits_then``), for an old clutter track
        (a player's, a line's) can take the returning shuttle's blob into its gate (bwf_00001
        90 with the gate slack at 30 px: a track that had sat at (733, 317) for 52 frames).
        """
        points = list(tr.recent)
        if tr.ident < first:
            gained = tr.hits - hits_then.get(tr.ident, tr.hits)
            points = points[len(points) - gained:] if gained > 0 else []
        return any(_near_edge(x, y, w, h, entry) for x, y in points)

    def _split_merged(self, gray: np.ndarray, mask: np.ndarray, contours, length_all: np.ndarray,
                      t: float, w: int, sx: float, sy: float, fresh: tuple[int, int, int, int]):
        """(mask of the parts, parts as (index, length, short side, area, box)) split off the
        frame's long blobs (``contour_length.split_min_length``), or None.

        A shuttle touching a racket, an arm, or the ghost a racket leaves on a lit line merges
        with it into one blob that filters 1 and 2 reject or that scores as a poor shuttle; the
        tracker then loses the shuttle or follows the racket. The shuttle moves by about its
        own size a frame, so the pixels of a long blob that brightened by ``split_threshold``
        since the previous frame (processing scale) hold it: each compact group of them (grown
        by a pixel like the mask, and within filters 1 and 2) inside the followed tracklet's
        gate becomes a candidate of its own, measured on its own pixels. ``fresh`` (model px
        x0, y0, x1, y1) is the part of ``gray`` made this frame (the window, when windowed);
        a blob is split only where the previous frame's grey image was made too (windows
        overlap while they follow the shuttle: rally_11-48-00 left 483–492, coarse, a shuttle
        merged with a player for 10 frames). Only around a track seen lately
        (``split_max_misses``): the grown gate of one that lost its blob behind a player holds
        brightening parts of the player, split off in both cameras alike.
        """
        cl = self.params.contour_length
        prev, self._previous_gray = self._previous_gray, None
        if cl.split_min_length <= 0:
            return None
        fx0, fy0, fx1, fy1 = fresh
        self._previous_gray = (gray[fy0:fy1, fx0:fx1].copy(), fx0, fy0, gray.shape)
        if prev is None or prev[3] != gray.shape:
            return None
        prev_gray, px0, py0, _ = prev
        ph, pw = prev_gray.shape
        # Only where the followed shuttle may be (its tracklet's gate around its prediction):
        # elsewhere a moving hand or racket edge split off a player would start tracks of its own.
        followed = self._associator.followed
        if followed is None or not followed.velocity_known:
            return None
        if followed.misses > cl.split_max_misses:
            # A track that lost its blob a while ago: its gate has grown, and what brightens
            # in it then is more often part of a player than the shuttle (hidden
            # behind the player).
            return None
        px, py = followed.predict(t)
        radius = self._associator.gate(followed, max(t - followed.t, 1e-3))
        big = np.flatnonzero(length_all >= cl.split_min_length * w / 1280.0)
        if not len(big):
            return None
        s_mean = 0.5 * (sx + sy)
        tr = self.params.tilted_rect
        core_mask = None
        parts = []
        h_m, w_m = mask.shape[:2]
        for k in big.tolist():
            x0, y0, bw, bh = cv2.boundingRect(contours[k])
            if not (x0 * sx - radius <= px <= (x0 + bw) * sx + radius
                    and y0 * sy - radius <= py <= (y0 + bh) * sy + radius):
                continue
            if not (px0 <= x0 and py0 <= y0 and x0 + bw <= px0 + pw and y0 + bh <= py0 + ph):
                continue   # the previous frame's grey image was not made here
            blob = np.zeros((bh, bw), np.uint8)
            cv2.drawContours(blob, contours, k, 255, -1, offset=(-x0, -y0))
            rise = cv2.subtract(gray[y0:y0 + bh, x0:x0 + bw],
                                prev_gray[y0 - py0:y0 - py0 + bh, x0 - px0:x0 - px0 + bw])
            core = cv2.compare(rise, float(cl.split_threshold), cv2.CMP_GT)
            cv2.bitwise_and(core, blob, dst=core)
            if not cv2.countNonZero(core):
                continue
            core = cv2.dilate(core, GROW)
            cv2.bitwise_and(core, blob, dst=core)
            found, _ = cv2.findContours(core, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
            for c in found:
                length = cv2.arcLength(c, True) * s_mean
                short_side = min(cv2.minAreaRect(c)[1]) * s_mean
                if not (cl.min_length <= length <= min(cl.max_length, 0.5 * length_all[k])
                        and tr.min_short_side <= short_side <= tr.max_short_side):
                    continue
                cx, cy, cw, ch = cv2.boundingRect(c)
                if math.hypot((x0 + cx + cw / 2) * sx - px, (y0 + cy + ch / 2) * sy - py) > radius:
                    continue
                if core_mask is None:
                    core_mask = np.zeros((h_m, w_m), np.uint8)
                cv2.drawContours(core_mask, [c], 0, 255, -1, offset=(x0, y0))
                box = scaled_boxes(np.array([[cx + x0, cy + y0, cw, ch]], dtype=float), sx, sy)[0]
                parts.append((k, length, short_side, cv2.contourArea(c) * sx * sy, tuple(box.tolist())))
        if not parts:
            return None
        return core_mask, parts

    def _model_grey(self, frame_bgr: np.ndarray, scale: float) -> np.ndarray:
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

    def is_blind(self, x: float, y: float) -> bool:
        """True when a shuttle at full-resolution (x, y) cannot show in this camera's mask."""
        scale = self._mask_scale
        return scale > 0 and self._background.is_blind(x * scale, y * scale)

    def is_merged(self, x: float, y: float) -> bool:
        """True when full-resolution (x, y) is foreground of a blob too large for a shuttle.

        A shuttle crossing a player, a racket or a lit line merges with it into one blob that
        filters 1 and 2 reject: the detector cannot isolate it there (the mask, within a pixel
        at the processing scale, inside the box of a blob rejected as too long or too wide).
        """
        mask, boxes, scale = self._last_mask, self._large_boxes, self._mask_scale
        if mask is None or scale <= 0 or not len(boxes):
            return False
        inside = ((boxes[:, 0] <= x) & (x < boxes[:, 0] + boxes[:, 2])
                  & (boxes[:, 1] <= y) & (y < boxes[:, 1] + boxes[:, 3]))
        if not inside.any():
            return False
        mx, my = int(round(x * scale)), int(round(y * scale))
        h, w = mask.shape[:2]
        return bool((mask[max(my - 1, 0):min(my + 2, h), max(mx - 1, 0):min(mx + 2, w)] > 0).any())

    def tracklet_hits(self, candidate: Candidate) -> int:
        """Frames the candidate's tracklet has been seen (0 when it is on none)."""
        tr = self._associator.tracklet(candidate.tracklet)
        return 0 if tr is None else tr.hits

    def vouchable(self, candidate: Candidate, min_quality: float) -> tuple[float, float] | None:
        """Image velocity (px/s) of a candidate the association held back (filter 4: its tracklet
        is not confirmed yet, or not travelling far enough) while the tracklet is seen this frame,
        has a known velocity and a running quality of at least ``min_quality``; else None.

        The stereo tracker lets such a candidate through when the other camera sees a partner
        on its epipolar line moving the same way in 3D (``StereoTracker._vouch``): the flight's
        first frames after a serve or a hit, a shuttle coming back slowly into view.
        """
        if candidate.rejected_by != REJECT_MOTION or candidate.predicted:
            return None
        tr = self._associator.tracklet(candidate.tracklet)
        if (tr is not None and tr.hit_now and tr.velocity_known and tr.quality >= min_quality
                and len(tr.recent) >= 2
                and math.hypot(tr.x - tr.recent[-2][0], tr.y - tr.recent[-2][1]) >= VOUCH_MIN_STEP):
            return tr.vx, tr.vy
        return None

    def first_sighting(self, candidate: Candidate, min_quality: float) -> bool:
        """The held-back candidate starts a track this frame (no velocity yet) and scores at
        least ``min_quality`` by its looks: the other camera may vouch for it by position alone."""
        if candidate.rejected_by != REJECT_MOTION or candidate.predicted or candidate.score < min_quality:
            return False
        tr = self._associator.tracklet(candidate.tracklet)
        return tr is not None and tr.hit_now and tr.hits == 1

    def vouch(self, candidate: Candidate, score: float) -> Candidate:
        """The held-back candidate let through with ``score`` (it keeps its tracklet)."""
        return dataclasses.replace(candidate, rejected_by=None, score=score)

    def tracklet_velocity(self, candidate: Candidate) -> tuple[float, float] | None:
        """Image velocity (px/s) of the candidate's tracklet, or None when not yet known."""
        tr = self._associator.tracklet(candidate.tracklet)
        return (tr.vx, tr.vy) if tr is not None and tr.velocity_known else None

    def _velocity_of(self, ident: int) -> tuple[float, float] | None:
        """Image velocity (px/s) of the tracklet ``ident`` (or of the followed one's ghost)."""
        if ident < 0:
            return None
        tr = self._associator.tracklet(ident)
        if tr is not None:
            return (tr.vx, tr.vy) if tr.velocity_known else None
        ghost = self._associator.followed
        if ghost is not None and ghost.ident == ident and ghost.velocity_known:
            return ghost.vx, ghost.vy
        return None

    def lead_to_head(self, result: CameraResult, chosen: Candidate | None
                     ) -> tuple[CameraResult, Candidate | None]:
        """Move a moving detection forward along its tracklet to the cork (``colour.head_lead``).

        The bright centroid of a moving shuttle trails its cork: the skirt is behind it and the
        motion blur smears the white backwards too. The lead is proportional to the blob's width
        (the shuttle's apparent size, which blur does not stretch). Call after ``commit`` (the
        tracklet's velocity then includes this frame); the associator keeps the measured
        position, only the reported one moves. Returns the result with the moved candidate in
        place of the old one, and the moved candidate; no candidate (None) when the cork is led
        out of the image.
        """
        c = self.params.colour
        w, h = result.image_size
        if chosen is not None and chosen.predicted:
            # A coasting prediction (no blob) at the edge its track leaves through: the blob is
            # missing because the shuttle has left the image, not because it is hidden.
            velocity = self._velocity_of(chosen.tracklet)
            if (c.edge_exit > 0 and w > 0 and velocity is not None
                    and _leaving_edge(chosen.x, chosen.y, velocity, w, h, c.edge_exit * w / 1280.0)):
                return result, None
            return result, chosen
        if (chosen is None or (c.head_lead <= 0 and c.edge_exit <= 0)
                or not math.isfinite(chosen.short_side)):
            return result, chosen
        velocity = self.tracklet_velocity(chosen)
        if velocity is None:
            return result, chosen
        moved = chosen
        speed = math.hypot(*velocity)
        if c.head_lead > 0 and speed >= c.head_lead_min_speed:
            width = chosen.short_side
            widths = self._widths.get(chosen.tracklet)
            if c.head_lead_width_frames > 1 and widths:
                # A shuttle merged with a racket or an arm: the blob is wider than the shuttle,
                # whose own width shows in the tracklet's recent frames.
                width = min(width, min(widths))
            lead = c.head_lead * width / speed
            moved = dataclasses.replace(chosen, x=chosen.x + lead * velocity[0],
                                        y=chosen.y + lead * velocity[1])
            if w > 0 and not (-0.5 <= moved.x < w - 0.5 and -0.5 <= moved.y < h - 0.5):
                # The cork has left the image (only the skirt's end still shows at the border):
                # no point inside the frame is the shuttle's, and none outside it can be reported.
                return result, None
        if (c.edge_exit > 0 and w > 0
                and _leaving_edge(moved.x, moved.y, velocity, w, h, c.edge_exit * w / 1280.0)):
            # A shuttle clipped by the edge it is leaving through: its visible part's bright
            # centroid stays inside while the cork is already out (``colour.edge_exit``). The
            # cork leads, so it is out once the blob has lost a good part of its usual area.
            areas = self._areas.get(chosen.tracklet)
            if areas is not None and len(areas) >= 3:
                usual = float(np.median(list(areas)[:-1]))
                if chosen.area < c.edge_exit_area * usual:
                    return result, None
        if moved is chosen:
            return result, chosen
        candidates = tuple(moved if cand is chosen else cand for cand in result.candidates)
        return dataclasses.replace(result, candidates=candidates), moved

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
        self._associator.select(detection.tracklet if detection.tracklet >= 0 else None)

    def protect_report(self, report: Candidate | None, width: int) -> None:
        """The next frame's mask keeps the pixels around ``report`` from a lower threshold
        (``BackgroundModel.protect``; None: nowhere). The stereo tracker passes its held landed
        shuttle, which a quarter-scale model otherwise loses when it dims a little."""
        if report is None or report.predicted or self._mask_scale <= 0:
            self._background.protect(None)
            return
        s = self._mask_scale
        r = math.ceil(PROTECT_RADIUS * width / 1280.0 * s) + int(self.params.background.shake_tolerance)
        x, y = report.x * s, report.y * s
        self._background.protect((int(x) - r, int(y) - r, int(x) + r + 1, int(y) + r + 1))

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
        """(x, y, whiteness, saturation, appearance features) of one blob (see ``measure_blobs``)."""
        x, y, whiteness, saturation, features = measure_blobs(frame, mask, [box], sx, sy, head_fraction)
        return float(x[0]), float(y[0]), float(whiteness[0]), float(saturation[0]), features[0]


def _leaving_edge(x: float, y: float, velocity: tuple[float, float], w: int, h: int,
                  margin: float) -> bool:
    """True when (x, y) lies within ``margin`` px of an image edge that ``velocity`` moves
    towards (pixel centres are integers: the image spans -0.5 … w - 0.5)."""
    vx, vy = velocity
    return ((vx < 0 and x + 0.5 < margin) or (vx > 0 and w - 0.5 - x < margin)
            or (vy < 0 and y + 0.5 < margin) or (vy > 0 and h - 0.5 - y < margin))


def _near_edge(x: float, y: float, w: int, h: int, margin: float) -> bool:
    """True when (x, y) lies within ``margin`` px of any image edge."""
    return min(x + 0.5, y + 0.5, w - 0.5 - x, h - 0.5 - y) < margin


def model_scale(background, width: int) -> float:
    """The scale the background model runs at for frames ``width`` px wide.

    The processing scale, halved for large frames when ``coarse_from_width`` asks for it: at
    2048×1536 a 512 px model instead of 1024 px cuts the image work ~4× and, with far fewer
    noise contours to measure, the CPU per camera frame by ~45 % (issue #7). With the default
    classifier (trained at half scale) it costs accuracy: on rally_11-46-04 the F1 fell from
    96.9 % to 95.1–95.5 % (the 4× coarser mask lets dilated noise pass the length filter and
    shifts the mask-based features). The ``coarse`` preset pairs it with a classifier trained
    on coarse-scale candidates, windowed tracking and the landed hold's protected mask: within
    0.2 F1 points of the default on the tuned-on rallies and 0.45 on the held-out ones
    (eighteenth round, README Speed). It stays opt-in: presets are the operator's choice.
    """
    scale = float(background.processing_scale)
    if 0 < int(background.coarse_from_width) <= width:
        scale *= 0.5
    return scale

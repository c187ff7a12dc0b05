"""One camera's shuttle detector: the per-camera stages in order, for one frame at a time.

Why this file exists: it is the per-camera half of the pipeline. It keeps every candidate with
the measurement of each filter and the name of the filter that rejected it, so the tuning view
can show *why* a blob is not the shuttle, and it follows the shuttle over frames rather than the
last thing that moved. The stages live in ``core/detect/``; ``CameraDetector`` runs them:

1. segmentation (``detect/segmentation.py``): grey image at the processing scale →
   :class:`BackgroundModel` → binary mask (default: the pixels *brighter* than a running
   average: a white shuttle in a dark hall; lights ignored) → external contours; in a window
   around the followed shuttle when windowed tracking is on (``core/window.py``);
2. candidates (``detect/candidates.py``): filter 1 (contour length) and filter 2 (shortest
   side of the tilted rectangle) at the processing scale, converted to full-resolution pixels;
   the ``association.max_measured`` most promising blobs go on; parts split off long blobs;
3. measurement and scoring (``detect/measure.py``, ``detect/scoring.py``): a small
   full-resolution window per blob: filter 3 (whiteness, saturation, contrast above the local
   background), appearance features and a sub-pixel head position; the features give each
   candidate a quality in [0, 1] (the learned classifier of ``core/classifier.py``, or a
   hand-made contrast + size score);
4. tracklets (``detect/tracklets.py``, ``core/association.py``): filter 4, multi-frame:
   candidates are joined into tracklets with a speed-aware gate; only candidates on a
   confirmed, travelling, smooth tracklet of good mean quality pass, scored by the tracklet's
   merit; the followed shuttle crossing a blind spot (a light, a white line:
   ``binarize.max_background``) is stood in for by its track's prediction for up to
   ``motion.coast_blind`` frames, flagged ``Candidate.predicted`` and never triangulated;
5. readout: the best surviving candidate by score is the detection (the tracker may override
   this with a stereo-consistent choice, ``choose`` / ``commit``), moved forward to the cork
   (``lead_to_head``).

Latency: none (causal); a flight costs its first ``association.min_hits`` frames.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .association import TrackletAssociator
from .background import BackgroundModel
from .detect.candidates import (ContourShapes, MergedBlobSplitter, gate_factors, measure_contours,
                                rank_for_measuring, shape_filters, shape_rejects, too_large)
from .detect.measure import (FEATURE_NAMES, PATCH_CELLS, PATCH_HALF, PATCH_NAMES,  # noqa: F401
                             BlobMeasurements, measure_blobs, patch_features)
from .detect.answers import DetectorSnapshot, TrackletQueries, _leaving_edge  # noqa: F401
from .detect.diagnostics import DetectionDiagnostics, ScoreReport, ShapeReport
from .detect.scoring import BlobScorer, ScoredBlobs, ScoreFunction, ShapedBlob, score_blobs
from .detect.segmentation import ModelGrey, Segmented, external_contours, model_scale  # noqa: F401
from .detect.shuttle_scale import GateScale, ShuttleScaleMap, from_image, from_rig
from .detect.tracklets import TrackletStage
from .params import TrackerParams
from .types import REJECT_MOTION, REJECT_SCORE, REJECT_WHITENESS, CameraResult, Candidate
from .window import WindowTracker



@dataclasses.dataclass(slots=True)
class _FrameMemory:
    """What the detector remembers from the frames it has seen: a fresh one on ``reset``."""

    # plan_window's choice for the coming frame: (its time, the window or None)
    planned: tuple[float, tuple[int, int, int, int] | None] | None = None
    # the last frame's measured blob positions (the still-blob rule of the scoring stage)
    previous_positions: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 2)))
    splitter: MergedBlobSplitter = dataclasses.field(default_factory=MergedBlobSplitter)


class CameraDetector(TrackletQueries):
    """Finds the shuttle in one camera's frames (the questions the stereo stage asks about its
    candidates: ``TrackletQueries``)."""

    def __init__(self, params: TrackerParams | None = None, geometry: tuple[object, int] | None = None) -> None:
        """``geometry``: (a rig with its court pose, this camera's index in it), whose view of the
        court gives the shuttle's image scale (``shuttle_scale.enabled``; None: the image alone)."""
        self.params = params or TrackerParams()
        self._background = BackgroundModel(self.params.background, self.params.binarize)
        self._associator = TrackletAssociator(self.params.motion, self.params.association)
        self._window = WindowTracker(self.params)   # windowed tracking (``window.enabled``)
        self._scorer = BlobScorer(self.params)
        self._grey = ModelGrey()
        self.last_features: list = []   # (x, y, features, rejected_by) of the last frame's blobs
        # The last frame's measured blobs as the classifier saw them: positions (N, 2) and feature
        # rows (N, F), the patch included when the classifier reads it (core/adaptation.py).
        self.last_scored: tuple[np.ndarray, np.ndarray] = (np.zeros((0, 2)), np.zeros((0, 0)))
        self._mask_scale = 0.0   # mask px per full-resolution px (0: no frame yet)
        self._last_mask: np.ndarray | None = None
        self._large_boxes = np.zeros((0, 4), np.int64)   # full-res boxes of blobs too large (filters 1, 2)
        # Set by the stereo tracker while it holds a landed shuttle for this camera: the frame is
        # processed whole, since the window follows the association's track (after a rally, a
        # player walking past) and the lying shuttle outside it would have no candidate.
        self.keep_whole = False
        self.last_split = 0   # candidates split off merged blobs in the last frame
        self.last_diagnostics: DetectionDiagnostics | None = None   # the last frame, stage by stage
        # ``shuttle_scale.enabled``: the camera's geometry (a rig with its court pose and this
        # camera's index; None: the image alone) and the map and gate factors made from it for
        # (its parameters, the frame size).
        self._geometry = geometry
        self._scale: tuple[object, ShuttleScaleMap, GateScale] | None = None
        self._model_scale: tuple[object, float] | None = None   # (what it was made from, scale)
        self._fresh_state()

    def _fresh_state(self) -> None:
        """The state learnt from frames, as before the first frame."""
        self._memory = _FrameMemory()
        self._tracklets = TrackletStage(self._associator, self.params)

    # ---- configuration ---------------------------------------------------------------------
    def set_params(self, params: TrackerParams) -> None:
        self.params = params
        self._background.set_params(params.background, params.binarize)
        self._associator.set_params(params.motion, params.association)
        self._window.set_params(params)
        self._scorer.set_params(params)
        self._tracklets.params = params

    def use_rig(self, rig, camera: int) -> None:
        """Take the shuttle's image scale from camera ``camera`` of ``rig`` (which has its court
        pose) instead of the image alone (``shuttle_scale.enabled``)."""
        self._geometry = (rig, int(camera))
        self._scale = None
        self._model_scale = None

    def scale_map(self, width: int, height: int) -> ShuttleScaleMap:
        """The shuttle's image sizes and speeds over frames of this size: from the camera's
        view of the court when it has one, else from the image alone (an assumed lens)."""
        sp = self.params.shuttle_scale
        key = (sp, int(width), int(height))
        if self._scale is None or self._scale[0] != key:
            shuttle_map = None
            if self._geometry is not None and tuple(self._geometry[0].image_size) == key[1:]:
                try:
                    shuttle_map = from_rig(self._geometry[0], self._geometry[1], sp)
                except ValueError:
                    shuttle_map = None   # no line of sight meets the play volume: the image alone
            if shuttle_map is None:
                shuttle_map = from_image(int(width), int(height), sp)
            self._scale = (key, shuttle_map, shuttle_map.gate_scale(sp.reference_scale, sp.per_position))
        return self._scale[1]

    def model_scale(self, width: int, height: int) -> float:
        """The scale this camera's background model runs at for frames of this size
        (``segmentation.model_scale``: the processing scale, or half of it when the far
        shuttle still shows there)."""
        bg = self.params.background
        key = (bg, self.params.shuttle_scale, int(width), int(height))   # use_rig clears it
        if self._model_scale is None or self._model_scale[0] != key:
            far = None
            if bg.coarse_shuttle_px > 0 and bg.coarse_from_width == 0:
                far = self.scale_map(width, height).far_length
            self._model_scale = (key, model_scale(bg, width, far))
        return self._model_scale[1]

    def _gate_scale(self, width: int, height: int) -> GateScale | None:
        """The gate factors of filters 1, 2 and 4 for frames of this size (None: off)."""
        if not self.params.shuttle_scale.enabled:
            return None
        self.scale_map(width, height)
        return self._scale[2]

    def reset(self) -> None:
        self._background.reset()
        self._window.reset()
        self._associator.reset()
        self._fresh_state()

    @property
    def associator(self) -> TrackletAssociator:
        """This camera's image tracklets (filter 4): a candidate's ``tracklet`` field names one."""
        return self._associator

    @property
    def window_tracker(self) -> WindowTracker:
        """Where this camera's windows go (``window.enabled``) and how many frames were windowed."""
        return self._window

    @property
    def _looks(self):
        """Each tracklet's recent blob widths and areas (``TrackletQueries.lead_to_head``)."""
        return self._tracklets.looks

    def snapshot(self, result: CameraResult) -> DetectorSnapshot:
        """What the stereo stage may ask about ``result`` (this detector's last frame) until the
        next frame, for a stand-in in another process (``core/camera_process.py``); the
        classifier's view of the blobs (``last_scored``) only while the court adaptation reads it."""
        scored = self.last_scored if self.params.adapt.enabled else None
        return DetectorSnapshot.of(self._associator, self._tracklets.looks, result,
                                   self.last_diagnostics, scored)

    @property
    def tracking(self) -> bool:
        return self._associator.selected is not None

    @property
    def classifier(self):
        """The classifier scoring candidates (None: the hand-made score)."""
        return self._scorer.classifier

    def use_classifier(self, classifier) -> None:
        """Score candidates with this classifier object instead of the preset's file (until the
        next ``set_params``): a leave-one-clip-out study trains one per left-out clip
        (``benchmarks/train_classifier.py --leave-one-out``) without writing ``resources/``."""
        self._scorer.use_classifier(classifier)

    def use_score(self, score: ScoreFunction | None) -> None:
        """Score the measured blobs with ``score(xs, ys, lengths, contrasts, features)`` instead
        of the classifier (None: back to it): a study's oracle scores them from the labels."""
        self._scorer.use_score(score)

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
        window = (self._window.plan(self._associator, t, w, h, self.model_scale(w, h),
                                    self.keep_whole, self._large_boxes)
                  if p.window.enabled else None)
        self._memory.planned = (t, window)
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
        scale = self.model_scale(w, h)
        # Windowed tracking (core/window.py): only around the followed shuttle's prediction,
        # as chosen by ``plan_window`` for this frame, or now.
        planned, self._memory.planned = self._memory.planned, None
        if planned is not None and planned[0] == t:
            window = planned[1]
        else:
            window = (self._window.plan(self._associator, t, w, h, scale, self.keep_whole,
                                        self._large_boxes)
                      if p.window.enabled else None)
        windowed = None if window is None else self._window.model_mask(frame_bgr, scale, window,
                                                                       self._background)
        if windowed is not None:
            return Segmented(*windowed, window, True)
        if window is not None:
            self._window.note(None)
        gray = self._grey(frame_bgr, scale)
        self._window.before_whole(self._background, gray)
        mask = self._background.apply(gray)
        return Segmented(gray, mask, external_contours(mask), None, False)

    def candidates_from(self, frame_bgr: np.ndarray, t: float, segmented: Segmented,
                        keep_mask: bool = True) -> CameraResult:
        """The measuring half of ``find_candidates``: filters 1–4 on ``segment``'s contours,
        stage after stage (shapes → measurement and score → tracklets)."""
        h, w = frame_bgr.shape[:2]
        mask = segmented.mask
        sx, sy = w / mask.shape[1], h / mask.shape[0]
        self._mask_scale = mask.shape[1] / w
        self._scorer.at_scale(self._mask_scale < 0.75 * self.params.background.processing_scale)
        gates = self._gate_scale(w, h)
        self._associator.scale = gates
        rejected, blobs, shapes, shape_counts, factor = self._shape_stage(segmented, t, w, sx, sy, gates)
        scored = self._score_stage(frame_bgr, segmented, blobs, shapes, t, w, sx, sy, factor)
        blind = None
        if self.params.motion.coast_blind > 0:
            ms_x, ms_y = 1.0 / sx, 1.0 / sy

            def blind(x: float, y: float) -> bool:
                return self._background.is_blind(x * ms_x, y * ms_y)
        linked, tracklet_report = self._tracklets.link(t, scored, w, h, blind)
        reasons = scored.rejected_by
        self.last_diagnostics = DetectionDiagnostics(
            segmented.windowed, ShapeReport(*shape_counts, self.last_split),
            ScoreReport(len(reasons), reasons.count(REJECT_WHITENESS), reasons.count(REJECT_MOTION),
                        reasons.count(REJECT_SCORE)),
            tracklet_report)
        window = segmented.window
        return CameraResult(detection=None, candidates=tuple(rejected + linked),
                            mask=mask if keep_mask else None,
                            mask_scale=mask.shape[1] / w, image_size=(w, h),
                            window=None if window is None else tuple(int(v) for v in window),
                            left_picture=self._tracklets.exit_hold.left_picture)

    def _shape_stage(self, segmented: Segmented, t: float, w: int, sx: float, sy: float,
                     gates: GateScale | None) -> tuple[list[Candidate], list[ShapedBlob], ContourShapes,
                                                       tuple[int, int, int, int], np.ndarray | float]:
        """Filters 1 and 2 on the contours, then at most ``association.max_measured`` blobs for
        the full-resolution look: (the candidates rejected on the way, the blobs that go on,
        every contour's shape, the counts of ``ShapeReport`` but the split parts, the contours'
        gate factors)."""
        p = self.params
        mask = segmented.mask
        shapes = measure_contours(segmented.contours, sx, sy)
        factor = gate_factors(shapes, gates)
        length_ok, short_ok = shape_filters(shapes, p, self._associator.followed, t, w, factor)
        self._last_mask = mask
        self._large_boxes = too_large(shapes, p, factor)
        rejected, blobs = shape_rejects(shapes, length_ok, short_ok)
        limit = int(p.association.max_measured)
        dropped = []
        if len(blobs) > limit:
            bg = self._background
            blobs, dropped = rank_for_measuring(blobs, limit, self._associator.live_predictions(t),
                                                bg.last_difference, segmented.gray, bg.last_unlit,
                                                shapes, mask.shape)
            rejected += dropped
        counts = (len(shapes.length), int(np.count_nonzero(~length_ok)),
                  int(np.count_nonzero(length_ok & ~short_ok)), len(dropped))
        return rejected, blobs, shapes, counts, factor

    def _score_stage(self, frame_bgr: np.ndarray, segmented: Segmented, blobs: list[ShapedBlob],
                     shapes: ContourShapes, t: float, w: int, sx: float, sy: float,
                     factor: np.ndarray | float = 1.0) -> ScoredBlobs:
        """Filter 3, the features and the score of the blobs, and of the parts split off long
        blobs (measured on their own pixels)."""
        p = self.params
        head = p.colour.head_fraction
        measured = measure_blobs(frame_bgr, segmented.mask, [b.box for b in blobs], sx, sy, head)
        split = self._memory.splitter.split(p, self._associator, segmented.gray, segmented.mask,
                                            segmented.contours, shapes, t, w,
                                            segmented.fresh_part(self._mask_scale), factor)
        self.last_split = len(split[1]) if split is not None else 0
        if split is not None:
            core_mask, parts = split
            more = measure_blobs(frame_bgr, core_mask, [b.box for b in parts], sx, sy, head)
            measured = BlobMeasurements.concatenate(measured, more)
            blobs = blobs + parts
        scored = score_blobs(p, self._scorer, frame_bgr, blobs, measured, self._memory.previous_positions)
        positions = scored.positions
        self._memory.previous_positions = positions
        # The same positions array, no second copy on the per-frame path.
        self.last_scored = (positions, scored.features)
        self.last_features = list(zip(scored.x, scored.y, scored.shape_features, scored.rejected_by))
        return scored

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
        r = math.ceil(self.params.background.protect_radius * width / 1280.0 * s) + int(self.params.background.shake_tolerance)
        x, y = report.x * s, report.y * s
        self._background.protect((int(x) - r, int(y) - r, int(x) + r + 1, int(y) + r + 1))

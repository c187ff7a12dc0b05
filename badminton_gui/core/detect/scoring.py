"""Candidate scoring: how shuttle-like each measured blob looks, and the one-frame rules that
reject it before the tracklets see it.

Why this file exists: after filters 1 and 2 and the full-resolution measurement, each blob gets
its verdict from filter 3 (whiteness, saturation, contrast above the local background), the
paper's one-frame motion rule (a blob where a blob was last frame is still clutter), and a
quality in [0, 1] — the learned classifier's probability (``core/classifier.py``) or a
hand-made contrast + size score — below which it is rejected by its score. What comes out,
``ScoredBlobs``, is what the tracklets stage (``detect/tracklets.py``) links over frames.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Callable, NamedTuple

import numpy as np

from ..classifier import load_classifier
from ..params import TrackerParams
from ..types import REJECT_MOTION, REJECT_SCORE, REJECT_WHITENESS
from .measure import FEATURE_NAMES, BlobMeasurements, patch_features

# (x, y, lengths, contrasts, features) of a frame's measured blobs → their qualities in [0, 1]:
# a score used instead of the classifier or the hand-made one (``BlobScorer.use_score``).
ScoreFunction = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]


class ShapedBlob(NamedTuple):
    """A blob that passed filters 1 and 2, measured at the processing scale (a named tuple: one
    is made per blob of every frame, at half a dataclass's cost)."""

    contour: int                        # its contour's index in the frame (a part split off: the whole's)
    length: float                       # contour length, full-resolution px
    short_side: float                   # shortest side of the tilted rectangle, full-resolution px
    area: float                         # contour area, full-resolution px²
    box: tuple[int, int, int, int]      # full-resolution bounding box (x, y, w, h)


@dataclasses.dataclass(frozen=True, slots=True)
class ScoredBlobs:
    """A frame's measured blobs with their verdicts, one entry per blob in every column."""

    x: list[float]
    y: list[float]
    length: list[float]
    short_side: list[float]
    whiteness: list[float]
    area: list[float]
    quality: list[float]                 # the score in [0, 1]
    rejected_by: list[str | None]        # filter 3, the still-blob rule or the score; None: on to filter 4
    shape_features: np.ndarray           # (N, len(FEATURE_NAMES)) shape and appearance features
    features: np.ndarray                 # (N, F) the rows the classifier read (the patch too, when it reads it)

    @property
    def positions(self) -> np.ndarray:
        """(N, 2) positions, full-resolution px."""
        return np.asarray(list(zip(self.x, self.y)), dtype=float).reshape(-1, 2)


class BlobScorer:
    """Scores blobs: the learned classifier of the parameters (or one given), or the hand-made
    blend of contrast and size, or a score function installed for a study (``use_score``)."""

    def __init__(self, params: TrackerParams) -> None:
        self.params = params
        self.classifier = None
        self._score: ScoreFunction | None = None
        self._coarse = False    # the background model runs at half the processing scale
        self._given = False     # a classifier given by ``use_classifier`` is kept at any scale
        self.set_params(params)

    def set_params(self, params: TrackerParams) -> None:
        self.params = params
        self._given = False
        self._load()

    def at_scale(self, coarse: bool) -> None:
        """Score the coming frames' blobs as measured on a mask at the processing scale or at
        half of it (``classifier.coarse_model``: the mask-based features differ)."""
        if coarse != self._coarse:
            self._coarse = coarse
            if not self._given:
                self._load()

    def _load(self) -> None:
        cp = self.params.classifier
        name = cp.coarse_model if self._coarse else cp.model
        if not cp.enabled:
            self.classifier = None
        elif self.classifier is None or self.classifier.name != name:
            self.classifier = load_classifier(name)

    def use_classifier(self, classifier) -> None:
        self.classifier = classifier
        self._given = True

    def use_score(self, score: ScoreFunction | None) -> None:
        """Score with ``score`` instead (None: back to the classifier or the hand-made score)."""
        self._score = score

    @property
    def needs_patches(self) -> bool:
        """A classifier trained with the patch features reads them after FEATURE_NAMES."""
        return self.classifier is not None and len(self.classifier.feature_names) > len(FEATURE_NAMES)

    def qualities(self, xs: np.ndarray, ys: np.ndarray, lengths: np.ndarray, contrasts: np.ndarray,
                  features: np.ndarray) -> np.ndarray:
        """Shape/contrast scores of lone candidates in [0, 1] (the soft side of filters 1 and 3).

        With the learned classifier enabled this is its probability that each blob is the
        shuttle; otherwise a hand-made blend of contrast and size.
        """
        if self._score is not None:
            return self._score(xs, ys, lengths, contrasts, features)
        if self.classifier is not None:
            return self.classifier.probability(features)
        c = self.params.colour
        bright = np.minimum(np.maximum(contrasts - c.min_contrast, 0.0)
                            / max(c.contrast_reference - c.min_contrast, 1.0), 1.0)
        size = np.minimum(lengths / max(self.params.contour_length.min_length * 2.0, 1.0), 1.0)
        return 0.7 * bright + 0.3 * size


def still_blobs(previous: np.ndarray, xs: np.ndarray, ys: np.ndarray, min_displacement: float) -> np.ndarray:
    """Per blob (xs, ys): within ``min_displacement`` px of one of the previous frame's blobs."""
    if len(previous) == 0 or len(xs) == 0:
        return np.zeros(len(xs), dtype=bool)
    d = np.hypot(previous[None, :, 0] - xs[:, None], previous[None, :, 1] - ys[:, None])
    return d.min(axis=1) < min_displacement


def judge_blobs(params: TrackerParams, blobs: list[ShapedBlob], m: BlobMeasurements,
                previous: np.ndarray) -> tuple[list[str | None], np.ndarray]:
    """Filter 3 and the still-blob rule per blob, and the shape + appearance features:
    (the reason each blob is rejected or None, features (N, FEATURE_NAMES)), for all blobs at
    once. ``previous``: the previous frame's measured positions."""
    p = params
    n = len(blobs)
    features = np.empty((n, len(FEATURE_NAMES)))
    features[:, 4:] = m.appearance
    if n == 0:
        return [], features
    _, lengths, short_sides, areas, _ = zip(*blobs)
    contrast = features[:, 4]
    white = ((m.whiteness < p.colour.min_whiteness) | (m.saturation > p.colour.max_saturation)
             | (contrast < p.colour.min_contrast))
    reasons: list[str | None] = [REJECT_WHITENESS if w else None for w in white.tolist()]
    if p.motion.min_displacement > 0:
        for k in np.flatnonzero(~white & still_blobs(previous, m.x, m.y, p.motion.min_displacement)).tolist():
            reasons[k] = REJECT_MOTION
    # math.log1p, not np.log1p: numpy's SIMD logarithm may differ from the C library's in the
    # last bit, and the classifiers were trained on these values.
    features[:, 0] = [math.log1p(v) for v in lengths]
    features[:, 1] = [math.log1p(v) for v in short_sides]
    features[:, 2] = [math.log1p(v) for v in areas]
    short = np.array(short_sides)
    features[:, 3] = np.maximum(np.array(lengths) / 2.0 - short, short) / np.maximum(short, 1e-3)
    return reasons, features


def score_blobs(params: TrackerParams, scorer: BlobScorer, frame_bgr: np.ndarray,
                blobs: list[ShapedBlob], m: BlobMeasurements, previous: np.ndarray) -> ScoredBlobs:
    """The verdicts of a frame's measured blobs (``judge_blobs``), then their qualities in one
    call; a blob not rejected yet whose quality is below ``association.min_quality`` is
    rejected by its score."""
    reasons, shape_features = judge_blobs(params, blobs, m, previous)
    features = shape_features
    qualities: list[float] = []
    if not blobs:
        return ScoredBlobs([], [], [], [], [], [], qualities, reasons, shape_features, features)
    xs, ys = m.x, m.y
    _, lengths, short_sides, areas, _ = zip(*blobs)
    if scorer.needs_patches:
        features = np.concatenate((shape_features, patch_features(frame_bgr, xs, ys)), axis=1)
    qualities = scorer.qualities(xs, ys, np.array(lengths), shape_features[:, 4], features).tolist()
    min_quality = params.association.min_quality
    reasons = [REJECT_SCORE if reason is None and q < min_quality else reason
               for reason, q in zip(reasons, qualities)]
    return ScoredBlobs(xs.tolist(), ys.tolist(), list(lengths), list(short_sides), m.whiteness.tolist(),
                       list(areas), qualities, reasons, shape_features, features)

"""The candidate stage's vectorised rewrites (issue 40) give exactly what the plain code gave.

Why this file exists: the candidate stage runs for both cameras one after the other with the
GIL held, so its per-blob Python was rewritten as whole-frame numpy. The plain per-blob code is
kept here as the reference, on random blobs, contours and frames, and the fast code must match
it bit for bit (the classifiers were trained on these values; ``benchmarks/golden.py --check``
compares the outputs).
"""

import cv2
import numpy as np
import pytest

from badminton_gui.core.detect.measure import PATCH_CELLS, PATCH_HALF, patch_features


def reference_patch_features(frame, xs, ys):
    """``patch_features`` as first written: np.median and max of each patch's cells."""
    h, w = frame.shape[:2]
    half = max(PATCH_HALF, int(round(PATCH_HALF * w / 1280.0)))
    offsets = np.arange(-half, half)
    squares = []
    for x, y in zip(np.rint(xs).astype(np.int64), np.rint(ys).astype(np.int64)):
        rows = np.clip(y + offsets, 0, h - 1)
        cols = np.clip(x + offsets, 0, w - 1)
        squares.append(frame[rows[:, None], cols[None, :]])
    luma = cv2.cvtColor(np.concatenate(squares).astype(np.float32), cv2.COLOR_BGR2GRAY)
    cells = cv2.resize(luma, (PATCH_CELLS, len(squares) * PATCH_CELLS),
                       interpolation=cv2.INTER_AREA).reshape(len(squares), -1)
    median = np.median(cells, axis=1, keepdims=True)
    peak = np.maximum(cells.max(axis=1, keepdims=True) - median, 8.0)
    return (cells - median) / peak


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("w", [640, 1280, 1440, 1600, 1760, 1920, 2048, 2240, 3840])
def test_patch_features_are_the_median_and_max_of_each_patch(seed, w):
    """Each patch's cells as in a canvas of its own patches one below the other, at every
    square size (fractional and whole cell widths) and any number of patches."""
    rng = np.random.default_rng(seed)
    h = w * 3 // 4
    frame = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
    if seed % 3 == 0:
        frame[:] = frame // 64 * 64            # few grey levels: ties between the middle cells
    if seed == 4:
        frame[:] = 17                          # flat: every patch's peak is the floor of 8
    n = int(rng.integers(1, 70))
    xs = rng.uniform(-3, w + 3, n)
    ys = rng.uniform(-3, h + 3, n)
    got = patch_features(frame, xs, ys)
    expected = reference_patch_features(frame, xs, ys)
    assert got.dtype == expected.dtype and np.array_equal(got, expected)


def reference_score_blobs(params, scorer, frame_bgr, blobs, m, previous):
    """``judge_blobs`` and ``score_blobs`` as first written: a Python loop over the blobs."""
    import math

    from badminton_gui.core.detect.measure import FEATURE_NAMES
    from badminton_gui.core.types import REJECT_MOTION, REJECT_SCORE, REJECT_WHITENESS

    p = params
    features = np.empty((len(blobs), len(FEATURE_NAMES)))
    features[:, 4:] = m.appearance
    judged = []
    for row, (blob, x, y, whiteness, saturation, contrast) in enumerate(zip(
            blobs, m.x.tolist(), m.y.tolist(), m.whiteness.tolist(),
            m.saturation.tolist(), features[:, 4].tolist())):
        length, short_side, area = blob.length, blob.short_side, blob.area
        reason = None
        if (whiteness < p.colour.min_whiteness or saturation > p.colour.max_saturation
                or contrast < p.colour.min_contrast):
            reason = REJECT_WHITENESS
        elif p.motion.min_displacement > 0 and len(previous) and bool(
                np.hypot(previous[:, 0] - x, previous[:, 1] - y).min() < p.motion.min_displacement):
            reason = REJECT_MOTION
        long_side = max(length / 2.0 - short_side, short_side)
        features[row, :4] = (math.log1p(length), math.log1p(short_side), math.log1p(area),
                             long_side / max(short_side, 1e-3))
        judged.append([x, y, length, short_side, whiteness, area, reason])
    shape_features = features
    qualities, reasons = [], [j[6] for j in judged]
    if judged:
        xs = np.array([j[0] for j in judged])
        ys = np.array([j[1] for j in judged])
        if scorer.needs_patches:
            features = np.hstack([shape_features, patch_features(frame_bgr, xs, ys)])
        qualities = scorer.qualities(xs, ys, np.array([j[2] for j in judged]), shape_features[:, 4],
                                     features).tolist()
        reasons = [REJECT_SCORE if r is None and q < p.association.min_quality else r
                   for r, q in zip(reasons, qualities)]
    columns = [[j[k] for j in judged] for k in range(6)]
    return columns, qualities, reasons, shape_features, features


@pytest.mark.parametrize("preset", ["default", "coarse", "broadcast"])
@pytest.mark.parametrize("seed", range(4))
def test_score_blobs_judges_as_the_per_blob_loop(preset, seed):
    import dataclasses

    from badminton_gui.core.detect.measure import BlobMeasurements
    from badminton_gui.core.detect.scoring import BlobScorer, ShapedBlob, score_blobs
    from badminton_gui.io.presets import load_preset

    rng = np.random.default_rng(seed)
    params = load_preset(None if preset == "default" else preset)
    # Every rule reachable: filter 3 on each of its three measures, the still-blob rule.
    params = dataclasses.replace(
        params, colour=dataclasses.replace(params.colour, min_whiteness=60.0, max_saturation=120.0,
                                           min_contrast=12.0),
        motion=dataclasses.replace(params.motion, min_displacement=0.0 if seed == 0 else 6.0),
        association=dataclasses.replace(params.association, min_quality=0.5))
    scorer = BlobScorer(params)
    frame = rng.integers(0, 256, (720, 1280, 3), dtype=np.uint8)
    n = [0, 1, 7, 40][seed]
    blobs = [ShapedBlob(k, float(rng.uniform(4, 250)), float(rng.choice([0.0, rng.uniform(0, 30)])),
                        float(rng.uniform(1, 900)), (1, 2, 3, 4)) for k in range(n)]
    xy = rng.uniform(0, 1280, (n, 2))
    appearance = rng.uniform(0, 255, (n, 9)).astype(np.float32)
    m = BlobMeasurements(xy[:, 0], xy[:, 1], rng.uniform(40, 255, n), rng.uniform(0, 140, n), appearance)
    previous = np.concatenate([xy[: n // 2] + rng.normal(0, 4, (n // 2, 2)), rng.uniform(0, 1280, (3, 2))])
    got = score_blobs(params, scorer, frame, blobs, m, previous)
    columns, qualities, reasons, shape_features, features = reference_score_blobs(
        params, scorer, frame, blobs, m, previous)
    assert [got.x, got.y, got.length, got.short_side, got.whiteness, got.area] == columns
    assert got.quality == qualities and got.rejected_by == reasons
    assert np.array_equal(got.shape_features, shape_features) and np.array_equal(got.features, features)
    if n >= 40:
        assert {"whiteness", "motion"} <= set(reasons) and len(set(reasons)) >= 3   # the rules were reached


def test_classifier_probability_is_the_clipped_logistic():
    from badminton_gui.core.classifier import CandidateClassifier, load_classifier

    rng = np.random.default_rng(5)
    # A linear one (logits far beyond the clip, NaN too) and the shipped ones.
    linear = CandidateClassifier("linear", np.zeros(3), np.ones(3), (rng.normal(0, 20, (3, 1)),), (np.zeros(1),))
    for clf in [linear] + [load_classifier(name) for name in
                           ("candidate_classifier", "candidate_classifier_coarse", "candidate_classifier_broadcast")]:
        n_features = len(clf.mean)
        features = rng.normal(0, 1, (200, n_features)) * clf.scale + clf.mean
        features[:20] *= rng.choice([-1e4, 1e4], (20, 1))
        features[20, 0] = np.nan
        h = (features - clf.mean) / clf.scale
        for k, (w, b) in enumerate(zip(clf.weights, clf.biases)):
            h = h @ w + b
            if k < len(clf.weights) - 1:
                h = np.tanh(h)
        expected = 1.0 / (1.0 + np.exp(-np.clip(h[:, 0], -30, 30)))
        got = clf.probability(features)
        assert np.array_equal(got, expected, equal_nan=True)
    assert (np.abs(linear.probability(np.full((1, 3), 1e4)) - 0.5) > 0.49).all()

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
def test_patch_features_are_the_median_and_max_of_each_patch(seed):
    rng = np.random.default_rng(seed)
    h, w = (720, 1280) if seed % 2 else (1536, 2048)
    frame = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
    if seed % 3 == 0:
        frame[:] = frame // 64 * 64            # few grey levels: ties between the middle cells
    if seed == 4:
        frame[:] = 17                          # flat: every patch's peak is the floor of 8
    n = int(rng.integers(1, 40))
    xs = rng.uniform(-3, w + 3, n)
    ys = rng.uniform(-3, h + 3, n)
    got = patch_features(frame, xs, ys)
    expected = reference_patch_features(frame, xs, ys)
    assert got.dtype == expected.dtype and np.array_equal(got, expected)

"""Full-resolution measurements of the blobs that passed filters 1 and 2.

Why this file exists: the mask is made at a reduced processing scale, but whether a blob is
white (filter 3), how it looks to the classifier and where its cork is to a fraction of a pixel
can only be told on the full-resolution pixels around it. This module measures that, for all
the frame's blobs at once (``measure_blobs``), and cuts the grey patch a patch-reading
classifier looks at (``patch_features``). It knows nothing of tracking or parameters beyond its
arguments.

Speed: both cameras run this in two threads, and only OpenCV calls and numpy operations on large
arrays release the GIL, so per-blob Python is kept out of it: the windows share one canvas and
every step runs once on the canvas. Every value is the one the plain per-window numpy formulas
give, which the classifiers were trained on (tests/test_detector_fast_paths.py).
"""

from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np

from ..background import median_float32

# Margin (full-res px) around a blob's box for the sub-pixel refinement window. A constant, not
# a parameter: the appearance features the shipped classifiers were trained on are measured in
# this window, so changing it means retraining them (resources/candidate_classifier*.json).
REFINE_MARGIN = 5
# The mask grown by one full-resolution pixel: the blur fringe of a blob belongs to it.
GROW = np.ones((3, 3), np.uint8)
# Appearance features measured in the full-resolution window (order matters: the classifier).
APPEARANCE_NAMES = ("contrast", "background", "log_bright_area", "spill", "whiteness",
                    "saturation", "log_mask_area", "peak_saturation", "window_std")
N_APPEARANCE = len(APPEARANCE_NAMES)
# Shape features from the contour, then the appearance features: the classifier's input.
FEATURE_NAMES = ("log_length", "log_short_side", "log_area", "aspect") + APPEARANCE_NAMES
# A classifier may also read the blob's look itself: the grey patch around its centroid
# (``PATCH_HALF`` px either side at 1280 px width, scaled with the frame), averaged down to
# PATCH_CELLS × PATCH_CELLS and normalised (``patch_features``), after FEATURE_NAMES.
PATCH_HALF = 8
PATCH_CELLS = 8
PATCH_NAMES = tuple(f"patch_{r}{c}" for r in range(PATCH_CELLS) for c in range(PATCH_CELLS))


@dataclasses.dataclass(frozen=True, slots=True)
class BlobMeasurements:
    """What ``measure_blobs`` found for N blobs, in the order of their boxes."""

    x: np.ndarray            # (N,) head position, full-resolution px
    y: np.ndarray            # (N,)
    whiteness: np.ndarray    # (N,) mean min(B, G, R) on the blob's pixels (filter 3)
    saturation: np.ndarray   # (N,) mean max - min of B, G, R on the blob's pixels
    appearance: np.ndarray   # (N, N_APPEARANCE) float32, see APPEARANCE_NAMES

    def __iter__(self):
        # x, y, whiteness, saturation, appearance = measure_blobs(...)
        return iter((self.x, self.y, self.whiteness, self.saturation, self.appearance))

    @staticmethod
    def concatenate(a: "BlobMeasurements", b: "BlobMeasurements") -> "BlobMeasurements":
        return BlobMeasurements(*(np.concatenate([u, v]) for u, v in zip(a, b)))


@dataclasses.dataclass(frozen=True, slots=True)
class _Canvas:
    """The measured windows copied one below the other, left-aligned, with a blank row after
    each (so growing a mask by a pixel never reaches the next window)."""

    image: np.ndarray      # (rows, cols, 3) the windows' colour pixels
    inside: np.ndarray     # (rows, cols) the blobs' mask pixels, 0 / 255
    start: np.ndarray      # each window's first row
    height: np.ndarray     # each window's height (its blank row not counted)
    width: np.ndarray      # each window's width
    seg_rows: np.ndarray   # each window's rows with its blank row
    padding: np.ndarray    # (rows, cols) True outside every window
    local_row: np.ndarray  # each canvas row's row inside its window

    def window_sum(self, per_row: np.ndarray) -> np.ndarray:
        return np.add.reduceat(per_row, self.start)

    def window_max(self, image: np.ndarray) -> np.ndarray:
        # A window's rows (and its blank row) are one contiguous range of the flat canvas.
        return np.maximum.reduceat(image.ravel(), self.start * self.image.shape[1])


def _row_sums(image: np.ndarray, depth: int) -> np.ndarray:
    # cv2.reduce: 3-4x faster than numpy's axis-1 sum on these narrow images
    return cv2.reduce(image, 1, cv2.REDUCE_SUM, dtype=depth)[:, 0]


def _paste_mask(mask: np.ndarray, window: tuple[int, int, int, int], sx: float, sy: float,
                dst: np.ndarray) -> None:
    """The blob's pixels at full resolution: the mask under ``window``, resized (0 / 255)
    straight into ``dst`` (no temporary, no second copy)."""
    x0, y0, x1, y1 = window
    mx0, my0 = int(x0 / sx), int(y0 / sy)
    mx1, my1 = max(math.ceil(x1 / sx), mx0 + 1), max(math.ceil(y1 / sy), my0 + 1)
    mcrop = mask[my0:my1, mx0:mx1]
    if mcrop.shape == dst.shape:
        dst[...] = mcrop
    else:
        cv2.resize(mcrop, (dst.shape[1], dst.shape[0]), dst=dst, interpolation=cv2.INTER_NEAREST)


def _stack(frame: np.ndarray, mask: np.ndarray, windows: list, heights: list, widths: list,
           sx: float, sy: float) -> _Canvas:
    """The canvas of the windows and its row bookkeeping: each window owns its rows and the
    blank row after it."""
    m = len(windows)
    height = np.array(heights)
    width = np.array(widths)
    start = np.zeros(m, dtype=np.intp)
    np.cumsum(height[:-1] + 1, out=start[1:])
    rows, cols = int(start[-1] + height[-1] + 1), int(width.max())
    canvas = np.zeros((rows, cols, 3), np.uint8)
    inside = np.zeros((rows, cols), np.uint8)
    for (x0, y0, x1, y1), r0 in zip(windows, start.tolist()):
        r1, cw = r0 + y1 - y0, x1 - x0
        canvas[r0:r1, :cw] = frame[y0:y1, x0:x1]
        _paste_mask(mask, (x0, y0, x1, y1), sx, sy, inside[r0:r1, :cw])
    seg_rows = height + 1
    row_width = np.repeat(width, seg_rows)
    row_width[start + height] = 0   # the blank rows
    padding = np.arange(cols) >= row_width[:, None]
    local_row = np.arange(rows) - np.repeat(start, seg_rows)
    return _Canvas(canvas, inside, start, height, width, seg_rows, padding, local_row)


def _border_median(cv: _Canvas, gray: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(each window's border median (float32), the border values, their window, each window's
    border length). The border is in numpy's order (top row, bottom row, left column, right
    column; corners twice), as flat canvas indices; each window's median comes from one sort of
    window × 1024 + value keys (exact in double: the values are float32 below 256)."""
    start, height, width, cols = cv.start, cv.height, cv.width, cv.image.shape[1]
    m = len(start)
    along_row = _ragged_arange(width)
    row_owner = np.repeat(np.arange(m), width)
    col_owner = np.repeat(np.arange(m), height)
    top = start[row_owner] * cols + along_row
    bottom = top + ((height - 1) * cols)[row_owner]
    left = (start[col_owner] + _ragged_arange(height)) * cols
    right = left + (width - 1)[col_owner]
    border_owner = np.concatenate([row_owner, row_owner, col_owner, col_owner])
    border = gray.ravel()[np.concatenate([top, bottom, left, right])]
    border_len = 2 * (width + height)
    # A stable sort (timsort) takes the keys' runs, one window after another: 3-4x faster here
    # than the default introsort, and sorted values are the same whatever the sort.
    keyed = np.sort(border_owner * 1024.0 + border, kind="stable")
    first = np.zeros(m, dtype=np.intp)
    np.cumsum(border_len[:-1], out=first[1:])
    half_len = border_len // 2
    upper = (keyed[first + half_len] - np.arange(m) * 1024.0).astype(np.float32)
    lower = (keyed[first + half_len - 1] - np.arange(m) * 1024.0).astype(np.float32)
    odd = border_len % 2 == 1
    # np.median averages the two middle values in float32 (sum, then / 2).
    background = np.where(odd, upper, (lower + upper) / np.float32(2)).astype(np.float32)
    return background, border, border_owner, border_len


def _appearance(cv: _Canvas) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(appearance features (N_APPEARANCE, m) float32, whiteness, saturation, each pixel's
    excess over its window's background (-inf on padding), each window's peak excess)."""
    blue, green, red = cv2.split(cv.image)
    cmin = cv2.min(cv2.min(blue, green), red)
    cmax = cv2.max(cv2.max(blue, green), red)
    inside = cv.inside
    n_inside = cv.window_sum(_row_sums(inside, cv2.CV_32S)) // 255
    white_sum = cv.window_sum(_row_sums(cv2.bitwise_and(cmin, inside), cv2.CV_32S))
    sat_sum = cv.window_sum(_row_sums(cv2.bitwise_and(cv2.subtract(cmax, cmin), inside), cv2.CV_32S))
    has_inside = n_inside > 0
    whiteness = np.where(has_inside, white_sum / np.maximum(n_inside, 1), 0.0)
    saturation = np.where(has_inside, sat_sum / np.maximum(n_inside, 1), 255.0)
    # mean(B, G, R) in float32: the integer sum is exact, then one float32 division.
    gray = cv2.add(blue, green, dtype=cv2.CV_32F)
    cv2.add(gray, red, dst=gray, dtype=cv2.CV_32F)
    np.divide(gray, 3, out=gray)
    background, border, border_owner, border_len = _border_median(cv, gray)

    excess = gray - np.repeat(background, cv.seg_rows)[:, None]
    np.copyto(excess, -np.inf, where=cv.padding)
    peak = cv.window_max(excess)
    half_peak = np.float32(0.5) * peak
    half_row = np.repeat(half_peak, cv.seg_rows)
    n_bright = cv.window_sum(_row_sums((excess > half_row[:, None]).view(np.uint8), cv2.CV_32S))
    border_bright = (border - background[border_owner]) > half_peak[border_owner]
    spill = np.bincount(border_owner, weights=border_bright, minlength=len(cv.start)) / border_len
    peak_sat = cv.window_max(cmax).astype(np.float64) - cv.window_max(cmin).astype(np.float64)
    # Standard deviation from the sums of g and g² in double (products of float32 values are
    # exact there; padding is 0 and adds nothing).
    n_pixels = cv.height * cv.width
    mean = cv.window_sum(_row_sums(gray, cv2.CV_64F)) / n_pixels
    mean_square = cv.window_sum(_row_sums(cv2.multiply(gray, gray, dtype=cv2.CV_64F), cv2.CV_64F)) / n_pixels
    window_std = np.sqrt(np.maximum(mean_square - mean * mean, 0.0))
    # One row per feature, cast to float32 as it is written (what assigning np.stack's
    # float64 rows did, without np.stack's ~10 µs of Python wrappers).
    appearance = np.empty((N_APPEARANCE, len(cv.start)), np.float32)
    for row, values in enumerate((peak, background, np.log1p(n_bright), spill, whiteness,
                                  saturation, np.log1p(n_inside), peak_sat, window_std)):
        appearance[row] = values
    return appearance, whiteness, saturation, excess, peak


def _head_positions(cv: _Canvas, excess: np.ndarray, peak: np.ndarray, windows: list,
                    head_fraction: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(x, y) of each window's head, and the weights and totals behind them (for the rare
    windows ``_rare_positions`` redoes).

    The position is measured on the blob's own pixels only (its mask, grown by one
    full-resolution pixel for the blur fringe): a light or a court line inside the window is
    brighter than the shuttle and used to drag the centroid towards itself. Off the support
    the excess counts as 0 (so a blob's peak is at least 0); padding stays -inf or 0.
    (the excess where the grown mask is set, +0.0 elsewhere, as np.where(support, excess, 0)
    gave: a masked AND of the float image with itself into zeros — a masked OpenCV call
    leaves dst untouched where the mask is 0 —, 4x faster than the comparison and np.where)
    """
    blob_excess = cv2.bitwise_and(excess, excess, dst=np.zeros_like(excess),
                                  mask=cv2.dilate(cv.inside, GROW))
    blob_peak = np.maximum(cv.window_max(blob_excess), 0)
    # No support, or nothing on it above the background: the whole window's excess instead.
    whole = blob_peak <= 0
    if whole.any():
        whole_rows = np.repeat(whole, cv.seg_rows)
        blob_excess[whole_rows] = np.maximum(excess[whole_rows], 0)
        blob_peak = np.where(whole, peak, blob_peak)
    # Keep the part of the blob above ``head_fraction`` of its peak: the cork is whiter than
    # the feathers (0 = the whole blob's intensity centroid). The cut is rounded to float32
    # as numpy rounded ``float32 array - Python float``.
    cut = (head_fraction * blob_peak.astype(np.float64)).astype(np.float32)
    weights = blob_excess - np.repeat(cut, cv.seg_rows)[:, None]
    np.maximum(weights, 0, out=weights)
    row_weight = _row_sums(weights, cv2.CV_64F)
    total = cv.window_sum(row_weight)
    # OpenCV's convention: integer coordinates are pixel centres (as projectPoints gives).
    sum_x = cv.window_sum(weights @ np.arange(cv.image.shape[1], dtype=np.float64))
    sum_y = cv.window_sum(row_weight * cv.local_row)
    origin_x = np.array([win[0] for win in windows], dtype=float)
    origin_y = np.array([win[1] for win in windows], dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        x = sum_x / total + origin_x
        y = sum_y / total + origin_y
    return x, y, blob_excess, total


def _rare_position(cv: _Canvas, k: int, window: tuple[int, int, int, int], box,
                   blob_excess: np.ndarray, peak: float) -> tuple[float, float]:
    """Window ``k``'s position when nothing in it is brighter than the border (the mask's
    centroid, or the box's centre without one), or nothing is above the cut (the whole blob's
    intensity centroid)."""
    x0, y0 = window[0], window[1]
    r0 = int(cv.start[k])
    rows_k = slice(r0, r0 + int(cv.height[k]))
    cols_k = slice(0, int(cv.width[k]))
    if peak <= 0:
        ys, xs = np.nonzero(cv.inside[rows_k, cols_k])
        if len(xs) == 0:
            return box[0] + box[2] / 2, box[1] + box[3] / 2
        return x0 + xs.mean(), y0 + ys.mean()
    fallback = np.maximum(blob_excess[rows_k, cols_k], 0).astype(np.float64)
    ys, xs = np.mgrid[0:fallback.shape[0], 0:fallback.shape[1]]
    return ((fallback * xs).sum() / fallback.sum() + x0, (fallback * ys).sum() / fallback.sum() + y0)


def measure_blobs(frame: np.ndarray, mask: np.ndarray, boxes, sx: float, sy: float,
                  head_fraction: float = 0.5) -> BlobMeasurements:
    """(x, y, whiteness, saturation, appearance features) of blobs, in full-resolution windows.

    Per blob, its window is the box grown by ``REFINE_MARGIN``. The position is the
    intensity-weighted centroid of the blob's brightest part above the window's local
    background (median of the window border), which locates the white cork head rather than
    the middle of head + skirt, to a fraction of a pixel. The appearance features (see
    ``FEATURE_NAMES``) describe how small, bright, isolated and white the blob is; the
    candidate classifier and the hand-made score read them.

    Speed: the windows are copied into one canvas (``_Canvas``) and every step runs once on
    it: per-window sums as row sums (``cv2.reduce``) added over each window's rows, per-window
    maxima over each window's contiguous range of the flat canvas (both by ``reduceat``). A
    few dozen calls per frame instead of ~30 per blob. Padding pixels are made neutral for
    every step (0 for counts and sums, -inf for maxima). Grey is ``mean(B, G, R)`` in float32,
    the border median is numpy's, counts and sums of integers are exact; only the window's
    standard deviation (from the sums of g and g²) and the centroid's sums are accumulated in
    double instead of float32 (relative differences ~1e-7).
    """
    n = len(boxes)
    h, w = frame.shape[:2]
    pos_x = np.empty(n)
    pos_y = np.empty(n)
    whiteness = np.zeros(n)
    saturation = np.full(n, 255.0)
    features = np.zeros((n, N_APPEARANCE), dtype=np.float32)
    blobs, windows, heights, widths = [], [], [], []
    for i, box in enumerate(boxes):
        x0 = max(box[0] - REFINE_MARGIN, 0)
        y0 = max(box[1] - REFINE_MARGIN, 0)
        x1 = min(box[0] + box[2] + REFINE_MARGIN, w)
        y1 = min(box[1] + box[3] + REFINE_MARGIN, h)
        if x1 <= x0 or y1 <= y0:
            pos_x[i], pos_y[i] = box[0] + box[2] / 2, box[1] + box[3] / 2
            continue
        blobs.append(i)
        windows.append((x0, y0, x1, y1))
        heights.append(y1 - y0)
        widths.append(x1 - x0)
    if not blobs:
        return BlobMeasurements(pos_x, pos_y, whiteness, saturation, features)
    if n == 1:
        # A windowed frame's usual case: the same canvas and arithmetic without the
        # bookkeeping that spreads it over several windows (tests/test_detector_fast_paths.py).
        return measure_one(frame, mask, boxes[0], windows[0], sx, sy, head_fraction)
    cv = _stack(frame, mask, windows, heights, widths, sx, sy)
    appearance, whiteness[blobs], saturation[blobs], excess, peak = _appearance(cv)
    features[blobs] = appearance.T
    x, y, blob_excess, total = _head_positions(cv, excess, peak, windows, head_fraction)
    pos_x[blobs] = x
    pos_y[blobs] = y
    for k in ((peak <= 0) | (total <= 0)).nonzero()[0].tolist():
        i = blobs[k]
        pos_x[i], pos_y[i] = _rare_position(cv, k, windows[k], boxes[i], blob_excess, peak[k])
    return BlobMeasurements(pos_x, pos_y, whiteness, saturation, features)


def _one_window(frame: np.ndarray, mask: np.ndarray, window: tuple[int, int, int, int],
                sx: float, sy: float) -> tuple[np.ndarray, np.ndarray]:
    """The canvas of one window (its rows, then the blank row) and the blob's pixels on it."""
    x0, y0, x1, y1 = window
    height, width = y1 - y0, x1 - x0
    canvas = np.zeros((height + 1, width, 3), np.uint8)
    canvas[:height] = frame[y0:y1, x0:x1]
    inside = np.zeros((height + 1, width), np.uint8)
    _paste_mask(mask, window, sx, sy, inside[:height])
    return canvas, inside


def _one_appearance(canvas: np.ndarray, inside: np.ndarray
                    ) -> tuple[np.ndarray, float, float, np.ndarray, float]:
    """``_appearance`` of a single window: (features (1, N_APPEARANCE) float32, whiteness,
    saturation, excess over the background, peak excess)."""
    height, width = canvas.shape[0] - 1, canvas.shape[1]
    blue, green, red = cv2.split(canvas)
    cmin = cv2.min(cv2.min(blue, green), red)
    cmax = cv2.max(cv2.max(blue, green), red)
    # Integer counts and sums: exact however they are added.
    n_inside = int(cv2.countNonZero(inside))
    if n_inside:
        whiteness = int(cv2.sumElems(cv2.bitwise_and(cmin, inside))[0]) / n_inside
        saturation = int(cv2.sumElems(cv2.bitwise_and(cv2.subtract(cmax, cmin), inside))[0]) / n_inside
    else:
        whiteness, saturation = 0.0, 255.0
    gray = cv2.add(blue, green, dtype=cv2.CV_32F)
    cv2.add(gray, red, dst=gray, dtype=cv2.CV_32F)
    np.divide(gray, 3, out=gray)
    # The border in numpy's order (top row, bottom row, left column, right column).
    border = np.concatenate((gray[0], gray[height - 1], gray[:height, 0], gray[:height, width - 1]))
    background = np.float32(median_float32(border))
    excess = gray - background
    excess[height] = -np.inf                 # the blank row, padding as on the shared canvas
    peak = excess.max()
    half_peak = np.float32(0.5) * peak
    n_bright = int(np.count_nonzero(excess > half_peak))
    spill = int(np.count_nonzero((border - background) > half_peak)) / border.size
    peak_sat = float(cmax.max()) - float(cmin.max())
    n_pixels = height * width
    start = _FIRST_ROW
    mean = np.add.reduceat(cv2.reduce(gray, 1, cv2.REDUCE_SUM, dtype=cv2.CV_64F)[:, 0], start) / n_pixels
    mean_square = np.add.reduceat(cv2.reduce(cv2.multiply(gray, gray, dtype=cv2.CV_64F), 1, cv2.REDUCE_SUM,
                                             dtype=cv2.CV_64F)[:, 0], start) / n_pixels
    window_std = math.sqrt(max(float(mean_square[0]) - float(mean[0]) * float(mean[0]), 0.0))
    features = np.array([[peak, background, math.log1p(n_bright), spill, whiteness, saturation,
                          math.log1p(n_inside), peak_sat, window_std]], dtype=np.float32)
    return features, whiteness, saturation, excess, peak


def measure_one(frame: np.ndarray, mask: np.ndarray, box, window: tuple[int, int, int, int],
                sx: float, sy: float, head_fraction: float) -> BlobMeasurements:
    """``measure_blobs`` of a single blob: the canvas of one window (its rows, then the blank
    row), every sum, maximum and median taken as there, but on whole arrays and scalars instead
    of through the per-window index bookkeeping (≈ 40 fewer numpy calls; with the GIL held
    those calls were most of a windowed frame's measure). Same values bit for bit: the float
    sums go through the same ``cv2.reduce`` rows and ``np.add.reduceat`` over the same
    (blank-row-terminated) vectors, maxima and integer counts are exact, and the border median
    is the same order statistic (``median_float32``)."""
    x0, y0 = window[0], window[1]
    canvas, inside = _one_window(frame, mask, window, sx, sy)
    height, width = canvas.shape[0] - 1, canvas.shape[1]
    features, whiteness, saturation, excess, peak = _one_appearance(canvas, inside)
    start = _FIRST_ROW
    blob_excess = cv2.bitwise_and(excess, excess, dst=np.zeros_like(excess),   # (as in measure_blobs)
                                  mask=cv2.dilate(inside, GROW))
    blob_peak = max(blob_excess.max(), 0)
    if blob_peak <= 0:
        blob_excess = np.maximum(excess, 0)
        blob_peak = peak
    cut = np.float32(head_fraction * float(blob_peak))
    weights = blob_excess - cut
    np.maximum(weights, 0, out=weights)
    row_weight = cv2.reduce(weights, 1, cv2.REDUCE_SUM, dtype=cv2.CV_64F)[:, 0]
    total = float(np.add.reduceat(row_weight, start)[0])
    if peak <= 0:
        ys, xs = np.nonzero(inside[:height])
        if len(xs) == 0:
            x, y = box[0] + box[2] / 2, box[1] + box[3] / 2
        else:
            x, y = x0 + xs.mean(), y0 + ys.mean()
    elif total <= 0:
        fallback = np.maximum(blob_excess[:height], 0).astype(np.float64)
        ys, xs = np.mgrid[0:fallback.shape[0], 0:fallback.shape[1]]
        x = (fallback * xs).sum() / fallback.sum() + x0
        y = (fallback * ys).sum() / fallback.sum() + y0
    else:
        sum_x = float(np.add.reduceat(weights @ np.arange(width, dtype=np.float64), start)[0])
        sum_y = float(np.add.reduceat(row_weight * np.arange(height + 1), start)[0])
        x, y = sum_x / total + x0, sum_y / total + y0
    return BlobMeasurements(np.array([x]), np.array([y]), np.array([whiteness]),
                            np.array([saturation]), features)


def patch_features(frame: np.ndarray, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """(N, PATCH_CELLS²) normalised grey patches around the points (xs, ys), full-res px.

    Each patch is the square of ``2 × PATCH_HALF`` px (at 1280 px width and below; scaled with
    a larger frame, the image border repeated) around the rounded point, in luma (OpenCV's BGR → grey, in
    float), area-averaged to PATCH_CELLS × PATCH_CELLS cells, minus the patch's median cell,
    divided by its peak above that median (at least 8 grey levels, so a flat patch stays flat).
    The hand-made features say how bright, white and small a blob is; the patch says what shape
    its brightness has around it — a cork with its skirt, a line, a shoe's edge, a logo's
    letter (with the patch the shuttle ranked first among its frame's candidates in ≈ 10 % more
    TV frames, leave-one-clip-out).

    Speed: the squares are copied one below the other into one canvas (a slice each; an
    advanced-index gather of all of them at once took 3× longer), and the grey conversion runs
    once on the canvas. The area averaging runs once too, on the grey squares laid side by
    side: OpenCV's area averaging costs per source row (2.2x faster at 2048 px, 26 px squares,
    3.25 px cells), and each cell is averaged with the weights and in the order of a patch of
    its own either way (the grey conversion is not: its rows' SIMD body and scalar tail round
    differently, so it keeps the canvas of ``2 × half`` px rows).
    """
    xs = np.asarray(xs, dtype=float)
    ys = np.asarray(ys, dtype=float)
    n = len(xs)
    if n == 0:
        return np.zeros((0, PATCH_CELLS * PATCH_CELLS), np.float32)
    h, w = frame.shape[:2]
    # Never below the 1280 px square: scaled down with a small frame it shrank to the blob
    # itself (a 6 px dot at 320 px filled its 8 px square), a look no classifier was shown.
    half = max(PATCH_HALF, int(round(PATCH_HALF * w / 1280.0)))
    size = 2 * half
    canvas = np.empty((n * size, size, 3), np.uint8)
    offsets = np.arange(-half, half)
    for k, (x, y) in enumerate(zip(np.rint(xs).astype(np.int64).tolist(),
                                   np.rint(ys).astype(np.int64).tolist())):
        if half <= x <= w - half and half <= y <= h - half:
            canvas[k * size:(k + 1) * size] = frame[y - half:y + half, x - half:x + half]
        else:
            rows = np.clip(y + offsets, 0, h - 1)
            cols = np.clip(x + offsets, 0, w - 1)
            canvas[k * size:(k + 1) * size] = frame[rows[:, None], cols[None, :]]
    luma = cv2.cvtColor(canvas.astype(np.float32), cv2.COLOR_BGR2GRAY)
    wide = luma.reshape(n, size, size).transpose(1, 0, 2).reshape(size, n * size)
    cells = cv2.resize(wide, (n * PATCH_CELLS, PATCH_CELLS), interpolation=cv2.INTER_AREA)
    cells = cells.reshape(PATCH_CELLS, n, PATCH_CELLS).transpose(1, 0, 2).reshape(n, -1)
    median, top = _row_median_and_max(cells)
    peak = np.maximum(top - median, 8.0)
    return (cells - median) / peak


def _row_median_and_max(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N, 1) medians and maxima of the rows of a float32 (N, K) array without NaN: one sort
    of the rows (``np.median``'s wrappers cost 5x that on a frame's few patches), the two middle
    values averaged in float32 as numpy's median does (sum, then / 2)."""
    ordered = np.sort(values, axis=1)
    k = ordered.shape[1]
    if k % 2:
        median = ordered[:, k // 2:k // 2 + 1]
    else:
        median = (ordered[:, k // 2 - 1:k // 2] + ordered[:, k // 2:k // 2 + 1]) / values.dtype.type(2)
    return median, ordered[:, k - 1:]


_FIRST_ROW = np.zeros(1, dtype=np.intp)


def window_maxima(images: tuple[np.ndarray, ...], x0: np.ndarray, y0: np.ndarray,
                  width: np.ndarray, height: np.ndarray,
                  counts_where: np.ndarray | None = None) -> list[np.ndarray]:
    """Maximum of each image in each window (all non-empty, inside the images), one gather each.

    The images have the same size, so they share the windows' pixel indices (computed once).
    ``counts_where``: an image of that size, 0 where the *first* image is to be taken as 0.
    """
    counts = height * width
    local = _ragged_arange(counts)
    row_width = np.repeat(width, counts)
    rows = local // row_width
    flat = ((np.repeat(y0, counts) + rows) * images[0].shape[1] + np.repeat(x0, counts)
            + local - rows * row_width)
    starts = np.cumsum(counts) - counts
    maxima = []
    for k, image in enumerate(images):
        values = image.ravel()[flat]
        if k == 0 and counts_where is not None:
            values = np.where(counts_where.ravel()[flat] != 0, values, values.dtype.type(0))
        maxima.append(np.maximum.reduceat(values, starts))
    return maxima


def scaled_boxes(rects: np.ndarray, sx: float, sy: float) -> np.ndarray:
    """(N, 4) float boxes (x, y, w, h) at the mask scale → full-resolution int64 boxes.

    Origin rounded down, size up: ``floor(x·sx), floor(y·sy), ceil(w·sx), ceil(h·sy)``, in
    four operations on the whole array (it was four per column and a stack).
    """
    scaled = rects * np.array([sx, sy, sx, sy])
    np.floor(scaled[:, :2], out=scaled[:, :2])
    np.ceil(scaled[:, 2:], out=scaled[:, 2:])
    return scaled.astype(np.int64)


def _ragged_arange(lengths: np.ndarray) -> np.ndarray:
    """``np.concatenate([np.arange(k) for k in lengths])`` in three vector operations."""
    total = int(lengths.sum())
    offsets = np.repeat(np.cumsum(lengths) - lengths, lengths)
    return np.arange(total) - offsets

"""Looking for the shuttle where its 3D flight says it must be, when the detector has lost it.

Why this file exists: the background difference and the tracklets lose a shuttle that is in
plain view for a few frames at a time — it merges with a player's blob or a court line, or its
tracklet is not confirmed yet after a change of direction — while the 3D flight (a drag-model
filter fed by both cameras) knows where it is to a few millimetres. ``find_spot`` examines a
small window of the full-resolution frame around the flight's projection and returns the
centroid of a compact, moving spot clearly brighter and whiter than its surroundings, or None: a
shuttle hidden behind a player leaves no such spot, so nothing is invented where nothing is
seen; a court line or the net's tape crosses the window (not compact) and does not move.

Pure numpy + cv2 (no Qt), one window per camera and frame: cheap.
"""

from __future__ import annotations

import math

import cv2
import numpy as np


# A shuttle is white: its colour channels are nearly equal. Skin, a red racket frame or a
# yellow line are bright in their darkest channel too, but far more saturated.
MAX_SATURATION = 0.3
# ``white_near`` looks at single pixels, where skin blended with a shirt's edge comes close to
# 0.3: the shuttle's cork is nearly grey-free.
WHITE_SATURATION = 0.1


def find_spot(frame_bgr: np.ndarray, u: float, v: float, radius: float, min_contrast: float,
              max_area: float, previous_bgr: np.ndarray | None = None
              ) -> tuple[float, float, float, float] | None:
    """The bright compact spot nearest (u, v) within ``radius`` px, or None.

    Returns (x, y, contrast, area): the intensity-weighted centroid of the spot, its peak
    brightness above the window's median (grey levels of min(B, G, R): a shuttle is white, so
    its darkest channel is bright, unlike a coloured shirt), and its area in px. The spot must
    be at least ``min_contrast`` above the median, unsaturated (white, not skin), at most ``max_area`` px (a player's white
    shirt is not a spot), clear of the window's border (a line or the net's tape crosses it),
    and — given the previous frame — it must have changed since then by at least half the
    contrast on average (a static glint is not a shuttle in flight).
    """
    h, w = frame_bgr.shape[:2]
    half = int(math.ceil(radius)) + 4
    x0, x1 = max(int(round(u)) - half, 0), min(int(round(u)) + half + 1, w)
    y0, y1 = max(int(round(v)) - half, 0), min(int(round(v)) + half + 1, h)
    if x1 - x0 < 5 or y1 - y0 < 5:
        return None
    patch = frame_bgr[y0:y1, x0:x1]
    white = patch.min(axis=2).astype(np.int16)
    contrast = white - int(np.median(white))
    peak = int(contrast.max())
    if peak < min_contrast:
        return None
    mask = (contrast >= max(min_contrast * 0.5, peak * 0.5)).astype(np.uint8)
    n, labels, stats, centroids = cv2.connectedComponentsWithStats(mask, connectivity=8)
    moved = None
    if previous_bgr is not None and previous_bgr.shape == frame_bgr.shape:
        before = previous_bgr[y0:y1, x0:x1].min(axis=2).astype(np.int16)
        moved = np.abs(white - before)
    pw, ph = x1 - x0, y1 - y0
    best = None
    for k in range(1, n):
        area = float(stats[k, cv2.CC_STAT_AREA])
        left, top = stats[k, cv2.CC_STAT_LEFT], stats[k, cv2.CC_STAT_TOP]
        if (area > max_area or left == 0 or top == 0
                or left + stats[k, cv2.CC_STAT_WIDTH] >= pw or top + stats[k, cv2.CC_STAT_HEIGHT] >= ph):
            continue
        sel = labels == k
        weights = contrast[sel].astype(np.float64)
        if float(weights.max()) < min_contrast:
            continue
        if moved is not None and float(moved[sel].mean()) < 0.5 * float(weights.max()) * 0.5:
            continue
        pixels = patch[sel].astype(np.float32)
        brightest = pixels.max(axis=1)
        saturation = float(np.mean((brightest - pixels.min(axis=1)) / np.maximum(brightest, 1.0)))
        if saturation > MAX_SATURATION:
            continue
        ys, xs = np.nonzero(sel)
        cx = float(np.dot(xs, weights) / weights.sum()) + x0
        cy = float(np.dot(ys, weights) / weights.sum()) + y0
        dist = math.hypot(cx - u, cy - v)
        if dist <= radius and (best is None or dist < best[0]):
            best = (dist, cx, cy, float(weights.max()), area)
    if best is None:
        return None
    return best[1], best[2], best[3], best[4]


def _around(frame_bgr: np.ndarray, u: float, v: float, radius: float
            ) -> tuple[np.ndarray, np.ndarray] | None:
    """(the pixels within ``radius`` px of (u, v), a window four times as wide around them) of the
    frame, clipped to it; None when (u, v) lies outside."""
    h, w = frame_bgr.shape[:2]
    ui, vi = int(round(u)), int(round(v))
    if not (0 <= ui < w and 0 <= vi < h):
        return None
    r = max(int(math.ceil(radius)), 1)
    big = 4 * r
    window = frame_bgr[max(vi - big, 0):vi + big + 1, max(ui - big, 0):ui + big + 1]
    patch = frame_bgr[max(vi - r, 0):vi + r + 1, max(ui - r, 0):ui + r + 1]
    return patch, window


def white_near(frame_bgr: np.ndarray, u: float, v: float, radius: float, min_contrast: float) -> bool:
    """True when a white pixel lies within ``radius`` px of (u, v): its darkest channel at least
    ``min_contrast`` above the median of a window four times as wide, and unsaturated.

    For a shuttle that merged with a larger blob (a player's arm, a racket) ``find_spot`` finds
    no compact spot, but its white still shows at the flight's projection; a shuttle hidden
    behind the player shows the player's shirt, skin or hair there instead.
    """
    around = _around(frame_bgr, u, v, radius)
    if around is None:
        return False
    patch, window = around
    level = float(np.median(window.min(axis=2))) + min_contrast
    patch = patch.astype(np.float32)
    darkest = patch.min(axis=2)
    brightest = patch.max(axis=2)
    white = (darkest >= level) & ((brightest - darkest) / np.maximum(brightest, 1.0) <= WHITE_SATURATION)
    return bool(white.any())


def bright_near(frame_bgr: np.ndarray, u: float, v: float, radius: float, min_contrast: float) -> bool:
    """True when a pixel within ``radius`` px of (u, v) is at least ``min_contrast`` grey levels
    brighter (mean of B, G, R) than the median of a window four times as wide.

    Weaker evidence than ``white_near``: no test of colour. On the NYCU rallies' cameras a
    shuttle in flight often shows pale blue, not white, and ``white_near`` refuses it (its
    darkest channel is red); what this rules out is a projection on plain background — the
    shuttle hidden behind something dark, or a flight the other camera's sight pulled off.
    """
    around = _around(frame_bgr, u, v, radius)
    if around is None:
        return False
    patch, window = around
    return bool(float(patch.mean(axis=2).max()) >= float(np.median(window.mean(axis=2))) + min_contrast)

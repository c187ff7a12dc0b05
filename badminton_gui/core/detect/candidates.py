"""From the mask's contours to the blobs worth measuring: filters 1 and 2 of the paper.

Why this file exists: filter 1 (contour length) and filter 2 (shortest side of the tilted,
minimum-area rectangle) are decided on the mask's contours at the processing scale, converted to
full-resolution pixels, for all contours at once (``measure_contours``, ``shape_filters``); the
contours they reject become candidates that say which filter it was (the tuning view shows
them). When more blobs pass than ``association.max_measured``, the most promising are kept for
the full-resolution look (``rank_for_measuring``). A shuttle merged with a racket or an arm
into one long blob is split off it where it brightened since the last frame (``MergedBlobSplitter``).
"""

from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np

from ..association import Tracklet, TrackletAssociator
from ..params import TrackerParams
from ..types import REJECT_LENGTH, REJECT_SHORT_SIDE, REJECT_WHITENESS, Candidate, make_candidate
from .measure import GROW, scaled_boxes, window_maxima
from .scoring import ShapedBlob
from .shuttle_scale import GateScale

@dataclasses.dataclass(frozen=True, slots=True)
class ContourShapes:
    """Filters 1 and 2's measurements of every contour of a frame, full-resolution px."""

    length: np.ndarray      # (N,) contour length
    short_side: np.ndarray  # (N,) shortest side of the tilted rectangle
    area: np.ndarray        # (N,) contour area, px²
    rects: np.ndarray       # (N, 4) bounding boxes at the mask scale (x, y, w, h), float
    boxes: np.ndarray       # (N, 4) the same at full resolution, int64
    sx: float               # full-resolution px per mask px, across
    sy: float               # ... and down

    @property
    def centres(self) -> tuple[np.ndarray, np.ndarray]:
        """The bounding boxes' centres, full-resolution px."""
        r = self.rects
        return (r[:, 0] + r[:, 2] / 2) * self.sx, (r[:, 1] + r[:, 3] / 2) * self.sy


def measure_contours(contours, sx: float, sy: float) -> ContourShapes:
    """OpenCV measures each contour; the scaling is done for all contours at once (one list per
    measurement: a row assignment per contour costs as much as a call)."""
    s_mean = 0.5 * (sx + sy)
    length = np.array([cv2.arcLength(c, True) for c in contours], dtype=float) * s_mean
    short = np.array([min(cv2.minAreaRect(c)[1]) for c in contours], dtype=float) * s_mean
    area = np.array([cv2.contourArea(c) for c in contours], dtype=float) * sx * sy
    rects = np.array([cv2.boundingRect(c) for c in contours], dtype=float).reshape(-1, 4)
    return ContourShapes(length, short, area, rects, scaled_boxes(rects, sx, sy), sx, sy)


def gate_factors(shapes: ContourShapes, scale: GateScale | None) -> np.ndarray | float:
    """Per contour, the factor of the pixel gates at its centre (``shuttle_scale.enabled``:
    the shuttle's image scale there against the one the pixel values hold at); 1 without."""
    if scale is None or not len(shapes.length):
        return 1.0
    return scale.at(*shapes.centres)


def shape_filters(shapes: ContourShapes, params: TrackerParams, followed: Tracklet | None,
                  t: float, width: int, factor: np.ndarray | float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(filter 1 passed, filter 2 passed) per contour; ``factor`` (``gate_factors``) scales
    each contour's pixel limits.

    Guided exception to filter 1 (``contour_length.guided_min_length``): a short blob where the
    followed shuttle is predicted passes it.
    """
    cl, tr = params.contour_length, params.tilted_rect
    length, short = shapes.length, shapes.short_side
    min_length = cl.min_length * factor
    length_ok = (min_length <= length) & (length <= cl.max_length * factor)
    short_ok = (tr.min_short_side * factor <= short) & (short <= tr.max_short_side * factor)
    if 0 < cl.guided_min_length < cl.min_length and len(length):
        if followed is not None and followed.velocity_known:
            px, py = followed.predict(t)
            cx, cy = shapes.centres
            shorter = (cl.guided_min_length * factor <= length) & (length < min_length)
            # px at 1280 px width, scaled with the width, with the camera's geometry too: the
            # radius covers the prediction's error, pixels of the mask's jitter whatever the
            # shuttle's scale (as the travel thresholds, core/association.py).
            radius = cl.guided_radius * width / 1280.0
            near = np.hypot(cx - px, cy - py) <= radius
            length_ok = length_ok | (shorter & near)
    return length_ok, short_ok


def too_large(shapes: ContourShapes, params: TrackerParams, factor: np.ndarray | float = 1.0) -> np.ndarray:
    """Full-resolution boxes of the blobs too large for a shuttle (a player, a racket and what
    touches them): a shuttle merged into one cannot be told apart (``CameraDetector.is_merged``)."""
    return shapes.boxes[(shapes.length > params.contour_length.max_length * factor)
                        | (shapes.short_side > params.tilted_rect.max_short_side * factor)]


def shape_rejects(shapes: ContourShapes, length_ok: np.ndarray, short_ok: np.ndarray
                  ) -> tuple[list[Candidate], list[ShapedBlob]]:
    """(the candidates filter 1 or 2 rejected, each naming its filter; the blobs that passed)."""
    passed = length_ok & short_ok
    rejected = (~passed).nonzero()[0]
    out: list[Candidate] = []
    if len(rejected):
        cx, cy = shapes.centres
        reasons = np.where(length_ok[rejected], REJECT_SHORT_SIDE, REJECT_LENGTH).tolist()
        for x, y, length, short_side, area, reason in zip(
                cx[rejected].tolist(), cy[rejected].tolist(), shapes.length[rejected].tolist(),
                shapes.short_side[rejected].tolist(), shapes.area[rejected].tolist(), reasons):
            out.append(make_candidate(x, y, length, short_side, math.nan, area, math.nan, 0.0, reason))
    kept = passed.nonzero()[0]
    blobs = [ShapedBlob(k, length, short_side, area, tuple(box)) for k, length, short_side, area, box
             in zip(kept.tolist(), shapes.length[kept].tolist(), shapes.short_side[kept].tolist(),
                    shapes.area[kept].tolist(), shapes.boxes[kept].tolist())]
    return out, blobs


def rank_for_measuring(blobs: list[ShapedBlob], limit: int, live: np.ndarray,
                       difference: np.ndarray | None, gray: np.ndarray, unlit: np.ndarray | None,
                       shapes: ContourShapes, mask_shape: tuple[int, ...]
                       ) -> tuple[list[ShapedBlob], list[Candidate]]:
    """(the ``limit`` most promising blobs, the others as candidates rejected by filter 3).

    Cheap ranking at the processing scale: blobs near a live tracklet (``live``: predicted x,
    y and gate per tracklet) first, then the strongest brightening (``difference``, the
    background model's last difference image; ``unlit``: where it counts as 0), plus plain
    brightness: a shuttle held still before the serve fades into the average but stays the
    brightest thing around. Ties keep the contour order (a stable sort).
    """
    sx, sy = shapes.sx, shapes.sy
    boxes = np.array([b.box for b in blobs], dtype=np.int64).reshape(-1, 4)
    centre_x = boxes[:, 0] + boxes[:, 2] / 2
    centre_y = boxes[:, 1] + boxes[:, 3] / 2
    if len(live):
        near = (np.hypot(live[None, :, 0] - centre_x[:, None], live[None, :, 1] - centre_y[:, None])
                <= live[None, :, 2]).any(axis=1)
    else:
        near = np.zeros(len(blobs), dtype=bool)
    if difference is not None:
        # Each box's window at the processing scale, maxima of all windows in one gather.
        x0 = (boxes[:, 0] / sx).astype(np.int64)
        y0 = (boxes[:, 1] / sy).astype(np.int64)
        win_w = np.minimum(np.maximum((boxes[:, 2] / sx).astype(np.int64), 1), mask_shape[1] - x0)
        win_h = np.minimum(np.maximum((boxes[:, 3] / sy).astype(np.int64), 1), mask_shape[0] - y0)
        diff_max, gray_max = window_maxima((difference, gray), x0, y0, win_w, win_h, unlit)
        strength = diff_max.astype(np.float64) + 0.5 * gray_max.astype(np.float64)
    else:
        strength = -np.array([b.area for b in blobs])   # MOG2 gives no strength: smaller blobs first
    order = np.lexsort((-strength, ~near)).tolist()
    dropped = []
    for i in order[limit:]:
        _, length, short_side, area, box = blobs[i]
        dropped.append(make_candidate(box[0] + box[2] / 2, box[1] + box[3] / 2, length, short_side,
                                      math.nan, area, math.nan, 0.0, REJECT_WHITENESS))
    return [blobs[i] for i in order[:limit]], dropped


class MergedBlobSplitter:
    """Parts split off the frame's long blobs (``contour_length.split_min_length``).

    A shuttle touching a racket, an arm, or the ghost a racket leaves on a lit line merges
    with it into one blob that filters 1 and 2 reject or that scores as a poor shuttle; the
    tracker then loses the shuttle or follows the racket. The shuttle moves by about its
    own size a frame, so the pixels of a long blob that brightened by ``split_threshold``
    since the previous frame (processing scale) hold it: each compact group of them (grown
    by a pixel like the mask, and within filters 1 and 2) inside the followed tracklet's
    gate becomes a candidate of its own, measured on its own pixels. A blob is split only
    where the previous frame's grey image was made too (windows overlap while they follow
    the shuttle: rally_11-48-00 left 483–492, coarse, a shuttle merged with a player for 10
    frames). Only around a track seen lately (``split_max_misses``): the grown gate of one
    that lost its blob behind a player holds brightening parts of the player, split off in
    both cameras alike.
    """

    def __init__(self) -> None:
        # The last frame's grey image where it was made (its window, or the whole frame), that
        # part's model-pixel origin and the whole model's shape.
        self._previous: tuple[np.ndarray, int, int, tuple[int, int]] | None = None

    def split(self, params: TrackerParams, associator: TrackletAssociator, gray: np.ndarray,
              mask: np.ndarray, contours, shapes: ContourShapes, t: float, width: int,
              fresh: tuple[int, int, int, int], factor: np.ndarray | float = 1.0
              ) -> tuple[np.ndarray, list[ShapedBlob]] | None:
        """(mask of the parts, the parts), or None. ``fresh`` (model px x0, y0, x1, y1) is the
        part of ``gray`` made this frame (the window, when windowed); ``factor``: the contours'
        gate factors (``gate_factors``)."""
        cl = params.contour_length
        prev, self._previous = self._previous, None
        if cl.split_min_length <= 0:
            return None
        fx0, fy0, fx1, fy1 = fresh
        self._previous = (gray[fy0:fy1, fx0:fx1].copy(), fx0, fy0, gray.shape)
        if prev is None or prev[3] != gray.shape:
            return None
        # Only where the followed shuttle may be (its tracklet's gate around its prediction):
        # elsewhere a moving hand or racket edge split off a player would start tracks of its own.
        followed = associator.followed
        if followed is None or not followed.velocity_known:
            return None
        if followed.misses > cl.split_max_misses:
            # A track that lost its blob a while ago: its gate has grown, and what brightens
            # in it then is more often part of a player than the shuttle (hidden behind it).
            return None
        # The length a blob must reach to be split is px at 1280 px width, scaled with the width,
        # with the camera's geometry too: it is the size of what the shuttle merges with (a
        # racket, an arm, a mark on the floor), not the shuttle's. Scaled down with the shuttle
        # where a camera sees it small, it split the blob of a landed shuttle rolling over a
        # floor mark, and the mark's still tracklet took the shuttle from its flight.
        big = np.flatnonzero(shapes.length >= cl.split_min_length * width / 1280.0)
        if not len(big):
            return None
        factors = np.broadcast_to(np.asarray(factor, dtype=float), shapes.length.shape)
        centre = followed.predict(t)
        radius = associator.gate(followed, max(t - followed.t, 1e-3))
        core_mask = None
        parts: list[ShapedBlob] = []
        for k in big.tolist():
            # The parts pass filters 1 and 2 as any blob does (scaled at the blob with geometry).
            found = self._parts_of(params, gray, prev, contours, k, shapes, centre, radius,
                                   float(factors[k]))
            for c, x0, y0, length, short_side in found:
                if core_mask is None:
                    core_mask = np.zeros(mask.shape[:2], np.uint8)
                cv2.drawContours(core_mask, [c], 0, 255, -1, offset=(x0, y0))
                cx, cy, cw, ch = cv2.boundingRect(c)
                box = scaled_boxes(np.array([[cx + x0, cy + y0, cw, ch]], dtype=float), shapes.sx, shapes.sy)[0]
                parts.append(ShapedBlob(k, length, short_side, cv2.contourArea(c) * shapes.sx * shapes.sy,
                                        tuple(box.tolist())))
        if not parts:
            return None
        return core_mask, parts

    @staticmethod
    def _parts_of(params: TrackerParams, gray: np.ndarray, prev, contours, k: int,
                  shapes: ContourShapes, centre: tuple[float, float], radius: float, factor: float) -> list:
        """(contour, x0, y0, length, short side) of the parts of long blob ``k`` that brightened since the previous
        frame, within filters 1 and 2 (their pixel limits × ``factor``) and the followed tracklet's gate."""
        cl, tr = params.contour_length, params.tilted_rect
        sx, sy = shapes.sx, shapes.sy
        px, py = centre
        prev_gray, px0, py0, _ = prev
        ph, pw = prev_gray.shape
        x0, y0, bw, bh = cv2.boundingRect(contours[k])
        if not (x0 * sx - radius <= px <= (x0 + bw) * sx + radius
                and y0 * sy - radius <= py <= (y0 + bh) * sy + radius):
            return []
        if not (px0 <= x0 and py0 <= y0 and x0 + bw <= px0 + pw and y0 + bh <= py0 + ph):
            return []   # the previous frame's grey image was not made here
        blob = np.zeros((bh, bw), np.uint8)
        cv2.drawContours(blob, contours, k, 255, -1, offset=(-x0, -y0))
        rise = cv2.subtract(gray[y0:y0 + bh, x0:x0 + bw],
                            prev_gray[y0 - py0:y0 - py0 + bh, x0 - px0:x0 - px0 + bw])
        core = cv2.compare(rise, float(cl.split_threshold), cv2.CMP_GT)
        cv2.bitwise_and(core, blob, dst=core)
        if not cv2.countNonZero(core):
            return []
        core = cv2.dilate(core, GROW)
        cv2.bitwise_and(core, blob, dst=core)
        found, _ = cv2.findContours(core, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        s_mean = 0.5 * (sx + sy)
        out = []
        for c in found:
            length = cv2.arcLength(c, True) * s_mean
            short_side = min(cv2.minAreaRect(c)[1]) * s_mean
            if not (cl.min_length * factor <= length <= min(cl.max_length * factor, 0.5 * shapes.length[k])
                    and tr.min_short_side * factor <= short_side <= tr.max_short_side * factor):
                continue
            cx, cy, cw, ch = cv2.boundingRect(c)
            if math.hypot((x0 + cx + cw / 2) * sx - px, (y0 + cy + ch / 2) * sy - py) > radius:
                continue
            out.append((c, x0, y0, length, short_side))
        return out

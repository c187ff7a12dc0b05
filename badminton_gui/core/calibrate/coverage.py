"""Pose diversity and coverage of captured calibration views (ROS camera_calibration's idea).

Why this file exists: the wizard must tell the operator, honestly, how much of the field of
view and of the pose space the *captured* views cover, and whether the view in front of the
camera now would add anything. That logic is core and is unit-tested; the wizard
only draws the bars.

Each view is summarised by four numbers in 0..1 computed from the board's four outer corners,
as ROS does (``get_parameters``): X and Y of the board's centre (with the board's own size taken
off the range, so a board touching both edges counts as "centre"), size (sqrt of the board's
area / image area) and skew (how far the board is tilted from fronto-parallel). A bar's
progress is the spread (max - min) of that number over the captured views divided by the spread
wanted (X 0.7, Y 0.8, size 0.4, skew 0.5); size and skew count from 0, since small and
fronto-parallel is the easy case. Only captured views count: the live view never fills a bar.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .board import BoardDetection, BoardSpec

COVERAGE_NAMES = ("X", "Y", "size", "skew")
# Spread of each parameter that fills its bar (ROS camera_calibration's param_ranges).
WANTED_SPREAD = (0.7, 0.8, 0.4, 0.5)


@dataclass(frozen=True, slots=True)
class ViewParams:
    """Where the board is in one camera's image, all in 0..1."""

    x: float
    y: float
    size: float
    skew: float

    def as_tuple(self) -> tuple[float, float, float, float]:
        return (self.x, self.y, self.size, self.skew)


def _angle(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> float:
    """Angle ABC (radians)."""
    ab, cb = a - b, c - b
    cos = float(np.dot(ab, cb) / max(np.linalg.norm(ab) * np.linalg.norm(cb), 1e-12))
    return math.acos(max(-1.0, min(1.0, cos)))


def view_params(outer: np.ndarray, image_size: tuple[int, int]) -> ViewParams:
    """Four outer corners (TL, TR, BR, BL), (4, 2) px, and (width, height) → ViewParams."""
    outer = np.asarray(outer, np.float64).reshape(4, 2)
    width, height = image_size
    up_left, up_right, down_right, down_left = outer
    a = up_right - up_left
    b = down_right - up_right
    c = down_left - down_right
    p, q = b + c, a + b
    area = abs(p[0] * q[1] - p[1] * q[0]) / 2.0        # quadrilateral area via its diagonals
    border = math.sqrt(area)
    mean_x, mean_y = outer.mean(axis=0)
    # The centre can only range over (image - board size); normalise to that range.
    px = min(1.0, max(0.0, (mean_x - border / 2) / max(width - border, 1e-9)))
    py = min(1.0, max(0.0, (mean_y - border / 2) / max(height - border, 1e-9)))
    size = math.sqrt(area / (width * height))
    skew = min(1.0, 2.0 * abs(math.pi / 2 - _angle(up_left, up_right, down_right)))
    return ViewParams(px, py, min(1.0, size), skew)


def detection_params(det: BoardDetection, spec: BoardSpec) -> ViewParams | None:
    """ViewParams of a detection, or None when an outer corner is not visible."""
    outer = det.outer_corners(spec)
    if outer is None:
        return None
    return view_params(outer, det.image_size)


@dataclass(frozen=True, slots=True)
class Coverage:
    """Progress 0..1 of each bar for one camera, from the captured views only."""

    x: float = 0.0
    y: float = 0.0
    size: float = 0.0
    skew: float = 0.0
    n_views: int = 0

    def as_tuple(self) -> tuple[float, float, float, float]:
        return (self.x, self.y, self.size, self.skew)

    @property
    def complete(self) -> bool:
        return all(p >= 1.0 for p in self.as_tuple())


def coverage(captured: Sequence[ViewParams]) -> Coverage:
    """Coverage bars of one camera from the views captured so far."""
    if not captured:
        return Coverage()
    arr = np.array([v.as_tuple() for v in captured])
    lo = arr.min(axis=0)
    hi = arr.max(axis=0)
    lo[2:] = 0.0          # size and skew: the small, flat end is always "covered"
    progress = [min(float(h - l) / r, 1.0) for l, h, r in zip(lo, hi, WANTED_SPREAD)]
    return Coverage(*progress, n_views=len(captured))


def param_distance(a: Sequence[float], b: Sequence[float]) -> float:
    """L1 distance between two parameter vectors (ROS ``param_distance``)."""
    return float(sum(abs(x - y) for x, y in zip(a, b)))


@dataclass(frozen=True, slots=True)
class NoveltyVerdict:
    """Is a candidate view different enough from every captured one?"""

    is_new: bool
    distance: float          # L1 distance to the nearest captured view (inf: none captured)
    min_distance: float

    @property
    def reason(self) -> str:
        if self.is_new:
            return ""
        return (f"too similar to a captured view (difference {self.distance:.2f}, needs "
                f"{self.min_distance:.2f}): move, tilt or bring the board closer")


def novelty(candidate: Sequence[float], captured: Sequence[Sequence[float]],
            min_distance: float = 0.2) -> NoveltyVerdict:
    """ROS ``is_good_sample``: new enough when the nearest captured view is > min_distance away.

    For a stereo rig pass the left and right parameters concatenated (8 numbers), as ROS's
    stereo calibrator does.
    """
    if not captured:
        return NoveltyVerdict(True, float("inf"), min_distance)
    d = min(param_distance(candidate, c) for c in captured)
    return NoveltyVerdict(d > min_distance, d, min_distance)

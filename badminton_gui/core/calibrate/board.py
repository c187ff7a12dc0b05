"""Calibration boards: what the board is, finding it in an image, and judging one view of it.

Why this file exists: the calibration wizard, the ``calibrate`` CLI and the tests all detect
the same boards the same way, and every view that is refused is refused with a sentence the
operator can act on ("board moving: hold it still"), never silently. Only numpy
and cv2 here (core layer).

Detection is coarse-to-fine so that live use stays fast on large frames: the board is searched
on a copy downscaled to at most ``search_max_side`` pixels, then the corners are refined with
``cornerSubPix`` on the full-resolution image.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

BOARD_KINDS = ("chessboard", "charuco")


def charuco_available() -> bool:
    """True when this OpenCV build has the ChArUco detector (cv2.aruco.CharucoDetector)."""
    return hasattr(cv2, "aruco") and hasattr(cv2.aruco, "CharucoDetector")


class BoardError(ValueError):
    """A board description that cannot work (too few corners, unknown kind, no ArUco)."""


@dataclass(frozen=True, slots=True)
class BoardSpec:
    """A planar calibration target.

    ``cols`` × ``rows`` count the *inner* corners (OpenCV's pattern size: a board of 10 × 7
    squares has 9 × 6 inner corners), for ChArUco boards too. ``square`` is the side of one
    square in metres: it sets the unit of the baseline and of every 3D result.
    """

    cols: int = 9
    rows: int = 6
    square: float = 0.025
    kind: str = "chessboard"
    marker: float = 0.0                 # ChArUco marker side (m); 0 → 0.7 × square
    dictionary: str = "DICT_4X4_250"    # ChArUco ArUco dictionary name

    def __post_init__(self) -> None:
        if self.kind not in BOARD_KINDS:
            raise BoardError(f"board kind {self.kind!r} is not one of {', '.join(BOARD_KINDS)}")
        if self.cols < 2 or self.rows < 2:
            raise BoardError(f"a board needs at least 2×2 inner corners, not "
                             f"{self.cols}×{self.rows}")
        if self.cols == self.rows and self.kind == "chessboard":
            # A square chessboard looks the same turned by 90°: the corner order is ambiguous.
            raise BoardError(f"a {self.cols}×{self.rows} chessboard is square, so its corner "
                             f"order is ambiguous; use a board with different counts (e.g. 9×6)")
        if not (self.square > 0 and math.isfinite(self.square)):
            raise BoardError(f"square size must be a positive length in metres, not "
                             f"{self.square!r}")
        if self.kind == "charuco" and not charuco_available():
            raise BoardError("this OpenCV build has no cv2.aruco.CharucoDetector: ChArUco "
                             "boards are not available, use a chessboard")

    @classmethod
    def parse(cls, text: str, square: float, kind: str = "chessboard") -> "BoardSpec":
        """``"9x6"`` (inner corners) and a square size in metres → BoardSpec."""
        try:
            cols, rows = (int(v) for v in text.lower().replace("×", "x").split("x"))
        except ValueError:
            raise BoardError(f"board {text!r} is not COLSxROWS inner corners, e.g. 9x6") from None
        return cls(cols=cols, rows=rows, square=float(square), kind=kind)

    @property
    def pattern_size(self) -> tuple[int, int]:
        return (self.cols, self.rows)

    @property
    def n_corners(self) -> int:
        return self.cols * self.rows

    def object_points(self) -> np.ndarray:
        """(cols·rows, 3) float32 corner positions on the board plane (Z = 0), metres.

        Row-major, x fastest: the order of ``findChessboardCorners`` and of ChArUco ids.
        """
        grid = np.mgrid[0:self.cols, 0:self.rows].T.reshape(-1, 2).astype(np.float32)
        pts = np.zeros((self.n_corners, 3), np.float32)
        pts[:, :2] = grid * np.float32(self.square)
        return pts

    def outer_ids(self) -> tuple[int, int, int, int]:
        """Ids of the four outer corners: top-left, top-right, bottom-right, bottom-left."""
        c, r = self.cols, self.rows
        return (0, c - 1, c * r - 1, c * (r - 1))

    def describe(self) -> str:
        return (f"{self.kind} {self.cols}×{self.rows} inner corners, "
                f"square {self.square * 1000:g} mm")

    # ---- ChArUco --------------------------------------------------------------------------
    def charuco_board(self):
        """The cv2.aruco.CharucoBoard of this spec (squares = inner corners + 1)."""
        if self.kind != "charuco":
            raise BoardError("not a ChArUco board")
        dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, self.dictionary))
        marker = self.marker if self.marker > 0 else 0.7 * self.square
        return cv2.aruco.CharucoBoard((self.cols + 1, self.rows + 1), self.square, marker,
                                      dictionary)


@dataclass(frozen=True, slots=True)
class BoardDetection:
    """The corners of one board found in one image (full-resolution pixels).

    ``ids`` index :meth:`BoardSpec.object_points`; for a chessboard they are 0..N-1.
    """

    corners: np.ndarray          # (N, 2) float32
    ids: np.ndarray              # (N,) int32
    image_size: tuple[int, int]  # (width, height)
    n_expected: int

    @property
    def complete(self) -> bool:
        return len(self.ids) == self.n_expected

    def outer_corners(self, spec: BoardSpec) -> np.ndarray | None:
        """(4, 2) outer corners TL, TR, BR, BL (board order), or None if one is not seen."""
        lookup = {int(i): k for k, i in enumerate(self.ids)}
        try:
            return np.array([self.corners[lookup[i]] for i in spec.outer_ids()], np.float64)
        except KeyError:
            return None

    def square_px(self, spec: BoardSpec) -> float:
        """Median distance between horizontally adjacent corners, px (size of a square)."""
        if len(self.ids) == spec.n_corners:
            grid = self.corners.reshape(spec.rows, spec.cols, 2)
            steps = np.linalg.norm(np.diff(grid, axis=1), axis=2)
            return float(np.median(steps))
        hull = cv2.convexHull(self.corners.reshape(-1, 1, 2))
        return float(math.sqrt(cv2.contourArea(hull) / max(len(self.ids), 1)))


def to_gray(image: np.ndarray) -> np.ndarray:
    if image.ndim == 2:
        return image
    return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)


def _subpix_window(corners: np.ndarray, spec: BoardSpec) -> int:
    """Half-size of the cornerSubPix window: about a third of the smallest square, 3..11 px.

    Measured on OpenCV's stereo sample (640×480, squares 25–40 px): half a square capped at 15
    (ROS's choice) gives 1.04 px RMS, OpenCV's fixed 11 gives 0.41 px, a third of a square
    0.18 px: a window reaching the neighbouring corners biases the corner.
    """
    if len(corners) == spec.n_corners:
        grid = corners.reshape(spec.rows, spec.cols, 2)
        spacing = float(np.min(np.linalg.norm(np.diff(grid, axis=1), axis=2)))
        spacing = min(spacing, float(np.min(np.linalg.norm(np.diff(grid, axis=0), axis=2))))
    else:
        d = np.linalg.norm(corners[:, None] - corners[None], axis=2)
        d[d == 0] = np.inf
        spacing = float(np.min(d))
    fraction = 0.35
    if spec.kind == "charuco":
        # Only the ring between the corner and its markers is plain chessboard.
        marker = spec.marker if spec.marker > 0 else 0.7 * spec.square
        fraction = min(fraction, 0.5 * (1.0 - marker / spec.square))
    return int(max(2, min(11, math.ceil(spacing * fraction))))


_SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 40, 0.001)


def detect_board(image: np.ndarray, spec: BoardSpec, search_max_side: int = 1000,
                 fast_check: bool = True,
                 subpix_half_window: int | None = None) -> BoardDetection | None:
    """Find the board; sub-pixel corners at full resolution, or None when it is not found.

    ``fast_check`` makes frames without a board cheap to reject (live use); the offline CLI can
    turn it off to be thorough. ``subpix_half_window`` fixes the cornerSubPix half-window
    (OpenCV's stereo sample uses 11); None adapts it to the board's size in the image.
    """
    gray = to_gray(image)
    h, w = gray.shape[:2]
    scale = min(1.0, search_max_side / float(max(h, w)))
    small = gray if scale == 1.0 else cv2.resize(gray, (round(w * scale), round(h * scale)),
                                                 interpolation=cv2.INTER_AREA)
    if spec.kind == "chessboard":
        flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
        if fast_check:
            flags |= cv2.CALIB_CB_FAST_CHECK
        found, corners = cv2.findChessboardCorners(small, spec.pattern_size, flags=flags)
        if not found or corners is None:
            return None
        ids = np.arange(spec.n_corners, dtype=np.int32)
    else:
        detector = cv2.aruco.CharucoDetector(spec.charuco_board())
        corners, ids, _, _ = detector.detectBoard(small)
        if corners is None or ids is None or len(ids) < 6:
            return None
        ids = ids.reshape(-1).astype(np.int32)
    corners = corners.reshape(-1, 1, 2).astype(np.float32)
    if scale != 1.0:
        # Pixel centres: (x + 0.5) / scale - 0.5 maps a downscaled pixel to full resolution.
        corners = (corners + 0.5) / np.float32(scale) - 0.5
    win = subpix_half_window or _subpix_window(corners.reshape(-1, 2), spec)
    corners = cv2.cornerSubPix(gray, corners, (win, win), (-1, -1), _SUBPIX_CRITERIA)
    return BoardDetection(corners=corners.reshape(-1, 2), ids=ids, image_size=(w, h),
                          n_expected=spec.n_corners)


# ---- per-view quality -----------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class QualityLimits:
    """Thresholds of the per-view checks (full-resolution pixels unless a fraction)."""

    border_margin_frac: float = 0.015   # corners closer than this × min(w, h) to an edge
    border_margin_min_px: float = 4.0
    blur_max_px: float = 4.0            # edge transition width allowed (OpenCV: "below ~3")
    blur_max_square_frac: float = 0.15  # … or this fraction of a square, if larger
    still_max_frac: float = 0.002       # mean corner motion between frames × image diagonal
    still_max_min_px: float = 1.0
    min_visible_fraction: float = 1.0   # ChArUco: share of corners that must be seen


def edge_width_px(gray: np.ndarray, det: BoardDetection, spec: BoardSpec) -> float:
    """Width of the black→white transition (px), the worse of the two directions; nan if n/a.

    OpenCV's ``estimateChessboardSharpness``: below ~3 px is sharp. Motion blur only widens
    edges across the motion, hence the worse of horizontal and vertical.
    """
    if not det.complete or spec.kind != "chessboard":
        return float("nan")
    pts = det.corners.reshape(-1, 1, 2)
    try:
        horizontal = cv2.estimateChessboardSharpness(gray, spec.pattern_size, pts)[0][0]
        vertical = cv2.estimateChessboardSharpness(gray, spec.pattern_size, pts,
                                                   vertical=True)[0][0]
    except cv2.error:
        return float("nan")
    return float(max(horizontal, vertical))


def board_motion_px(det: BoardDetection, previous: BoardDetection | None) -> float:
    """Mean displacement of the common corners since the previous frame (px); nan if unknown."""
    if previous is None:
        return float("nan")
    common, a, b = np.intersect1d(det.ids, previous.ids, return_indices=True)
    if len(common) == 0:
        return float("nan")
    return float(np.mean(np.linalg.norm(det.corners[a] - previous.corners[b], axis=1)))


def check_view(det: BoardDetection | None, gray: np.ndarray | None, spec: BoardSpec,
               previous: BoardDetection | None = None,
               limits: QualityLimits = QualityLimits(), require_still: bool = True) -> list[str]:
    """Every reason this view is not fit for calibration; an empty list means it is good.

    The checks: board found, whole board visible, not touching the image border, sharp, and
    (when ``require_still`` and the previous frame's detection is given) not moving.
    """
    if det is None:
        return ["board not found"]
    reasons: list[str] = []
    w, h = det.image_size
    seen = len(det.ids) / det.n_expected
    if seen < limits.min_visible_fraction:
        reasons.append(f"only {len(det.ids)} of {det.n_expected} corners visible: "
                       f"show the whole board")
    margin = max(limits.border_margin_min_px, limits.border_margin_frac * min(w, h))
    xs, ys = det.corners[:, 0], det.corners[:, 1]
    gaps = {"left": float(xs.min()), "right": float(w - 1 - xs.max()),
            "top": float(ys.min()), "bottom": float(h - 1 - ys.max())}
    close = [side for side, gap in gaps.items() if gap < margin]
    if close:
        reasons.append(f"board at the {' and '.join(close)} image border "
                       f"(closer than {margin:.0f} px): move it inwards")
    if gray is not None:
        width = edge_width_px(gray, det, spec)
        limit = max(limits.blur_max_px, limits.blur_max_square_frac * det.square_px(spec))
        if width > limit:
            reasons.append(f"blurred (edges {width:.1f} px wide, limit {limit:.1f} px): "
                           f"hold the board still or add light")
    if require_still and previous is not None:
        motion = board_motion_px(det, previous)
        limit = max(limits.still_max_min_px, limits.still_max_frac * math.hypot(w, h))
        if math.isfinite(motion) and motion > limit:
            reasons.append(f"board moving ({motion:.1f} px since the last frame, limit "
                           f"{limit:.1f} px): hold it still")
    return reasons

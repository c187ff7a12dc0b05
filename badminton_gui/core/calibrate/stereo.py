"""Stereo calibration: from board views to a rig file, with honest figures and reasons.

Why this file exists: the calibration wizard and the ``calibrate`` CLI run exactly this code;
the wizard only renders it. It holds

* :class:`StereoView` (one board seen by both cameras) and :func:`pair_detections`,
* :class:`CaptureGate`, the live capture decision (quality reasons + novelty + coverage),
* :func:`solve_stereo`: per-camera ``calibrateCameraExtended`` → ``stereoCalibrateExtended``
  → outlier rejection and re-solve → ``stereoRectify`` → :class:`CalibrationResult`,
  with a progress callback and a cancel flag checked between stages,
* :func:`rectified_preview`, the rectified pair with horizontal lines.

Board detection and per-view checks live in ``board``, coverage in ``coverage``, the court
pose (left camera in the court frame from clicked points) in ``court_pose``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Sequence

import cv2
import numpy as np

from .board import (BoardDetection, BoardSpec, QualityLimits, check_view,  # noqa: F401
                          detect_board, to_gray, charuco_available, BoardError)
from .coverage import Coverage, coverage, detection_params, novelty
from ..rig import StereoRig

ProgressCallback = Callable[[float, str], None]
CancelFlag = Callable[[], bool]

# Epipolar error scale shown to the user (px): below the first is excellent, below the second
# acceptable.
EPIPOLAR_EXCELLENT_PX = 0.1
EPIPOLAR_ACCEPTABLE_PX = 0.25


class CalibrationError(RuntimeError):
    """The solve cannot give a usable rig; the message says why and what to do."""


class CalibrationCancelled(RuntimeError):
    """The user cancelled the solve."""


def epipolar_grade(error_px: float) -> str:
    """"excellent" / "acceptable" / "poor" on the scale < 0.1 px / < 0.25 px."""
    if error_px < EPIPOLAR_EXCELLENT_PX:
        return "excellent"
    if error_px < EPIPOLAR_ACCEPTABLE_PX:
        return "acceptable"
    return "poor"


# ---- views ----------------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class StereoView:
    """One board pose seen by both cameras: corners of the ids both saw, in the same order."""

    view_id: str
    object_points: np.ndarray    # (N, 3) float32, metres
    left: np.ndarray             # (N, 2) float32 px
    right: np.ndarray            # (N, 2) float32 px


def pair_detections(view_id: str, left: BoardDetection, right: BoardDetection,
                    spec: BoardSpec) -> StereoView:
    """Match the two detections by corner id → StereoView.

    A chessboard's corner order is only defined up to a half turn; when one camera's order runs
    the other way round (the first→last corner vectors point in opposite directions), the right
    camera's corners are reversed so that both lists describe the same physical corners.
    """
    common, a, b = np.intersect1d(left.ids, right.ids, return_indices=True)
    if len(common) < 6:
        raise CalibrationError(f"view {view_id}: only {len(common)} corners seen by both cameras")
    pl = left.corners[a]
    pr = right.corners[b]
    if spec.kind == "chessboard" and len(common) == spec.n_corners:
        if float(np.dot(pl[-1] - pl[0], pr[-1] - pr[0])) < 0:
            pr = pr[::-1].copy()
    obj = spec.object_points()[common]
    return StereoView(str(view_id), obj.astype(np.float32), pl.astype(np.float32),
                      pr.astype(np.float32))


# ---- live capture decision ------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class CaptureVerdict:
    """What the capture gate thinks of the current frame pair."""

    found_left: bool
    found_right: bool
    reasons: tuple[str, ...]      # why this frame cannot be captured (empty: it can)
    is_new: bool                  # adds pose diversity compared with the captured views
    novelty_distance: float

    @property
    def acceptable(self) -> bool:
        """Good enough for a manual capture (quality only)."""
        return not self.reasons

    @property
    def auto_capture(self) -> bool:
        """Good and new: the wizard captures it by itself."""
        return not self.reasons and self.is_new


@dataclass
class CaptureGate:
    """Decides, frame after frame, whether a stereo frame pair is worth capturing.

    Mutable by design (it accumulates captured views); it belongs to one worker thread, and the
    values it hands out (:class:`CaptureVerdict`, :class:`Coverage`) are frozen.
    """

    spec: BoardSpec
    limits: QualityLimits = QualityLimits()
    min_novelty: float = 0.2
    captured_params: list = field(default_factory=list)   # 8-vectors (left 4 + right 4)
    _previous: tuple = (None, None)

    def evaluate(self, left: BoardDetection | None, right: BoardDetection | None,
                 gray_left: np.ndarray | None = None,
                 gray_right: np.ndarray | None = None) -> CaptureVerdict:
        """Check one frame pair; remembers it as "previous" for the stillness check."""
        prev_l, prev_r = self._previous
        self._previous = (left, right)
        reasons: list[str] = []
        for name, det, gray, prev in (("left", left, gray_left, prev_l),
                                      ("right", right, gray_right, prev_r)):
            for reason in check_view(det, gray, self.spec, prev, self.limits,
                                     require_still=True):
                reasons.append(f"{name}: {reason}")
            if det is not None and prev is None:
                reasons.append(f"{name}: waiting for a second frame to check that the board "
                               f"is still")
        params = self._params(left, right)
        if params is None:
            return CaptureVerdict(left is not None, right is not None, tuple(reasons), False,
                                  float("nan"))
        verdict = novelty(params, self.captured_params, self.min_novelty)
        return CaptureVerdict(True, True, tuple(reasons), verdict.is_new, verdict.distance)

    def _params(self, left, right):
        if left is None or right is None:
            return None
        pl = detection_params(left, self.spec)
        pr = detection_params(right, self.spec)
        if pl is None or pr is None:
            return None
        return pl.as_tuple() + pr.as_tuple()

    def add(self, left: BoardDetection, right: BoardDetection) -> None:
        """Record a captured pair (its parameters count for coverage from now on)."""
        params = self._params(left, right)
        if params is not None:
            self.captured_params.append(params)

    def remove(self, index: int) -> None:
        del self.captured_params[index]

    def coverage(self) -> tuple[Coverage, Coverage]:
        """Coverage bars (left, right) of the captured views."""
        from .coverage import ViewParams
        left = [ViewParams(*p[:4]) for p in self.captured_params]
        right = [ViewParams(*p[4:]) for p in self.captured_params]
        return coverage(left), coverage(right)


# ---- the solve ------------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class SolveOptions:
    """Choices of the solve (the defaults suit a hand-held board and a rigid stereo rig)."""

    min_views: int = 5
    outlier_factor: float = 2.0        # reject a view whose error > factor × median …
    outlier_min_px: float = 1.0        # … and > this (never reject good views of a good solve)
    max_rejection_rounds: int = 3
    intrinsics: str = "auto"           # "auto" | "fix" | "refine" in the stereo step
    rectify_alpha: float = 0.0         # stereoRectify alpha: 0 = only valid pixels
    max_rectify_angle_deg: float = 45.0  # beyond this between optical axes: no rectification


@dataclass(frozen=True, slots=True)
class ViewError:
    """Reprojection and epipolar error of one view (px)."""

    view_id: str
    left_px: float
    right_px: float
    epipolar_px: float

    @property
    def rms_px(self) -> float:
        return math.sqrt(0.5 * (self.left_px ** 2 + self.right_px ** 2))


@dataclass(frozen=True, slots=True)
class RejectedView:
    view_id: str
    reason: str


@dataclass(frozen=True, slots=True)
class CalibrationResult:
    """Everything the solve found; ``to_rig()`` gives the rig the tracker uses."""

    board: BoardSpec
    image_size: tuple[int, int]
    M1: np.ndarray
    D1: np.ndarray
    M2: np.ndarray
    D2: np.ndarray
    R: np.ndarray
    T: np.ndarray
    R1: np.ndarray | None
    R2: np.ndarray | None
    P1: np.ndarray | None
    P2: np.ndarray | None
    Q: np.ndarray | None
    rectification_note: str            # why R1..Q are absent, or a note on them
    rms_left: float                    # per-camera calibration RMS (px)
    rms_right: float
    rms_stereo: float                  # stereoCalibrate RMS (px)
    epipolar_px: float                 # mean distance of corners to their epipolar lines
    view_errors: tuple[ViewError, ...]
    rejected: tuple[RejectedView, ...]
    std_left: dict                     # one-sigma uncertainty: fx fy cx cy k1 k2 p1 p2 k3
    std_right: dict
    baseline_std: float                # standard error of the baseline from per-view poses
    intrinsics_mode: str               # "fixed" or "refined" in the stereo step, and why

    @property
    def baseline(self) -> float:
        return float(np.linalg.norm(self.T))

    @property
    def rectified(self) -> bool:
        return self.P1 is not None

    @property
    def epipolar_grade(self) -> str:
        return epipolar_grade(self.epipolar_px)

    def to_rig(self) -> StereoRig:
        return StereoRig(M1=self.M1, D1=self.D1, M2=self.M2, D2=self.D2, R=self.R, T=self.T,
                         image_size=self.image_size, R1=self.R1, R2=self.R2, P1=self.P1,
                         P2=self.P2, Q=self.Q)

    def summary_lines(self) -> list[str]:
        """Human-readable figures (the CLI prints them; the wizard shows the same)."""
        lines = [
            f"board: {self.board.describe()}; image {self.image_size[0]}×{self.image_size[1]}",
            f"views used: {len(self.view_errors)}, rejected: {len(self.rejected)}",
            f"RMS reprojection error: left {self.rms_left:.3f} px, right "
            f"{self.rms_right:.3f} px, stereo {self.rms_stereo:.3f} px",
            f"epipolar error: {self.epipolar_px:.3f} px ({self.epipolar_grade}; < "
            f"{EPIPOLAR_ACCEPTABLE_PX} px acceptable, < {EPIPOLAR_EXCELLENT_PX} px excellent)",
            f"baseline: {self.baseline:.4f} m ± {self.baseline_std:.4f} "
            f"({self.baseline / self.board.square:.3f} squares); "
            f"T = [{', '.join(f'{v:.4f}' for v in self.T)}]",
        ]
        for name, m, std in (("left", self.M1, self.std_left), ("right", self.M2, self.std_right)):
            # Values after the stereo step; ± is the per-camera calibration's one sigma.
            lines.append(
                f"{name}: fx {m[0, 0]:.2f} ± {std['fx']:.2f}, "
                f"fy {m[1, 1]:.2f} ± {std['fy']:.2f}, "
                f"cx {m[0, 2]:.2f} ± {std['cx']:.2f}, cy {m[1, 2]:.2f} ± {std['cy']:.2f} px")
        lines.append(f"intrinsics in the stereo step: {self.intrinsics_mode}; ± = one sigma "
                     f"of the per-camera calibration")
        lines.append(f"rectification: {self.rectification_note}")
        return lines


_STD_NAMES = ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3")


def _calibrate_camera(obj, img, size):
    rms, k, d, rvecs, tvecs, std_int, _std_ext, per_view = cv2.calibrateCameraExtended(
        obj, img, size, None, None)
    std = {n: float(v) for n, v in zip(_STD_NAMES, np.asarray(std_int).ravel())}
    return float(rms), k, d, rvecs, tvecs, std, np.asarray(per_view).ravel()


def _per_view_baselines(rv_l, tv_l, rv_r, tv_r) -> np.ndarray:
    """|T| implied by each view's two independent board poses (right ← left)."""
    out = []
    for a, b, c, d in zip(rv_l, tv_l, rv_r, tv_r):
        r_l = cv2.Rodrigues(a)[0]
        r_r = cv2.Rodrigues(c)[0]
        r_rel = r_r @ r_l.T
        out.append(np.linalg.norm(d.reshape(3) - r_rel @ b.reshape(3)))
    return np.array(out)


def _rectify(k1, d1, k2, d2, size, r, t, options: SolveOptions):
    """stereoRectify, or (None × 5, reason) when the rig geometry makes it degenerate."""
    angle = math.degrees(np.linalg.norm(cv2.Rodrigues(r)[0]))
    t_unit = t.reshape(3) / max(np.linalg.norm(t), 1e-12)
    if angle > options.max_rectify_angle_deg:
        return None, (f"not computed: the optical axes differ by {angle:.0f}° (more than "
                      f"{options.max_rectify_angle_deg:.0f}°; cameras facing each other cannot "
                      f"be rectified). The rig triangulates without it.")
    if abs(t_unit[2]) > 0.7:
        return None, ("not computed: the baseline points mostly along the optical axis "
                      f"(|Tz|/|T| = {abs(t_unit[2]):.2f}); epipoles inside the image make "
                      "rectification degenerate. The rig triangulates without it.")
    r1, r2, p1, p2, q, roi1, roi2 = cv2.stereoRectify(
        k1, d1, k2, d2, size, r, t, flags=cv2.CALIB_ZERO_DISPARITY, alpha=options.rectify_alpha)
    mats = (r1, r2, p1, p2, q)
    if not all(np.all(np.isfinite(m)) for m in mats) or p1[0, 0] <= 0:
        return None, "not computed: stereoRectify returned a degenerate result"
    if roi1[2] * roi1[3] == 0 or roi2[2] * roi2[3] == 0:
        return None, ("not computed: no image area stays valid after rectification (the views "
                      "overlap too little)")
    return mats, (f"computed (alpha {options.rectify_alpha:g}); valid areas "
                  f"{roi1[2]}×{roi1[3]} and {roi2[2]}×{roi2[3]} px")


def _epipolar_per_view(rig: StereoRig, views: Sequence[StereoView]) -> list[float]:
    """Mean symmetric distance (px, undistorted) of each view's corners to epipolar lines."""
    out = []
    for v in views:
        errs = rig.epipolar_errors(v.left, v.right)
        out.append(float(np.mean(np.diag(errs))))
    return out


@dataclass(slots=True)
class _Round:
    """One solve of the active views: both cameras' fits and the stereo fit with them fixed."""
    obj: list
    img_l: list
    img_r: list
    left: tuple            # calibrateCameraExtended's output for the left camera
    right: tuple           # ... and for the right one
    fixed: tuple           # stereoCalibrateExtended with CALIB_FIX_INTRINSIC


def _check_views(active: list[StereoView], options: SolveOptions) -> None:
    if len(active) < options.min_views:
        raise CalibrationError(f"only {len(active)} usable view(s); at least "
                               f"{options.min_views} are needed: capture more board poses")
    if len({v.view_id for v in active}) != len(active):
        raise CalibrationError("two views share the same id")


def _solve_round(active: list[StereoView], size, report, check_cancel, base: float,
                 span: float) -> _Round:
    """Each camera on its own, then the pair with those intrinsics fixed."""
    report(base, f"calibrating the left camera ({len(active)} views)")
    obj = [v.object_points for v in active]
    img_l = [v.left.reshape(-1, 1, 2) for v in active]
    img_r = [v.right.reshape(-1, 1, 2) for v in active]
    try:
        left = _calibrate_camera(obj, img_l, size)
        check_cancel()
        report(base + span * 0.3, "calibrating the right camera")
        right = _calibrate_camera(obj, img_r, size)
        check_cancel()
        report(base + span * 0.6, "calibrating the stereo pair")
        fixed = cv2.stereoCalibrateExtended(
            obj, img_l, img_r, left[1], left[2], right[1], right[2], size, None, None,
            flags=cv2.CALIB_FIX_INTRINSIC)
    except cv2.error as exc:
        raise CalibrationError("OpenCV could not solve the calibration ("
                               f"{str(exc).strip().splitlines()[-1]}): capture more "
                               "varied views") from None
    return _Round(obj, img_l, img_r, left, right, fixed)


def _outliers(active: list[StereoView], fixed, options: SolveOptions):
    """The views to drop this round (worst first, keeping ``min_views``), with their reasons."""
    per_view = np.asarray(fixed[11]).reshape(-1, 2)
    rms_each = np.sqrt(0.5 * (per_view[:, 0] ** 2 + per_view[:, 1] ** 2))
    median = float(np.median(rms_each))
    limit = max(options.outlier_factor * median, options.outlier_min_px)
    worst_first = np.argsort(-rms_each)
    to_reject = [i for i in worst_first if rms_each[i] > limit]
    room = len(active) - options.min_views
    to_reject = to_reject[:max(room, 0)]
    reasons = [RejectedView(
        active[i].view_id,
        f"reprojection error {rms_each[i]:.2f} px (left {per_view[i, 0]:.2f}, right "
        f"{per_view[i, 1]:.2f}) > limit {limit:.2f} px = max({options.outlier_factor:g}"
        f" × median {median:.2f}, {options.outlier_min_px:g})") for i in to_reject]
    return to_reject, reasons


def _solve_rejecting_outliers(views, size, options: SolveOptions, report, check_cancel):
    """Solve, drop the outlier views, re-solve, for up to ``max_rejection_rounds`` rounds."""
    active = list(views)
    rejected: list[RejectedView] = []
    _check_views(active, options)
    rounds = options.max_rejection_rounds + 1
    for round_index in range(rounds):
        check_cancel()
        solved = _solve_round(active, size, report, check_cancel, round_index / rounds * 0.8,
                              0.8 / rounds)
        to_reject, reasons = _outliers(active, solved.fixed, options)
        if not to_reject or round_index == rounds - 1:
            break
        rejected.extend(reasons)
        drop = set(to_reject)
        active = [v for i, v in enumerate(active) if i not in drop]
    return active, rejected, solved


def _choose_intrinsics(solved: _Round, active, size, options: SolveOptions):
    """Fixed or jointly refined intrinsics: ``(rms, m1, d1, m2, d2, R, T, per_view, mode)``.

    Fixed intrinsics are the safe choice: each camera's intrinsics were fitted on all its
    views. Refining them jointly can lower the stereo error when there are enough varied
    views, but with few views it trades intrinsic accuracy for a smaller residual; accept
    the refinement only when it helps and moves the focal lengths by < 2 %.
    """
    fixed, k1, d1, k2, d2 = solved.fixed, *solved.left[1:3], *solved.right[1:3]
    chosen = (float(fixed[0]), k1, d1, k2, d2, fixed[5], fixed[6],
              np.asarray(fixed[11]).reshape(-1, 2))
    mode = "fixed (per-camera intrinsics kept)"
    if options.intrinsics == "refine" or (options.intrinsics == "auto" and len(active) >= 10):
        try:
            refined = cv2.stereoCalibrateExtended(
                solved.obj, solved.img_l, solved.img_r, k1.copy(), d1.copy(), k2.copy(),
                d2.copy(), size, None, None, flags=cv2.CALIB_USE_INTRINSIC_GUESS)
        except cv2.error:
            refined = None
        if refined is not None:
            shift = max(abs(refined[1][0, 0] / k1[0, 0] - 1), abs(refined[3][0, 0] / k2[0, 0] - 1))
            if options.intrinsics == "refine" or (refined[0] <= chosen[0] and shift < 0.02):
                chosen = (float(refined[0]), *refined[1:7], np.asarray(refined[11]).reshape(-1, 2))
                mode = (f"refined jointly ({len(active)} views; focal lengths moved "
                        f"{shift * 100:.2f} %)")
            else:
                mode = (f"fixed (joint refinement gave RMS {refined[0]:.3f} px and moved focal "
                        f"lengths {shift * 100:.2f} %: not better)")
    elif options.intrinsics == "auto":
        mode = f"fixed (only {len(active)} views; joint refinement needs ≥ 10)"
    return (*chosen, mode)


def _refuse_one_camera(tv_l, T) -> None:
    """Identical left and right images (one camera's views given twice) solve "perfectly"
    with T = 0 and an epipolar error of 0: refuse rather than report an excellent rig."""
    distance = float(np.median([np.linalg.norm(t) for t in tv_l]))
    if float(np.linalg.norm(T)) < 1e-3 * distance:
        raise CalibrationError(
            f"the two cameras came out at the same place (baseline "
            f"{float(np.linalg.norm(T)):.2g} m, board {distance:.2g} m away): the left and right "
            f"images look like the same camera's; check that the right images come from the "
            f"right camera")


def solve_stereo(views: Sequence[StereoView], image_size: tuple[int, int], board: BoardSpec,
                 options: SolveOptions = SolveOptions(),
                 progress: ProgressCallback | None = None,
                 cancel: CancelFlag | None = None) -> CalibrationResult:
    """Calibrate both cameras and their relative pose from paired board views.

    Stages (progress fractions are approximate): per-camera calibration, stereo calibration,
    outlier rejection (re-solving after each round), rectification, figures. ``cancel`` is
    polled between stages; when it returns True, :class:`CalibrationCancelled` is raised.
    """
    report = progress or (lambda fraction, text: None)
    size = (int(image_size[0]), int(image_size[1]))

    def check_cancel():
        if cancel is not None and cancel():
            raise CalibrationCancelled("calibration cancelled")

    check_cancel()
    active, rejected, solved = _solve_rejecting_outliers(views, size, options, report,
                                                         check_cancel)
    rms_l, _, _, rv_l, tv_l, std_l, _ = solved.left
    rms_r, _, _, rv_r, tv_r, std_r, _ = solved.right

    check_cancel()
    report(0.82, "choosing between fixed and refined intrinsics")
    rms_s, m1, dd1, m2, dd2, R, T, per_view, mode = _choose_intrinsics(solved, active, size,
                                                                       options)
    _refuse_one_camera(tv_l, T)

    check_cancel()
    report(0.88, "rectifying")
    rect, note = _rectify(m1, dd1, m2, dd2, size, R, T, options)

    check_cancel()
    report(0.94, "measuring epipolar errors")
    rig = StereoRig(M1=m1, D1=dd1, M2=m2, D2=dd2, R=R, T=T, image_size=size)
    epi = _epipolar_per_view(rig, active)
    n_pts = np.array([len(v.left) for v in active])
    epi_mean = float(np.sum(np.array(epi) * n_pts) / np.sum(n_pts))
    view_errors = tuple(ViewError(v.view_id, float(e[0]), float(e[1]), float(ep))
                        for v, e, ep in zip(active, per_view, epi))
    baselines = _per_view_baselines(rv_l, tv_l, rv_r, tv_r)
    baseline_std = float(np.std(baselines, ddof=1) / math.sqrt(len(baselines))) \
        if len(baselines) > 1 else float("nan")
    r1 = r2 = p1 = p2 = q = None
    if rect is not None:
        r1, r2, p1, p2, q = rect
    report(1.0, "done")
    return CalibrationResult(
        board=board, image_size=size, M1=m1, D1=dd1.ravel(), M2=m2, D2=dd2.ravel(),
        R=R, T=T.reshape(3), R1=r1, R2=r2, P1=p1, P2=p2, Q=q, rectification_note=note,
        rms_left=rms_l, rms_right=rms_r, rms_stereo=rms_s, epipolar_px=epi_mean,
        view_errors=view_errors, rejected=tuple(rejected), std_left=std_l, std_right=std_r,
        baseline_std=baseline_std, intrinsics_mode=mode)

def rectified_preview(result: CalibrationResult, left: np.ndarray, right: np.ndarray,
                      line_step: int = 32) -> np.ndarray | None:
    """Side-by-side rectified pair with horizontal lines (BGR), or None without rectification.

    On a good calibration every feature lies on the same line in both halves.
    """
    if not result.rectified:
        return None
    size = result.image_size
    halves = []
    for image, m, d, r, p in ((left, result.M1, result.D1, result.R1, result.P1),
                              (right, result.M2, result.D2, result.R2, result.P2)):
        map_x, map_y = cv2.initUndistortRectifyMap(m, d, r, p, size, cv2.CV_32FC1)
        img = image if image.ndim == 3 else cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
        halves.append(cv2.remap(img, map_x, map_y, cv2.INTER_LINEAR))
    out = np.hstack(halves)
    thickness = max(1, round(out.shape[1] / 1000))     # stays visible when shown shrunk
    for y in range(line_step // 2, out.shape[0], line_step):
        cv2.line(out, (0, y), (out.shape[1] - 1, y), (0, 200, 0), thickness)
    return out

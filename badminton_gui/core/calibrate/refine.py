"""Self-calibration: refine a rig's relative pose from points both cameras saw.

Why this file exists: a rig put together from two cameras calibrated separately against the
court (the NYCU recordings' ``.cfg`` pair, io/nycu.py) carries both cameras' pose errors into
their relative pose. On the NYCU rallies the labelled shuttle misses its partner's epipolar line
by 34 px (median; p90 98 px) with the imported rig, where a good rig gives a pixel or two — so
the epipolar gate must be learnt wide (≈ 75 px), pairs beyond it get no 3D point, and wrong
partners inside it get one. A tracked shuttle provides hundreds of correspondences a minute:
the essential matrix fitted to them (five-point RANSAC on undistorted, normalised points) gives
the rotation and the direction of the baseline. The intrinsics, the baseline's length (the
metric scale, which point pairs cannot give) and the left camera's court pose are kept, so the
court frame stays where it was.

A rig whose pairs already miss their epipolar lines by less than ``min_error_px`` (median) is
kept as it is: a detected centroid is itself uncertain by about a pixel, so a refit below that
fits the detections' noise (the demo court's true rig was "improved" 0.30 → 0.06 px).
Otherwise a refit is only accepted when it is clearly better on the pairs it was fitted to (median
epipolar error at least ``min_improvement`` times smaller), when most pairs agree with it, when
the pairs spread over the image (a single flight lies in one plane, which leaves the essential
matrix ambiguous), and when it does not turn the rig by more than ``max_rotation_deg``.

The desktop application runs the refit on a worker thread while tracking goes on
(gui/refine_dialog.py): ``progress`` reports its stages and ``cancel`` stops it between them
(and between polishing iterations) with :class:`RefineCancelled`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Callable

import cv2
import numpy as np

from ..rig import StereoRig

# The fewest pairs a refit looks at, and the share of the image's width and height the agreeing
# pairs must span in both cameras (``refine_relative_pose``'s defaults; the GUI's refine dialog
# shows the collection against them).
DEFAULT_MIN_PAIRS = 100
DEFAULT_MIN_SPREAD = 0.1


class RefineCancelled(Exception):
    """The refit stopped because its ``cancel`` callable said so; nothing was changed."""


@dataclass(frozen=True, slots=True)
class RefineReport:
    """What a refinement found; ``accepted`` says whether ``rig`` is the refined one."""

    pairs: int
    inliers: int
    before_median_px: float
    after_median_px: float
    before_p90_px: float
    after_p90_px: float
    rotation_change_deg: float
    baseline_turn_deg: float
    # The last third of the pairs under a refit of the first two thirds (median px), and the
    # same pairs under the original rig.
    held_back_before_px: float
    held_back_after_px: float
    accepted: bool
    reason: str

    def summary(self) -> str:
        verdict = "refined" if self.accepted else f"kept the rig ({self.reason})"
        return (f"{self.pairs} pairs, {self.inliers} agree with the refit; epipolar error median "
                f"{self.before_median_px:.1f} → {self.after_median_px:.1f} px, p90 "
                f"{self.before_p90_px:.1f} → {self.after_p90_px:.1f} px (last third under a refit of "
                f"the rest {self.held_back_before_px:.1f} → {self.held_back_after_px:.1f} px); "
                f"rotation changed by "
                f"{self.rotation_change_deg:.2f}°, baseline turned by {self.baseline_turn_deg:.2f}°: "
                f"{verdict}")


def refine_relative_pose(rig: StereoRig, pts_left, pts_right, *, threshold_px: float = 3.0,
                         min_pairs: int = DEFAULT_MIN_PAIRS, min_improvement: float = 2.0,
                         min_inlier_share: float = 0.3, min_spread: float = DEFAULT_MIN_SPREAD,
                         max_rotation_deg: float = 30.0, min_error_px: float = 1.0,
                         progress: Callable[[float, str], None] | None = None,
                         cancel: Callable[[], bool] | None = None) -> tuple[StereoRig, RefineReport]:
    """The rig with R and T's direction refitted to the matched pixel points, and a report.

    ``pts_left`` / ``pts_right``: (N, 2) raw (distorted) pixel positions of the same physical
    points in the two cameras, in time order. ``threshold_px``: RANSAC inlier distance. ``min_spread``: the
    agreeing pairs must cover at least this share of the image's width and of its height in
    both cameras. ``min_error_px``: a rig whose median error is already below this is kept without
a refit. Returns the input rig unchanged (``report.accepted`` False, with the reason)
    when any condition fails. ``progress(fraction, what)`` is called as the stages begin;
    ``cancel()`` is asked between stages and polishing iterations, and True raises
    :class:`RefineCancelled`.
    """

    def check() -> None:
        if cancel is not None and cancel():
            raise RefineCancelled("refit cancelled")

    def stage(fraction: float, what: str) -> None:
        check()
        if progress is not None:
            progress(fraction, what)

    pl = np.asarray(pts_left, dtype=np.float64).reshape(-1, 2)
    pr = np.asarray(pts_right, dtype=np.float64).reshape(-1, 2)
    if len(pl) != len(pr):
        raise ValueError(f"{len(pl)} left points but {len(pr)} right points")
    n = len(pl)
    nan = float("nan")

    split = (2 * n) // 3
    held_back = None

    def report(inliers: int, after: np.ndarray | None, rot: float, turn: float, ok: bool,
               reason: str) -> RefineReport:
        return _report(n, split, before, after, held_back, inliers, rot, turn, ok, reason)

    stage(0.0, "measuring the rig's epipolar error")
    before = rig.pair_errors(pl, pr) if n else np.zeros(0)
    if n < min_pairs:
        return rig, report(0, None, nan, nan, False, f"only {n} pairs, {min_pairs} needed")
    if float(np.median(before)) < min_error_px:
        return rig, report(0, None, nan, nan, False,
                           f"the pairs miss their epipolar lines by {np.median(before):.2f} px "
                           f"(median), under {min_error_px:g} px: the rig already fits")
    stage(0.05, f"fitting the cameras' relative pose to all {n} pairs")
    fitted = _fit_pose(rig, pl, pr, threshold_px, check)
    if fitted is None:
        return rig, report(0, None, nan, nan, False, "no essential matrix fits the pairs")
    # The pairs come in time order: a refit of the first two thirds must also explain the last
    # third (other flights, other planes), or the fit is one flight's ambiguity.
    stage(0.5, "refitting the first two thirds of the pairs to check the last third")
    early = _fit_pose(rig, pl[:split], pr[:split], threshold_px, check)
    stage(0.95, "comparing the errors")
    if early is not None:
        held_back = _with_pose(rig, early[1], early[2]).pair_errors(pl[split:], pr[split:])
    inliers, rot, direction, agree = fitted
    refined = _with_pose(rig, rot, direction)
    after = refined.pair_errors(pl, pr)
    rotation_change, baseline_turn = _pose_change(rig, rot, direction)
    reason = _why_not(rig, pl[agree], pr[agree], before, after, held_back, split, n,
                      int(inliers), rotation_change, min_improvement=min_improvement,
                      min_inlier_share=min_inlier_share, min_spread=min_spread,
                      max_rotation_deg=max_rotation_deg)
    if reason:
        return rig, report(int(inliers), after, rotation_change, baseline_turn, False, reason)
    return refined, report(int(inliers), after, rotation_change, baseline_turn, True, "")


def _report(n: int, split: int, before: np.ndarray, after: np.ndarray | None,
            held_back: np.ndarray | None, inliers: int, rot: float, turn: float, ok: bool,
            reason: str) -> RefineReport:
    """The report's figures: before/after percentiles and the held-back third's medians."""
    nan = float("nan")
    b50, b90 = (np.percentile(before, [50, 90]) if n else (nan, nan))
    a50, a90 = (np.percentile(after, [50, 90]) if after is not None and n else (nan, nan))
    hb = float(np.median(before[split:])) if n > split else nan
    ha = float(np.median(held_back)) if held_back is not None and len(held_back) else nan
    return RefineReport(n, inliers, float(b50), float(a50), float(b90), float(a90), rot, turn,
                        hb, ha, ok, reason)


def _pose_change(rig: StereoRig, rot: np.ndarray, direction: np.ndarray) -> tuple[float, float]:
    """How far the refit turns the rig (degrees) and turns its baseline's direction (degrees)."""
    scale = float(np.linalg.norm(rig.T))
    rotation_change = math.degrees(float(np.linalg.norm(cv2.Rodrigues(rot @ rig.R.T)[0])))
    cos_turn = float(np.dot(direction, rig.T / scale)) if scale > 0 else 1.0
    return rotation_change, math.degrees(math.acos(max(-1.0, min(1.0, cos_turn))))


def _why_not(rig: StereoRig, agree_left: np.ndarray, agree_right: np.ndarray,
             before: np.ndarray, after: np.ndarray, held_back: np.ndarray | None, split: int,
             n: int, inliers: int, rotation_change: float, *, min_improvement: float,
             min_inlier_share: float, min_spread: float, max_rotation_deg: float) -> str:
    """Why the refit is refused (the first failing condition), or "" when it is accepted."""

    def spread(points: np.ndarray) -> float:
        return min(image_spread(points, rig.image_size))

    reason = ""
    if not np.median(after) * min_improvement <= np.median(before):
        reason = (f"the median error would go {np.median(before):.1f} → {np.median(after):.1f} px, "
                  f"less than {min_improvement:g}× better: the rig already fits")
    elif inliers < min_inlier_share * n:
        reason = f"only {inliers} of {n} pairs agree with the refit"
    elif min(spread(agree_left), spread(agree_right)) < min_spread:
        reason = "the pairs cover too little of the image"
    elif held_back is None or not (np.median(held_back) * min_improvement
                                   <= np.median(before[split:])):
        reason = ("a refit of the first two thirds of the pairs does not explain the last third "
                  "(too few flights, or one flight's plane leaves the fit ambiguous)")
    elif rotation_change > max_rotation_deg:
        reason = f"the refit turns the rig by {rotation_change:.1f}° (> {max_rotation_deg:g}°)"
    return reason


def image_spread(points, image_size: tuple[int, int]) -> tuple[float, float]:
    """The share of the image's width and of its height that the points span (5th to 95th
    percentile, so a few stray pairs do not count); (0, 0) for fewer than two points."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if len(pts) < 2:
        return 0.0, 0.0
    w, h = image_size
    lo, hi = np.percentile(pts, [5, 95], axis=0)
    return float((hi[0] - lo[0]) / w), float((hi[1] - lo[1]) / h)


def _fit_pose(rig: StereoRig, pl: np.ndarray, pr: np.ndarray, threshold_px: float,
              check: Callable[[], None] | None = None):
    """(agreeing pairs, R, unit T, agreement mask) of the essential matrix that most pairs agree
    with (five-point RANSAC on undistorted normalised points), or None. ``check()`` is called
    between the steps (it raises to cancel)."""
    if len(pl) < 5:
        return None
    nl = rig.undistort(0, pl)
    nr = rig.undistort(1, pr)
    focal = float(np.mean([rig.M1[0, 0], rig.M1[1, 1], rig.M2[0, 0], rig.M2[1, 1]]))
    essentials, inlier_mask = cv2.findEssentialMat(nl, nr, np.eye(3), method=cv2.RANSAC,
                                                   prob=0.999, threshold=threshold_px / focal)
    if essentials is None or inlier_mask is None:
        return None
    if check is not None:
        check()
    best = None
    # Few points can leave several solutions stacked (3k × 3): keep the one most pairs agree with.
    for k in range(0, essentials.shape[0] - 2, 3):
        good, rot, trans, mask = cv2.recoverPose(essentials[k:k + 3], nl, nr, np.eye(3),
                                                 mask=inlier_mask.copy())
        if best is None or good > best[0]:
            best = (int(good), rot, trans.ravel(), mask.ravel() > 0)
    good, rot, direction, agree = best
    rot, direction, cost = _polish(rig, pl[agree], pr[agree], rot, direction, threshold_px,
                                   check=check)
    # Pairs near one surface (a few flights) admit two poses; RANSAC may pick the one far from
    # the rig. The rig's own pose, polished on the same pairs, wins unless clearly worse.
    scale = float(np.linalg.norm(rig.T))
    if scale > 0:
        near_rot, near_dir, near_cost = _polish(rig, pl[agree], pr[agree], rig.R, rig.T / scale,
                                                threshold_px, check=check)
        if near_cost <= 1.2 * cost:
            rot, direction = near_rot, near_dir
    return good, rot, direction, agree


def _polish(rig: StereoRig, pl: np.ndarray, pr: np.ndarray, rot: np.ndarray,
            direction: np.ndarray, threshold_px: float, iterations: int = 15,
            check: Callable[[], None] | None = None) -> tuple[np.ndarray, np.ndarray, float]:
    """Gauss–Newton on the pairs' Sampson distances (undistorted pixels, Huber-weighted beyond
    ``threshold_px``) over the rotation (3) and the baseline's direction (2).

    The five-point RANSAC solution rests on five pairs; this spends all the agreeing ones (on a
    short binocular baseline the RANSAC direction is ~2° off, the polished one a few tenths).
    Returns the pose and its cost, the median absolute Sampson distance (px).
    """
    if len(pl) < 8:
        return rot, direction, math.inf
    ul = np.hstack([rig.undistort_pixels(0, pl), np.ones((len(pl), 1))])
    ur = np.hstack([rig.undistort_pixels(1, pr), np.ones((len(pr), 1))])
    k1_inv, k2_inv_t = np.linalg.inv(rig.M1), np.linalg.inv(rig.M2).T

    def pose(params: np.ndarray, base_rot: np.ndarray, base_dir: np.ndarray):
        b1 = np.cross(base_dir, [1.0, 0.0, 0.0] if abs(base_dir[0]) < 0.9 else [0.0, 1.0, 0.0])
        b1 /= np.linalg.norm(b1)
        b2 = np.cross(base_dir, b1)
        d = base_dir + params[3] * b1 + params[4] * b2
        return cv2.Rodrigues(params[:3])[0] @ base_rot, d / np.linalg.norm(d)

    def residuals(r: np.ndarray, d: np.ndarray) -> np.ndarray:
        tx = np.array([[0, -d[2], d[1]], [d[2], 0, -d[0]], [-d[1], d[0], 0]])
        f = k2_inv_t @ tx @ r @ k1_inv
        fl = ul @ f.T
        ftr = ur @ f
        num = np.einsum("ij,ij->i", ur, fl)
        return num / np.sqrt(fl[:, 0] ** 2 + fl[:, 1] ** 2 + ftr[:, 0] ** 2 + ftr[:, 1] ** 2)

    for _ in range(iterations):
        if check is not None:
            check()
        res = residuals(rot, direction)
        scale = np.max(np.abs(res)) + 1e-12
        jac = np.empty((len(res), 5))
        step = 1e-6
        for k in range(5):
            delta = np.zeros(5)
            delta[k] = step
            jac[:, k] = (residuals(*pose(delta, rot, direction)) - res) / step
        weights = np.minimum(1.0, threshold_px / np.maximum(np.abs(res), 1e-12))   # Huber
        jw = jac * weights[:, None]
        try:
            update = np.linalg.solve(jw.T @ jac + 1e-9 * scale * np.eye(5), -(jw.T @ res))
        except np.linalg.LinAlgError:
            break
        rot, direction = pose(update, rot, direction)
        if np.linalg.norm(update) < 1e-10:
            break
    return rot, direction, float(np.median(np.abs(residuals(rot, direction))))


def _with_pose(rig: StereoRig, rot: np.ndarray, direction: np.ndarray) -> StereoRig:
    """The rig with a new relative pose, the baseline's length kept; its rectification is void."""
    scale = float(np.linalg.norm(rig.T))
    return replace(rig, R=rot, T=direction * scale, R1=None, R2=None, P1=None, P2=None, Q=None,
                   _cache={})


class PairCollector:
    """Gathers, from a tracker's results, pairs of detections that are the same shuttle.

    Labels are never read: a pair is kept when both cameras' detections are measured (not a
    coasting prediction) and each has been its camera's detection on the same tracklet for
    ``min_track_frames`` frames in a row — the followed shuttle, not a one-frame blob. The
    epipolar geometry is not asked (it is what is being refitted). A pair is also skipped unless
    the shuttle moved ``min_step_px`` in both images since the last kept pair, so a shuttle at
    rest does not outweigh a flight.
    """

    def __init__(self, min_track_frames: int = 5, min_step_px: float = 1.0,
                 max_pairs: int = 20000) -> None:
        self.min_track_frames = int(min_track_frames)
        self.min_step_px = float(min_step_px)
        self.max_pairs = int(max_pairs)
        self._runs = [(-1, 0), (-1, 0)]     # per camera: (tracklet, frames in a row)
        self._left: list[tuple[float, float]] = []
        self._right: list[tuple[float, float]] = []

    def __len__(self) -> int:
        return len(self._left)

    def add(self, result) -> bool:
        """Look at one ``TrackResult``; True when its pair was kept."""
        dets = (result.left.detection, result.right.detection)
        for cam, det in enumerate(dets):
            if det is None or det.predicted or det.tracklet < 0:
                self._runs[cam] = (-1, 0)
            elif det.tracklet == self._runs[cam][0]:
                self._runs[cam] = (det.tracklet, self._runs[cam][1] + 1)
            else:
                self._runs[cam] = (det.tracklet, 1)
        if min(run for _, run in self._runs) < self.min_track_frames or len(self._left) >= self.max_pairs:
            return False
        left, right = (dets[0].x, dets[0].y), (dets[1].x, dets[1].y)
        if self._left:
            step_l = math.dist(left, self._left[-1])
            step_r = math.dist(right, self._right[-1])
            if min(step_l, step_r) < self.min_step_px:
                return False
        self._left.append(left)
        self._right.append(right)
        return True

    def points(self) -> tuple[np.ndarray, np.ndarray]:
        """(N, 2) left and right pixel points of the kept pairs."""
        return (np.array(self._left, dtype=np.float64).reshape(-1, 2),
                np.array(self._right, dtype=np.float64).reshape(-1, 2))

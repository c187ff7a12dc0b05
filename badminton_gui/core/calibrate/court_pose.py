"""The court pose: the left camera's pose in the court frame from points clicked on the floor.

Why this file exists: after the stereo solve (``stereo``) the wizard asks for ≥ 4 court line
intersections in the left image; this turns those clicks into the rig's court pose.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import cv2
import numpy as np

from ..rig import StereoRig
from .stereo import CalibrationError


@dataclass(frozen=True, slots=True)
class CourtPoseResult:
    rig: StereoRig
    errors_px: np.ndarray      # (N,) reprojection error of each clicked point
    rms_px: float


def solve_court_pose_detailed(rig: StereoRig, left_image_points, court_points) -> CourtPoseResult:
    """Left camera's pose in the court frame from ≥ 4 clicked points (distorted left pixels).

    Court points are usually all on the floor (Z = 0), a plane: IPPE gives the (up to two)
    planar solutions, the one with the smaller reprojection error and the points in front of
    the camera wins, then Levenberg–Marquardt refines it.
    """
    img = np.asarray(left_image_points, np.float64).reshape(-1, 2)
    obj = np.asarray(court_points, np.float64).reshape(-1, 3)
    if len(img) != len(obj):
        raise CalibrationError(f"{len(img)} image points but {len(obj)} court points")
    if len(img) < 4:
        raise CalibrationError(f"the court pose needs at least 4 points, got {len(img)}")
    planar = np.ptp(obj[:, 2]) < 1e-9
    candidates = []
    method = cv2.SOLVEPNP_IPPE if planar else cv2.SOLVEPNP_SQPNP
    try:
        n, rvecs, tvecs, _ = cv2.solvePnPGeneric(obj, img, rig.M1, rig.D1, flags=method)
    except cv2.error as exc:
        raise CalibrationError(f"the court pose could not be solved ("
                               f"{str(exc).strip().splitlines()[-1]}): check the clicked "
                               f"points") from None
    for rvec, tvec in zip(rvecs[:n], tvecs[:n]):
        rvec, tvec = cv2.solvePnPRefineLM(obj, img, rig.M1, rig.D1, rvec.copy(), tvec.copy())
        rot = cv2.Rodrigues(rvec)[0]
        depth = (obj @ rot.T + tvec.reshape(3))[:, 2]
        proj = cv2.projectPoints(obj, rvec, tvec, rig.M1, rig.D1)[0].reshape(-1, 2)
        err = np.linalg.norm(proj - img, axis=1)
        candidates.append((bool(np.all(depth > 0)), float(np.sqrt(np.mean(err ** 2))), rot,
                           tvec.reshape(3), err))
    if not candidates:
        raise CalibrationError("the court pose could not be solved: check the clicked points")
    candidates.sort(key=lambda c: (not c[0], c[1]))
    in_front, rms, rot, tvec, err = candidates[0]
    if not in_front:
        raise CalibrationError("no court pose puts the clicked points in front of the camera: "
                               "check that each click matches the highlighted court point")
    # solvePnP: X_left = rot·X_court + t  →  X_court = rotᵀ·X_left − rotᵀ·t
    r_court = rot.T
    t_court = -rot.T @ tvec
    return CourtPoseResult(rig.with_court_pose(r_court, t_court), err, rms)


def solve_court_pose(rig: StereoRig, left_image_points, court_points) -> StereoRig:
    """The rig with R_court, T_court set (X_court = R_court·X_left + T_court)."""
    return solve_court_pose_detailed(rig, left_image_points, court_points).rig


class CourtClicks:
    """The court-pose step's state: which keypoint to click next, what was clicked.

    The operator clicks keypoints in a fixed order and may skip those not visible; the pose
    can be solved once 4 points are clicked. Mutable, owned by the GUI thread; the wizard draws
    ``current_name`` highlighted on its court drawing.
    """

    DEFAULT_ORDER = ("near back corner left", "near back corner right",
                     "near short service right", "near short service left",
                     "near short service centre", "near back centre", "net foot left",
                     "net foot right", "far short service left", "far short service right",
                     "far back corner left", "far back corner right")

    def __init__(self, order: Sequence[str] = DEFAULT_ORDER) -> None:
        from ..court import court_keypoints
        self.keypoints = court_keypoints()
        unknown = [n for n in order if n not in self.keypoints]
        if unknown:
            raise ValueError(f"unknown court keypoints: {', '.join(unknown)}")
        self.order = tuple(order)
        self.clicked: dict[str, tuple[float, float]] = {}
        self._history: list[str] = []        # clicked or skipped names, in order
        self._position = 0

    @property
    def current_name(self) -> str | None:
        """The keypoint to click next, or None when the list is exhausted."""
        return self.order[self._position] if self._position < len(self.order) else None

    def click(self, x: float, y: float) -> None:
        name = self.current_name
        if name is None:
            return
        self.clicked[name] = (float(x), float(y))
        self._history.append(name)
        self._position += 1

    def skip(self) -> None:
        if self.current_name is not None:
            self._history.append(self.current_name)
            self._position += 1

    def undo(self) -> None:
        if self._history:
            name = self._history.pop()
            self.clicked.pop(name, None)
            self._position -= 1

    @property
    def ready(self) -> bool:
        return len(self.clicked) >= 4

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        names = [n for n in self.order if n in self.clicked]
        return (np.array([self.clicked[n] for n in names], np.float64).reshape(-1, 2),
                np.array([self.keypoints[n] for n in names], np.float64).reshape(-1, 3))

    def solve(self, rig: StereoRig) -> CourtPoseResult:
        image_points, court_points = self.arrays()
        return solve_court_pose_detailed(rig, image_points, court_points)

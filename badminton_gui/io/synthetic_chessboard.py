"""A FrameSource showing a chessboard that moves in front of a known stereo rig.

Why this file exists: calibration needs ground truth to be tested (project through
known cameras, run the pipeline, assert the error bound), and the calibration wizard must be
usable without cameras. The board is rendered exactly through each camera, distortion included:
every output pixel is undistorted to a ray (cached per camera), the ray is intersected with the
board plane, and the board texture is sampled there (``cv2.remap``). Rendering at
``supersample``× and averaging down (INTER_AREA) anti-aliases the edges.

The board holds still at each of a sequence of random poses for ``hold_frames`` frames, then
moves to the next pose over ``move_frames`` frames, the way an operator presents a board.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import cv2
import numpy as np

from ..core.calibrate.board import BoardSpec
from ..core.rig import StereoRig, undistort_points_iterated
from ..core.types import StereoFrame


def default_synthetic_rig(image_size: tuple[int, int] = (640, 480)) -> StereoRig:
    """A plausible parallel rig: 12 cm baseline, slightly different cameras, mild barrel."""
    w, h = image_size
    s = w / 640.0
    m1 = np.array([[620.0 * s, 0, 0.5 * w + 2.0 * s], [0, 618.0 * s, 0.5 * h - 2.0 * s],
                   [0, 0, 1]])
    m2 = np.array([[610.0 * s, 0, 0.5 * w - 2.0 * s], [0, 611.0 * s, 0.5 * h + 2.0 * s],
                   [0, 0, 1]])
    d1 = np.array([-0.08, 0.04, 0.0, 0.0, 0.0])
    d2 = np.array([-0.06, 0.03, 0.0, 0.0, 0.0])
    r = cv2.Rodrigues(np.array([0.01, -0.04, 0.005]))[0]
    centre_right = np.array([0.12, 0.002, -0.003])      # right camera, left-camera frame (m)
    t = -r @ centre_right
    return StereoRig(M1=m1, D1=d1, M2=m2, D2=d2, R=r, T=t, image_size=image_size)


@dataclass(frozen=True, slots=True)
class BoardPose:
    """Board → left camera: X_left = R·X_board + t (board origin at its first inner corner)."""

    rvec: np.ndarray
    tvec: np.ndarray


class SyntheticChessboardSource:
    """FrameSource: a board posed randomly (seeded) in front of ``rig``, rendered exactly."""

    def __init__(self, board: BoardSpec | None = None, rig: StereoRig | None = None,
                 n_poses: int = 30, hold_frames: int = 6, move_frames: int = 6,
                 seed: int = 0, noise_sigma: float = 1.5, supersample: int = 2,
                 loop: bool = True, realtime_fps: float | None = None,
                 distance_range: tuple[float, float] = (0.45, 1.0)) -> None:
        self.board = board or BoardSpec(9, 6, 0.03)
        self.rig = rig or default_synthetic_rig()
        self.name = f"synthetic chessboard ({self.board.cols}×{self.board.rows})"
        self.hold_frames = int(hold_frames)
        self.move_frames = int(move_frames)
        self.noise_sigma = float(noise_sigma)
        self.supersample = int(supersample)
        self.loop = loop
        self.realtime_fps = realtime_fps
        self._rng = np.random.default_rng(seed)
        self._noise_rng = np.random.default_rng(seed + 1)
        self._distance_range = distance_range
        self._texture, self._texture_scale, self._texture_origin = self._make_texture()
        self._rays = [self._pixel_rays(0), self._pixel_rays(1)]
        self.poses = [self._random_pose() for _ in range(n_poses)]
        self._frame = 0
        self._last_time = None
        self._closed = False

    # ---- FrameSource protocol ---------------------------------------------------------------
    @property
    def image_size(self) -> tuple[int, int]:
        return self.rig.image_size

    @property
    def fps(self) -> float | None:
        return self.realtime_fps

    def read(self) -> StereoFrame | None:
        if self._closed:
            return None
        period = self.hold_frames + self.move_frames
        total = period * len(self.poses)
        if self._frame >= total and not self.loop:
            return None
        if self.realtime_fps:
            now = time.monotonic()
            if self._last_time is not None:
                wait = self._last_time + 1.0 / self.realtime_fps - now
                if wait > 0:
                    time.sleep(wait)
            self._last_time = time.monotonic()
        pose = self.pose_at(self._frame)
        left, right = self.render_pair(pose)
        t = self._frame / (self.realtime_fps or 30.0)
        frame = StereoFrame(left, right, t, t, self._frame)
        self._frame += 1
        return frame

    def close(self) -> None:
        self._closed = True

    # ---- poses ------------------------------------------------------------------------------
    def pose_at(self, frame_index: int) -> BoardPose:
        """Hold at pose k, then interpolate linearly (rvec, t) towards pose k+1."""
        period = self.hold_frames + self.move_frames
        k, phase = divmod(frame_index % (period * len(self.poses)), period)
        a = self.poses[k]
        if phase < self.hold_frames:
            return a
        b = self.poses[(k + 1) % len(self.poses)]
        f = (phase - self.hold_frames + 1) / (self.move_frames + 1)
        return BoardPose((1 - f) * a.rvec + f * b.rvec, (1 - f) * a.tvec + f * b.tvec)

    def is_still(self, frame_index: int) -> bool:
        period = self.hold_frames + self.move_frames
        return (frame_index % period) < self.hold_frames

    def _camera_pose(self, camera: int, pose: BoardPose) -> tuple[np.ndarray, np.ndarray]:
        r_b = cv2.Rodrigues(np.asarray(pose.rvec, np.float64))[0]
        t_b = np.asarray(pose.tvec, np.float64).reshape(3)
        if camera == 1:
            r_b, t_b = self.rig.R @ r_b, self.rig.R @ t_b + self.rig.T
        return r_b, t_b

    def ground_truth_corners(self, camera: int, pose: BoardPose) -> np.ndarray:
        """(N, 2) exact pixel positions of the inner corners in a camera."""
        r_b, t_b = self._camera_pose(camera, pose)
        m, d = (self.rig.M1, self.rig.D1) if camera == 0 else (self.rig.M2, self.rig.D2)
        pts = cv2.projectPoints(self.board.object_points().astype(np.float64),
                                cv2.Rodrigues(r_b)[0], t_b, m, d)[0]
        return pts.reshape(-1, 2)

    def _random_pose(self) -> BoardPose:
        """A pose with the whole board (plus a margin) inside both images."""
        w, h = self.image_size
        b = self.board
        centre = np.array([(b.cols - 1) * b.square / 2, (b.rows - 1) * b.square / 2, 0.0])
        for _ in range(1000):
            tilt = np.array([self._rng.uniform(-0.6, 0.6), self._rng.uniform(-0.6, 0.6),
                             self._rng.uniform(-0.35, 0.35)])
            r_b = cv2.Rodrigues(tilt)[0]
            z = self._rng.uniform(*self._distance_range)
            u = self._rng.uniform(0.1 * w, 0.9 * w)
            v = self._rng.uniform(0.1 * h, 0.9 * h)
            m = self.rig.M1
            centre_cam = z * np.array([(u - m[0, 2]) / m[0, 0], (v - m[1, 2]) / m[1, 1], 1.0])
            t_b = centre_cam - r_b @ centre
            pose = BoardPose(tilt, t_b)
            if all(self._board_inside(cam, pose) for cam in (0, 1)):
                return pose
        raise RuntimeError("could not place the board inside both images: the board is too "
                           "large for the distance range")

    def _board_inside(self, camera: int, pose: BoardPose) -> bool:
        w, h = self.image_size
        r_b, t_b = self._camera_pose(camera, pose)
        # The outer edge of the printed squares, one square beyond the inner corners.
        b = self.board
        outline = np.array([[-b.square, -b.square, 0], [b.cols * b.square, -b.square, 0],
                            [b.cols * b.square, b.rows * b.square, 0],
                            [-b.square, b.rows * b.square, 0]])
        if np.any((outline @ r_b.T + t_b)[:, 2] <= 0.05):
            return False
        m, d = (self.rig.M1, self.rig.D1) if camera == 0 else (self.rig.M2, self.rig.D2)
        pts = cv2.projectPoints(outline, cv2.Rodrigues(r_b)[0], t_b, m, d)[0].reshape(-1, 2)
        margin = 0.04 * min(w, h)
        return bool(np.all((pts[:, 0] > margin) & (pts[:, 0] < w - 1 - margin)
                           & (pts[:, 1] > margin) & (pts[:, 1] < h - 1 - margin)))

    # ---- rendering --------------------------------------------------------------------------
    def _make_texture(self):
        """Board image: (cols+1)×(rows+1) squares plus a white quiet zone of one square."""
        b = self.board
        px = 48                                   # texture pixels per square
        n_x, n_y = b.cols + 1, b.rows + 1
        tex = np.full(((n_y + 2) * px, (n_x + 2) * px), 235, np.uint8)
        if b.kind == "charuco":
            # OpenCV draws the ChArUco pattern; its inner corner ids run like ours (x fastest).
            pattern = b.charuco_board().generateImage((n_x * px, n_y * px), marginSize=0)
            tex[px:(n_y + 1) * px, px:(n_x + 1) * px] = np.where(pattern > 127, 235, 25)
        else:
            for j in range(n_y):
                for i in range(n_x):
                    if (i + j) % 2 == 0:
                        tex[(j + 1) * px:(j + 2) * px, (i + 1) * px:(i + 2) * px] = 25
        scale = px / b.square                     # texture px per metre
        # Board coordinate (0, 0) = first inner corner = texture point (2 px-squares in).
        origin = np.array([2 * px - 0.5, 2 * px - 0.5])
        return tex, scale, origin

    def _pixel_rays(self, camera: int) -> np.ndarray:
        """Undistorted normalised coordinates of every (supersampled) pixel, (H·s, W·s, 2)."""
        w, h = self.image_size
        s = self.supersample
        xs = (np.arange(w * s) + 0.5) / s - 0.5
        ys = (np.arange(h * s) + 0.5) / s - 0.5
        grid = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 1, 2)
        m, d = (self.rig.M1, self.rig.D1) if camera == 0 else (self.rig.M2, self.rig.D2)
        criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-10)
        norm = undistort_points_iterated(grid, m, d, criteria)
        return norm.reshape(h * s, w * s, 2).astype(np.float32)

    def render(self, camera: int, pose: BoardPose) -> np.ndarray:
        """BGR image of the board in one camera."""
        r_b, t_b = self._camera_pose(camera, pose)
        # Board plane (X, Y, 1) → normalised image coordinates: H = [r1 r2 t].
        homography = np.column_stack([r_b[:, 0], r_b[:, 1], t_b])
        inv = np.linalg.inv(homography)
        rays = self._rays[camera]
        x, y = rays[..., 0], rays[..., 1]
        bx = inv[0, 0] * x + inv[0, 1] * y + inv[0, 2]
        by = inv[1, 0] * x + inv[1, 1] * y + inv[1, 2]
        bw = inv[2, 0] * x + inv[2, 1] * y + inv[2, 2]
        behind = bw <= 0                     # rays that meet the plane behind the camera
        bw = np.where(behind, 1.0, bw)
        map_x = (bx / bw * self._texture_scale + self._texture_origin[0]).astype(np.float32)
        map_y = (by / bw * self._texture_scale + self._texture_origin[1]).astype(np.float32)
        map_x[behind] = -1e6
        hi = cv2.remap(self._texture, map_x, map_y, cv2.INTER_LINEAR,
                       borderMode=cv2.BORDER_CONSTANT, borderValue=90)
        w, h = self.image_size
        gray = hi if self.supersample == 1 else cv2.resize(hi, (w, h),
                                                           interpolation=cv2.INTER_AREA)
        if self.noise_sigma > 0:
            noise = self._noise_rng.normal(0, self.noise_sigma, gray.shape)
            gray = np.clip(gray + noise, 0, 255).astype(np.uint8)
        return cv2.cvtColor(gray, cv2.COLOR_GRAY2BGR)

    def render_pair(self, pose: BoardPose) -> tuple[np.ndarray, np.ndarray]:
        return self.render(0, pose), self.render(1, pose)

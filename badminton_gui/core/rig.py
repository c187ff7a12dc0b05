"""The stereo rig: two calibrated cameras, their relative pose, and optionally the court pose.

Why this file exists: every 3D quantity of the product (distance, speed, landing point) comes
from here. The rig file is OpenCV FileStorage YAML with the key names of OpenCV's stereo
calibration sample: ``M1 D1 M2 D2 R T`` (X_right = R·X_left + T), ``image_width``,
``image_height``, optionally ``R1 R2 P1 P2 Q`` and the court pose ``R_court T_court``
(X_court = R_court·X_left + T_court).

Triangulation works on undistorted, normalised image points with P_left = [I|0] and
P_right = [R|T]. That serves parallel binocular rigs and rigs whose cameras face each other
(the NYCU rig, which ``stereoRectify`` cannot handle) alike; the paper's Z = f·Tx/disparity is
only the special case of a rectified parallel rig.
"""

from __future__ import annotations

import math
import os
import re
import stat
import tempfile
from dataclasses import dataclass, field, replace
from pathlib import Path

import cv2
import numpy as np

from .errors import TrackerInputError


_UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-12)


def undistort_points_iterated(pts: np.ndarray, camera_matrix: np.ndarray, dist: np.ndarray,
                              criteria) -> np.ndarray:
    """``cv2.undistortPoints`` with its iteration criteria, on every supported OpenCV: 4.x takes
    them only through ``undistortPointsIter``, 5.x as ``undistortPoints``' last argument (and
    has no ``undistortPointsIter``). Same result on both."""
    if _UNDISTORT_ITER is not None:
        return _UNDISTORT_ITER(pts, camera_matrix, dist, None, None, criteria)
    return cv2.undistortPoints(pts, camera_matrix, dist, None, None, None, criteria)


_UNDISTORT_ITER = getattr(cv2, "undistortPointsIter", None)

# px at 1280 px image width: a running rig whose sure shuttle pairs miss their epipolar lines by
# more than this (median, ``StereoTracker.rig_epipolar_px``) is worth refining (``refine-calib``).
# A chessboard-calibrated rig misses by a px or two there (the blobs' centroids in two views of a
# moving shuttle), the demo court's exact rig by 0.06 px; the NYCU rig imported from its ``.cfg``
# files by 29–51 px at 2048 px (refined: ≈ 1.5 px).
REFINE_FROM_PX = 6.0


def refine_threshold(image_width: int) -> float:
    """REFINE_FROM_PX scaled to frames ``image_width`` px wide."""
    return REFINE_FROM_PX * image_width / 1280.0


def inputs_look_swapped(epipolar_px: float | None, swapped_px: float | None, image_width: int) -> bool:
    """True when the sure pairs fit the rig far better with the left and right images exchanged:
    the error as given is worth refining (``refine_threshold``) and the exchanged one at most a
    third of it. A wrong relative pose is about as wrong both ways round; exchanged cameras on a
    rig that is also off (the NYCU rig from its .cfg files: 313 px as given, 34 exchanged) still
    show the ratio."""
    if epipolar_px is None or swapped_px is None:
        return False
    return epipolar_px > refine_threshold(image_width) and 3.0 * swapped_px <= epipolar_px


def swapped_sentence(epipolar_px: float, swapped_px: float) -> str:
    """What the operator is told when ``inputs_look_swapped``."""
    return (f"The left and right cameras look swapped: the shuttle's pairs miss their epipolar lines "
            f"by {epipolar_px:.0f} px as given but by {swapped_px:.1f} px the other way round, so the "
            f"3D points are wrong.")


class RigError(TrackerInputError):
    """A rig file that cannot be read, a rig that cannot be right, or one that does not fit the
    frames it is used on."""


# Largest deviation of Rᵀ·R from the identity (each element) still taken for a rotation: a rig
# file written with six decimals is off by ~1e-6; a matrix off by more is not a rotation at all.
ROTATION_TOLERANCE = 1e-3
# Lengths of a distortion vector OpenCV understands (k1 k2 p1 p2 [k3 [k4 k5 k6 [s1..s4 [τx τy]]]]).
DISTORTION_LENGTHS = (4, 5, 8, 12, 14)
# px: the largest image side a rig may state (a larger one is a typo or a corrupt file).
MAX_IMAGE_SIDE = 100_000


def _arr(a, shape=None, key: str = "") -> np.ndarray:
    """``a`` as float64 (reshaped to ``shape``), or a RigError that names ``key``."""
    try:
        out = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError):
        raise RigError(f"{key} is {_describe(a)}, not a matrix of numbers") from None
    if shape is not None:
        if out.size != int(np.prod(shape)):
            want = "×".join(str(abs(n)) for n in shape)
            raise RigError(f"{key} must be {want} ({int(np.prod(shape))} numbers) but has "
                           f"{'×'.join(map(str, out.shape)) or 'one number'} ({out.size})")
        out = out.reshape(shape)
    if not np.all(np.isfinite(out)):
        raise RigError(f"{key} holds a value that is not finite (NaN or infinity)")
    return out


# Element types of a one-channel !!opencv-matrix ("dt"), and the largest side a rig's matrix has.
_MATRIX_TYPES = ("d", "f", "i", "s", "w", "u", "c")
_MATRIX_MAX_SIDE = 16


def _read_matrix(node) -> np.ndarray | None:
    """An !!opencv-matrix node's values, read field by field; None when the node is not one.

    ``FileNode.mat()`` trusts the node's rows and cols: a file saying ``cols: -2.5`` makes it
    write outside its buffer and the process dies later in malloc. Reading the fields here,
    after checking that they agree, never hands OpenCV a shape it has not been shown to hold."""
    if not node.isMap():
        return None
    rows, cols, dt, data = (node.getNode(k) for k in ("rows", "cols", "dt", "data"))
    if not (rows.isInt() and cols.isInt() and dt.isString() and data.isSeq()):
        return None
    n_rows, n_cols = int(rows.real()), int(cols.real())
    if not (1 <= n_rows <= _MATRIX_MAX_SIDE and 1 <= n_cols <= _MATRIX_MAX_SIDE):
        return None
    if dt.string() not in _MATRIX_TYPES or data.size() != n_rows * n_cols:
        return None
    values = []
    for i in range(n_rows * n_cols):
        item = data.at(i)
        if not (item.isInt() or item.isReal()):
            return None
        values.append(item.real())
    return np.asarray(values, dtype=np.float64).reshape(n_rows, n_cols)


def _describe(value) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _camera_matrix(m, key: str) -> np.ndarray:
    m = _arr(m, (3, 3), key)
    if not (m[0, 0] > 0 and m[1, 1] > 0):
        raise RigError(f"{key} has focal lengths fx = {m[0, 0]:g}, fy = {m[1, 1]:g}: both must be "
                       f"positive (pixels)")
    if not np.allclose(m[2], (0.0, 0.0, 1.0), atol=1e-6):
        raise RigError(f"{key}'s last row is {m[2].tolist()}, not [0, 0, 1]: not a camera matrix")
    return m


def _distortion(d, key: str) -> np.ndarray:
    d = _arr(d, None, key).ravel()
    if len(d) not in DISTORTION_LENGTHS:
        raise RigError(f"{key} has {len(d)} coefficients; OpenCV takes "
                       f"{', '.join(map(str, DISTORTION_LENGTHS[:-1]))} or {DISTORTION_LENGTHS[-1]}")
    return d


def _rotation(r, key: str) -> np.ndarray:
    r = _arr(r, (3, 3), key)
    off = float(np.max(np.abs(r.T @ r - np.eye(3))))
    if off > ROTATION_TOLERANCE or np.linalg.det(r) <= 0:
        raise RigError(f"{key} is not a rotation matrix (RᵀR differs from the identity by {off:.3g}, "
                       f"det {np.linalg.det(r):.3g}; a rotation has 0 and 1)")
    return r


def _translation(t, key: str, nonzero: bool) -> np.ndarray:
    t = _arr(t, (3,), key)
    if nonzero and not np.linalg.norm(t) > 0:
        raise RigError(f"{key} is zero: the two cameras would be at the same place, and nothing "
                       f"can be triangulated")
    return t


def _image_size(size) -> tuple[int, int]:
    try:
        w, h = size
        fw, fh = float(w), float(h)
    except (TypeError, ValueError):
        raise RigError(f"image size {_describe(size)} is not (width, height)") from None
    for name, v in (("image_width", fw), ("image_height", fh)):
        if not (math.isfinite(v) and v == int(v) and 1 <= v <= MAX_IMAGE_SIDE):
            raise RigError(f"{name} is {v:g}: it must be a whole number of pixels, 1 to {MAX_IMAGE_SIDE}")
    return int(fw), int(fh)


@dataclass(frozen=True)
class StereoRig:
    """Intrinsics and extrinsics of a two-camera rig."""

    M1: np.ndarray
    D1: np.ndarray
    M2: np.ndarray
    D2: np.ndarray
    R: np.ndarray
    T: np.ndarray
    image_size: tuple[int, int]                 # (width, height) of both cameras
    R1: np.ndarray | None = None
    R2: np.ndarray | None = None
    P1: np.ndarray | None = None
    P2: np.ndarray | None = None
    Q: np.ndarray | None = None
    R_court: np.ndarray | None = None
    T_court: np.ndarray | None = None
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self) -> None:
        # Every rig is checked once, here, so that a rig that cannot be right (a zero focal
        # length, an R that is no rotation, NaN) is refused with its key named instead of
        # giving no 3D point, or a cv2.error, in the middle of a run.
        object.__setattr__(self, "M1", _camera_matrix(self.M1, "M1"))
        object.__setattr__(self, "M2", _camera_matrix(self.M2, "M2"))
        object.__setattr__(self, "D1", _distortion(self.D1, "D1"))
        object.__setattr__(self, "D2", _distortion(self.D2, "D2"))
        object.__setattr__(self, "R", _rotation(self.R, "R"))
        object.__setattr__(self, "T", _translation(self.T, "T", nonzero=True))
        object.__setattr__(self, "image_size", _image_size(self.image_size))
        if (self.R_court is None) != (self.T_court is None):
            raise RigError("the court pose needs both R_court and T_court")
        if self.R_court is not None:
            object.__setattr__(self, "R_court", _rotation(self.R_court, "R_court"))
            object.__setattr__(self, "T_court", _translation(self.T_court, "T_court", nonzero=False))
        for key in ("R1", "R2", "P1", "P2", "Q"):
            if getattr(self, key) is not None:
                object.__setattr__(self, key, _arr(getattr(self, key), None, key))

    # ---- file I/O --------------------------------------------------------------------------
    @classmethod
    def load(cls, path: str | Path) -> "StereoRig":
        path = Path(path)
        if not path.is_file():
            raise RigError(f"rig file not found: {path}")
        try:
            fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
        except (cv2.error, SystemError) as exc:
            # OpenCV's parser raises cv2.error, or a SystemError wrapping one, on garbage; the
            # SystemError's own text ("... returned a result with an exception set") says nothing
            # to a user, so the message names the cause OpenCV gave, or none.
            cause = exc.__cause__ if isinstance(exc, SystemError) and exc.__cause__ else exc
            text = str(cause)
            where = re.search(r"\((\d+)\): ([^']+)'", text)   # "...file.yaml(2): Incorrect indentation'"
            # OpenCV 4 names no line: "OpenCV(4.13.0) /path/persistence.cpp:753: error: (-5:Bad
            # argument) Input file is invalid in function 'open'" -> "Input file is invalid".
            said = re.search(r"error: \(-?\d+:[^)]*\) (.+?)(?: in function '[^']*')?$", text.strip())
            lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
            detail = (f"line {where.group(1)}: {where.group(2)}" if where else
                      said.group(1) if said else
                      lines[-1] if lines and "exception set" not in lines[-1] and ".cpp" not in lines[-1]
                      else "")
            raise RigError(f"rig file {path} is not an OpenCV FileStorage YAML/XML rig file"
                           + (f" ({detail})" if detail else "")) from None
        if not fs.isOpened():
            raise RigError(f"rig file {path} cannot be opened as OpenCV FileStorage")
        try:
            def mat(key: str, required: bool = True):
                node = fs.getNode(key)
                if node.empty() or node.isNone():
                    if required:
                        raise RigError(f"rig file {path} lacks the key {key!r}")
                    return None
                m = _read_matrix(node)
                if m is None:
                    raise RigError(f"rig file {path}: key {key!r} is not a matrix "
                                   f"(an !!opencv-matrix with rows, cols, dt and data that agree)")
                return m

            def num(key: str):
                node = fs.getNode(key)
                if node.empty() or node.isNone():
                    raise RigError(f"rig file {path} lacks the key {key!r}")
                if not (node.isInt() or node.isReal()):
                    raise RigError(f"rig file {path}: {key} is not a number")
                return node.real()

            size = (num("image_width"), num("image_height"))
            r_court = mat("R_court", required=False)
            t_court = mat("T_court", required=False)
            if (r_court is None) != (t_court is None):
                raise RigError(f"rig file {path} has only one of R_court / T_court")
            values = dict(M1=mat("M1"), D1=mat("D1"), M2=mat("M2"), D2=mat("D2"), R=mat("R"),
                          T=mat("T"), image_size=size, R1=mat("R1", False), R2=mat("R2", False),
                          P1=mat("P1", False), P2=mat("P2", False), Q=mat("Q", False),
                          R_court=r_court, T_court=t_court)
            try:
                return cls(**values)
            except RigError as exc:
                raise RigError(f"rig file {path}: {exc}") from None
        finally:
            fs.release()

    def save(self, path: str | Path) -> None:
        """Write the rig file; ``path`` gets the whole file or stays as it was. A symlink is
        written through (the link kept, the file it points to replaced)."""
        # The same rules as io/safe_write.py's ``replacing``, restated here because the core
        # imports nothing from io: a uniquely named temporary file beside the target (its
        # extension kept: FileStorage picks the format by it), renamed over it when complete,
        # and removed whatever fails.
        path = Path(os.path.realpath(path)) if os.path.islink(path) else Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp" + path.suffix, dir=path.parent)
        os.close(fd)
        tmp = Path(name)
        try:
            self._write_file_storage(tmp, path)
            # FileStorage does not report a failed write (a full disk): read the file back.
            type(self).load(tmp)
            try:
                mode = stat.S_IMODE(os.stat(path).st_mode)
            except OSError:
                mode = 0o644
            os.chmod(tmp, mode)
            os.replace(tmp, path)
        finally:
            if tmp.exists():
                tmp.unlink()

    def _write_file_storage(self, tmp: Path, path: Path) -> None:
        fs = cv2.FileStorage(str(tmp), cv2.FILE_STORAGE_WRITE)
        if not fs.isOpened():
            raise RigError(f"cannot write rig file {path}")
        try:
            fs.write("image_width", int(self.image_size[0]))
            fs.write("image_height", int(self.image_size[1]))
            for key in ("M1", "D1", "M2", "D2", "R", "T"):
                val = getattr(self, key)
                fs.write(key, val.reshape(1, -1) if key.startswith("D") else
                         (val.reshape(3, 1) if key == "T" else val))
            for key in ("R1", "R2", "P1", "P2", "Q"):
                val = getattr(self, key)
                if val is not None:
                    fs.write(key, np.asarray(val, dtype=np.float64))
            if self.R_court is not None:
                fs.write("R_court", self.R_court)
                fs.write("T_court", self.T_court.reshape(3, 1))
        finally:
            fs.release()

    # ---- derived quantities ----------------------------------------------------------------
    @property
    def has_court_pose(self) -> bool:
        return self.R_court is not None

    @property
    def baseline(self) -> float:
        """Distance between the two optical centres (m)."""
        return float(np.linalg.norm(self.T))

    def with_court_pose(self, R_court, T_court) -> "StereoRig":
        return replace(self, R_court=R_court, T_court=T_court, _cache={})

    def camera_centres(self) -> np.ndarray:
        """(2, 3) optical centres of the left and right camera, in the output frame."""
        c_left = np.zeros(3)
        c_right = -self.R.T @ self.T
        return self.to_output(np.stack([c_left, c_right]))

    def camera_rotations(self) -> tuple[np.ndarray, np.ndarray]:
        """Rotation from each camera's frame to the output frame (court if known)."""
        r_left = np.eye(3) if self.R_court is None else self.R_court
        return r_left, r_left @ self.R.T

    def check_image_size(self, width: int, height: int, what: str = "the frames") -> None:
        """Raise a clear error when the rig was calibrated for another resolution."""
        if (int(width), int(height)) != self.image_size:
            raise RigError(
                f"the rig was calibrated for {self.image_size[0]}×{self.image_size[1]} but "
                f"{what} are {int(width)}×{int(height)}: calibrate again at this resolution "
                f"or choose the matching rig file")

    def fundamental(self) -> np.ndarray:
        """Fundamental matrix between *undistorted* pixel coordinates (left → right)."""
        if "F" not in self._cache:
            tx = np.array([[0, -self.T[2], self.T[1]], [self.T[2], 0, -self.T[0]],
                           [-self.T[1], self.T[0], 0]])
            essential = tx @ self.R
            self._cache["F"] = np.linalg.inv(self.M2).T @ essential @ np.linalg.inv(self.M1)
        return self._cache["F"]

    # ---- points ----------------------------------------------------------------------------
    def undistort(self, camera: int, pts) -> np.ndarray:
        """Pixel points (N, 2) of camera 0 (left) or 1 (right) → normalised coordinates (N, 2)."""
        pts = np.asarray(pts, dtype=np.float64).reshape(-1, 1, 2)
        m, d = (self.M1, self.D1) if camera == 0 else (self.M2, self.D2)
        if len(pts) == 0:
            return np.zeros((0, 2))
        if not np.any(d):
            return cv2.undistortPoints(pts, m, d).reshape(-1, 2)
        # More iterations than cv2.undistortPoints' default: strong barrel lenses (the NYCU rig)
        # otherwise leave micrometre-level errors that add up in triangulation.
        return undistort_points_iterated(pts, m, d, _UNDISTORT_CRITERIA).reshape(-1, 2)

    def undistort_pixels(self, camera: int, pts) -> np.ndarray:
        """Pixel points → undistorted pixel points of the same camera matrix."""
        norm = self.undistort(camera, pts)
        m = self.M1 if camera == 0 else self.M2
        return norm @ m[:2, :2].T + m[:2, 2]

    def epipolar_errors(self, pts_left, pts_right) -> np.ndarray:
        """Symmetric epipolar distance (px) for every pair (i, j): (N_left, N_right)."""
        ul = self.undistort_pixels(0, pts_left)
        ur = self.undistort_pixels(1, pts_right)
        if len(ul) == 0 or len(ur) == 0:
            return np.zeros((len(ul), len(ur)))
        f = self.fundamental()
        hl = np.hstack([ul, np.ones((len(ul), 1))])
        hr = np.hstack([ur, np.ones((len(ur), 1))])
        lines_r = hl @ f.T          # epipolar lines in the right image, one per left point
        lines_l = hr @ f            # epipolar lines in the left image, one per right point
        num = hr @ lines_r.T        # (N_right, N_left): x_r^T F x_l
        num = np.abs(num.T)         # (N_left, N_right)
        d_right = num / np.hypot(lines_r[:, 0], lines_r[:, 1])[:, None]
        d_left = num / np.hypot(lines_l[:, 0], lines_l[:, 1])[None, :]
        return 0.5 * (d_right + d_left)

    def pair_errors(self, pts_left, pts_right) -> np.ndarray:
        """Symmetric epipolar distance (px) of each matched pair (i, i): (N,), the diagonal of
        ``epipolar_errors`` without its N × N matrix."""
        ul = self.undistort_pixels(0, pts_left)
        ur = self.undistort_pixels(1, pts_right)
        if len(ul) == 0:
            return np.zeros(0)
        f = self.fundamental()
        hl = np.hstack([ul, np.ones((len(ul), 1))])
        hr = np.hstack([ur, np.ones((len(ur), 1))])
        lines_r = hl @ f.T
        lines_l = hr @ f
        num = np.abs(np.einsum("ij,ij->i", hr, lines_r))
        return 0.5 * (num / np.hypot(lines_r[:, 0], lines_r[:, 1])
                      + num / np.hypot(lines_l[:, 0], lines_l[:, 1]))

    def triangulate(self, pts_left, pts_right) -> np.ndarray:
        """Matched pixel points (N, 2) × 2 → 3D points (N, 3) in the left camera's frame."""
        nl = self.undistort(0, pts_left)
        nr = self.undistort(1, pts_right)
        if len(nl) == 0:
            return np.zeros((0, 3))
        p_left = np.hstack([np.eye(3), np.zeros((3, 1))])
        p_right = np.hstack([self.R, self.T.reshape(3, 1)])
        hom = cv2.triangulatePoints(p_left, p_right, nl.T.copy(), nr.T.copy())
        return (hom[:3] / hom[3]).T

    def noise_shape(self, pts_left, pts_right, step: float = 0.25) -> np.ndarray:
        """Covariance (N, 3, 3) of the triangulated output-frame points for 1 px of independent
        noise on each image coordinate: J·Jᵀ with J = ∂point/∂(xl, yl, xr, yr).

        Depth is several times less sure than the directions across the rays (and grows with
        the range squared); the trajectory filter weighs each point by this shape. J is taken by
        finite differences of :meth:`triangulate` (one batched call, exact enough for a smooth map).
        """
        pl = np.asarray(pts_left, dtype=np.float64).reshape(-1, 2)
        pr = np.asarray(pts_right, dtype=np.float64).reshape(-1, 2)
        n = len(pl)
        left = np.repeat(pl[None], 5, axis=0)
        right = np.repeat(pr[None], 5, axis=0)
        left[1, :, 0] += step
        left[2, :, 1] += step
        right[3, :, 0] += step
        right[4, :, 1] += step
        pts = self.to_output(self.triangulate(left.reshape(-1, 2), right.reshape(-1, 2))).reshape(5, n, 3)
        jac = (pts[1:] - pts[0][None]) / step            # (4, N, 3): one column per coordinate
        return np.einsum("knj,kni->nij", jac, jac)

    def rays(self, camera: int, pts) -> tuple[np.ndarray, np.ndarray]:
        """Pixel points (N, 2) of a camera → (its optical centre (3,), unit directions (N, 3)) in
        the output frame: the lines of sight on which those image points lie."""
        norm = self.undistort(camera, pts)
        dirs = np.hstack([norm, np.ones((len(norm), 1))]) @ self.camera_rotations()[camera].T
        return self.camera_centres()[camera], dirs / np.linalg.norm(dirs, axis=1, keepdims=True)

    def to_output(self, pts_left_frame) -> np.ndarray:
        """Left-camera-frame points → court frame when the pose is known (else unchanged)."""
        pts = np.asarray(pts_left_frame, dtype=np.float64).reshape(-1, 3)
        if self.R_court is None:
            return pts
        return pts @ self.R_court.T + self.T_court

    def to_left(self, pts_output) -> np.ndarray:
        """Output-frame points → left-camera frame (inverse of :meth:`to_output`)."""
        pts = np.asarray(pts_output, dtype=np.float64).reshape(-1, 3)
        if self.R_court is None:
            return pts
        return (pts - self.T_court) @ self.R_court

    def project(self, camera: int, pts_output) -> np.ndarray:
        """Output-frame 3D points (N, 3) → distorted pixel coordinates (N, 2) of a camera."""
        pts = self.to_left(pts_output)
        if camera == 0:
            rvec, tvec, m, d = np.zeros(3), np.zeros(3), self.M1, self.D1
        else:
            rvec, tvec, m, d = cv2.Rodrigues(self.R)[0].ravel(), self.T, self.M2, self.D2
        if len(pts) == 0:
            return np.zeros((0, 2))
        img, _ = cv2.projectPoints(pts.reshape(-1, 1, 3), rvec, tvec, m, d)
        return img.reshape(-1, 2)

    def depth(self, camera: int, pts_output) -> np.ndarray:
        """Z of output-frame points in the given camera's frame (positive = in front)."""
        pts = self.to_left(pts_output)
        if camera == 1:
            pts = pts @ self.R.T + self.T
        return pts[:, 2]

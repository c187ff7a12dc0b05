"""Import of the NYCU recordings' per-camera ``.cfg`` calibration into a rig file.

Why this file exists: the NYCU rig is two cameras at the two ends of a court, each calibrated
separately against the court (``extrinsic_mat`` maps the court/world frame to the camera). A rig
file wants the right camera relative to the left one plus the left camera's court pose:

    X_cam1 = E1 · [X_w; 1]         X_cam2 = E2 · [X_w; 1]
    R = R2 R1ᵀ,  T = t2 − R t1      (X_right = R X_left + T)
    R_court = R1ᵀ,  T_court = −R1ᵀ t1   (X_court = R_court X_left + T_court)

Intrinsics are ``ks`` with ``dist``; ``newcameramtx`` is only the NYCU code's re-projection
matrix after undistortion, which cancels out when triangulating in normalised coordinates.
"""

from __future__ import annotations

import configparser
import json
from pathlib import Path

import numpy as np

from ..core.rig import DISTORTION_LENGTHS, MAX_IMAGE_SIDE, RigError, StereoRig


def read_nycu_cfg(path: str | Path) -> dict[str, np.ndarray | tuple[int, int]]:
    """Camera matrix, distortion, extrinsics and resolution of one NYCU ``.cfg`` file.

    Every value is checked here (finite numbers, the shapes, positive focal lengths, a distortion
    vector OpenCV takes, an extrinsic rotation), so a file that cannot become a valid rig is
    refused with its name and key rather than written into a rig that fails later."""
    path = Path(path)
    if not path.is_file():
        raise RigError(f"calibration file not found: {path}")
    # No interpolation: a value holding "%" is data, not a reference to another key.
    parser = configparser.ConfigParser(interpolation=None)
    try:
        text = _read_text(path)
        parser.read_string(text, source=str(path))
    except configparser.Error as exc:
        detail = " ".join(str(exc).split())
        raise RigError(f"{path} is not an INI file: {detail}") from None
    if not parser.has_section("Other"):
        raise RigError(f"{path} has no [Other] section: not a NYCU CameraReader .cfg")

    def arr(key: str, shape: tuple[int, ...]) -> np.ndarray:
        if not parser.has_option("Other", key):
            raise RigError(f"{path} lacks {key} in [Other]")
        raw = parser.get("Other", key)
        try:
            value = np.asarray(json.loads(raw), dtype=float)
        except (json.JSONDecodeError, TypeError, ValueError, RecursionError):
            raise RigError(f"{path}: {key} in [Other] is not a list of numbers "
                           f"(JSON like [[1.0, 0.0], …]): {_short(raw)}") from None
        want = int(np.prod([n for n in shape if n > 0]))
        if (-1 not in shape and value.size != want) or value.ndim > 2:
            raise RigError(f"{path}: {key} in [Other] must be "
                           f"{'×'.join(map(str, shape))} numbers, not {'×'.join(map(str, value.shape))}")
        if not np.all(np.isfinite(value)):
            raise RigError(f"{path}: {key} in [Other] holds a value that is not finite (NaN or infinity)")
        return value.reshape(shape)

    size = (0, 0)
    if parser.has_option("Camera", "RecordResolution"):
        text = parser.get("Camera", "RecordResolution").strip("() ")
        try:
            w, h = (int(v) for v in text.split(","))
            size = (w, h)
        except ValueError:
            raise RigError(f"{path}: RecordResolution {text!r} is not (width, height)") from None
        if not (0 < w <= MAX_IMAGE_SIDE and 0 < h <= MAX_IMAGE_SIDE):
            raise RigError(f"{path}: RecordResolution {text!r} is not a frame size in pixels")
    k = arr("ks", (3, 3))
    dist = arr("dist", (-1,))
    extrinsic = arr("extrinsic_mat", (3, 4))
    # The same rules as a rig's (core/rig.py), said with this file's key names.
    if not (k[0, 0] > 0 and k[1, 1] > 0):
        raise RigError(f"{path}: ks in [Other] has focal lengths {k[0, 0]:g} and {k[1, 1]:g}: "
                       f"both must be positive")
    if not np.allclose(k[2], (0.0, 0.0, 1.0), atol=1e-6):
        raise RigError(f"{path}: ks in [Other] has the last row {k[2].tolist()}, not [0, 0, 1]")
    if len(dist) not in DISTORTION_LENGTHS:
        raise RigError(f"{path}: dist in [Other] has {len(dist)} coefficients; OpenCV takes "
                       f"{', '.join(map(str, DISTORTION_LENGTHS[:-1]))} or {DISTORTION_LENGTHS[-1]}")
    if abs(np.linalg.det(extrinsic[:, :3])) < 0.5:
        raise RigError(f"{path}: extrinsic_mat in [Other] does not start with a rotation "
                       f"(determinant {np.linalg.det(extrinsic[:, :3]):.3g})")
    return {"K": k, "dist": dist, "extrinsic": extrinsic, "size": size}


def _read_text(path: Path) -> str:
    """The file's text: UTF-8 (with or without a byte-order mark, which some Windows editors
    add), else Latin-1, which the NYCU tool's Windows machines may have written comments in."""
    data = path.read_bytes()
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        pass
    text = data.decode("latin-1")
    if "\x00" in text:
        raise RigError(f"{path} is not a text file (it holds NUL bytes): not a NYCU CameraReader .cfg")
    return text


def _short(text: str) -> str:
    text = " ".join(text.split())
    return repr(text if len(text) <= 40 else text[:37] + "...")


def rig_from_nycu(cfg_left: str | Path, cfg_right: str | Path) -> StereoRig:
    """A stereo rig (with court pose) from the two cameras' ``.cfg`` files."""
    a = read_nycu_cfg(cfg_left)
    b = read_nycu_cfg(cfg_right)
    if a["size"] != b["size"]:
        raise RigError(f"the two cameras were calibrated at different resolutions "
                       f"({a['size']} and {b['size']})")
    if a["size"] == (0, 0):
        raise RigError(f"{cfg_left} does not state RecordResolution in [Camera]")
    r1, t1 = a["extrinsic"][:, :3], a["extrinsic"][:, 3]
    r2, t2 = b["extrinsic"][:, :3], b["extrinsic"][:, 3]
    # The NYCU extrinsics are close to, but not exactly, rotations: project onto SO(3).
    r1, r2 = _nearest_rotation(r1), _nearest_rotation(r2)
    r = r2 @ r1.T
    t = t2 - r @ t1
    try:
        return StereoRig(M1=a["K"], D1=a["dist"], M2=b["K"], D2=b["dist"], R=r, T=t,
                         image_size=a["size"], R_court=r1.T, T_court=-r1.T @ t1)
    except RigError as exc:
        raise RigError(f"{cfg_left} and {cfg_right} do not make a rig: {exc}") from None


def _nearest_rotation(m: np.ndarray) -> np.ndarray:
    u, _, vt = np.linalg.svd(m)
    r = u @ vt
    if np.linalg.det(r) < 0:
        u[:, -1] *= -1
        r = u @ vt
    return r

"""Import of the NYCU recordings' per-camera ``.cfg`` calibration into a rig file (GUIDE §5).

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

from ..core.rig import RigError, StereoRig


def read_nycu_cfg(path: str | Path) -> dict[str, np.ndarray | tuple[int, int]]:
    """Camera matrix, distortion, extrinsics and resolution of one NYCU ``.cfg`` file."""
    path = Path(path)
    if not path.is_file():
        raise RigError(f"calibration file not found: {path}")
    parser = configparser.ConfigParser()
    try:
        parser.read(path, encoding="utf-8")
    except configparser.Error as exc:
        raise RigError(f"{path} is not an INI file: {exc}") from None
    if not parser.has_section("Other"):
        raise RigError(f"{path} has no [Other] section: not a NYCU CameraReader .cfg")

    def arr(key: str, shape: tuple[int, ...]) -> np.ndarray:
        if not parser.has_option("Other", key):
            raise RigError(f"{path} lacks {key} in [Other]")
        try:
            value = np.asarray(json.loads(parser.get("Other", key)), dtype=float)
            return value.reshape(shape)
        except (json.JSONDecodeError, ValueError) as exc:
            raise RigError(f"{path}: {key} is not a {shape} array ({exc})") from None

    size = (0, 0)
    if parser.has_option("Camera", "RecordResolution"):
        text = parser.get("Camera", "RecordResolution").strip("() ")
        try:
            w, h = (int(v) for v in text.split(","))
            size = (w, h)
        except ValueError:
            raise RigError(f"{path}: RecordResolution {text!r} is not (width, height)") from None
    return {"K": arr("ks", (3, 3)), "dist": arr("dist", (-1,)),
            "extrinsic": arr("extrinsic_mat", (3, 4)), "size": size}


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
    return StereoRig(M1=a["K"], D1=a["dist"], M2=b["K"], D2=b["dist"], R=r, T=t,
                     image_size=a["size"], R_court=r1.T, T_court=-r1.T @ t1)


def _nearest_rotation(m: np.ndarray) -> np.ndarray:
    u, _, vt = np.linalg.svd(m)
    r = u @ vt
    if np.linalg.det(r) < 0:
        u[:, -1] *= -1
        r = u @ vt
    return r

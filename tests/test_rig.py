"""Stereo rig: file round trip (also read by plain cv2.FileStorage), triangulation, epipolar check."""

import math

import cv2
import numpy as np
import pytest

from badminton_gui.core.rig import RigError, StereoRig
from badminton_gui.io.nycu import rig_from_nycu

from .conftest_data import NYCU_DIR, requires_data


def make_rig(court=True) -> StereoRig:
    k = np.array([[900.0, 0, 640.5], [0, 905.0, 359.5], [0, 0, 1]])
    rvec = np.array([0.0, -0.05, 0.01])
    r = cv2.Rodrigues(rvec)[0]
    kwargs = {}
    if court:
        kwargs = dict(R_court=cv2.Rodrigues(np.array([1.2, 0.1, -0.3]))[0], T_court=[-6.0, 1.0, 1.4])
    return StereoRig(k, np.array([-0.1, 0.02, 0.001, -0.001, 0.0]), k * [[1.01], [1.0], [1]],
                     np.zeros(5), r, [-0.5, 0.01, 0.02], (1280, 720), **kwargs)


def test_round_trip_and_plain_filestorage(tmp_path):
    rig = make_rig()
    path = tmp_path / "rig.yaml"
    rig.save(path)
    back = StereoRig.load(path)
    for key in ("M1", "D1", "M2", "D2", "R", "T", "R_court", "T_court"):
        np.testing.assert_allclose(getattr(back, key), getattr(rig, key), atol=1e-12, err_msg=key)
    assert back.image_size == (1280, 720)
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    assert fs.isOpened()
    np.testing.assert_allclose(fs.getNode("M1").mat(), rig.M1)
    np.testing.assert_allclose(fs.getNode("T").mat().ravel(), rig.T)
    assert int(fs.getNode("image_width").real()) == 1280
    fs.release()
    assert not list(tmp_path.glob("*.tmp*")), "temporary file left behind"


def test_triangulation_is_exact_with_distortion():
    rig = make_rig()
    rng = np.random.default_rng(1)
    pts = rng.uniform([-3, -6, 0.2], [3, 6, 5], size=(400, 3))
    front = (rig.depth(0, pts) > 0.5) & (rig.depth(1, pts) > 0.5)
    uv_l, uv_r = rig.project(0, pts), rig.project(1, pts)
    # Only points inside both images: outside, a lens model need not be invertible.
    inside = front & np.all((uv_l > 0) & (uv_l < [1280, 720]) & (uv_r > 0) & (uv_r < [1280, 720]), axis=1)
    assert inside.sum() >= 5
    pts, uv_l, uv_r = pts[inside], uv_l[inside], uv_r[inside]
    back = rig.to_output(rig.triangulate(uv_l, uv_r))
    np.testing.assert_allclose(back, pts, atol=1e-6)
    epi = np.diag(rig.epipolar_errors(uv_l, uv_r))
    assert epi.max() < 1e-6
    shifted = np.diag(rig.epipolar_errors(uv_l, uv_r + [0.0, 5.0]))
    assert np.all(shifted > 1.0)


def test_missing_and_bad_rig_files(tmp_path):
    with pytest.raises(RigError, match="not found"):
        StereoRig.load(tmp_path / "nope.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("%YAML:1.0\n---\nM1: 3\n")
    with pytest.raises(RigError, match="lacks the key|not a matrix"):
        StereoRig.load(bad)
    garbage = tmp_path / "garbage.yaml"
    garbage.write_bytes(b"\x00\x01 this is not yaml {{{")
    with pytest.raises(RigError):
        StereoRig.load(garbage)
    # A text file that is not YAML: one sentence with the line OpenCV choked on, not the
    # binding's "returned a result with an exception set" nor OpenCV's source path.
    prose = tmp_path / "notes.yaml"
    prose.write_text("hello: [1, 2\nthis is not yaml {{{\n")
    with pytest.raises(RigError) as info:
        StereoRig.load(prose)
    message = str(info.value)
    assert "not an OpenCV FileStorage" in message
    # OpenCV 5 names the line; OpenCV 4 only that the input is invalid.
    assert "line 2" in message if cv2.__version__ >= "5" else "Input file is invalid" in message
    assert "exception set" not in message and ".cpp" not in message


def test_wrong_resolution_message():
    rig = make_rig()
    with pytest.raises(RigError, match="calibrated for 1280×720 but the videos are 640×480"):
        rig.check_image_size(640, 480, "the videos")


@requires_data
def test_nycu_import_matches_their_projection_matrices():
    """Our rig reprojects court points exactly as the NYCU projection matrices do."""
    import configparser
    import json

    d = NYCU_DIR / "rally_11-46-04"
    rig = rig_from_nycu(d / "CameraReader_1.cfg", d / "CameraReader_2.cfg")
    assert rig.has_court_pose and rig.image_size == (2048, 1536)
    pts = np.array([[0.0, 0.0, 0.0], [1.0, 3.0, 1.5], [-2.5, -4.0, 3.0]])
    for cam, name in ((0, "CameraReader_1.cfg"), (1, "CameraReader_2.cfg")):
        cfg = configparser.ConfigParser()
        cfg.read(d / name)
        proj = np.array(json.loads(cfg.get("Other", "projection_mat")))
        newk = np.array(json.loads(cfg.get("Other", "newcameramtx")))
        hom = (proj @ np.hstack([pts, np.ones((3, 1))]).T).T
        their = hom[:, :2] / hom[:, 2:]
        # Ours, undistorted and re-projected through newcameramtx, must agree.
        ours = rig.project(cam, pts)
        m, dist = (rig.M1, rig.D1) if cam == 0 else (rig.M2, rig.D2)
        ours_undist = cv2.undistortPoints(ours.reshape(-1, 1, 2), m, dist, None, newk).reshape(-1, 2)
        np.testing.assert_allclose(ours_undist, their, atol=0.5)


def test_noise_shape_is_the_triangulation_jacobian():
    """Depth is far less sure than across. Parallel rig, point on the left optical axis, 1 px per
    coordinate: σ_Z = Z²/(f·B)·√2 (both x's move the disparity), σ_X = Z/f (the left x),
    σ_Y = Z/(f·√2) (both cameras see y)."""
    f, baseline, z = 800.0, 0.5, 6.0
    k = np.array([[f, 0, 640], [0, f, 360], [0, 0, 1.0]])
    rig = StereoRig(M1=k, D1=np.zeros(5), M2=k.copy(), D2=np.zeros(5), R=np.eye(3),
                    T=np.array([-baseline, 0, 0]), image_size=(1280, 720))
    point = np.array([[0.0, 0.0, z]])
    left = np.array([[640.0, 360.0]])
    right = left - [[f * baseline / z, 0.0]]
    assert np.allclose(rig.triangulate(left, right), point, atol=1e-9)
    cov = rig.noise_shape(left, right)[0]
    assert cov.shape == (3, 3) and np.allclose(cov, cov.T)
    sigma_z = z * z / (f * baseline) * math.sqrt(2)     # both cameras' x move the disparity
    assert math.sqrt(cov[2, 2]) == pytest.approx(sigma_z, rel=0.02)
    assert math.sqrt(cov[0, 0]) == pytest.approx(z / f, rel=0.02)
    assert math.sqrt(cov[1, 1]) == pytest.approx(z / f / math.sqrt(2), rel=0.02)
    assert cov[2, 2] > 50 * cov[0, 0]

"""Stereo calibration core + CLI: real OpenCV sample boards, synthetic ground truth, errors.

Why this file exists: the wizard only renders ``core.calibrate.stereo``; these tests pin that core
to OpenCV's published figures on its own sample pairs and to exact ground truth rendered
through known cameras. No Qt here.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from badminton_gui.cli import main as cli_main
from badminton_gui.core.calibrate.board import (BoardDetection, BoardSpec, BoardError,
                                            charuco_available, check_view, detect_board)
from badminton_gui.core.calibrate.coverage import coverage, novelty, view_params
from badminton_gui.core.calibrate.stereo import (CalibrationCancelled, CalibrationError,
                                            CaptureGate, SolveOptions, StereoView,
                                            epipolar_grade, pair_detections, solve_stereo)
from badminton_gui.core.calibrate.court_pose import solve_court_pose, solve_court_pose_detailed
from badminton_gui.core.court import court_keypoints
from badminton_gui.core.rig import StereoRig
from badminton_gui.io.synthetic_chessboard import (SyntheticChessboardSource,
                                                   default_synthetic_rig)

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
CHESS = DATA / "chessboard-stereo"
needs_chess = pytest.mark.skipif(not CHESS.is_dir(), reason="../shared/data/chessboard-stereo "
                                                              "absent")


# ---- helpers --------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def synthetic_views():
    """Views detected on 16 rendered board poses, and the source that knows the truth."""
    src = SyntheticChessboardSource(n_poses=16, seed=5)
    views = []
    for k, pose in enumerate(src.poses):
        left, right = src.render_pair(pose)
        det_l, det_r = detect_board(left, src.board), detect_board(right, src.board)
        assert det_l is not None and det_r is not None, f"pose {k} not detected"
        views.append(pair_detections(f"pose{k:02d}", det_l, det_r, src.board))
    return src, views


def _projected_views(rig: StereoRig, board: BoardSpec, n: int, seed: int = 0,
                     noise: float = 0.05, distance: float = 1.0) -> list[StereoView]:
    """Board views made by projecting (no rendering) through ``rig``; the board faces the
    left camera and is tilted randomly."""
    rng = np.random.default_rng(seed)
    obj = board.object_points().astype(np.float64)
    centre = obj.mean(axis=0)
    views = []
    for k in range(n):
        rvec = rng.uniform(-0.5, 0.5, 3)
        r_b = cv2.Rodrigues(rvec)[0]
        t_b = np.array([rng.uniform(-0.1, 0.1), rng.uniform(-0.08, 0.08),
                        distance * rng.uniform(0.8, 1.2)]) - r_b @ centre
        pts_left = obj @ r_b.T + t_b
        img_l = rig.project(0, pts_left) + rng.normal(0, noise, (len(obj), 2))
        img_r = rig.project(1, pts_left) + rng.normal(0, noise, (len(obj), 2))
        views.append(StereoView(f"v{k}", obj.astype(np.float32), img_l.astype(np.float32),
                                img_r.astype(np.float32)))
    return views


def _run_cli(args, capsys):
    code = cli_main(args)
    out = capsys.readouterr()
    return code, out.out, out.err


# ---- real boards: OpenCV's stereo sample -----------------------------------------------------
@needs_chess
def test_cli_reproduces_opencv_reference(tmp_path, capsys):
    """With the sample's settings (cornerSubPix 11×11, every view kept) the figures match
    OpenCV's published ones: RMS 0.41 / 0.46 / 0.45 px, fx ≈ 536, cx ≈ 342, cy ≈ 236,
    baseline ≈ 3.34."""
    out_file = tmp_path / "rig.yaml"
    code, out, err = _run_cli(
        ["calibrate", "--left-dir", str(CHESS), "--right-dir", str(CHESS),
         "--left-glob", "left*", "--right-glob", "right*", "--board", "9x6", "--square", "1",
         "--subpix-window", "11", "--outlier-px", "5", "-o", str(out_file)], capsys)
    assert code == 0, err
    assert "rejected views: none" in out
    rig = StereoRig.load(out_file)
    # Re-run the core to read the RMS values directly (the CLI prints the same numbers).
    from badminton_gui.core.calibrate.folders import pair_image_files, views_from_pairs
    pairs = pair_image_files(CHESS, CHESS, "left*", "right*")
    spec = BoardSpec(9, 6, 1.0)
    found = views_from_pairs(pairs, spec, subpix_half_window=11)
    res = solve_stereo(found.views, found.image_size, spec, SolveOptions(outlier_min_px=5))
    assert abs(res.rms_left - 0.41) < 0.05
    assert abs(res.rms_right - 0.46) < 0.05
    assert abs(res.rms_stereo - 0.45) < 0.05
    assert f"left {res.rms_left:.3f} px, right {res.rms_right:.3f} px" in out
    assert abs(rig.M1[0, 0] / 536 - 1) < 0.01 and abs(rig.M1[1, 1] / 536 - 1) < 0.01
    assert abs(rig.M1[0, 2] - 342) < 3 and abs(rig.M1[1, 2] - 236) < 3
    assert abs(rig.baseline / 3.34 - 1) < 0.01
    assert abs(rig.T[0] + 3.34) < 0.05          # right camera along +x of the left one
    assert rig.P1 is not None and rig.Q is not None


@needs_chess
def test_default_corner_window_beats_reference(tmp_path, capsys):
    """The adaptive sub-pixel window (a third of a square) fits the model better than the
    sample's fixed 11 px, with the same focal length."""
    code, out, err = _run_cli(
        ["calibrate", "--left-dir", str(CHESS), "--right-dir", str(CHESS),
         "--left-glob", "left*", "--right-glob", "right*", "--board", "9x6", "--square", "1",
         "-o", str(tmp_path / "rig.yaml")], capsys)
    assert code == 0, err
    rig = StereoRig.load(tmp_path / "rig.yaml")
    line = next(l for l in out.splitlines() if l.startswith("RMS reprojection error"))
    values = [float(tok) for tok in line.replace(",", " ").split() if tok[0].isdigit()]
    assert max(values) < 0.41
    assert abs(rig.M1[0, 0] / 536 - 1) < 0.01
    assert abs(rig.baseline / 3.34 - 1) < 0.01


def test_cli_as_subprocess_help():
    proc = subprocess.run([sys.executable, "-m", "badminton_gui.cli", "calibrate", "--help"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0 and "--left-dir" in proc.stdout


# ---- CLI errors -----------------------------------------------------------------------------
def _write_pairs(tmp_path, n_left, n_right, image=None):
    left, right = tmp_path / "L", tmp_path / "R"
    left.mkdir(), right.mkdir()
    img = image if image is not None else np.full((120, 160), 128, np.uint8)
    for i in range(n_left):
        cv2.imwrite(str(left / f"{i:02d}.png"), img)
    for i in range(n_right):
        cv2.imwrite(str(right / f"{i:02d}.png"), img)
    return left, right


@pytest.mark.parametrize("n_left, n_right, message", [
    (3, 2, "3 left images but 2 right images"),
    (0, 2, "no images"),
    (2, 2, "was not found in both images of any of the 2 pairs"),
])
def test_cli_user_errors(tmp_path, capsys, n_left, n_right, message):
    left, right = _write_pairs(tmp_path, n_left, n_right)
    code, out, err = _run_cli(["calibrate", "--left-dir", str(left), "--right-dir", str(right),
                               "--square", "0.03", "-o", str(tmp_path / "r.yaml")], capsys)
    assert code == 2
    assert message in err
    assert not (tmp_path / "r.yaml").exists()


def test_cli_unreadable_image(tmp_path, capsys):
    left, right = _write_pairs(tmp_path, 2, 2)
    (left / "01.png").write_bytes(b"not a png")
    code, out, err = _run_cli(["calibrate", "--left-dir", str(left), "--right-dir", str(right),
                               "--square", "0.03", "-o", str(tmp_path / "r.yaml")], capsys)
    assert code == 2 and "cannot read image" in err and "01.png" in err


def test_cli_bad_board_and_missing_dir(tmp_path, capsys):
    code, _, err = _run_cli(["calibrate", "--left-dir", str(tmp_path), "--right-dir",
                             str(tmp_path), "--board", "9by6", "--square", "0.03",
                             "-o", str(tmp_path / "r.yaml")], capsys)
    assert code == 2 and "COLSxROWS" in err
    code, _, err = _run_cli(["calibrate", "--left-dir", str(tmp_path / "nope"), "--right-dir",
                             str(tmp_path), "--square", "0.03", "-o", str(tmp_path / "r.yaml")],
                            capsys)
    assert code == 2 and "is not a folder" in err


def test_cli_on_synthetic_folders(tmp_path, capsys):
    """End to end on rendered images written to two folders (no shared data needed)."""
    src = SyntheticChessboardSource(n_poses=12, seed=11)
    left, right = tmp_path / "left", tmp_path / "right"
    left.mkdir(), right.mkdir()
    for k, pose in enumerate(src.poses):
        a, b = src.render_pair(pose)
        cv2.imwrite(str(left / f"img{k:02d}.png"), a)
        cv2.imwrite(str(right / f"img{k:02d}.png"), b)
    code, out, err = _run_cli(["calibrate", "--left-dir", str(left), "--right-dir", str(right),
                               "--board", "9x6", "--square", "0.03", "-o",
                               str(tmp_path / "rig.yaml")], capsys)
    assert code == 0, err
    for needle in ("RMS reprojection error", "epipolar error", "baseline", "fx", "img00.png",
                   "rejected views"):
        assert needle in out
    rig = StereoRig.load(tmp_path / "rig.yaml")
    assert abs(rig.baseline / src.rig.baseline - 1) < 0.01


def test_cli_one_folder_holding_both_cameras(tmp_path, capsys):
    """OpenCV's sample layout (left01.jpg, right01.jpg … in one folder) given as both folders:
    the images are split by name, never paired with themselves."""
    src = SyntheticChessboardSource(n_poses=10, seed=12)
    for k, pose in enumerate(src.poses):
        a, b = src.render_pair(pose)
        cv2.imwrite(str(tmp_path / f"left{k:02d}.png"), a)
        cv2.imwrite(str(tmp_path / f"right{k:02d}.png"), b)
    code, out, err = _run_cli(["calibrate", "--left-dir", str(tmp_path), "--right-dir",
                               str(tmp_path), "--square", "0.03", "-o",
                               str(tmp_path / "rig.yaml")], capsys)
    assert code == 0, err
    assert "10 image pairs" in out and "left00.png|right00.png" in out
    assert abs(StereoRig.load(tmp_path / "rig.yaml").baseline / src.rig.baseline - 1) < 0.01


def test_cli_refuses_an_image_paired_with_itself(tmp_path, capsys):
    left, _ = _write_pairs(tmp_path, 3, 0)
    code, out, err = _run_cli(["calibrate", "--left-dir", str(left), "--right-dir", str(left),
                               "--square", "0.03", "-o", str(tmp_path / "r.yaml")], capsys)
    assert code == 2 and "both the left and the right image" in err
    assert not (tmp_path / "r.yaml").exists()


def test_same_camera_twice_is_refused_not_graded_excellent(synthetic_views):
    """Copies of the left images given as the right ones solve with T = 0 and an epipolar
    error of 0: that must be an error, not an "excellent" rig."""
    src, views = synthetic_views
    twins = [StereoView(v.view_id, v.object_points, v.left, v.left.copy()) for v in views]
    with pytest.raises(CalibrationError, match="same place"):
        solve_stereo(twins, src.image_size, src.board)


# ---- synthetic ground truth -----------------------------------------------------------------
def test_synthetic_corners_are_accurate(synthetic_views):
    src, views = synthetic_views
    errs = [np.linalg.norm(v.left - src.ground_truth_corners(0, p), axis=1)
            for v, p in zip(views, src.poses)]
    assert float(np.sqrt(np.mean(np.concatenate(errs) ** 2))) < 0.1


def test_synthetic_recovers_intrinsics_and_baseline(synthetic_views):
    src, views = synthetic_views
    seen = []
    res = solve_stereo(views, src.image_size, src.board,
                       progress=lambda f, text: seen.append(f))
    truth = src.rig
    for got, want in ((res.M1, truth.M1), (res.M2, truth.M2)):
        assert abs(got[0, 0] / want[0, 0] - 1) < 0.005
        assert abs(got[0, 2] / want[0, 2] - 1) < 0.005
    assert abs(res.baseline / truth.baseline - 1) < 0.005
    assert res.rms_stereo < 0.2 and res.epipolar_px < 0.1
    assert res.rectified and res.R1 is not None
    assert not res.rejected
    assert seen == sorted(seen) and seen[-1] == 1.0
    assert res.std_left["fx"] > 0 and math.isfinite(res.baseline_std)


def test_rig_round_trip(tmp_path, synthetic_views):
    src, views = synthetic_views
    res = solve_stereo(views, src.image_size, src.board)
    rig = res.to_rig()
    path = tmp_path / "rig.yaml"
    rig.save(path)
    back = StereoRig.load(path)
    for key in ("M1", "D1", "M2", "D2", "R", "T", "R1", "R2", "P1", "P2", "Q"):
        np.testing.assert_allclose(getattr(back, key), getattr(rig, key), rtol=1e-12,
                                   atol=1e-12, err_msg=key)
    assert back.image_size == src.image_size


def test_outlier_view_is_rejected_with_reason():
    rig = default_synthetic_rig()
    board = BoardSpec(9, 6, 0.03)
    views = _projected_views(rig, board, 12, seed=2, distance=0.7)
    bad = views[4]
    shifted = bad.right + np.random.default_rng(0).normal(0, 4.0, bad.right.shape)
    views[4] = StereoView(bad.view_id, bad.object_points, bad.left,
                          shifted.astype(np.float32))
    res = solve_stereo(views, rig.image_size, board)
    assert [r.view_id for r in res.rejected] == ["v4"]
    assert "reprojection error" in res.rejected[0].reason and "median" in res.rejected[0].reason
    assert "v4" not in [v.view_id for v in res.view_errors]
    assert abs(res.baseline / rig.baseline - 1) < 0.005


def test_facing_cameras_are_not_rectified():
    """A rig whose cameras face each other (like NYCU's) gets no R1..Q, and says why."""
    base = default_synthetic_rig()
    r = cv2.Rodrigues(np.array([0.0, math.pi * 0.75, 0.0]))[0]   # 135° about Y
    centre_right = np.array([1.0, 0.0, 1.2])
    rig = StereoRig(M1=base.M1, D1=base.D1, M2=base.M2, D2=base.D2, R=r, T=-r @ centre_right,
                    image_size=base.image_size)
    board = BoardSpec(9, 6, 0.03)
    # Board between the cameras, seen nearly edge-on by neither: turn it to face both halfway.
    obj = board.object_points().astype(np.float64)
    rng = np.random.default_rng(1)
    views = []
    for k in range(8):
        r_b = cv2.Rodrigues(np.array([rng.uniform(-0.3, 0.3), 0.6 + rng.uniform(-0.2, 0.2),
                                      rng.uniform(-0.3, 0.3)]))[0]
        t_b = np.array([rng.uniform(0.05, 0.25), rng.uniform(-0.1, 0.0), 0.6])
        pts = obj @ r_b.T + t_b
        views.append(StereoView(f"v{k}", obj.astype(np.float32),
                                rig.project(0, pts).astype(np.float32),
                                rig.project(1, pts).astype(np.float32)))
    res = solve_stereo(views, rig.image_size, board, SolveOptions(intrinsics="fix"))
    assert not res.rectified and res.R1 is None and res.Q is None
    assert "optical axes differ" in res.rectification_note
    assert res.to_rig().P1 is None


def test_cancel_and_too_few_views(synthetic_views):
    src, views = synthetic_views
    calls = []

    def cancel():
        calls.append(1)
        return len(calls) > 1

    with pytest.raises(CalibrationCancelled):
        solve_stereo(views, src.image_size, src.board, cancel=cancel)
    with pytest.raises(CalibrationError, match="at least 5"):
        solve_stereo(views[:3], src.image_size, src.board)


def test_epipolar_grade_scale():
    assert epipolar_grade(0.05) == "excellent"
    assert epipolar_grade(0.2) == "acceptable"
    assert epipolar_grade(0.3) == "poor"


# ---- court pose -----------------------------------------------------------------------------
def test_court_pose_from_synthetic_clicks():
    rig = default_synthetic_rig((1280, 720))
    # Left camera 8 m behind the near baseline, 4 m up, looking down the court.
    cam_centre = np.array([0.5, -14.0, 4.0])
    forward = -cam_centre + np.array([0.0, 0.0, 0.0])
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0, 0, 1.0])
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    r_cam_from_court = np.stack([right, down, forward])       # rows: camera axes in court
    t_cam = -r_cam_from_court @ cam_centre
    r_court_true, t_court_true = r_cam_from_court.T, cam_centre
    truth = rig.with_court_pose(r_court_true, t_court_true)
    kp = court_keypoints()
    names = ["near back corner left", "near back corner right", "near short service left",
             "near short service right", "far short service centre", "net foot left"]
    court_pts = np.array([kp[n] for n in names])
    clicks = truth.project(0, court_pts)
    clicks += np.random.default_rng(0).normal(0, 0.5, clicks.shape)   # half-pixel clicking
    result = solve_court_pose_detailed(rig, clicks, court_pts)
    assert result.rms_px < 1.5
    got = result.rig
    assert np.linalg.norm(got.T_court - t_court_true) < 0.1           # camera centre, metres
    angle = np.linalg.norm(cv2.Rodrigues(got.R_court @ r_court_true.T)[0])
    assert math.degrees(angle) < 0.5
    # The pose maps the left camera's frame into the court frame.
    pts_left = (court_pts - t_court_true) @ r_court_true
    np.testing.assert_allclose(got.to_output(pts_left), court_pts, atol=0.1)
    assert solve_court_pose(rig, clicks, court_pts).has_court_pose
    with pytest.raises(CalibrationError, match="at least 4"):
        solve_court_pose(rig, clicks[:3], court_pts[:3])


# ---- board detection, view checks, coverage -------------------------------------------------
def test_detection_downscales_large_frames():
    rig = default_synthetic_rig((1920, 1440))
    src = SyntheticChessboardSource(rig=rig, n_poses=2, seed=4, supersample=1)
    pose = src.poses[0]
    image = src.render(0, pose)
    det = detect_board(image, src.board, search_max_side=640)
    assert det is not None and det.complete
    err = np.linalg.norm(det.corners - src.ground_truth_corners(0, pose), axis=1)
    assert float(np.max(err)) < 0.3


def test_view_checks_give_reasons():
    src = SyntheticChessboardSource(n_poses=3, seed=8, noise_sigma=0.5)
    image = src.render(0, src.poses[0])
    gray = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    det = detect_board(gray, src.board)
    assert check_view(det, gray, src.board) == []
    assert check_view(None, gray, src.board) == ["board not found"]
    moved = BoardDetection(det.corners + 5.0, det.ids, det.image_size, det.n_expected)
    assert any("board moving" in r for r in check_view(moved, gray, src.board, previous=det))
    blurred = cv2.GaussianBlur(gray, (0, 0), 4.0)
    det_b = detect_board(blurred, src.board)
    assert det_b is not None
    assert any("blurred" in r for r in check_view(det_b, blurred, src.board))
    at_edge = BoardDetection(det.corners - det.corners.min(axis=0) + 1.0, det.ids,
                             det.image_size, det.n_expected)
    reasons = check_view(at_edge, None, src.board)
    assert any("left and top image border" in r for r in reasons)
    partial = BoardDetection(det.corners[:20], det.ids[:20], det.image_size, det.n_expected)
    assert any("only 20 of 54 corners" in r for r in check_view(partial, None, src.board))


def test_coverage_is_honest_and_novelty_gates():
    size = (640, 480)
    centred = view_params(np.array([[270, 190], [370, 190], [370, 290], [270, 290]]), size)
    assert abs(centred.x - 0.5) < 1e-9 and abs(centred.y - 0.5) < 1e-9 and centred.skew < 1e-9
    empty = coverage([])
    assert empty.as_tuple() == (0, 0, 0, 0)
    one = coverage([centred])
    assert one.x == 0 and one.y == 0 and one.skew == 0 and 0 < one.size < 1
    left = view_params(np.array([[10, 190], [110, 190], [110, 290], [10, 290]]), size)
    right = view_params(np.array([[530, 190], [630, 190], [630, 290], [530, 290]]), size)
    two = coverage([left, right])
    assert two.x == 1.0 and two.y == 0.0
    tilted = view_params(np.array([[270, 190], [370, 150], [370, 330], [270, 290]]), size)
    assert tilted.skew > 0.3
    assert not novelty(centred.as_tuple(), [centred.as_tuple()]).is_new
    verdict = novelty(centred.as_tuple(), [left.as_tuple()])
    assert verdict.is_new and verdict.distance > 0.2
    assert "too similar" in novelty(centred.as_tuple(), [centred.as_tuple()]).reason


def test_capture_gate_on_synthetic_stream():
    """Still frames of a new pose are auto-captured; moving frames and repeats are not."""
    src = SyntheticChessboardSource(n_poses=4, hold_frames=3, move_frames=3, seed=9)
    gate = CaptureGate(src.board)
    captured = []
    for i in range(4 * 6):
        frame = src.read()
        gl = cv2.cvtColor(frame.left, cv2.COLOR_BGR2GRAY)
        gr = cv2.cvtColor(frame.right, cv2.COLOR_BGR2GRAY)
        dl, dr = detect_board(gl, src.board), detect_board(gr, src.board)
        verdict = gate.evaluate(dl, dr, gl, gr)
        if verdict.auto_capture:
            assert src.is_still(i) and src.is_still(i - 1)
            gate.add(dl, dr)
            captured.append(i)
        elif dl is not None and dr is not None and i % 6 in (3, 4):
            assert any("moving" in r for r in verdict.reasons), verdict.reasons
    assert len(captured) == 4                     # one per pose, never the same pose twice
    cov_l, cov_r = gate.coverage()
    assert cov_l.n_views == 4 and 0 < cov_l.x <= 1 and 0 < cov_r.size <= 1


def test_board_spec_validation():
    with pytest.raises(BoardError):
        BoardSpec(6, 6, 0.03)
    with pytest.raises(BoardError):
        BoardSpec(9, 6, -1.0)
    assert BoardSpec.parse("9x6", 0.025).n_corners == 54


@pytest.mark.skipif(not charuco_available(), reason="cv2.aruco.CharucoDetector absent")
def test_charuco_detection():
    spec = BoardSpec(6, 4, 0.04, kind="charuco")
    image = spec.charuco_board().generateImage((700, 500), marginSize=40)
    canvas = np.full((600, 800), 255, np.uint8)
    canvas[50:550, 50:750] = image
    det = detect_board(canvas, spec)
    assert det is not None and det.complete
    assert sorted(det.ids.tolist()) == list(range(spec.n_corners))


def test_core_calibration_does_not_import_qt():
    code = ("import sys; sys.modules['PySide6'] = None; "
            "import badminton_gui.core.calibrate.stereo, badminton_gui.core.calibrate.folders, "
            "badminton_gui.io.synthetic_chessboard; print('ok')")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 0 and "ok" in proc.stdout, proc.stderr


def test_court_clicks_sequence_and_preview(synthetic_views):
    from badminton_gui.core.calibrate.court_pose import CourtClicks
    from badminton_gui.core.calibrate.stereo import rectified_preview
    clicks = CourtClicks()
    first = clicks.current_name
    clicks.click(10, 20)
    clicks.skip()
    clicks.click(30, 40)
    assert len(clicks.clicked) == 2 and not clicks.ready
    clicks.undo()
    assert len(clicks.clicked) == 1 and clicks.current_name == clicks.order[2]
    clicks.undo()
    clicks.undo()
    assert clicks.current_name == first and not clicks.clicked
    src, views = synthetic_views
    res = solve_stereo(views, src.image_size, src.board)
    left, right = src.render_pair(src.poses[0])
    preview = rectified_preview(res, left, right)
    assert preview.shape == (480, 1280, 3)


@pytest.mark.skipif(not charuco_available(), reason="cv2.aruco.CharucoDetector absent")
def test_charuco_stereo_on_synthetic_renders():
    """ChArUco views may be partial: pairs use the ids both cameras saw."""
    spec = BoardSpec(7, 5, 0.04, kind="charuco")
    src = SyntheticChessboardSource(spec, n_poses=12, seed=5)
    views = []
    for k, pose in enumerate(src.poses):
        left, right = src.render_pair(pose)
        det_l, det_r = detect_board(left, spec), detect_board(right, spec)
        if det_l is not None and det_r is not None:
            truth = src.ground_truth_corners(0, pose)[det_l.ids]
            assert float(np.max(np.abs(det_l.corners - truth))) < 0.5
            views.append(pair_detections(f"p{k}", det_l, det_r, spec))
    assert len(views) >= 10
    res = solve_stereo(views, src.image_size, spec)
    assert abs(res.M1[0, 0] / src.rig.M1[0, 0] - 1) < 0.005
    assert abs(res.baseline / src.rig.baseline - 1) < 0.005

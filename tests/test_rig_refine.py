"""Self-calibration of a rig's relative pose (core/calibrate/refine.py, `badminton-track refine-calib`)."""

import math
from types import SimpleNamespace

import cv2
import numpy as np
import pytest

from badminton_gui.cli import main
from badminton_gui.core.rig import StereoRig
from badminton_gui.core.calibrate.refine import PairCollector, refine_relative_pose
from badminton_gui.io.demo_scene import make_rig


def rotated(rig: StereoRig, axis, degrees: float, turn_t_deg: float = 0.0) -> StereoRig:
    """The rig with its relative rotation turned by ``degrees`` about ``axis`` and its baseline
    turned by ``turn_t_deg`` about the same axis: a rig assembled from slightly wrong poses."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    rot = cv2.Rodrigues(axis * math.radians(degrees))[0]
    turn = cv2.Rodrigues(axis * math.radians(turn_t_deg))[0]
    return StereoRig(M1=rig.M1, D1=rig.D1, M2=rig.M2, D2=rig.D2, R=rot @ rig.R, T=turn @ rig.T,
                     image_size=rig.image_size, R_court=rig.R_court, T_court=rig.T_court)


def visible_pairs(rig: StereoRig, n: int, seed: int = 0, noise_px: float = 0.3):
    """Pixel pairs of random points of a court-sized volume that both cameras see."""
    rng = np.random.default_rng(seed)
    pts = np.column_stack([rng.uniform(-3.0, 3.0, 4 * n), rng.uniform(-6.5, 6.5, 4 * n),
                           rng.uniform(0.2, 6.0, 4 * n)])
    w, h = rig.image_size
    left, right = rig.project(0, pts), rig.project(1, pts)
    seen = ((rig.depth(0, pts) > 0.5) & (rig.depth(1, pts) > 0.5)
            & (left[:, 0] >= 0) & (left[:, 0] < w) & (left[:, 1] >= 0) & (left[:, 1] < h)
            & (right[:, 0] >= 0) & (right[:, 0] < w) & (right[:, 1] >= 0) & (right[:, 1] < h))
    left, right = left[seen][:n], right[seen][:n]
    assert len(left) == n
    return (left + rng.normal(0, noise_px, left.shape), right + rng.normal(0, noise_px, right.shape))


def angle_between(r_a: np.ndarray, r_b: np.ndarray) -> float:
    return math.degrees(float(np.linalg.norm(cv2.Rodrigues(r_a @ r_b.T)[0])))


@pytest.mark.parametrize("kind", ["binocular", "ends"])
def test_a_rig_several_degrees_off_is_refitted_from_its_pairs(kind):
    truth = make_rig(kind)
    wrong = rotated(truth, (0.3, 1.0, 0.2), 4.0, turn_t_deg=3.0)
    left, right = visible_pairs(truth, 400)
    assert np.median(wrong.pair_errors(left, right)) > 5.0
    refined, report = refine_relative_pose(wrong, left, right)
    assert report.accepted, report.reason
    assert angle_between(refined.R, truth.R) < 0.3
    cos_t = np.dot(refined.T, truth.T) / (np.linalg.norm(refined.T) * np.linalg.norm(truth.T))
    assert math.degrees(math.acos(min(1.0, cos_t))) < 1.5
    # What the refit cannot know is kept: the baseline's length, the intrinsics, the court pose.
    assert np.linalg.norm(refined.T) == pytest.approx(np.linalg.norm(wrong.T))
    assert np.array_equal(refined.M1, wrong.M1) and np.array_equal(refined.R_court, wrong.R_court)
    assert report.after_median_px < 1.0 < 5.0 < report.before_median_px
    # New pairs, never fitted, agree with the refined rig as with the true one.
    fresh_l, fresh_r = visible_pairs(truth, 200, seed=1)
    assert np.median(refined.pair_errors(fresh_l, fresh_r)) < 1.0


def test_a_good_rig_is_kept_and_so_is_one_with_too_few_pairs():
    truth = make_rig("binocular")
    left, right = visible_pairs(truth, 300)
    kept, report = refine_relative_pose(truth, left, right)
    assert kept is truth and not report.accepted and "already fits" in report.reason
    # Noisier detections (median error over a pixel): the refit is tried, and refused because it
    # is not clearly better than the true rig.
    noisy_l, noisy_r = visible_pairs(truth, 300, noise_px=2.0)
    kept, report = refine_relative_pose(truth, noisy_l, noisy_r)
    assert report.before_median_px > 1.0
    assert kept is truth and not report.accepted and "better" in report.reason
    wrong = rotated(truth, (0, 1, 0), 3.0)
    kept, report = refine_relative_pose(wrong, left[:50], right[:50])
    assert kept is wrong and not report.accepted and "50 pairs" in report.reason


def test_a_rig_within_a_pixel_is_not_refitted_to_the_noise():
    """Sub-pixel pairs: the refit would 'improve' them by fitting noise; the rig is kept before
    any fit, and a rig a few pixels off is still refitted from the same pairs."""
    truth = make_rig("binocular")
    left, right = visible_pairs(truth, 300, noise_px=0.1)
    slightly = rotated(truth, (0, 1, 0), 0.02)
    assert 0.05 < np.median(slightly.pair_errors(left, right)) < 1.0
    kept, report = refine_relative_pose(slightly, left, right)
    assert kept is slightly and not report.accepted and "under 1 px" in report.reason
    assert report.inliers == 0          # refused before fitting anything
    off = rotated(truth, (0, 1, 0), 3.0)
    assert np.median(off.pair_errors(left, right)) > 2.0
    refined, report = refine_relative_pose(off, left, right)
    assert report.accepted, report.reason


def test_a_refit_that_does_not_hold_on_later_pairs_is_refused():
    """Pairs that fit one geometry early and are junk later (a wrong match followed for the last
    third of the run) must not be trusted: the refit of the first two thirds fails on the last."""
    truth = make_rig("ends")
    wrong = rotated(truth, (1, 0, 0), 5.0)
    left, right = visible_pairs(truth, 300)
    rng = np.random.default_rng(3)
    w, h = truth.image_size
    right[200:] = rng.uniform([0, 0], [w, h], size=(100, 2))
    kept, report = refine_relative_pose(wrong, left, right)
    assert kept is wrong and not report.accepted


def test_pair_errors_is_the_diagonal_of_epipolar_errors():
    rig = rotated(make_rig("ends"), (0, 0, 1), 2.0)
    left, right = visible_pairs(make_rig("ends"), 30)
    assert np.allclose(rig.pair_errors(left, right), np.diag(rig.epipolar_errors(left, right)))


def result(left, right):
    """A stand-in for a TrackResult: what PairCollector reads of it."""
    def det(d):
        if d is None:
            return None
        x, y, tracklet, predicted = d
        return SimpleNamespace(x=x, y=y, tracklet=tracklet, predicted=predicted)
    return SimpleNamespace(left=SimpleNamespace(detection=det(left)),
                           right=SimpleNamespace(detection=det(right)))


def test_pair_collector_keeps_only_the_followed_shuttle_in_both_cameras():
    collector = PairCollector(min_track_frames=3, min_step_px=2.0)
    kept = []
    for i in range(10):
        # Left follows tracklet 7 all along; right switches from tracklet 1 to 2 at frame 4.
        kept.append(collector.add(result((10.0 * i, 5.0, 7, False), (20.0 * i, 9.0, 1 if i < 4 else 2, False))))
    assert kept == [False, False, True, True, False, False, True, True, True, True]
    # A coasting prediction breaks the run; a shuttle at rest adds no new pair.
    assert not collector.add(result((200.0, 5.0, 7, True), (300.0, 9.0, 2, False)))
    for _ in range(3):
        collector.add(result((100.0, 5.0, 7, False), (200.0, 9.0, 2, False)))
    n = len(collector)
    assert not collector.add(result((100.5, 5.0, 7, False), (200.0, 9.0, 2, False)))
    left, right = collector.points()
    assert left.shape == right.shape == (n, 2)


def test_refine_calib_command_on_a_demo_recording(tmp_path, capsys):
    """End to end: a demo rally, a rig turned by 3°, the command writes a rig close to the truth."""
    assert main(["demo", "--frames", "600", "--out", str(tmp_path), "--size", "640x360",
                 "--rig", "binocular", "--seed", "2"]) == 0
    truth = StereoRig.load(tmp_path / "rig.yaml")
    wrong = rotated(truth, (0.2, 1.0, 0.1), 3.0)
    wrong.save(tmp_path / "wrong.yaml")
    out = tmp_path / "refined.yaml"
    code = main(["refine-calib", "--left", str(tmp_path / "left.mp4"), "--right",
                 str(tmp_path / "right.mp4"), "--calib", str(tmp_path / "wrong.yaml"), "-o", str(out),
                 "--quiet"])
    text = capsys.readouterr()
    assert code == 0, text.err
    assert "refined" in text.out
    refined = StereoRig.load(out)
    # A short baseline leaves a little give between the rotation and the baseline's direction.
    assert angle_between(refined.R, truth.R) < 0.6 < 2.5 < angle_between(wrong.R, truth.R)
    assert np.median(refined.pair_errors(*visible_pairs(truth, 200, seed=4))) < 1.0


def test_refine_calib_says_why_it_wrote_nothing(tmp_path, capsys):
    assert main(["demo", "--frames", "60", "--out", str(tmp_path), "--size", "640x360"]) == 0
    out = tmp_path / "refined.yaml"
    code = main(["refine-calib", "--left", str(tmp_path / "left.mp4"), "--right",
                 str(tmp_path / "right.mp4"), "--calib", str(tmp_path / "rig.yaml"), "-o", str(out),
                 "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and "not refined" in err and "pairs" in err and not out.exists()

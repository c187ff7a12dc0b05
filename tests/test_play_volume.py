"""Two cameras' detections pair only where the shuttle can be (``stereo.play_volume``).

An LED board's moving dot beside the court is seen by both cameras where it is, so its two
blobs meet the epipolar gate like the shuttle's. On the demo court's rig behind the baselines a
dot 5.6 m from the centre line (2.55 m outside the doubles sideline, beyond the play volume's
2 m margin) that scores higher than the shuttle in both cameras is not paired, and the shuttle
is; with the switch off (the default) the dot wins, as it did on the randomised courts. A
camera whose shuttle is out of the other camera's view does not keep the dot as its own choice
either.
"""

import numpy as np

from badminton_gui.core.params import TrackerParams
from badminton_gui.core.tracker import StereoTracker
from badminton_gui.core.types import CameraResult, Candidate
from badminton_gui.io.demo_scene import make_rig

ON = TrackerParams().with_value("stereo.play_volume", True)
OFF = TrackerParams().with_value("stereo.play_volume", False)
SHUTTLE = (0.5, 2.0, 3.0)     # court frame, m: over the far half
BOARD_DOT = (5.6, 1.0, 0.5)   # on a board standing beside the court


def _results(rig):
    """Each camera's candidates: the board dot (higher score) and the shuttle, both passed."""
    out = []
    for cam in (0, 1):
        cands = []
        for where, score in ((BOARD_DOT, 0.9), (SHUTTLE, 0.6)):
            u, v = rig.project(cam, np.array([where]))[0]
            assert 0 <= u < rig.image_size[0] and 0 <= v < rig.image_size[1]
            cands.append(Candidate(float(u), float(v), 30.0, 4.0, 200.0, 12.0, float("nan"), score, None))
        out.append(CameraResult(None, tuple(cands), image_size=rig.image_size))
    return out


def _pair(params):
    rig = make_rig("ends", (1280, 720))
    tracker = StereoTracker(rig, params, parallel=False)
    try:
        left, right = _results(rig)
        pair = tracker.pairing.choose_pair(left, right)
        board_alone = tracker.pairing.pair_point(left.candidates[0], right.candidates[0])[0]
        return rig, pair, board_alone
    finally:
        tracker.close()


def test_on_by_default():
    assert TrackerParams().stereo.play_volume


def test_a_pair_outside_the_play_volume_is_not_the_shuttle():
    rig, pair, board_alone = _pair(ON)
    assert pair.point is not None
    assert np.allclose(rig.to_output(pair.point)[0], SHUTTLE, atol=0.05)
    assert pair.left.score == 0.6 and pair.right.score == 0.6
    assert board_alone is None


def test_switched_off_the_board_dot_pairs():
    rig, pair, board_alone = _pair(OFF)
    assert np.allclose(rig.to_output(pair.point)[0], BOARD_DOT, atol=0.05)
    assert board_alone is not None


def test_the_margin_is_the_play_volume_one():
    # A margin wide enough to hold the board takes the dot back.
    params = ON.with_value("shuttle_scale.court_margin", 3.0)
    rig, pair, _ = _pair(params)
    assert np.allclose(rig.to_output(pair.point)[0], BOARD_DOT, atol=0.05)


def test_a_camera_left_without_a_pair_does_not_keep_the_board_dot():
    # The shuttle out of the right camera's view (above its picture): the right camera sees
    # only the dot, the left both. The dot pairs only outside the play volume, so it is
    # rejected in both cameras and the left camera's own choice is the shuttle.
    rig = make_rig("ends", (1280, 720))
    tracker = StereoTracker(rig, ON, parallel=False)
    try:
        left, right = _results(rig)
        right = CameraResult(None, right.candidates[:1], image_size=rig.image_size)
        left, right = tracker.pairing.reject_off_volume(left, right)
        assert [c.rejected_by for c in left.candidates] == ["stereo", None]
        assert [c.rejected_by for c in right.candidates] == ["stereo"]
        assert tracker.left.choose(left.candidates).score == 0.6
        assert tracker.right.choose(right.candidates) is None
        # Inside a play volume wide enough to hold the board, the dot may be the shuttle.
        inside = ON.with_value("shuttle_scale.court_margin", 3.0)
        tracker.set_params(inside)
        left, right = _results(rig)
        kept = tracker.pairing.reject_off_volume(left, right)
        assert kept[0] is left and kept[1] is right
    finally:
        tracker.close()

"""The guided look for the shuttle at its flight's projection (core/guided.py, no Qt).

It must find a small white moving spot, and refuse what is not a shuttle in flight: nothing
bright, a court line crossing the window, a white shirt, a glint that did not move.
"""

import math

import cv2
import numpy as np

from badminton_gui.core.guided import find_spot


def floor(seed=0):
    rng = np.random.default_rng(seed)
    img = np.full((120, 160, 3), (90, 60, 40), np.uint8)              # blue-ish court
    return np.clip(img + rng.normal(0, 2.5, img.shape), 0, 255).astype(np.uint8)


def with_shuttle(img, x, y, r=2.0):
    out = img.copy()
    cv2.circle(out, (int(round(x * 16)), int(round(y * 16))), int(r * 16), (235, 235, 235), -1,
               lineType=cv2.LINE_AA, shift=4)
    return out


def test_a_white_moving_spot_is_found_at_its_centroid():
    before = with_shuttle(floor(1), 70.0, 58.0)
    now = with_shuttle(floor(2), 80.3, 61.6)
    spot = find_spot(now, 78.0, 60.0, radius=8.0, min_contrast=25, max_area=60, previous_bgr=before)
    assert spot is not None
    x, y, contrast, area = spot
    assert math.hypot(x - 80.3, y - 61.6) < 0.3
    assert contrast > 100 and 5 <= area <= 30


def test_nothing_bright_far_or_static_is_no_spot():
    empty = floor(3)
    assert find_spot(empty, 80, 60, 8.0, 25, 60) is None
    now = with_shuttle(floor(4), 100.0, 60.0)
    assert find_spot(now, 80, 60, 8.0, 25, 60) is None                      # beyond the radius
    glint = with_shuttle(floor(5), 80.0, 60.0)
    assert find_spot(glint, 80, 60, 8.0, 25, 60, previous_bgr=glint.copy()) is None   # did not move
    assert find_spot(glint, 80, 60, 8.0, 25, 60) is not None                # no previous frame: no test


def test_a_line_crossing_the_window_or_a_white_shirt_is_no_spot():
    line = floor(6)
    cv2.line(line, (0, 60), (159, 60), (230, 230, 230), 2)
    assert find_spot(line, 80, 60, 8.0, 25, 60, previous_bgr=floor(7)) is None
    shirt = floor(8)
    cv2.rectangle(shirt, (74, 54), (86, 66), (240, 240, 240), -1)           # 169 px: not a shuttle
    assert find_spot(shirt, 80, 60, 8.0, 25, 60, previous_bgr=floor(9)) is None
    for colour in ((40, 40, 230), (150, 180, 235)):                         # a red frame, a hand
        spot = floor(10)
        cv2.circle(spot, (80, 60), 2, colour, -1)                           # bright, but not white
        assert find_spot(spot, 80, 60, 8.0, 25, 60, previous_bgr=floor(11)) is None


def test_the_flight_projection_stands_in_only_where_the_camera_is_blind():
    """``FlightLook.coast``: a camera with no detection reports the 3D flight's
    projection only inside its blind spot (a light: background ≥ ``binarize.max_background``)
    or on a blob too large for a shuttle; a coasting prediction is moved onto the projection;
    a real detection is left alone."""
    from badminton_gui.core.tracker import StereoTracker
    from badminton_gui.core.types import CameraResult, Candidate
    from badminton_gui.io.demo_scene import make_rig

    rig = make_rig("binocular", (320, 180))
    tracker = StereoTracker(rig, parallel=False)
    img = np.full((180, 320, 3), 60, np.uint8)
    cv2.rectangle(img, (200, 40), (260, 80), (250, 250, 250), -1)          # a light panel
    # The right camera sees the scene from its own place (shifted along the baseline): two
    # cameras never give identical images, and the tracker refuses a pair that does.
    tracker.process(img, np.roll(img, -8, axis=1), 0.0, 0, 0, keep_masks=False)

    def guide_at(u, v, depth=6.0):
        ray = np.linalg.solve(rig.M1, [u, v, 1.0]) * depth                # left-camera frame
        return rig.to_output(ray[None])[0], np.eye(3) * 1e-4

    assert np.allclose(rig.project(0, guide_at(230.0, 60.0)[0][None])[0], (230.0, 60.0))
    empty = CameraResult(detection=None, candidates=(), image_size=(320, 180))
    res, det = tracker.look.coast(0, img, empty, None, guide_at(230.0, 60.0))
    assert det is not None and det.predicted and math.hypot(det.x - 230, det.y - 60) < 1e-6
    assert det in res.candidates
    res, det = tracker.look.coast(0, img, empty, None, guide_at(100.0, 120.0))   # not blind there
    assert det is None and res.candidates == ()
    coasting = Candidate(240.0, 70.0, math.nan, math.nan, math.nan, math.nan, 0.0, 2.0, None, predicted=True)
    res, det = tracker.look.coast(0, img, dataclasses_replace(empty, coasting), coasting, guide_at(100.0, 120.0))
    assert det.predicted and math.hypot(det.x - 100, det.y - 120) < 1e-6 and det.score == 2.0
    assert res.candidates == (det,)
    # A blob too large for a shuttle (a player's arm) covers the projection: the shuttle
    # merged with it, the projection stands in (``stereo.guided_merged``); not on background.
    arm = img.copy()
    cv2.rectangle(arm, (20, 100), (160, 130), (150, 150, 150), -1)
    tracker.process(arm, np.roll(arm, -8, axis=1), 1 / 120, 1, 1, keep_masks=False)
    assert tracker.left.is_merged(90.0, 115.0) and not tracker.left.is_merged(90.0, 150.0)
    in_front = with_shuttle(arm, 90.0, 115.0, r=1.5)
    res, det = tracker.look.coast(0, in_front, empty, None, guide_at(90.0, 115.0))
    assert det is not None and det.predicted
    res, det = tracker.look.coast(0, arm, empty, None, guide_at(90.0, 115.0))   # hidden behind it
    assert det is None
    res, det = tracker.look.coast(0, in_front, empty, None, guide_at(90.0, 150.0))
    assert det is None
    seen = Candidate(150.0, 90.0, 30.0, 6.0, 200.0, 40.0, 1.0, 3.0, None)
    res, det = tracker.look.coast(0, img, dataclasses_replace(empty, seen), seen, guide_at(230.0, 60.0))
    assert det is seen
    tracker.close()


def dataclasses_replace(result, candidate):
    import dataclasses
    return dataclasses.replace(result, candidates=(candidate,))

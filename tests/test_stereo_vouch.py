"""The other camera vouches for a candidate the association held back (``stereo.stereo_vouch``).

A shuttle point moving at a few m/s in front of the demo rig, projected into both cameras: the
held-back candidates pass when they lie on each other's epipolar line and their tracks' image
velocities triangulate to a moving 3D point; not when the point is at rest, when one camera's
candidate is off the epipolar line, when its track moves another way, or when that camera
already has a survivor of its own (it is then only a partner). And the followed 3D flight
vouches for a pair of reports just off the epipolar gate (``StereoPairing.flight_vouched_pair``),
and the last step's pair of tracklets continues off it while its miss changes smoothly
(``StereoPairing.continued_pair``).
"""

import dataclasses

import numpy as np
import pytest

from badminton_gui.core.detector import CameraDetector
from badminton_gui.core.params import TrackerParams
from badminton_gui.core.stereo.look import ImagePaths, stereo_look
from badminton_gui.core.tracker import StereoTracker
from badminton_gui.core.types import REJECT_MOTION, CameraResult, Candidate
from badminton_gui.io.demo_scene import make_rig

DT = 0.02


class FakeDetector:
    """Stands in for a CameraDetector: per candidate, its track's image velocity."""

    def __init__(self, velocities: dict):
        self.velocities = velocities       # id(candidate) -> (vx, vy)
        self.vouched = []

    def vouchable(self, c, min_quality):
        return self.velocities.get(id(c)) if c.rejected_by == REJECT_MOTION else None

    def first_sighting(self, c, min_quality):
        return (c.rejected_by == REJECT_MOTION and id(c) in self.velocities
                and self.velocities[id(c)] is None and c.score >= min_quality)

    def tracklet_velocity(self, c):
        return self.velocities.get(id(c))

    def choose(self, candidates):
        return CameraDetector.choose(None, candidates)

    def vouch(self, c, score):
        self.vouched.append(c)
        return dataclasses.replace(c, rejected_by=None, score=score)


def _candidate(u, v, rejected=REJECT_MOTION, score=0.5):
    return Candidate(float(u), float(v), 30.0, 6.0, 200.0, 20.0, float("nan"), score, rejected)


def _scene(tracker, velocity_3d, right_offset=(0.0, 0.0), right_velocity_offset=(0.0, 0.0),
           right_rejected=REJECT_MOTION, first=False, score=0.5, right_score=None):
    rig = tracker.rig
    p = np.array([[0.3, -2.0, 1.8]])                 # court frame, m
    back = p - DT * np.asarray(velocity_3d)[None]
    res, dets = [], []
    for cam in (0, 1):
        now_uv = rig.project(cam, p)[0]
        back_uv = rig.project(cam, back)[0]
        vel = (now_uv - back_uv) / DT
        if cam == 1:
            now_uv = now_uv + np.asarray(right_offset)
            vel = vel + np.asarray(right_velocity_offset)
        c = _candidate(*now_uv, rejected=REJECT_MOTION if cam == 0 else right_rejected,
                       score=score if cam == 0 or right_score is None else right_score)
        clutter = _candidate(now_uv[0] + 200, now_uv[1] + 80)
        det = FakeDetector({id(c): None if first else tuple(vel), id(clutter): (0.0, 0.0)})
        res.append(CameraResult(None, (clutter, c), image_size=(1280, 720)))
        dets.append(det)
    tracker.left, tracker.right = dets
    tracker.vouch.detectors = tracker.pairing.detectors = tracker.look.detectors = tuple(dets)
    return res


@pytest.fixture
def tracker():
    t = StereoTracker(make_rig("binocular", (1280, 720)), TrackerParams(), parallel=False)
    yield t
    t.close()


def _passed(res):
    return [c for c in res.candidates if c.rejected_by is None]


def test_a_moving_consistent_pair_passes_in_both_cameras(tracker):
    left, right = tracker.vouch.apply(*_scene(tracker, (0.0, 3.0, 1.0)))
    (pl,), (pr,) = _passed(left), _passed(right)
    assert pl.score == pr.score == 0.5
    # ... and the pair is then the stereo choice
    pair = tracker.pairing.choose_pair(left, right)
    det_l, det_r, point = pair.left, pair.right, pair.point
    assert det_l is pl and det_r is pr and point is not None


def test_at_rest_off_the_epipolar_line_or_moving_apart_nothing_passes(tracker):
    for kwargs in ({"velocity_3d": (0.0, 0.0, 0.0)},
                   {"velocity_3d": (0.0, 3.0, 1.0), "right_offset": (0.0, 8.0)},
                   {"velocity_3d": (0.0, 3.0, 1.0), "right_velocity_offset": (0.0, 600.0)}):
        left, right = tracker.vouch.apply(*_scene(tracker, **kwargs))
        assert not _passed(left) and not _passed(right), kwargs


def test_a_camera_with_its_own_survivor_is_only_a_partner(tracker):
    left, right = tracker.vouch.apply(*_scene(tracker, (0.0, 3.0, 1.0), right_rejected=None))
    assert len(_passed(left)) == 1
    assert tracker.left.vouched and not tracker.right.vouched


def test_vouchable_needs_a_moving_track_of_enough_quality():
    det = CameraDetector(TrackerParams())
    # Two hits 3 px apart, 10 ms apart: a young tracklet (not confirmed yet) moving at 300 px/s.
    for k, x in enumerate((97.0, 100.0)):
        [(ident, _, merit)] = det.associator.update(k / 100.0, np.array([[x, 100.0]]), np.array([0.3]))
    assert merit < 0                                         # held back by the association
    c = dataclasses.replace(_candidate(100.0, 100.0), tracklet=ident)
    assert det.vouchable(c, 0.1) == pytest.approx((300.0, 0.0))
    assert det.vouchable(c, 0.5) is None                     # quality too low
    assert det.vouchable(dataclasses.replace(c, rejected_by=None), 0.1) is None
    assert det.vouchable(dataclasses.replace(c, tracklet=-1), 0.1) is None   # on no tracklet
    passed = det.vouch(c, 0.3)
    assert passed.rejected_by is None and passed.score == 0.3
    assert det.tracklet_velocity(passed) == det.tracklet_velocity(c) is not None   # keeps its tracklet
    [(same, _, _)] = det.associator.update(0.02, np.array([[100.5, 100.0]]), np.array([0.3]))
    assert same == ident
    assert det.vouchable(c, 0.1) is None                     # hardly moved in its last step


def test_off_by_the_flag():
    params = TrackerParams().with_value("stereo.stereo_vouch", False)
    t = StereoTracker(make_rig("binocular", (1280, 720)), params, parallel=False)
    try:
        called = []
        t.vouch.apply = lambda a, b: called.append(1) or (a, b)
        frame = np.zeros((720, 1280, 3), np.uint8)
        t.process(frame, frame, 0.0)
        assert not called
    finally:
        t.close()


def test_first_sightings_pass_by_position_when_they_look_like_a_shuttle(tracker):
    """Both tracks seen for the first time (no velocity): the pair passes on its epipolar
    agreement alone when both score at least ``vouch_first_quality``, not below it, not off the
    epipolar line, and never when that is 1."""
    q = tracker.params.stereo.vouch_first_quality
    assert q < 1.0
    left, right = tracker.vouch.apply(*_scene(tracker, (0.0, 0.0, 0.0), first=True, score=q + 0.05))
    assert len(_passed(left)) == len(_passed(right)) == 1
    for kwargs in ({"score": q - 0.05}, {"score": 0.9, "right_offset": (0.0, 8.0)}):
        left, right = tracker.vouch.apply(*_scene(tracker, (0.0, 0.0, 0.0), first=True, **kwargs))
        assert not _passed(left) and not _passed(right), kwargs
    tracker.params = tracker.params.with_value("stereo.vouch_first_quality", 1.0)
    left, right = tracker.vouch.apply(*_scene(tracker, (0.0, 0.0, 0.0), first=True, score=0.99))
    assert not _passed(left) and not _passed(right)


def test_a_weak_lone_detection_is_looked_past_at_the_flights_projection(tracker):
    """``stereo.guided_weak_score``: without a stereo pair, a detection scoring below it that
    lies off the flight's projection gives way to a white spot found there; a strong one, a
    paired one, or any with the setting at 0 does not."""
    import cv2

    guide = (np.array([0.3, -2.0, 1.8]), np.eye(3) * 1e-4)
    u, v = tracker.rig.project(1, guide[0][None])[0]
    frame = np.full((720, 1280, 3), 40, np.uint8)
    cv2.circle(frame, (int(round(u)), int(round(v))), 3, (255, 255, 255), -1)
    far = _candidate(u + 60, v + 40, rejected=None, score=1.0)
    assert tracker.look.weak_lone(far, paired=False)
    assert not tracker.look.weak_lone(dataclasses.replace(far, score=5.0), paired=False)
    assert not tracker.look.weak_lone(far, paired=True)
    assert not tracker.look.guided(1, frame, None, far, guide)                    # not looked past
    found = tracker.look.guided(1, frame, None, far, guide, override=True)
    assert found is not None and abs(found.x - u) < 1.5 and abs(found.y - v) < 1.5
    near = _candidate(u + 1, v, rejected=None, score=1.0)
    assert tracker.look.guided(1, frame, None, near, guide, override=True) is None  # already there
    tracker.params = tracker.params.with_value("stereo.guided_weak_score", 0.0)
    assert not tracker.look.weak_lone(far, paired=False)


def test_a_weak_first_sighting_passes_only_with_a_sure_partner(tracker):
    """``stereo.vouch_first_partner_quality``: a first sighting scoring below
    ``vouch_first_quality`` but at least this passes beside one that scores enough; two weak
    ones do not, nor one below it, nor any with the setting at 1."""
    tracker.params = tracker.params.with_value("stereo.vouch_first_partner_quality", 0.1)
    left, right = tracker.vouch.apply(*_scene(tracker, (0.0, 0.0, 0.0), first=True, score=0.6, right_score=0.15))
    assert len(_passed(left)) == len(_passed(right)) == 1
    for score, right_score in ((0.15, 0.15), (0.6, 0.05)):
        left, right = tracker.vouch.apply(*_scene(tracker, (0.0, 0.0, 0.0), first=True, score=score,
                                             right_score=right_score))
        assert not _passed(left) and not _passed(right), (score, right_score)
    tracker.params = tracker.params.with_value("stereo.vouch_first_partner_quality", 1.0)
    left, right = tracker.vouch.apply(*_scene(tracker, (0.0, 0.0, 0.0), first=True, score=0.6, right_score=0.15))
    assert not _passed(left) and not _passed(right)


def test_shuttle_like_blobs_pass_by_position_when_their_velocities_disagree(tracker):
    """``stereo.vouch_position_quality``: just after a hit the tracks' smoothed velocities mix
    the old and the new flight; a pair on the epipolar line whose held-back candidates both
    score at least this passes anyway, a less shuttle-like one does not, nor any off the line."""
    tracker.params = tracker.params.with_value("stereo.vouch_position_quality", 0.8)
    kwargs = {"velocity_3d": (0.0, 3.0, 1.0), "right_velocity_offset": (0.0, 600.0)}
    left, right = tracker.vouch.apply(*_scene(tracker, score=0.9, **kwargs))
    assert len(_passed(left)) == len(_passed(right)) == 1
    for extra in ({"score": 0.9, "right_score": 0.5}, {"score": 0.9, "right_offset": (0.0, 8.0)}):
        left, right = tracker.vouch.apply(*_scene(tracker, **kwargs, **extra))
        assert not _passed(left) and not _passed(right), extra
    tracker.params = tracker.params.with_value("stereo.vouch_position_quality", 1.0)
    left, right = tracker.vouch.apply(*_scene(tracker, score=0.99, **kwargs))
    assert not _passed(left) and not _passed(right)


def test_a_camera_whose_survivor_has_no_partner_is_helped(tracker):
    """``stereo.vouch_lone``: the right camera's only survivor (clutter) has no partner on the
    left camera's epipolar lines while its held-back shuttle lies on the left choice's: the
    shuttle passes and the stereo choice takes it; with the setting off, or when the right
    survivor does pair with the left choice, nothing is let through."""
    res_l, res_r = _scene(tracker, (0.0, 3.0, 1.0))
    left_shuttle = dataclasses.replace(res_l.candidates[1], rejected_by=None, score=4.0)
    tracker.left.velocities[id(left_shuttle)] = tracker.left.velocities[id(res_l.candidates[1])]
    res_l = dataclasses.replace(res_l, candidates=(res_l.candidates[0], left_shuttle))
    clutter_r = dataclasses.replace(res_r.candidates[0], rejected_by=None, score=1.5)
    tracker.right.velocities[id(clutter_r)] = (0.0, 0.0)
    res_r = dataclasses.replace(res_r, candidates=(clutter_r, res_r.candidates[1]))
    left, right = tracker.vouch.apply(res_l, res_r)
    assert tracker.right.vouched == [res_r.candidates[1]] and not tracker.left.vouched
    pair = tracker.pairing.choose_pair(left, right)
    det_l, det_r, point = pair.left, pair.right, pair.point
    assert det_l is left_shuttle and det_r.x == res_r.candidates[1].x and point is not None
    tracker.right.vouched.clear()
    tracker.params = tracker.params.with_value("stereo.vouch_lone", False)
    left, right = tracker.vouch.apply(res_l, res_r)
    assert len(_passed(right)) == 1 and not tracker.right.vouched
    # the right survivor pairs with the left choice: not lone, nothing is let through
    tracker.params = tracker.params.with_value("stereo.vouch_lone", True)
    paired_r = dataclasses.replace(res_r.candidates[1], rejected_by=None, score=1.5)
    tracker.right.velocities[id(paired_r)] = tracker.right.velocities[id(res_r.candidates[1])]
    held = dataclasses.replace(res_r.candidates[1], x=res_r.candidates[1].x + 1.0)
    tracker.right.velocities[id(held)] = tracker.right.velocities[id(res_r.candidates[1])]
    left, right = tracker.vouch.apply(res_l, dataclasses.replace(res_r, candidates=(paired_r, held)))
    assert not tracker.right.vouched


def test_a_lone_detection_at_the_border_gives_way_when_the_flight_has_left_the_image(tracker):
    """``stereo.exit_margin``: an unpaired detection this near the border is dropped when the
    3D flight projects just outside the image next to it; not when the projection is inside the
    image, nor far from the detection, nor for a detection away from the border."""
    frame = np.zeros((720, 1280, 3), np.uint8)
    rig = tracker.rig
    # court points 4 m in front of the left camera, projecting 2 px left of the image / 3 px inside
    K = rig.M1

    def at(u, v):
        cam = np.array([(u - K[0, 2]) * 4.0 / K[0, 0], (v - K[1, 2]) * 4.0 / K[1, 1], 4.0])
        return np.asarray(rig.to_output(cam[None]))[0]

    out, inside = at(-2.0, 300.0), at(3.0, 300.0)
    u, v = rig.project(0, out[None])[0]
    assert -2.5 < u < -1.5 and 0 <= v < 720
    tracker.params = tracker.params.with_value("stereo.exit_margin", 3.0)
    at_border = _candidate(0.8, v - 2.0, rejected=None, score=5.0)
    assert tracker.look.near_border(at_border, frame)
    assert tracker.look.gone_out(0, at_border, frame, out)
    assert rig.project(0, inside[None])[0][0] > 0
    assert not tracker.look.gone_out(0, at_border, frame, inside)
    far = dataclasses.replace(at_border, y=v + 80.0)
    assert not tracker.look.gone_out(0, far, frame, out)
    assert not tracker.look.near_border(dataclasses.replace(at_border, x=10.0), frame)
    tracker.params = tracker.params.with_value("stereo.exit_margin", 0.0)
    assert not tracker.look.near_border(dataclasses.replace(at_border, x=0.0), frame)


def test_the_stereo_look_finds_a_spot_on_the_path_and_the_epipolar_line(tracker):
    """``stereo.stereo_look``: a camera with no detection finds the white spot where its own
    image path continues, when it lies on the epipolar line of the other camera's detection;
    not a spot off that line, nor with a stale or missing report, nor far from the path."""
    import cv2

    rig = tracker.rig
    p = np.array([0.3, -2.0, 1.8])
    ul, vl = rig.project(0, p[None])[0]
    ur, vr = rig.project(1, p[None])[0]
    other = _candidate(ul, vl, rejected=None, score=4.0)
    dt = 1.0 / 120.0

    def frame_with(u, v):
        f = np.full((720, 1280, 3), 40, np.uint8)
        cv2.circle(f, (int(round(u)), int(round(v))), 2, (255, 255, 255), -1)
        return f

    def look(spot, reports, t=2 * dt):
        paths = ImagePaths()
        for report in reports:
            paths.note(1, *report)
        previous = np.full((720, 1280, 3), 40, np.uint8)
        return stereo_look(tracker.rig, tracker.params, tracker.gate, paths, 1, frame_with(*spot), previous,
                           other, t)

    # the right camera's path: 6 px a frame to the right, last reported one frame ago
    path = [(0.0, ur - 12.0, vr, None), (dt, ur - 6.0, vr, None)]
    found = look((ur, vr), path)
    assert found is not None and abs(found.x - ur) < 1.0 and abs(found.y - vr) < 1.0
    assert found.score == 0.0 and not found.predicted
    # with the track's own velocity instead of the two reports
    assert look((ur, vr), [(dt, ur - 6.0, vr, (720.0, 0.0))]) is not None
    assert look((ur, vr + 6.0), path) is None                 # off the epipolar line (6 px)
    assert look((ur, vr), path, t=dt + 0.05) is None           # the last report is stale
    assert look((ur, vr), path[1:]) is None                    # one report, no velocity
    assert look((ur, vr), [(0.0, ur - 40.0, vr, None), (dt, ur - 30.0, vr, None)]) is None  # off the path


def test_the_image_path_and_the_flight_say_when_the_shuttle_is_out_of_view(tracker):
    """``stereo.exit_by_path``: the camera's own image path (last report before now, moved on by
    its track's velocity) has left the image, or not; ``stereo.out_of_view_weak`` asks whether
    the flight projects outside the image."""
    frame = np.zeros((720, 1280, 3), np.uint8)
    dt = 1.0 / 120.0
    tracker.paths = ImagePaths()
    tracker.paths.note(0, 0.0, 1.3, 132.0, (-177.0, 274.0))
    tracker.paths.note(0, dt, 0.8, 133.5, None)
    # the report of this very frame is not used: the path from the one before leaves the image
    assert tracker.paths.leaves(0, frame, dt)
    tracker.paths = ImagePaths()
    tracker.paths.note(0, 0.0, 1.3, 132.0, (177.0, 274.0))
    assert not tracker.paths.leaves(0, frame, dt)          # moving into the image
    assert not tracker.paths.leaves(0, frame, 0.1)         # stale report: no path
    rig = tracker.rig
    p = np.array([0.3, -2.0, 1.8])
    assert not tracker.look.out_of_view(0, frame, p)
    K = rig.M1
    cam = np.array([(-50.0 - K[0, 2]) * 4.0 / K[0, 0], (300.0 - K[1, 2]) * 4.0 / K[1, 1], 4.0])
    assert tracker.look.out_of_view(0, frame, np.asarray(rig.to_output(cam[None]))[0])


def _measured_rig_error(tracker, median_px):
    for _ in range(40):
        tracker.gate.add_sample(median_px)


def test_the_gate_widens_to_the_rigs_error_only_for_pairs_moving_in_both_images(tracker):
    """``stereo.vouch_rig_factor``: on a rig whose sure pairs miss their epipolar lines by
    ~10 px (the NYCU rig's rough calibration: ~30 px), a pair 8 px off passes when both tracks
    move fast enough in the image; a slower pair, or first sightings (by position alone), only
    within the fixed gate."""
    fast = {"velocity_3d": (0.0, 6.0, 2.0), "right_offset": (0.0, 8.0)}     # ≈ 390 px/s
    slow = {"velocity_3d": (0.0, 3.0, 1.0), "right_offset": (0.0, 8.0)}     # ≈ 195 px/s
    left, right = tracker.vouch.apply(*_scene(tracker, **fast))
    assert not _passed(left) and not _passed(right)           # nothing measured yet: fixed gate
    _measured_rig_error(tracker, 10.0)
    left, right = tracker.vouch.apply(*_scene(tracker, **fast))
    assert len(_passed(left)) == 1 and len(_passed(right)) == 1
    left, right = tracker.vouch.apply(*_scene(tracker, **slow))
    assert not _passed(left) and not _passed(right)
    left, right = tracker.vouch.apply(*_scene(tracker, (0.0, 3.0, 1.0)))  # on the line: fixed gate
    assert len(_passed(left)) == 1 and len(_passed(right)) == 1
    left, right = tracker.vouch.apply(*_scene(tracker, first=True, score=0.9, **fast))
    assert not _passed(left) and not _passed(right)           # first sightings: by position


def test_the_widened_gate_is_off_at_factor_zero():
    p = TrackerParams()
    p = dataclasses.replace(p, stereo=dataclasses.replace(p.stereo, vouch_rig_factor=0.0))
    t = StereoTracker(make_rig("binocular", (1280, 720)), p, parallel=False)
    _measured_rig_error(t, 10.0)
    left, right = t.vouch.apply(*_scene(t, (0.0, 6.0, 2.0), right_offset=(0.0, 8.0)))
    assert not _passed(left) and not _passed(right)
    t.close()


# ---- the followed flight vouches for a pair just off the epipolar gate -----------------------
def _pair_off_its_line(rig, point, off_px):
    """Left and right candidates of a court point, ``off_px`` apart across the epipolar lines
    (the left one half of it up, the right one half of it down: a rig whose rays miss)."""
    (xl, yl), = rig.project(0, [point])
    (xr, yr), = rig.project(1, [point])

    def make(x, y):
        return Candidate(x=float(x), y=float(y), length=20.0, short_side=4.0, whiteness=200.0,
                         area=20.0, motion=1.0, score=5.0)
    return make(xl, yl - off_px / 2), make(xr, yr + off_px / 2)


def test_a_pair_just_off_the_epipolar_gate_is_taken_where_the_flight_puts_the_shuttle():
    """rally_11-46-04 1244–1270: both cameras follow the shuttle, the labels' own pairs miss each
    other's epipolar line by 117–124 px on the rough .cfg rig where the learnt gate is 113 px, and
    the robot got no 3D point for 27 frames. Up to 1.5 × the gate, a pair whose triangulation lies
    where the followed flight puts the shuttle (within 0.1 m + 3σ) is a pair; elsewhere, or
    farther off the line, it is not."""
    rig = make_rig("binocular", (1280, 720))
    tracker = StereoTracker(rig, TrackerParams(), parallel=False)
    try:
        tol = tracker.epipolar_tolerance()
        point = np.array([0.5, 2.0, 2.5])
        near_guide = (point + 0.03, np.eye(3) * 0.02 ** 2)
        far_guide = (point + np.array([0.0, 0.0, 0.5]), np.eye(3) * 0.02 ** 2)
        left, right = _pair_off_its_line(rig, point, 1.2 * tol)
        assert tracker.pairing.pair_point(left, right) == (None, None)         # off the gate
        found, err = tracker.pairing.flight_vouched_pair(left, right, near_guide)
        assert found is not None and tol < err <= 1.5 * tol
        assert np.linalg.norm(rig.to_output(found)[0] - point) < 0.1
        assert tracker.pairing.flight_vouched_pair(left, right, far_guide) == (None, None)
        assert tracker.pairing.flight_vouched_pair(left, right, None) == (None, None)
        tracker.params = tracker.params.with_value("stereo.flight_vouch", False)    # the rule off
        assert tracker.pairing.flight_vouched_pair(left, right, near_guide) == (None, None)
        tracker.params = tracker.params.with_value("stereo.flight_vouch", True)
        left, right = _pair_off_its_line(rig, point, 2.0 * tol)
        assert tracker.pairing.flight_vouched_pair(left, right, near_guide) == (None, None)
    finally:
        tracker.close()


def test_the_last_pair_of_tracklets_continues_off_the_gate_while_its_miss_changes_smoothly():
    """rally_11-47-02 800–860: the labelled shuttle's epipolar miss on the rough .cfg rig grew
    6 → 151 px and back along one flight (the learnt gate ≈ 113 px) while both cameras followed
    it, and the robot lost 50 frames of 3D points. The last step's pair of tracklets stays a pair
    while its miss moves by ≤ 0.005 × the image width a step, up to 2 × the gate."""
    rig = make_rig("binocular", (1280, 720))
    tracker = StereoTracker(rig, TrackerParams(), parallel=False)
    try:
        tol = tracker.epipolar_tolerance()
        point = np.array([0.5, 2.0, 2.5])
        left, right = (dataclasses.replace(c, tracklet=k) for c, k in zip(_pair_off_its_line(rig, point, 1.6 * tol), (3, 7)))
        err = float(rig.epipolar_errors([[left.x, left.y]], [[right.x, right.y]])[0, 0])
        assert err > 1.5 * tol and tracker.pairing.pair_point(left, right) == (None, None)
        assert tracker.pairing.continued_pair(left, right, 1.0) == (None, None)          # no last pair
        tracker.pairing.note_pair(0.99, left, dataclasses.replace(right, tracklet=7), err - 4.0)  # 4 px less a step ago
        found, got = tracker.pairing.continued_pair(left, right, 1.0)
        assert found is not None and got == pytest.approx(err)
        tracker.params = tracker.params.with_value("stereo.pair_continuity", False)  # the rule off
        assert tracker.pairing.continued_pair(left, right, 1.0) == (None, None)
        tracker.params = tracker.params.with_value("stereo.pair_continuity", True)
        assert np.linalg.norm(rig.to_output(found)[0] - point) < 0.2           # its triangulation
        assert tracker.pairing.continued_pair(left, right, 1.05) == (None, None)         # that pair too old
        tracker.pairing.note_pair(0.99, left, dataclasses.replace(right, tracklet=8), err - 4.0)  # another right tracklet
        assert tracker.pairing.continued_pair(left, right, 1.0) == (None, None)
        tracker.pairing.note_pair(0.99, left, dataclasses.replace(right, tracklet=7), err - 12.0)  # a jump, not a drift
        assert tracker.pairing.continued_pair(left, right, 1.0) == (None, None)
        far_left, far_right = (dataclasses.replace(c, tracklet=k) for c, k in zip(_pair_off_its_line(rig, point, 2.2 * tol), (3, 7)))
        far_err = float(rig.epipolar_errors([[far_left.x, far_left.y]], [[far_right.x, far_right.y]])[0, 0])
        tracker.pairing.note_pair(0.99, left, dataclasses.replace(right, tracklet=7), far_err - 2.0)
        assert tracker.pairing.continued_pair(far_left, far_right, 1.0) == (None, None)  # beyond 2 × the gate
    finally:
        tracker.close()

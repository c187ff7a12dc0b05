"""A camera does not keep alone what the two cameras paired off the play volume before
(``stereo.off_volume_radius``, ``core/stereo/off_volume.py``).

An LED board's dot beside the court pairs outside the play volume when both cameras keep it the
same step, and ``stereo.play_volume`` rejects it in both. A step later the right camera's dot is
no candidate (merged, held back by its track): the left camera's dot has no partner, so the
play-volume rule cannot see it. The place where the pair was refused is remembered, and a lone
candidate whose line of sight passes near it is rejected; a candidate elsewhere, or one paired
inside the play volume, is not.
"""

import numpy as np

from badminton_gui.core.params import TrackerParams
from badminton_gui.core.tracker import StereoTracker
from badminton_gui.core.types import CameraResult, Candidate
from badminton_gui.io.demo_scene import make_rig

ON = TrackerParams().with_value("stereo.off_volume_radius", 0.3)
SHUTTLE = (0.5, 2.0, 3.0)       # court frame, m: over the far half
BOARD_DOT = (5.6, 1.0, 0.5)     # on a board standing beside the court
DOT_LATER = (5.6, 1.15, 0.55)   # the dot a step later, moved along the board


def _candidate(rig, cam, where, score):
    u, v = rig.project(cam, np.array([where]))[0]
    assert 0 <= u < rig.image_size[0] and 0 <= v < rig.image_size[1]
    return Candidate(float(u), float(v), 30.0, 4.0, 200.0, 12.0, float("nan"), score, None)


def _result(rig, cam, *seen):
    return CameraResult(None, tuple(_candidate(rig, cam, w, s) for w, s in seen), image_size=rig.image_size)


def _lone_dot_after_a_refused_pair(params, t_later=0.01):
    """The left camera's verdicts on the dot alone (and the shuttle) after the dot's pair was refused."""
    rig = make_rig("ends", (1280, 720))
    tracker = StereoTracker(rig, params, parallel=False)
    try:
        both = [_result(rig, cam, (BOARD_DOT, 0.9)) for cam in (0, 1)]
        left, right = tracker.pairing.reject_off_volume(both[0], both[1], 0.0)
        assert [c.rejected_by for c in left.candidates + right.candidates] == ["stereo", "stereo"]
        # A step later the right camera sees only the shuttle: the dot is the left camera's alone.
        left = _result(rig, 0, (DOT_LATER, 0.9))
        right = _result(rig, 1, (SHUTTLE, 0.6))
        left, right = tracker.pairing.reject_off_volume(left, right, t_later)
        return [c.rejected_by for c in left.candidates], [c.rejected_by for c in right.candidates]
    finally:
        tracker.close()


def test_off_by_default_a_lone_dot_is_kept():
    assert _lone_dot_after_a_refused_pair(TrackerParams().with_value("stereo.off_volume_radius", 0.0)) == \
        ([None], [None])


def test_a_lone_candidate_where_a_pair_was_refused_is_rejected():
    # The right camera's lone shuttle lies nowhere near the refused place: kept.
    assert _lone_dot_after_a_refused_pair(ON) == (["stereo"], [None])


def test_the_place_is_forgotten_after_the_memory():
    params = ON.with_value("stereo.off_volume_memory", 5.0)
    assert _lone_dot_after_a_refused_pair(params, t_later=6.0) == ([None], [None])


def test_a_pair_inside_the_play_volume_is_kept_at_a_refused_place():
    # A shuttle on the left camera's line of sight to the board, both cameras seeing it: its pair
    # lies inside the play volume, so neither report is rejected although the left one's sight
    # passes the refused place.
    rig = make_rig("ends", (1280, 720))
    tracker = StereoTracker(rig, ON, parallel=False)
    try:
        both = [_result(rig, cam, (BOARD_DOT, 0.9)) for cam in (0, 1)]
        tracker.pairing.reject_off_volume(both[0], both[1], 0.0)
        centre, dirs = rig.rays(0, [list(rig.project(0, np.array([BOARD_DOT]))[0])])
        along = float((np.array(BOARD_DOT) - centre) @ dirs[0])
        in_front = tuple(centre + 0.8 * along * dirs[0])
        assert abs(in_front[0]) < 5.0
        left, right = (_result(rig, cam, (in_front, 0.6)) for cam in (0, 1))
        kept = tracker.pairing.reject_off_volume(left, right, 0.01)
        assert kept[0] is left and kept[1] is right
    finally:
        tracker.close()


def test_a_lone_candidate_where_the_followed_flight_puts_the_shuttle_is_kept():
    # A refused place on the left camera's line of sight to the followed shuttle, beyond it: the
    # shuttle seen by the left camera alone passes it, and is kept while the flight puts it there;
    # without a flight to ask, the same candidate is rejected.
    from badminton_gui.core import physics
    from badminton_gui.core.flight.guide import StepGuide
    from badminton_gui.core.stereo.pairing import in_play_volume

    rig = make_rig("binocular", (1280, 720))
    tracker = StereoTracker(rig, ON, parallel=False)
    try:
        ts, ps, _ = physics.simulate([0.0, -4.0, 1.2], [1.0, 14.0, 10.0], 20 / 120.0, dt=1.0 / 120.0)
        for t, p in zip(ts, ps):
            tracker.trajectory.update(float(t), tuple(p))
        t = float(ts[-1]) + 1.0 / 120.0
        shuttle = StepGuide(tracker.trajectory, t).get()[0]
        uv = rig.project(0, np.array([shuttle]))[0]
        centre, dirs = rig.rays(0, [list(uv)])
        along = float((shuttle - centre) @ dirs[0])
        place = next(centre + k * along * dirs[0] for k in np.arange(1.2, 6.0, 0.05)
                     if not in_play_volume(rig, ON, rig.to_left(centre + k * along * dirs[0])[0]))
        refused = [_result(rig, cam, (tuple(place), 0.9)) for cam in (0, 1)]
        left, right = tracker.pairing.reject_off_volume(refused[0], refused[1], t, None)
        assert [c.rejected_by for c in left.candidates + right.candidates] == ["stereo", "stereo"]
        lone = _result(rig, 0, (tuple(shuttle), 0.6))
        nothing = CameraResult(None, (), image_size=rig.image_size)
        kept, _ = tracker.pairing.reject_off_volume(lone, nothing, t, StepGuide(tracker.trajectory, t))
        assert kept is lone
        rejected, _ = tracker.pairing.reject_off_volume(lone, nothing, t, None)
        assert [c.rejected_by for c in rejected.candidates] == ["stereo"]
    finally:
        tracker.close()

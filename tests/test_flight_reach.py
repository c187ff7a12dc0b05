"""A pair the followed flight cannot have become is not the shuttle (``stereo.flight_reach``, off
by default: on the randomised courts it wins, on the NYCU rallies and behind the baselines it
moves a few frames each way).

An LED board beside the court shows a white dot moving like a shuttle; both cameras see it and
it pairs into a consistent 3D track metres from the flight. Scoring higher than the shuttle for
one frame, the dot's pair used to win, became each camera's followed track and kept both cameras
on the board for the rest of the flight. While a flight is followed, a pair beyond its reach
(the way a shuttle hit since the flight's last point could have gone) is not paired, a camera's
choice whose line of sight misses that reach gives way, and a pair where the flight puts the
shuttle comes before other pairs within reach.
"""

import numpy as np
import pytest

from badminton_gui.core import physics
from badminton_gui.core.flight.guide import StepGuide
from badminton_gui.core.params import TrackerParams
from badminton_gui.core.tracker import StereoTracker
from badminton_gui.core.types import REJECT_MOTION, CameraResult, Candidate
from badminton_gui.io.demo_scene import make_rig

FPS = 120.0
DOT = np.array([3.5, -8.0, 0.5])     # court frame, m: a board's dot 1.3 m behind the baseline


REACH = 160.0    # m/s: the fastest smash


@pytest.fixture
def tracker():
    params = TrackerParams().with_value("stereo.flight_reach", REACH)
    t = StereoTracker(make_rig("binocular", (1280, 720)), params, parallel=False)
    yield t
    t.close()


def test_on_by_default_at_the_fastest_smash():
    assert TrackerParams().stereo.flight_reach == REACH


def _follow_a_flight(tracker, frames: int = 20) -> float:
    """Feed the tracker's flight filter a clear's points at FPS; returns the next frame's time."""
    ts, ps, _ = physics.simulate([0.0, -4.0, 1.2], [1.0, 14.0, 10.0], frames / FPS, dt=1.0 / FPS)
    for t, p in zip(ts, ps):
        tracker.trajectory.update(float(t), tuple(p))
    return float(ts[-1]) + 1.0 / FPS


def _candidate(xy, score, rejected=None):
    return Candidate(float(xy[0]), float(xy[1]), 30.0, 6.0, 200.0, 20.0, float("nan"), score, rejected)


def _results(tracker, shuttle, scores=(3.0, 5.0), right_shuttle=True):
    """Each camera's candidates: the shuttle at ``shuttle`` and the dot, scoring ``scores``."""
    out = []
    for cam in (0, 1):
        uv_shuttle, uv_dot = tracker.rig.project(cam, np.stack([shuttle, DOT]))
        cands = [_candidate(uv_dot, scores[1])]
        if cam == 0 or right_shuttle:
            cands.insert(0, _candidate(uv_shuttle, scores[0]))
        else:
            cands.insert(0, _candidate(uv_shuttle, 0.1, REJECT_MOTION))   # a young track held back
        out.append(CameraResult(None, tuple(cands), image_size=(1280, 720)))
    return out


def _at(tracker, pair_or_det, cam=None):
    """The court point a pair triangulates to, or where a camera's report lies (px)."""
    if cam is None:
        return tracker.rig.to_output(pair_or_det.point[None])[0]
    return np.array([pair_or_det.x, pair_or_det.y])


def test_the_shuttle_pair_wins_over_a_higher_scoring_pair_beyond_the_flights_reach(tracker):
    t = _follow_a_flight(tracker)
    guide = StepGuide(tracker.trajectory, t)
    shuttle = guide.get()[0]
    res = _results(tracker, shuttle)
    pair = tracker.pairing.choose_pair(res[0], res[1], guide)
    assert np.linalg.norm(_at(tracker, pair) - shuttle) < 0.05
    assert pair.beyond_reach
    # Without a flight to ask, or with the rule off, the better scores win: the dot.
    assert np.linalg.norm(_at(tracker, tracker.pairing.choose_pair(res[0], res[1], None)) - DOT) < 0.05
    tracker.params = tracker.params.with_value("stereo.flight_reach", 0.0)
    off = tracker.pairing.choose_pair(res[0], res[1], StepGuide(tracker.trajectory, t))
    assert np.linalg.norm(_at(tracker, off) - DOT) < 0.05 and not off.beyond_reach


def test_with_the_shuttle_held_back_in_one_camera_neither_camera_is_handed_to_the_dot(tracker):
    t = _follow_a_flight(tracker)
    guide = StepGuide(tracker.trajectory, t)
    shuttle = guide.get()[0]
    res = _results(tracker, shuttle, right_shuttle=False)
    pair = tracker.pairing.choose_pair(res[0], res[1], guide)
    assert pair.point is None and pair.beyond_reach              # the dot's pair is no pair
    dets, moved = tracker.pairing.own_choices(res, guide)
    # The left camera's own choice (the dot) gives way to its shuttle; the right camera has
    # nothing within reach and reports nothing (the flight's look searches there).
    assert moved == [0, 1]
    uv = tracker.rig.project(0, shuttle[None])[0]
    assert np.linalg.norm(_at(tracker, dets[0], 0) - uv) < 1.0
    assert dets[1] is None
    # Without a flight each camera keeps its own choice.
    dets, moved = tracker.pairing.own_choices(res, None)
    assert moved == [] and dets[0].score == 5.0 and dets[1].score == 5.0


def test_the_reach_grows_while_the_flight_goes_unseen(tracker):
    """The shuttle may have been hit anywhere on its path since the flight's last point: the
    longer ago, the farther it may be, and the rule fades instead of holding on to a lost flight."""
    t = _follow_a_flight(tracker)
    near = StepGuide(tracker.trajectory, t).reach(REACH)
    later = StepGuide(tracker.trajectory, t + 0.1).reach(REACH)
    assert 1.0 < near[1] < 2.5
    assert later[1] > near[1] + 15.0
    shuttle = StepGuide(tracker.trajectory, t + 0.1).get()[0]
    res = _results(tracker, shuttle)
    pair = tracker.pairing.choose_pair(res[0], res[1], StepGuide(tracker.trajectory, t + 0.1))
    # Within reach both; the pair where the flight puts the shuttle still comes first.
    assert not pair.beyond_reach and np.linalg.norm(_at(tracker, pair) - shuttle) < 0.05

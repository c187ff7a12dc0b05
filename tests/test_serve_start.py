"""Before the serve, a pair is the shuttle only once its 3D track starts like a serve
(``stereo.serve_start``, ``core/stereo/serve_start.py``).

An LED board's moving dot standing inside the play volume's margin pairs like the shuttle, and
before the first serve there is no flight to ask where the shuttle is: both cameras reported the
dot until the serve. A serve leaves a player's hand or racket, climbs fast towards the net; the
dot slides along its board at about the same height, and a shuttle held before the serve is at
rest. Both are rejected in both cameras; the served shuttle is kept from its third pair on.
"""

import numpy as np

from badminton_gui.core import physics
from badminton_gui.core.params import TrackerParams
from badminton_gui.core.tracker import StereoTracker
from badminton_gui.core.types import CameraResult, Candidate
from badminton_gui.io.demo_scene import make_rig

ON = TrackerParams().with_value("stereo.serve_start", True)
FPS = 100.0


def _result(rig, cam, where, tracklet):
    u, v = rig.project(cam, np.array([where]))[0]
    assert 0 <= u < rig.image_size[0] and 0 <= v < rig.image_size[1]
    c = Candidate(float(u), float(v), 30.0, 4.0, 200.0, 12.0, float("nan"), 0.9, None, tracklet=tracklet)
    return CameraResult(None, (c,), image_size=rig.image_size)


def _verdicts(params, path, before_serve=True):
    """Each step's verdicts of both cameras on one object following ``path`` (court points, one
    a frame at FPS), on one tracklet per camera; and whether the shuttle was in play at the end."""
    rig = make_rig("binocular", (1280, 720))
    tracker = StereoTracker(rig, params, parallel=False)
    try:
        out = []
        for k, where in enumerate(path):
            left, right = (_result(rig, cam, tuple(where), 7 + cam) for cam in (0, 1))
            left, right = tracker.pairing.reject_before_serve(left, right, k / FPS, before_serve)
            out.append((left.candidates[0].rejected_by, right.candidates[0].rejected_by))
        return out, tracker.pairing.serve_start.in_play
    finally:
        tracker.close()


def _board_dot(steps=12):
    """A dot sliding along a board 1.6 m beside the court (inside the 2 m margin) at 6 m/s, its
    height wobbling by a few centimetres of triangulation noise."""
    rng = np.random.default_rng(3)
    return [(4.65, -2.0 + 6.0 * k / FPS, 0.5 + rng.normal(0.0, 0.02)) for k in range(steps)]


def _serve(steps=8):
    _, ps, _ = physics.simulate([0.5, -2.8, 1.0], [-0.3, 14.0, 12.0], steps / FPS, dt=1.0 / FPS)
    return ps[:steps]


def test_off_by_default():
    verdicts, _ = _verdicts(TrackerParams(), _board_dot())
    assert all(v == (None, None) for v in verdicts)


def test_a_board_dot_inside_the_margin_is_rejected_before_the_serve():
    verdicts, in_play = _verdicts(ON, _board_dot())
    assert all(v == ("stereo", "stereo") for v in verdicts)
    assert not in_play


def test_a_shuttle_held_before_the_serve_is_rejected():
    rng = np.random.default_rng(5)
    held = [(0.5 + rng.normal(0.0, 0.01), -2.8, 1.0 + rng.normal(0.0, 0.01)) for _ in range(12)]
    verdicts, in_play = _verdicts(ON, held)
    assert all(v == ("stereo", "stereo") for v in verdicts)
    assert not in_play


def test_a_serve_is_kept_from_its_third_pair():
    verdicts, in_play = _verdicts(ON, _serve())
    assert verdicts[:2] == [("stereo", "stereo")] * 2
    assert all(v == (None, None) for v in verdicts[2:])
    assert in_play


def test_a_shot_going_down_is_no_serve_but_in_play_nothing_is_rejected():
    _, ps, _ = physics.simulate([0.5, -2.8, 2.5], [0.0, 15.0, -8.0], 8 / FPS, dt=1.0 / FPS)
    verdicts, _ = _verdicts(ON, ps[:8])
    assert all(v == ("stereo", "stereo") for v in verdicts)
    verdicts, _ = _verdicts(ON, ps[:8], before_serve=False)
    assert all(v == (None, None) for v in verdicts)

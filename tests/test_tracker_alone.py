"""A detection only one camera reports is withheld unless it continues a stereo readout
(``stereo.alone_limit``, ``alone_max_frames``, ``alone_anchor_gap``).

Sequences of per-frame readouts go through the tracker's last readout step: a camera that
starts reporting on its own (a shuttle held before the serve, a shoe) is withheld after
``alone_max_frames`` frames; one whose readout continues a frame with a 3D point (the other
camera lost the flight) is kept, across gaps up to ``alone_anchor_gap`` frames but not longer;
both cameras reporting without a 3D point is not "alone"; the flag off changes nothing.
"""

import dataclasses

import pytest

from badminton_gui.core.params import TrackerParams
from badminton_gui.core.tracker import StereoTracker
from badminton_gui.core.types import REJECT_STEREO, CameraResult, Candidate
from badminton_gui.io.demo_scene import make_rig


def _result(seen: bool) -> CameraResult:
    if not seen:
        return CameraResult(None, (), image_size=(1280, 720))
    c = Candidate(600.0, 300.0, 30.0, 6.0, 200.0, 20.0, 1.0, 3.0, None, tracklet=7)
    return CameraResult(c, (c,), image_size=(1280, 720))


def _tracker(**stereo) -> StereoTracker:
    p = TrackerParams()
    p = dataclasses.replace(p, stereo=dataclasses.replace(p.stereo, **stereo))
    return StereoTracker(make_rig("binocular", (1280, 720)), p, parallel=False)


def _run(tracker: StereoTracker, frames: str) -> str:
    """``frames``: per frame L (left only), R (right only), B (both, no 3D point), 3 (both with
    a 3D point), P (right only, with the flight's 3D point), . (neither). Returns per frame what
    the readout shows: L, R, B or ."""
    out = []
    for f in frames:
        left, right = _result(f in "LB3"), _result(f in "RB3P")
        left, right = tracker._limit_alone(left, right, f in "3P")
        shown = (left.detection is not None, right.detection is not None)
        out.append({(True, True): "B", (True, False): "L", (False, True): "R", (False, False): "."}[shown])
        for res in (left, right):
            if res.detection is None and res.candidates:
                assert res.candidates[0].rejected_by == REJECT_STEREO
    tracker.close()
    return "".join(out)


def test_a_camera_starting_on_its_own_is_withheld_after_the_allowed_frames():
    assert _run(_tracker(alone_max_frames=0), "..LLLL..RRR.") == "............"
    assert _run(_tracker(alone_max_frames=2), "..LLLL..RRR.") == "..LL....RR.."


def test_a_readout_continuing_a_3d_point_is_kept_across_short_gaps_only():
    t = _tracker(alone_max_frames=0, alone_anchor_gap=3)
    assert _run(t, "333LLL..LL....LL") == "BBBLLL..LL......"
    # both cameras without a 3D point keep the anchor, and are never withheld
    assert _run(_tracker(alone_max_frames=0), "33BBRRBB") == "BBBBRRBB"
    # a 3D point while this camera reported nothing does not anchor it
    assert _run(_tracker(alone_max_frames=0), "PPPLLRR") == "RRR..RR"


def test_off_by_the_flag():
    assert _run(_tracker(alone_limit=False, alone_max_frames=0), "..LLLL..RRR.") == "..LLLL..RRR."


@pytest.mark.parametrize("frames", ["LLLBLLL", "RRR.RRR"])
def test_the_count_restarts_when_the_camera_is_not_alone(frames):
    assert _run(_tracker(alone_max_frames=3), frames) == frames
    assert _run(_tracker(alone_max_frames=2), frames) == frames[:2] + "." + frames[3:6] + "."

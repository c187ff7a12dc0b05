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
from badminton_gui.core.flight.camera_rules import FLOWN_MEMORY
from badminton_gui.core.flight.phase import PhaseState
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
        left, right = tracker.rules.limit_alone([left, right], f in "3P")
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


# ---- stereo.landed_frames ---------------------------------------------------------------------

def _cand(x, rejected=None):
    return Candidate(float(x), 500.0, 30.0, 6.0, 200.0, 20.0, 1.0, 0.5, rejected, tracklet=4)


def _hold(tracker, xs, last_z=0.0, t0=1.0, dt=0.01, paired=True, flown_at=0.5):
    """The first x is reported by the detector; the others are the same track's candidate held
    back by the association. ``flown_at``: when the track was last reported with a 3D point
    above the floor (None: never). Returns the x reported per frame (None: nothing)."""
    out = []
    if flown_at is not None:
        tracker.rules.note_flown(0, 4, flown_at)
    for k, x in enumerate(xs):
        t = t0 + k * dt
        if k == 0:
            tracker.phase = PhaseState(last_point=(t, last_z))
            c = _cand(x)
            res, det = tracker.rules.hold_landed(0, CameraResult(c, (c,), image_size=(1280, 720)), c, t, tracker.phase)
            tracker.rules.cams[0].anchored = paired        # that report had a 3D point (set by process())
        else:
            c = _cand(x, "motion")
            res, det = tracker.rules.hold_landed(0, CameraResult(None, (c,), image_size=(1280, 720)), None, t, tracker.phase)
            if det is not None:
                assert det.rejected_by is None and det in res.candidates
        out.append(None if det is None else det.x)
    tracker.close()
    return out


def test_a_landed_shuttle_is_held_while_it_stays_put_for_the_allowed_frames():
    xs = [100, 101, 101, 102, 102, 102]
    assert _hold(_tracker(landed_frames=3), xs) == [100, 101, 101, 102, None, None]
    assert _hold(_tracker(landed_frames=0), xs) == [100, None, None, None, None, None]


def test_no_hold_above_the_floor_when_the_flight_is_old_or_the_candidate_moves_off():
    xs = [100, 101, 101]
    assert _hold(_tracker(landed_frames=10), xs, last_z=1.2) == [100, None, None]
    # a track reported without a 3D point (clutter after the rally) is not held
    assert _hold(_tracker(landed_frames=10), xs, paired=False) == [100, None, None]
    t = _tracker(landed_frames=10)
    t.rules.note_flown(0, 4, -5.5)
    t.phase = PhaseState(last_point=(-5.0, 0.0))
    c = _cand(100)
    t.rules.hold_landed(0, CameraResult(c, (c,), image_size=(1280, 720)), c, 0.0, t.phase)
    t.rules.cams[0].anchored = True
    m = _cand(101, "motion")
    assert t.rules.hold_landed(0, CameraResult(None, (m,), image_size=(1280, 720)), None, 0.01, t.phase)[1] is None
    t.close()
    assert _hold(_tracker(landed_frames=10), [100, 101, 120, 121]) == [100, 101, None, None]


def test_only_a_track_seen_in_the_air_is_held():
    """A track paired at floor height that was never reported with a 3D point above the floor
    (a player's shoe seen by both cameras after the rally) is not held; one that carried the
    flight down is, unless that was longer than ``FLOWN_MEMORY`` ago."""
    xs = [100, 101, 101]
    assert _hold(_tracker(landed_frames=10), xs, flown_at=0.5) == [100, 101, 101]
    assert _hold(_tracker(landed_frames=10), xs, flown_at=None) == [100, None, None]
    assert _hold(_tracker(landed_frames=10), xs, flown_at=1.0 - FLOWN_MEMORY - 0.1) == [100, None, None]
    # another tracklet seen in the air does not vouch for this one
    t = _tracker(landed_frames=10)
    t.rules.note_flown(0, 5, 0.9)
    assert _hold(t, xs, flown_at=None) == [100, None, None]



def _landed(tracker, flown=(4,), flown_at=0.5):
    """Tracklet 4 reported at x 100 at t 1.0 with a 3D point just after a low flight point, the
    tracklets in ``flown`` seen in the air at ``flown_at``: a landed hold can start next frame."""
    for ident in flown:
        tracker.rules.note_flown(0, ident, flown_at if ident == 4 else 0.9)
    tracker.phase = PhaseState(last_point=(1.0, 0.0))
    shuttle = _cand(100)
    tracker.rules.hold_landed(0, CameraResult(shuttle, (shuttle,), image_size=(1280, 720)), shuttle, 1.0, tracker.phase)
    tracker.rules.cams[0].anchored = True


def test_a_shoe_walking_past_does_not_take_the_report_from_the_landed_shuttle():
    """After the landing the association's readout jumps to a track never seen in the air (a
    player's white shoe, tracklet 9) with no stereo partner above the floor: the shuttle lying
    where it landed (tracklet 4) stays the report while the hold lasts, then the shoe is. A
    track that flew, or a pair above the floor (a new serve), takes the report at once."""
    def run(tracker, shoe_flew=False, paired=False, frames=4):
        _landed(tracker, flown=(4, 9) if shoe_flew else (4,))
        out = []
        for k in range(1, frames + 1):
            lying = _cand(100 + 0.5 * k, "motion")
            shoe = dataclasses.replace(_cand(400 + 3 * k), tracklet=9)
            res, det = tracker.rules.hold_landed(0, CameraResult(shoe, (lying, shoe), image_size=(1280, 720)),
                                                 shoe, 1.0 + 0.01 * k, tracker.phase, paired)
            out.append(None if det is None else (det.tracklet, det.x))
        tracker.close()
        return out

    assert run(_tracker(landed_frames=10)) == [(4, 100.5), (4, 101.0), (4, 101.5), (4, 102.0)]
    assert run(_tracker(landed_frames=2)) == [(4, 100.5), (4, 101.0), (9, 409.0), (9, 412.0)]
    assert run(_tracker(landed_frames=10), shoe_flew=True)[0] == (9, 403.0)
    assert run(_tracker(landed_frames=10), paired=True)[0] == (9, 403.0)


def test_the_other_camera_holding_keeps_this_cameras_anchor():
    """The left camera's landed shuttle is held (no pair, no 3D point); the right camera still
    reports the same shuttle a few frames: its report stays anchored, so its own hold can start
    when its report stops. Without a hold on the other side, no 3D point drops the anchor."""
    t = _tracker(landed_frames=10)
    c = _cand(100)
    t.rules.note_anchor(1, c, True)
    t.rules.cams[0].holding = True
    t.rules.note_anchor(1, c, False)
    assert t.rules.cams[1].anchored
    t.rules.cams[0].holding = False
    t.rules.note_anchor(1, c, False)
    assert not t.rules.cams[1].anchored
    # a camera that was never anchored is not anchored by the other camera's hold
    t.rules.cams[0].holding = True
    t.rules.note_anchor(1, c, False)
    assert not t.rules.cams[1].anchored
    t.close()


# ---- stereo.cold_epipolar_error -----------------------------------------------------------------

def test_the_epipolar_gate_is_the_cold_one_until_the_rigs_error_is_learnt():
    """From a fresh start the pair gate is ``cold_epipolar_error`` (a rough rig misses by tens of
    px); after EPIPOLAR_LEARNT_SAMPLES sure pairs it is the learnt one, even when narrower; 0
    keeps the fixed tolerance; without learning there is no cold gate either."""
    from badminton_gui.core.stereo.epipolar import EPIPOLAR_LEARNT_SAMPLES

    t = _tracker(cold_epipolar_error=30.0, max_epipolar_error=6.0, adaptive_factor=2.5)
    assert t.epipolar_tolerance() == 30.0
    for _ in range(EPIPOLAR_LEARNT_SAMPLES - 1):
        t.gate.add_sample(4.0)
    assert t.epipolar_tolerance() == 30.0
    t.gate.add_sample(4.0)
    assert t.epipolar_tolerance() == 10.0          # 2.5 × the median 4 px
    t.reset()
    assert t.epipolar_tolerance() == 30.0
    t.close()
    for stereo in ({"cold_epipolar_error": 0.0}, {"adaptive_epipolar": False}):
        t = _tracker(max_epipolar_error=6.0, **stereo)
        assert t.epipolar_tolerance() == 6.0
        t.close()


def test_the_shoes_pair_is_no_3d_point_once_the_hold_takes_the_report_back():
    """The shoe walking past paired with the other camera into a point below the floor; when
    the landed hold gives the report back to the lying shuttle, that point is dropped. Without a
    hold to take the report back (no flight before), the pair stays as it was."""
    def run(flew):
        tracker = _tracker(landed_frames=10)
        _landed(tracker, flown=(4,) if flew else ())
        lying = _cand(100.5, "motion")
        shoe = dataclasses.replace(_cand(400), tracklet=9)
        other = dataclasses.replace(_cand(380), tracklet=2)
        below = tracker.rig.to_left([(0.0, 0.0, -1.7)])[0]
        left, right, point, epi = tracker.rules.hold_both(
            (CameraResult(shoe, (lying, shoe), image_size=(1280, 720)), shoe),
            (CameraResult(other, (other,), image_size=(1280, 720)), other), below, 2.0, 1.01, tracker.phase)
        tracker.close()
        return left[1], right[1], point, epi

    det, right, point, epi = run(flew=True)
    assert det.tracklet == 4 and right.tracklet == 2
    assert point is None and epi is None
    det, _, point, epi = run(flew=False)
    assert det.tracklet == 9 and point is not None and epi == 2.0


def test_the_hold_takes_an_untracked_blob_at_its_spot_but_not_another_tracks():
    """A lying shuttle dims and a classifier may refuse it before association: the blob at the
    held spot that no track took (tracklet -1) is still the held shuttle; another track's blob
    there is not (rally_11-48-00 right 641, coarse preset)."""
    for tracklet, expected in ((-1, 101.0), (9, None)):
        t = _tracker(landed_frames=10)
        t.rules.note_flown(0, 4, 0.5)
        t.phase = PhaseState(last_point=(1.0, 0.0))
        c = _cand(100)
        t.rules.hold_landed(0, CameraResult(c, (c,), image_size=(1280, 720)), c, 1.0, t.phase)
        t.rules.cams[0].anchored = True
        other = dataclasses.replace(_cand(101, "score"), tracklet=tracklet)
        res, det = t.rules.hold_landed(0, CameraResult(None, (other,), image_size=(1280, 720)), None, 1.01, t.phase)
        assert (None if det is None else det.x) == expected
        t.close()


def test_a_reported_landed_shuttle_lying_still_is_protected_in_the_mask():
    """``CameraRules.lying_landed``: the report of a track that carried the flight down, barely moving,
    just after the flight's last point lay near the floor, keeps its pixels in the next mask
    even while the association reports it itself (no hold); not a moving report, a track never
    seen in the air, or a flight still above the floor."""
    def lying(speed=0.0, flown=True, z=0.0, tracklet=4, landed_frames=10):
        t = _tracker(landed_frames=landed_frames)
        if flown:
            t.rules.note_flown(0, 4, 0.5)
        t.phase = PhaseState(last_point=(1.0, z))
        c = dataclasses.replace(_cand(100), tracklet=tracklet)
        t.paths.note(0, 1.01, c.x, c.y, (speed, 0.0))
        out = t.rules.lying_landed(0, c, 1.01, 1280, t.phase, t.paths)
        t.close()
        return out
    assert lying()
    assert not lying(speed=1000.0)
    assert not lying(flown=False)
    assert not lying(z=1.5)
    assert not lying(tracklet=-1)
    assert not lying(landed_frames=0)       # the hold off: no protection either

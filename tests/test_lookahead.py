"""The look-ahead readout (core/lookahead.py) on synthetic candidate streams, and `--lookahead` in the CLI."""

import csv
import dataclasses
import math

import numpy as np
import pytest

from badminton_gui.cli import main
from badminton_gui.core.flight.shot_filter import position_on_path
from badminton_gui.core.lookahead import CameraLookahead
from badminton_gui.core.params import TrackerParams
from badminton_gui.core.track_lookahead import CONFIRM_GATE_M, CONFIRM_HOLD_S, DelayedReadout, StereoLookahead
from badminton_gui.core.types import (REJECT_MOTION, REJECT_SCORE, CameraResult, Candidate, FlightInfo,
                                      TrackResult)
from badminton_gui.io.presets import load_preset

from .test_cli import make_rig_for, moving_dot_frames, write_video

FPS = 100.0


def cand(x, y, tracklet, rejected=REJECT_MOTION, short_side=0.0):
    return Candidate(x, y, 20.0, short_side, 200.0, 30.0, 0.0, 0.5, rejected, tracklet=tracklet)


def frame(cands, chosen_tracklet=None):
    """A CameraResult whose detection is the candidate on ``chosen_tracklet`` (None: no detection)."""
    out, det = [], None
    for c in cands:
        if c.tracklet == chosen_tracklet:
            c = Candidate(c.x, c.y, c.length, c.short_side, c.whiteness, c.area, c.motion, c.score,
                          None, tracklet=c.tracklet)
            det = c
        out.append(c)
    return CameraResult(detection=det, candidates=tuple(out), image_size=(1280, 720))


def params(k, **lookahead):
    p = TrackerParams().with_value("lookahead.frames", k).with_value("colour.head_lead", 0.0)
    for name, value in lookahead.items():
        p = p.with_value(f"lookahead.{name}", value)
    return p


def run(stream, p):
    la = CameraLookahead(p)
    out = []
    for i, res in enumerate(stream):
        out += la.push(res, i / FPS)
        # Held back K frames: nothing comes out until the window is full.
        assert len(out) == max(0, i + 1 - p.lookahead.frames)
    return out + la.flush(), la


def serve_stream():
    """A shuttle on tracklet 7 from frame 2, moving 10 px a frame; confirmed online from frame 5."""
    stream = []
    for i in range(12):
        cands = [cand(900.0, 600.0, 1)]                         # a static light, never followed
        if i >= 2:
            cands.append(cand(100.0 + 10 * (i - 2), 300.0, 7))
        stream.append(frame(cands, 7 if i >= 5 else None))
    return stream


def test_backfill_takes_the_unconfirmed_first_frames_of_the_followed_tracklet():
    stream = serve_stream()
    online, _ = run(stream, params(0))
    assert [r.detection is not None for r in online] == [False] * 5 + [True] * 7
    out, la = run(stream, params(4))
    assert len(out) == len(stream)
    # Frames 2–4 had the shuttle on tracklet 7 before it was confirmed: back-filled.
    assert [r.detection is not None for r in out] == [False, False] + [True] * 10
    for i in (2, 3, 4):
        d = out[i].detection
        assert (d.x, d.y, d.tracklet) == (100.0 + 10 * (i - 2), 300.0, 7)
        assert d.rejected_by is None
        assert sum(c.rejected_by is None for c in out[i].candidates) == 1
    assert la.changes["backfill"] == 3
    # Frames 0-1 have no candidate on tracklet 7: nothing to take.
    assert out[0].detection is None and out[1].detection is None


def test_backfill_reaches_only_k_frames_back():
    out, _ = run(serve_stream(), params(2))
    # Frame 4 sees tracklet 7 followed in both of its 2 future frames; frame 3 in only one of
    # them (fewer than min_support = 2): not back-filled.
    assert [r.detection is not None for r in out] == [False] * 4 + [True] * 8
    out, _ = run(serve_stream(), params(2, min_support=1))
    assert [r.detection is not None for r in out] == [False] * 3 + [True] * 9


def test_backfill_replaces_the_coasting_guess_of_a_tracklet_never_followed_again():
    """After a hit the followed racket's tracklet 3 loses its blob and coasts for a frame (its
    prediction is the online detection) while the shuttle's tracklet 9 is born; from the next
    frame on the readout follows 9 (1_02_01 frame 130)."""
    stream = []
    for i in range(10):
        if i < 4:
            stream.append(frame([cand(800.0, 400.0 + 20 * i, 3)], 3))
        elif i == 4:
            guess = Candidate(800.0, 480.0, math.nan, math.nan, math.nan, math.nan, 0.0, 4.0, None,
                              predicted=True, tracklet=3)
            shuttle = cand(680.0, 230.0, 9)
            stream.append(CameraResult(detection=guess, candidates=(shuttle, guess), image_size=(1280, 720)))
        else:
            stream.append(frame([cand(680.0 - 40 * (i - 4), 230.0 - 30 * (i - 4), 9)], 9))
    out, la = run(stream, params(4))
    d = out[4].detection
    assert (d.x, d.y, d.tracklet, d.predicted) == (680.0, 230.0, 9, False)
    assert la.changes["backfill"] == 1
    # A guess whose tracklet the readout follows again (a shuttle coasting behind a player) stays.
    stream[5] = frame([cand(800.0, 500.0, 3), cand(640.0, 200.0, 9)], 3)
    out, _ = run(stream, params(4))
    assert out[4].detection.predicted and out[4].detection.tracklet == 3


def test_no_backfill_of_a_shuttle_held_still_before_the_serve():
    stream = []
    for i in range(12):
        x = 100.0 if i < 5 else 100.0 + 10 * (i - 4)           # held still in frames 0-4
        stream.append(frame([cand(x, 300.0, 7)], 7 if i >= 7 else None))
    out, _ = run(stream, params(8))
    # Frame 4 is the last still one: its step to frame 5 is the first move, 10 px.
    assert [r.detection is not None for r in out] == [False] * 4 + [True] * 8


def hit_stream(racket_seen_at_handover=True, back_to_racket=False, converging=False):
    """The readout follows the racket (tracklet 1) after a hit while the shuttle leaves on 2."""
    stream = []
    for i in range(14):
        cands = []
        if racket_seen_at_handover or i < 7:
            cands.append(cand(500.0 + 1.0 * i, 400.0, 1))             # racket, slow
        if i >= 3:
            if converging:     # a player's racket closing in on the shuttle (tracklet 1)
                cands.append(cand(700.0 - 15 * (i - 3), 400.0, 2))
            else:              # the shuttle leaving the racket
                cands.append(cand(520.0 + 15 * (i - 3), 400.0 - 5 * (i - 3), 2))
        chosen = 1 if i < 7 else 2
        if back_to_racket and i == 10:
            chosen = 1
        stream.append(frame(cands, chosen))
    return stream


def test_switch_leaves_the_racket_for_the_shuttle_earlier():
    stream = hit_stream()
    out, la = run(stream, params(4))
    got = [r.detection.tracklet for r in out]
    # Handover at frame 7; with 4 frames of future, frames 4-6 see the shuttle's tracklet
    # followed at least min_support = 2 times and take it (frame 3 sees it once).
    assert got == [1, 1, 1, 1, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2]
    assert la.changes["switch"] == 3
    d = out[4].detection
    assert (d.x, d.y) == (535.0, 395.0)
    # The racket's candidate is still there, marked as a loser.
    assert [c.rejected_by for c in out[4].candidates if c.tracklet == 1] == [REJECT_SCORE]
    online, _ = run(stream, params(0))
    assert [r.detection.tracklet for r in online][:7] == [1] * 7


def test_switch_needs_a_clean_handover():
    out, _ = run(hit_stream(back_to_racket=True), params(4))
    got = [r.detection.tracklet for r in out]
    # The readout goes back to the racket at frame 10: frame 6's window (7-10) ends on it, so
    # frame 6 keeps the racket; frames 4-5 see the last handover to the shuttle (frames 7-9).
    assert got[:7] == [1, 1, 1, 1, 2, 2, 1]


def test_no_switch_from_a_lost_tracklet_or_to_one_closing_in():
    out, _ = run(hit_stream(racket_seen_at_handover=False), params(4))
    assert [r.detection.tracklet for r in out][:7] == [1] * 7
    out, _ = run(hit_stream(converging=True), params(4))
    assert [r.detection.tracklet for r in out][:7] == [1] * 7


def test_switch_and_backfill_can_be_turned_off():
    out, la = run(hit_stream(), params(4, switch=False))
    assert la.changes["switch"] == 0 and [r.detection.tracklet for r in out][:7] == [1] * 7
    out, la = run(serve_stream(), params(4, backfill=False))
    assert la.changes["backfill"] == 0 and out[4].detection is None


def test_a_taken_candidate_is_led_to_the_cork():
    stream = [frame([cand(100.0 + 10 * i, 300.0, 7, short_side=6.0)], 7 if i >= 3 else None)
              for i in range(8)]
    p = params(4).with_value("colour.head_lead", 0.5)
    out, _ = run(stream, p)
    # 10 px a frame at 100 fps = 1000 px/s ≥ head_lead_min_speed: moved 0.5 × 6 px forward.
    assert out[1].detection.x == pytest.approx(110.0 + 3.0)
    assert out[1].detection.y == pytest.approx(300.0)


def test_stereo_lookahead_retriangulates_a_rewritten_pair():
    rig = make_rig_for((1280, 720))
    p = params(4)
    la = StereoLookahead(rig, p, lambda: 6.0)
    out = []
    n = 12
    for i in range(n):
        lc, rc = [], []
        if i >= 2:
            x = 400.0 + 10 * (i - 2)
            lc.append(cand(x, 300.0, 7))
            rc.append(cand(x - 30.0, 300.0, 3))       # 30 px disparity on the same row
        left, right = frame(lc, 7 if i >= 5 else None), frame(rc, 3 if i >= 5 else None)
        out += la.push(TrackResult(index=i, timestamp=i / FPS, left=left, right=right))
    out += la.flush()
    assert [r.index for r in out] == list(range(n))
    r = out[3]
    assert r.left.detection is not None and r.right.detection is not None
    assert r.point is not None and la.retriangulated == 3
    # f = 300 px, baseline 0.3 m, disparity 30 px: Z = 3 m in the left camera's frame.
    assert r.point[2] == pytest.approx(3.0, rel=1e-3)
    assert r.distance == pytest.approx(math.dist((0, 0, 0), r.point), rel=1e-6)
    assert out[6] is not None and out[6].point is None   # not rewritten: the online result as it was


def _flight_from_held_points(k: int):
    """Frames 0-39 at FPS; frames 4 and 36 had a point online; at frame 36 a flight begins from
    the points of frames 1-36 (one every frame)."""
    rig = make_rig_for((1280, 720))
    la = StereoLookahead(rig, params(k), lambda: 6.0)
    out = []
    for i in range(40):
        flight = FlightInfo(confirmed=tuple((j / FPS, 0.1 * j, 0.0, 3.0) for j in range(1, 37))
                            if i == 36 else ())
        point = (9.0, 9.0, 9.0) if i in (4, 36) else None
        out += la.push(TrackResult(index=i, timestamp=i / FPS, left=frame([], None),
                                   right=frame([], None), point=point, flight=flight))
    out += la.flush()
    assert [r.index for r in out] == list(range(40))
    return rig, la, out


def test_stereo_lookahead_gives_held_frames_the_points_a_new_flight_took_up():
    rig, la, out = _flight_from_held_points(4)
    # The file readout holds its decided frames CONFIRM_HOLD_S (25 frames here) after the
    # newest: the frames since then get their points at frame 36; frame 4 keeps its own, the
    # older frames have left, frames after 36 are not in the flight's list.
    given = [i for i, r in enumerate(out) if r.point is not None and i not in (4, 36)]
    assert given == list(range(given[0], 36)) and la.confirmed == len(given)
    assert 36 - int(CONFIRM_HOLD_S * FPS) - 1 <= given[0] <= 36 - int(CONFIRM_HOLD_S * FPS)
    assert out[4].point == (9.0, 9.0, 9.0) and out[36].point == (9.0, 9.0, 9.0)
    assert out[20].point == pytest.approx((2.0, 0.0, 3.0)) and out[20].predicted_distance is None
    assert out[20].distance == pytest.approx(math.dist((0, 0, 0), rig.to_left([(2.0, 0.0, 3.0)])[0]))


def test_held_frames_measured_near_the_new_flight_take_its_path():
    """Frames the track left out (a point it dropped, one measured just before it began) get the
    flight's path where their own measured point lies within CONFIRM_GATE_M of it."""
    rig = make_rig_for((1280, 720))
    la = StereoLookahead(rig, params(4), lambda: 6.0)
    path = (0.36, 3.6, 0.0, 3.0, 10.0, 0.0, 2.0, 0.2)
    on = {i: position_on_path(path, i / FPS) for i in range(40)}
    measured = {27: np.add(on[27], (0.5 * CONFIRM_GATE_M, 0.0, 0.0)),    # near: taken
                28: np.add(on[28], (2.0 * CONFIRM_GATE_M, 0.0, 0.0)),    # off the path: not
                20: on[20]}                                              # long before the track
    out = []
    for i in range(40):
        flight = (FlightInfo(confirmed=tuple((j / FPS, *on[j]) for j in range(30, 37)), confirmed_path=path)
                  if i == 36 else FlightInfo())
        out += la.push(TrackResult(index=i, timestamp=i / FPS, left=frame([], None), right=frame([], None),
                                   point=on[i] if i == 36 else None, flight=flight,
                                   measured_point=None if i not in measured else tuple(measured[i])))
    out += la.flush()
    assert [i for i, r in enumerate(out) if r.point is not None] == [27] + list(range(30, 37))
    assert out[27].point == pytest.approx(on[27])


def test_a_flight_taking_a_point_again_gives_the_gap_before_it_its_path():
    """Frames the followed flight refused just before a point it took (no new flight) get its
    path where their measured point lies near it, back to the last frame with a point."""
    rig = make_rig_for((1280, 720))
    la = StereoLookahead(rig, params(4), lambda: 6.0)
    path = (0.09, 0.9, 0.0, 3.0, 10.0, 0.0, 2.0, 0.2)
    on = {i: position_on_path(path, i / FPS) for i in range(20)}
    near = {i: tuple(np.add(on[i], (0.5 * CONFIRM_GATE_M, 0.0, 0.0))) for i in range(20)}
    measured = {3: near[3], 6: near[6], 7: near[7], 8: tuple(np.add(on[8], (2.0 * CONFIRM_GATE_M, 0, 0)))}
    out = []
    for i in range(20):
        point = on[i] if i in (5, 9) else None
        flight = FlightInfo(confirmed_path=path) if i == 9 else FlightInfo()
        out += la.push(TrackResult(index=i, timestamp=i / FPS, left=frame([], None), right=frame([], None),
                                   point=point, flight=flight, measured_point=measured.get(i)))
    out += la.flush()
    # Frame 8 is off the path; frame 3 lies before frame 5's point, where the gap begins.
    assert [i for i, r in enumerate(out) if r.point is not None] == [5, 6, 7, 9]
    assert out[6].point == pytest.approx(on[6])


def test_the_live_readout_gives_no_frame_a_point_afterwards():
    _rig, la, out = _flight_from_held_points(0)
    assert [i for i, r in enumerate(out) if r.point is not None] == [4, 36] and la.confirmed == 0


def test_lookahead_range_is_validated():
    from badminton_gui.core.params import ParamError
    with pytest.raises(ParamError):
        TrackerParams().with_value("lookahead.frames", -1)


@pytest.mark.parametrize("k", ["0", "8"])
def test_cli_lookahead_keeps_the_output_format(tmp_path, k):
    frames_l, _ = moving_dot_frames()
    frames_r, _ = moving_dot_frames(offset=-10.0)
    write_video(tmp_path / "l.avi", frames_l)
    write_video(tmp_path / "r.avi", frames_r)
    make_rig_for().save(tmp_path / "rig.yaml")
    out_default, out_k = tmp_path / "a.csv", tmp_path / "b.csv"
    common = ["track", "--left", str(tmp_path / "l.avi"), "--right", str(tmp_path / "r.avi"),
              "--calib", str(tmp_path / "rig.yaml"), "--quiet"]
    assert main(common + ["-o", str(out_default)]) == 0
    assert main(common + ["-o", str(out_k), "--lookahead", k]) == 0
    a, b = list(csv.DictReader(out_default.open())), list(csv.DictReader(out_k.open()))
    assert len(a) == len(b) == len(frames_l)
    assert list(a[0].keys()) == list(b[0].keys())
    assert [r["Frame"] for r in b] == [str(i) for i in range(len(frames_l))]
    det_a, det_b = tmp_path / "da.csv", tmp_path / "db.csv"
    assert main(["detect", str(tmp_path / "l.avi"), "-o", str(det_a), "--quiet"]) == 0
    assert main(["detect", str(tmp_path / "l.avi"), "-o", str(det_b), "--quiet", "--lookahead", k]) == 0
    a, b = list(csv.DictReader(det_a.open())), list(csv.DictReader(det_b.open()))
    assert len(a) == len(b) == len(frames_l) and list(a[0].keys()) == list(b[0].keys())
    assert [r["Frame"] for r in b] == [str(i) for i in range(len(frames_l))]
    # A plain moving dot: every frame found online is found with the look-ahead too.
    assert sum(r["Visibility"] == "1" for r in b) >= sum(r["Visibility"] == "1" for r in a) - 0
    np.testing.assert_allclose([float(r["X"]) for r in a[10:30]], [float(r["X"]) for r in b[10:30]])


def test_cli_rejects_a_negative_lookahead(tmp_path, capsys):
    frames, _ = moving_dot_frames(n=5)
    write_video(tmp_path / "l.avi", frames)
    assert main(["detect", str(tmp_path / "l.avi"), "-o", str(tmp_path / "x.csv"), "--quiet",
                 "--lookahead", "-1"]) == 2


def test_a_tracklet_that_left_the_picture_takes_its_last_frames():
    """``CameraResult.left_picture`` (the detector's ``association.exit_margin``): tracklet 5
    rose out through the top edge after frame 7 while the online readout stayed on a player
    (tracklet 2). Tracklet 5 was the shuttle: the held-back frames back to its last gap take it;
    a frame before that gap keeps the online choice."""
    stream = []
    for i in range(10):
        cands = [cand(700.0, 300.0, 2)]
        if i in (2, 4, 5, 6, 7):
            cands.append(cand(700.0, 200.0 - 25 * i, 5))
        res = frame(cands, 2 if i < 8 else None)
        if i == 8:
            res = CameraResult(detection=None, candidates=res.candidates, image_size=(1280, 720),
                               left_picture=5)
        stream.append(res)
    out, la = run(stream, params(4))
    assert [r.detection.tracklet if r.detection else None for r in out] == (
        [2, 2, 2, 2, 5, 5, 5, 5, None, None])
    assert la.changes["exit"] == 4
    plain = [dataclasses.replace(r, left_picture=-1) for r in stream]
    out, la = run(plain, params(4))
    assert [r.detection.tracklet if r.detection else None for r in out][4:8] == [2] * 4
    assert la.changes["exit"] == 0


# --- lead-in (``lookahead.lead_in_run``): a run followed back through the held shuttle ---------

def held_then_served(held=10, flight=15, width=1280, step=2.0):
    """The shuttle held in the hand, drifting ``step`` px a frame (of a 1280-wide picture) and
    refused by filter 1 (too short), with a still light far away; then the serve flies 10 px a
    frame, detected online."""
    scale = width / 1280
    stream = []
    for i in range(held + flight):
        light = cand(900.0 * scale, 600.0, 1)
        if i < held:
            shuttle = Candidate((100.0 + step * i) * scale, 300.0, 4.0, 1.0, math.nan, 2.0, math.nan, 0.0,
                                "length")
            stream.append(CameraResult(None, (light, shuttle), image_size=(width, 720)))
        else:
            shuttle = cand((100.0 + step * held + 10 * (i - held)) * scale, 300.0, 7)
            stream.append(frame([light, shuttle], 7))
    return [dataclasses.replace(r, image_size=(width, 720)) for r in stream]


def run_all(stream, p):
    """Every result of one camera's look-ahead, and the number held back after each push."""
    la = CameraLookahead(p)
    out, held_back = [], []
    for i, res in enumerate(stream):
        out += la.push(res, i / FPS)
        held_back.append(i + 1 - len(out))
    return out + la.flush(), la, held_back


@pytest.mark.parametrize("k", [1, 4])
def test_lead_in_follows_a_run_back_through_the_held_shuttle(k):
    stream = held_then_served()
    out, la, held_back = run_all(stream, params(k, lead_in_run=10))
    assert len(out) == len(stream)
    assert [r.detection is not None for r in out] == [True] * len(stream)
    for i in range(10):
        d = out[i].detection
        assert (d.x, d.y, d.rejected_by) == (100.0 + 2 * i, 300.0, None)
        # The taken blob is the frame's one accepted candidate; the light is untouched.
        assert [c.rejected_by is None for c in out[i].candidates] == [False, True]
    assert la.changes["lead_in"] == 10
    # Held back K frames, then the run's 10 and lead_in_frames (60) more: the whole stream here.
    assert max(held_back) == len(stream)


def test_lead_in_is_off_by_default_and_on_in_the_broadcast_preset():
    assert TrackerParams().lookahead.lead_in_run == 0
    assert load_preset("broadcast").lookahead.lead_in_run > 0
    out, la, held_back = run_all(held_then_served(), params(4))
    assert [r.detection is not None for r in out] == [False] * 10 + [True] * 15
    assert la.changes["lead_in"] == 0 and max(held_back) == 4
    # Nor with look-ahead 0, the live readout: nothing held back.
    out, la, held_back = run_all(held_then_served(), params(0, lead_in_run=10))
    assert la.changes["lead_in"] == 0 and max(held_back) == 0


def test_lead_in_needs_a_long_enough_run():
    stream = held_then_served(flight=15)
    for i in range(16, 25):                      # the detections stop after 6 frames of flight
        stream[i] = dataclasses.replace(stream[i], detection=None)
    out, _, _ = run_all(stream, params(1, lead_in_run=10))
    assert [r.detection is not None for r in out[:10]] == [False] * 10
    out, _, _ = run_all(stream, params(1, lead_in_run=6))
    assert [r.detection is not None for r in out[:10]] == [True] * 10


def test_lead_in_stops_at_a_gap_a_player_or_its_reach():
    stream = held_then_served()
    # Frame 3 has no blob near the hand: frames 0-3 stay empty.
    stream[3] = CameraResult(None, (cand(900.0, 600.0, 1),), image_size=(1280, 720))
    # Frame 6: a player's blob (longer than filter 1's maximum) is nearer than the shuttle.
    player = Candidate(113.0, 300.0, 400.0, 60.0, math.nan, 5000.0, math.nan, 0.0, "length")
    stream[6] = dataclasses.replace(stream[6], candidates=stream[6].candidates + (player,))
    out, la, _ = run_all(stream, params(1, lead_in_run=10))
    assert [r.detection is not None for r in out[:10]] == [False] * 4 + [True] * 6
    assert out[6].detection.x == 112.0 and out[6].detection.length == 4.0
    assert la.changes["lead_in"] == 6
    # At most lead_in_frames back.
    out, _, _ = run_all(held_then_served(), params(1, lead_in_run=10, lead_in_frames=4))
    assert [r.detection is not None for r in out[:10]] == [False] * 6 + [True] * 4


def test_lead_in_radius_is_in_pixels_of_a_1280_wide_picture():
    # The held shuttle steps 5 px a frame at 1280 px wide, 10 px at 2560.
    for width in (1280, 2560):
        out, _, _ = run_all(held_then_served(width=width, step=5.0), params(1, lead_in_run=10, lead_in_radius=6.0))
        assert all(r.detection is not None for r in out[:10])
        out, _, _ = run_all(held_then_served(width=width, step=5.0), params(1, lead_in_run=10, lead_in_radius=4.0))
        assert not any(r.detection is not None for r in out[:10])


def test_stereo_lookahead_has_no_lead_in():
    la = StereoLookahead(None, params(4, lead_in_run=10))
    assert not la.left.lead_in and not la.right.lead_in


def with_report(result, x, y, tracklet):
    """``result`` with a blob at (x, y) on ``tracklet`` reported as the detection."""
    reported = Candidate(x, y, 20.0, 0.0, 200.0, 30.0, 0.0, 0.5, None, tracklet=tracklet)
    return dataclasses.replace(result, detection=reported, candidates=result.candidates + (reported,))


@pytest.mark.parametrize("k", [1, 4])
def test_lead_in_goes_through_clutter_reported_just_before_the_serve(k):
    # Frames 5-9: a player's hand (tracklet 3, far from the held shuttle) is reported. The serve's
    # run is counted from its own tracklet's first frame (10), not from the hand's (5), and the
    # chain back from it replaces the hand's five frames by the held shuttle, then goes on.
    stream = held_then_served()
    for i in range(5, 10):
        stream[i] = with_report(stream[i], 600.0 + 3 * i, 500.0, 3)
    out, la, _ = run_all(stream, params(k, lead_in_run=10))
    assert len(out) == len(stream)
    for i in range(10):
        d = out[i].detection
        assert (d.x, d.y) == (100.0 + 2 * i, 300.0)
    # The hand's blob stays among the candidates, marked as a loser; nothing else is lost.
    for i in range(5, 10):
        assert [(c.x, c.rejected_by) for c in out[i].candidates if c.tracklet == 3] == [(600.0 + 3 * i, REJECT_SCORE)]
        assert len(out[i].candidates) == len(stream[i].candidates)
    assert la.changes["lead_in"] == 10 and la.changes["lead_in_over"] == 5


@pytest.mark.parametrize("reported, kept", [(10, True), (9, False)])
def test_lead_in_keeps_an_earlier_run_of_its_own(reported, kept):
    # A track reported for ``reported`` frames up to the serve: a run of lead_in_run frames (10)
    # is a flight of its own and stays; a shorter one is replaced by the chain.
    stream = held_then_served()
    for i in range(10 - reported, 10):
        stream[i] = with_report(stream[i], 600.0 + 8 * i, 500.0, 3)
    out, la, _ = run_all(stream, params(1, lead_in_run=10))
    xs = [out[i].detection.x if out[i].detection else None for i in range(10)]
    if kept:
        assert xs == [600.0 + 8 * i for i in range(10)] and la.changes["lead_in"] == 0
    else:
        assert xs == [100.0 + 2 * i for i in range(10)] and la.changes["lead_in_over"] == 9


def test_lead_in_goes_on_through_the_held_shuttle_already_reported():
    # Frames 4-6: the held shuttle itself reported for a moment (a still blob the association let
    # through, here on a tracklet of its own, 8): the chain keeps those reports as they are and
    # goes on from them back to frame 0.
    stream = held_then_served()
    for i in range(4, 7):
        stream[i] = with_report(stream[i], 100.0 + 2 * i + 1.0, 300.0, 8)
    out, la, _ = run_all(stream, params(1, lead_in_run=10))
    assert [out[i].detection.x for i in range(10)] == (
        [100.0 + 2 * i for i in range(4)] + [109.0, 111.0, 113.0] + [100.0 + 2 * i for i in range(7, 10)])
    assert all(out[i].detection is stream[i].detection for i in range(4, 7))
    assert la.changes["lead_in"] == 7 and la.changes["lead_in_over"] == 0


def test_lead_in_not_through_stops_at_any_report():
    # lookahead.lead_in_through off (the adaptation's first pass): a run counts whatever the
    # tracklet, so the hand reported in frames 5-9 starts the serve's run, and nothing near the
    # hand leads back from it; frames 0-4 stay empty, the hand's reports stay.
    stream = held_then_served()
    for i in range(5, 10):
        stream[i] = with_report(stream[i], 600.0 + 3 * i, 500.0, 3)
    out, la, _ = run_all(stream, params(1, lead_in_run=10, lead_in_through=False))
    assert [out[i].detection.x if out[i].detection else None for i in range(10)] == (
        [None] * 5 + [600.0 + 3 * i for i in range(5, 10)])
    assert la.changes["lead_in"] == 0
    # Nor through the held shuttle reported already: the chain stops at its report.
    stream = held_then_served()
    for i in range(4, 7):
        stream[i] = with_report(stream[i], 100.0 + 2 * i + 1.0, 300.0, 8)
    out, la, _ = run_all(stream, params(1, lead_in_run=10, lead_in_through=False))
    assert [r.detection is not None for r in out[:10]] == [False] * 4 + [True] * 6
    assert la.changes["lead_in"] == 3


@pytest.mark.parametrize("cap, led_in", [(9, False), (10, True)])
def test_a_lead_in_replacing_more_reports_than_allowed_is_dropped_whole(cap, led_in):
    # Frames 0-9: a flight reported on two short tracklets (3 and 4, five frames each) beside
    # the still blob the serve's run leads back into: replacing ten reports is not leading in
    # a hand's few frames. Above ``lead_in_max_replaced`` the whole chain is dropped.
    stream = held_then_served()
    for i in range(10):
        stream[i] = with_report(stream[i], 600.0 + 20 * i, 500.0 - 10 * i, 3 if i < 5 else 4)
    out, la, _ = run_all(stream, params(1, lead_in_run=10, lead_in_max_replaced=cap))
    xs = [out[i].detection.x for i in range(10)]
    if led_in:
        assert xs == [100.0 + 2 * i for i in range(10)] and la.changes["lead_in_over"] == 10
    else:
        assert xs == [600.0 + 20 * i for i in range(10)]
        assert la.changes["lead_in"] == 0 and la.changes["lead_in_refused"] == 1


# --- gap fill (``lookahead.gap_fill_frames``): short gaps between detections ------------------

def flight_with_gap(gap=(8, 9), off=0.0, n=20, coast=False):
    """A shuttle flying 20 px a frame on tracklet 7 (too fast for the lead-in's 12-px steps),
    detected, except in the ``gap`` frames where its blob (``off`` px off its path) was refused by
    filter 1; a still light far away."""
    stream = []
    for i in range(n):
        light = cand(900.0, 600.0, 1)
        x = 100.0 + 20 * i
        if i in gap:
            short = Candidate(x, 300.0 + off, 4.0, 1.0, math.nan, 2.0, math.nan, 0.0, "length")
            cands = (light, short)
            det = None
            if coast:   # the followed tracklet's coasting guess, off the path
                det = Candidate(x + 15.0, 320.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, None, predicted=True, tracklet=7)
                cands = cands + (det,)
            stream.append(CameraResult(det, cands, image_size=(1280, 720)))
        else:
            stream.append(frame([light, cand(x, 300.0, 7)], 7))
    return stream


@pytest.mark.parametrize("k", [1, 4])
def test_a_short_gap_takes_the_blob_on_the_line_between_its_detections(k):
    out, la, _ = run_all(flight_with_gap(), params(k, lead_in_run=10, gap_fill_frames=6))
    assert len(out) == 20
    for i in (8, 9):
        d = out[i].detection
        assert (d.x, d.y, d.length, d.rejected_by) == (100.0 + 20 * i, 300.0, 4.0, None)
    assert la.changes["gap_fill"] == 2
    # A coasting guess in the gap is replaced too (marked as a loser, still there).
    out, la, _ = run_all(flight_with_gap(coast=True), params(k, lead_in_run=10, gap_fill_frames=6))
    assert [out[i].detection.x for i in (8, 9)] == [260.0, 280.0] and la.changes["gap_fill"] == 2
    assert [c.rejected_by for c in out[8].candidates if c.predicted] == [REJECT_SCORE]


def test_the_gap_fill_keeps_to_short_gaps_and_blobs_near_the_line():
    # 11 px off the line at radius 10: nothing; at 9: taken.
    out, la, _ = run_all(flight_with_gap(off=11.0), params(1, lead_in_run=10, gap_fill_frames=6))
    assert out[8].detection is None and la.changes["gap_fill"] == 0
    out, la, _ = run_all(flight_with_gap(off=9.0), params(1, lead_in_run=10, gap_fill_frames=6))
    assert out[8].detection.y == 309.0 and la.changes["gap_fill"] == 2
    # A gap of 7 frames is longer than 6: left as it is; 6 frames are filled.
    out, la, _ = run_all(flight_with_gap(gap=range(5, 12)), params(1, lead_in_run=10, gap_fill_frames=6))
    assert la.changes["gap_fill"] == 0 and all(out[i].detection is None for i in range(5, 12))
    out, la, _ = run_all(flight_with_gap(gap=range(5, 11)), params(1, lead_in_run=10, gap_fill_frames=6))
    assert la.changes["gap_fill"] == 6
    # No detection after the gap (the end of the video): nothing to fill towards.
    out, la, _ = run_all(flight_with_gap(gap=(18, 19)), params(1, lead_in_run=10, gap_fill_frames=6))
    assert la.changes["gap_fill"] == 0 and out[19].detection is None


def test_the_gap_fill_is_off_by_default_and_on_in_the_broadcast_preset():
    assert TrackerParams().lookahead.gap_fill_frames == 0
    assert load_preset("broadcast").lookahead.gap_fill_frames > 0
    out, la, _ = run_all(flight_with_gap(), params(1, lead_in_run=10))
    assert out[8].detection is None and la.changes["gap_fill"] == 0
    # Never live (look-ahead 0), and only with the lead-in stage it shares its delay with.
    for p in (params(0, lead_in_run=10, gap_fill_frames=6), params(1, gap_fill_frames=6)):
        out, la, held_back = run_all(flight_with_gap(), p)
        assert out[8].detection is None and la.changes["gap_fill"] == 0


# --- the GUI's look-ahead view (``DelayedReadout``): each decided result with its own frame ------

def test_the_live_view_passes_each_result_straight_through():
    readout = DelayedReadout(load_preset("broadcast"), 0)
    result = TrackResult(index=0, timestamp=0.0, left=frame([], None), right=frame([], None))
    assert readout.push(result, "frame 0") == [(result, "frame 0")]
    assert readout.flush() == [] and readout.held == 0


def test_a_one_camera_view_shows_detects_rows_each_with_its_own_frame():
    """A TV clip's view: the broadcast preset's look-ahead (lead-in included) decides the rows
    `detect` writes, and each comes out with the payload of the frame it was made from."""
    stream = held_then_served()
    p = params(4, lead_in_run=10)
    readout = DelayedReadout(p, 4)
    shown = []
    for i, res in enumerate(stream):
        shown += readout.push(TrackResult(index=i, timestamp=i / FPS, left=res,
                                          right=CameraResult(None, image_size=(1280, 720))), f"frame {i}")
        assert readout.held == i + 1 - len(shown)
    shown += readout.flush()
    assert readout.held == 0
    assert [payload for _, payload in shown] == [f"frame {i}" for i in range(len(stream))]
    assert [r.index for r, _ in shown] == list(range(len(stream)))
    expected, _, _ = run_all(stream, p)            # the rows of `detect` (CameraLookahead)
    assert [(r.left.detection.x, r.left.detection.y) for r, _ in shown] == \
        [(r.detection.x, r.detection.y) for r in expected]
    assert shown[0][0].left.detection.rejected_by is None      # led in: the held shuttle shown


def test_a_stereo_view_waits_exactly_its_frames_and_shows_the_new_flights_points():
    """No extra hold for the 3D points of a flight's start (the file readout's CONFIRM_HOLD_S):
    the view waits its K frames, and held frames still get them when the flight begins in time."""
    rig = make_rig_for((1280, 720))
    readout = DelayedReadout(params(4), 4, rig, lambda: 6.0)
    shown = []
    for i in range(40):
        flight = FlightInfo(confirmed=tuple((j / FPS, 0.1 * j, 0.0, 3.0) for j in range(33, 37))
                            if i == 36 else ())
        shown += readout.push(TrackResult(index=i, timestamp=i / FPS, left=frame([], None),
                                          right=frame([], None), flight=flight), i)
        assert readout.held == min(i + 1, 4)
    shown += readout.flush()
    assert [payload for _, payload in shown] == [r.index for r, _ in shown] == list(range(40))
    with_point = [r.index for r, _ in shown if r.point is not None]
    assert with_point == [33, 34, 35]     # 36 is the flight's own frame (its point came online)


def test_a_filter_tuned_mid_view_applies_to_the_held_frames_and_other_rules_are_refused():
    """``DelayedReadout.set_params``: the frames held keep their place and are decided with the
    new values (here the lead to the cork); other look-ahead rules need a new readout."""
    stream = held_then_served(held=0, flight=12)
    p = params(4)
    readout = DelayedReadout(p, 4)
    shown = []
    for i, res in enumerate(stream[:6]):
        shown += readout.push(TrackResult(index=i, timestamp=i / FPS, left=res,
                                          right=CameraResult(None, image_size=(1280, 720))), i)
    assert readout.held == 4
    readout.set_params(p.with_value("colour.head_lead", 1.0))
    assert readout.held == 4
    with pytest.raises(ValueError, match="new DelayedReadout"):
        readout.set_params(p.with_value("lookahead.min_support", 3))
    assert readout.params.colour.head_lead == 1.0 and readout.params.lookahead.frames == 4
    stereo = DelayedReadout(p, 4, make_rig_for((1280, 720)), lambda: 6.0)
    stereo.set_params(p.with_value("colour.head_lead", 1.0))
    assert stereo.params.colour.head_lead == 1.0
    assert DelayedReadout(p, 0).params is None

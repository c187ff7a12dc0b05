"""The per-camera readout rules as pure transitions (core/flight/camera_rules.py): the rows of
the table in its docstring, driven with hand-made states and inputs.

``hold_transition`` (the landed hold, before the 3D point is measured) and
``readout_transition`` (the caught shuttle, the hold's anchors, the tracks seen in the air, the
limit on reports alone) must leave the state they are given as it was, and name the rules that
changed the readout. Each switch is shown off as well as on.
"""

from __future__ import annotations

import dataclasses

import pytest

from badminton_gui.core.flight.camera_rules import (CameraReadoutState, HoldInputs, ReadoutInputs, ReadoutState,
                                                    hold_transition, readout_transition)
from badminton_gui.core.flight.phase import PhaseState
from badminton_gui.core.params import TrackerParams
from badminton_gui.core.types import REJECT_STEREO, CameraResult, Candidate

P = TrackerParams()
SIZE = (1280, 720)
T = 1.01                                   # the step's time
LANDED = PhaseState(last_point=(1.0, 0.0))  # the flight's last point, just before, on the floor


def _p(**stereo) -> TrackerParams:
    return dataclasses.replace(P, stereo=dataclasses.replace(P.stereo, **stereo))


def _cand(x: float, rejected: str | None = None, tracklet: int = 4, predicted: bool = False) -> Candidate:
    return Candidate(float(x), 500.0, 30.0, 6.0, 200.0, 20.0, 1.0, 0.5, rejected, predicted, tracklet)


def _result(report: Candidate | None, *others: Candidate) -> CameraResult:
    cands = ((report,) if report is not None else ()) + others
    return CameraResult(report, cands, image_size=SIZE)


EMPTY = CameraResult(None, (), image_size=SIZE)
# The left camera reported tracklet 4 at x 100 with a 3D point; that track flew at 0.5 s.
REMEMBERED = CameraReadoutState(hold_tracklet=4, hold_xy=(100.0, 500.0), anchored=True, flown=((4, 0.5),))


def _hold(cam0: CameraReadoutState, report: Candidate | None, *others: Candidate, params: TrackerParams = P,
          phase: PhaseState = LANDED, pair_height: float | None = None, has_court_pose: bool = True,
          path: tuple | None = None, cam1: CameraReadoutState = CameraReadoutState()):
    """The left camera through ``hold_transition``: (its state after, the report, the decision, fired)."""
    before = ReadoutState((cam0, cam1))
    kept = dataclasses.replace(before)
    inputs = HoldInputs(T, (_result(report, *others), EMPTY), (report, None), (0,), pair_height,
                        (path, None), phase, has_court_pose)
    after, decision, fired = hold_transition(before, inputs, params)
    assert before == kept, "the transition changed the state it was given"
    return after.cams[0], decision.reports[0], decision, fired


def _x(report: Candidate | None):
    return None if report is None else (report.tracklet, report.x)


SHOE = _cand(403, tracklet=9)
LYING = _cand(100.5, "motion")

# (why, state before, report, other candidates, keyword inputs, (tracklet, x) reported, rules fired)
HOLD_TABLE = [
    ("a report on a track is remembered",
     CameraReadoutState(), _cand(100), (), {}, (4, 100.0), ()),
    ("the report stops: its track's candidate at the spot is held",
     REMEMBERED, None, (_cand(101, "motion"),), {}, (4, 101.0), (("landed_hold", 0),)),
    ("... an untracked blob at the spot too (a lying shuttle a classifier refused)",
     REMEMBERED, None, (_cand(101, "score", tracklet=-1),), {}, (-1, 101.0), (("landed_hold", 0),)),
    ("... not another track's blob",
     REMEMBERED, None, (_cand(101, "score", tracklet=9),), {}, None, ()),
    ("... not a candidate that moved off (picked up)",
     REMEMBERED, None, (_cand(120, "motion"),), {}, None, ()),
    ("... not when the last report had no 3D point",
     dataclasses.replace(REMEMBERED, anchored=False), None, (_cand(101, "motion"),), {}, None, ()),
    ("... not when the flight's last point was above the floor",
     REMEMBERED, None, (_cand(101, "motion"),), {"phase": PhaseState(last_point=(1.0, 1.2))}, None, ()),
    ("... not when it is older than landed_recent",
     REMEMBERED, None, (_cand(101, "motion"),), {"phase": PhaseState(last_point=(T - 1.1, 0.0))}, None, ()),
    ("... not a track never seen in the air (a shoe paired at floor height)",
     dataclasses.replace(REMEMBERED, flown=()), None, (_cand(101, "motion"),), {}, None, ()),
    ("... not one seen in the air longer than flown_memory ago",
     dataclasses.replace(REMEMBERED, flown=((4, T - P.stereo.flown_memory - 0.1),)), None,
     (_cand(101, "motion"),), {}, None, ()),
    ("... nor another track seen in the air",
     dataclasses.replace(REMEMBERED, flown=((5, 0.9),)), None, (_cand(101, "motion"),), {}, None, ()),
    ("a hold goes on within landed_step px a frame",
     dataclasses.replace(REMEMBERED, hold_frames=2, holding=True), None, (_cand(103, "motion"),),
     {}, (4, 103.0), (("landed_hold", 0),)),
    ("... for landed_frames frames at most",
     dataclasses.replace(REMEMBERED, hold_frames=3, holding=True), None, (_cand(100, "motion"),),
     {"params": _p(landed_frames=3)}, None, ()),
    ("... landed_step wider",
     REMEMBERED, None, (_cand(108, "motion"),), {"params": _p(landed_step=10.0)}, (4, 108.0), (("landed_hold", 0),)),
    ("the hold off (landed_frames 0)",
     REMEMBERED, None, (_cand(101, "motion"),), {"params": _p(landed_frames=0)}, None, ()),
    ("no court pose: heights do not mean the floor",
     REMEMBERED, None, (_cand(101, "motion"),), {"has_court_pose": False}, None, ()),
    ("a shoe walking past does not take the report from the lying shuttle",
     REMEMBERED, SHOE, (LYING,), {}, (4, 100.5), (("landed_hold", 0), ("landed_shoe_past", 0))),
    ("... it does with landed_shoe_past off",
     REMEMBERED, SHOE, (LYING,), {"params": _p(landed_shoe_past=False)}, (9, 403.0), ()),
    ("... a shoe track seen in the air takes it",
     dataclasses.replace(REMEMBERED, flown=((4, 0.5), (9, 0.9))), SHOE, (LYING,), {}, (9, 403.0), ()),
    ("... a pair above the floor (a new serve) takes it",
     REMEMBERED, SHOE, (LYING,), {"pair_height": 1.0}, (9, 403.0), ()),
    ("... a shoe paired below the floor does not",
     REMEMBERED, SHOE, (LYING,), {"pair_height": -1.7}, (4, 100.5), (("landed_hold", 0), ("landed_shoe_past", 0))),
]


@pytest.mark.parametrize("why, before, report, others, kw, shown, fired", HOLD_TABLE, ids=[r[0] for r in HOLD_TABLE])
def test_the_hold_table(why, before, report, others, kw, shown, fired):
    after, reported, decision, got = _hold(before, report, *others, **kw)
    assert _x(reported) == shown, why
    assert got == fired, why
    assert after.holding == any(rule == "landed_hold" for rule, _ in fired), why
    if reported is not None and reported is not report:
        # the held candidate is the report, unrejected, among the camera's candidates
        assert reported.rejected_by is None and reported in decision.results[0].candidates


def test_a_report_remembers_its_track_and_a_predicted_one_forgets():
    after, *_ = _hold(CameraReadoutState(), _cand(100))
    assert (after.hold_tracklet, after.hold_frames, after.hold_xy) == (4, 0, (100.0, 500.0))
    after, *_ = _hold(REMEMBERED, _cand(100, predicted=True))
    assert after.hold_tracklet == -1


def _hold_sequence(xs: list[float], params: TrackerParams = P) -> list[float | None]:
    """The left camera reports tracklet 4 at xs[0] (with a 3D point), then only the same track's
    held-back candidates at xs[1:]: the x reported per frame."""
    state, out = ReadoutState(), []
    for k, x in enumerate(xs):
        t = 1.0 + 0.01 * k
        report = _cand(x) if k == 0 else None
        others = () if k == 0 else (_cand(x, "motion"),)
        state, decision, _ = hold_transition(state, HoldInputs(
            t, (_result(report, *others), EMPTY), (report, None), (0,), phase=PhaseState(last_point=(1.0, 0.0))),
            params)
        if k == 0:      # the report had a 3D point above the floor, its track carried the flight down
            state, _, _ = readout_transition(state, ReadoutInputs(t, (_result(report), EMPTY), (report, None),
                                                                  (0,), has_point=True), params)
            state = state.with_camera(0, dataclasses.replace(state.cams[0], flown=((4, 0.5),)))
        out.append(None if decision.reports[0] is None else decision.reports[0].x)
    return out


def test_a_landed_shuttle_is_held_while_it_stays_put_for_the_allowed_frames():
    xs = [100, 101, 101, 102, 102, 102]
    assert _hold_sequence(xs, _p(landed_frames=3)) == [100, 101, 101, 102, None, None]
    assert _hold_sequence(xs, _p(landed_frames=0)) == [100, None, None, None, None, None]
    assert _hold_sequence([100, 101, 120, 121], _p(landed_frames=10)) == [100, 101, None, None]


def test_the_shoes_pair_is_no_3d_point_once_the_hold_takes_the_report_back():
    """Both cameras: the left hold gives the report back to the lying shuttle, so the pair the
    shoe made with the right camera (below the floor) is dropped; with the rule off, or with no
    flight before to hold, the pair stays."""
    def run(params=P, left=REMEMBERED):
        other = _cand(380, tracklet=2)
        inputs = HoldInputs(T, (_result(SHOE, LYING), _result(other)), (SHOE, other), (0, 1), -1.7,
                            phase=LANDED)
        _, decision, _ = hold_transition(ReadoutState((left, CameraReadoutState())), inputs, params)
        return _x(decision.reports[0]), _x(decision.reports[1]), decision.drop_point

    assert run() == ((4, 100.5), (2, 380.0), True)
    assert run(_p(landed_shoe_past=False)) == ((9, 403.0), (2, 380.0), False)
    assert run(left=dataclasses.replace(REMEMBERED, flown=())) == ((9, 403.0), (2, 380.0), False)


@pytest.mark.parametrize("why, kw, protected", [
    ("a report on a track that carried the flight down, barely moving, just after a low point", {}, True),
    ("... not a moving one", {"speed": 1000.0}, False),
    ("... not a track never seen in the air", {"flown": ()}, False),
    ("... not while the flight's last point is above the floor", {"z": 1.5}, False),
    ("... not an untracked report", {"tracklet": -1}, False),
    ("... not with the hold off", {"params": _p(landed_frames=0)}, False),
    ("... not when the image path noted another spot", {"noted_x": 130.0}, False),
])
def test_a_lying_landed_shuttle_is_protected_in_the_mask(why, kw, protected):
    """A lying shuttle the association still reports keeps its pixels in the next mask (the
    quarter-scale model loses it when it dims), as a held one does."""
    report = _cand(100, tracklet=kw.get("tracklet", 4))
    state = CameraReadoutState(flown=kw.get("flown", ((4, 0.5),)))
    path = (T, kw.get("noted_x", 100.0), 500.0, (kw.get("speed", 0.0), 0.0))
    _, _, decision, _ = _hold(state, report, params=kw.get("params", P),
                              phase=PhaseState(last_point=(1.0, kw.get("z", 0.0))), path=path)
    assert (decision.protect[0] is report) is protected, why
    held = _hold(REMEMBERED, None, _cand(101, "motion"))[2]
    assert held.protect[0] is held.reports[0]


# ---- readout_transition: anchors, tracks in the air ---------------------------------------------

def _readout(before: ReadoutState, inputs: ReadoutInputs, params: TrackerParams = P):
    kept = dataclasses.replace(before)
    after, results, fired = readout_transition(before, inputs, params)
    assert before == kept, "the transition changed the state it was given"
    return after, results, fired


HOLDING = CameraReadoutState(holding=True)
ANCHORED = CameraReadoutState(anchored=True)

# (why, (left, right) before, right camera's report has a 3D point, params, right anchored after, fired)
ANCHOR_TABLE = [
    ("a report with a 3D point anchors", (CameraReadoutState(), CameraReadoutState()), True, P, True, ()),
    ("without one it does not", (CameraReadoutState(), ANCHORED), False, P, False, ()),
    ("the other camera holding keeps the anchor", (HOLDING, ANCHORED), False, P, True,
     (("landed_other_anchor", 1),)),
    ("... not with landed_other_anchor off", (HOLDING, ANCHORED), False, _p(landed_other_anchor=False), False, ()),
    ("... not a camera never anchored", (HOLDING, CameraReadoutState()), False, P, False, ()),
]


@pytest.mark.parametrize("why, before, has_point, params, anchored, fired", ANCHOR_TABLE,
                         ids=[r[0] for r in ANCHOR_TABLE])
def test_the_anchor_table(why, before, has_point, params, anchored, fired):
    report = _cand(100)
    after, _, got = _readout(ReadoutState(before), ReadoutInputs(
        T, (EMPTY, _result(report)), (None, report), (1,), has_point=has_point), params)
    assert after.cams[1].anchored is anchored, why
    assert tuple(f for f in got if f[0] != "alone_limit") == fired, why


def test_a_report_with_a_point_above_the_floor_marks_its_track_flown():
    report = _cand(100)
    for height, flown in ((1.0, True), (0.1, False), (None, False)):
        after, _, _ = _readout(ReadoutState(), ReadoutInputs(T, (_result(report), EMPTY), (report, None), (0,),
                                                             has_point=height is not None, height=height))
        assert after.cams[0].flown_recently(4, T, P) is flown
        assert not after.cams[0].flown_recently(4, T + P.stereo.flown_memory + 0.1, P)
    # old tracks are forgotten once a new one is noted
    old = ReadoutState((CameraReadoutState(flown=((7, T - P.stereo.flown_memory - 1.0),)), CameraReadoutState()))
    after, _, _ = _readout(old, ReadoutInputs(T, (_result(report), EMPTY), (report, None), (0,), True, 1.0))
    assert after.cams[0].flown == ((4, T),)


# ---- readout_transition: reports alone ----------------------------------------------------------

def _alone(frames: str, params: TrackerParams) -> str:
    """``frames``: per frame L (left only), R (right only), B (both, no 3D point), 3 (both with
    a 3D point), P (right only, with the flight's 3D point), . (neither). Returns per frame what
    the readout shows: L, R, B or ."""
    state, out = ReadoutState(), []
    for k, f in enumerate(frames):
        c = _cand(600, tracklet=7)
        left = _result(c) if f in "LB3" else EMPTY
        right = _result(c) if f in "RB3P" else EMPTY
        state, (left, right), _ = readout_transition(state, ReadoutInputs(
            0.01 * k, (left, right), (left.detection, right.detection), (0, 1), f in "3P"), params)
        shown = (left.detection is not None, right.detection is not None)
        out.append({(True, True): "B", (True, False): "L", (False, True): "R", (False, False): "."}[shown])
        for res in (left, right):
            if res.detection is None and res.candidates:
                assert res.candidates[0].rejected_by == REJECT_STEREO
    return "".join(out)


@pytest.mark.parametrize("why, params, frames, shown", [
    ("a camera starting on its own is withheld", _p(alone_max_frames=0), "..LLLL..RRR.", "............"),
    ("... after alone_max_frames", _p(alone_max_frames=2), "..LLLL..RRR.", "..LL....RR.."),
    ("a readout continuing a 3D point is kept across short gaps only", _p(alone_max_frames=0, alone_anchor_gap=3),
     "333LLL..LL....LL", "BBBLLL..LL......"),
    ("both cameras without a 3D point are never withheld", _p(alone_max_frames=0), "33BBRRBB", "BBBBRRBB"),
    ("a 3D point while this camera reported nothing does not anchor it", _p(alone_max_frames=0),
     "PPPLLRR", "RRR..RR"),
    ("off by the flag", _p(alone_limit=False, alone_max_frames=0), "..LLLL..RRR.", "..LLLL..RRR."),
    ("the count restarts when the camera is not alone", _p(alone_max_frames=3), "LLLBLLL", "LLLBLLL"),
    ("... withheld past the count", _p(alone_max_frames=2), "LLLBLLL", "LL.BLL."),
    ("... the other camera", _p(alone_max_frames=2), "RRR.RRR", "RR..RR."),
])
def test_reports_alone(why, params, frames, shown):
    assert _alone(frames, params) == shown, why


def test_the_limit_names_the_camera_it_withheld():
    c = _cand(600, tracklet=7)
    _, (left, _), fired = _readout(ReadoutState(), ReadoutInputs(0.0, (_result(c), EMPTY), (c, None), (0, 1)),
                                   _p(alone_max_frames=0))
    assert left.detection is None and fired == (("alone_limit", 0),)


def test_a_held_camera_does_not_confirm_the_other():
    """A camera holding its landed shuttle reports it, but no flight goes on: the other
    camera's report beside it is a report alone."""
    c = _cand(600, tracklet=7)
    before = ReadoutState((CameraReadoutState(), HOLDING))
    _, (left, right), _ = _readout(before, ReadoutInputs(0.0, (_result(c), _result(c)), (c, c), (0, 1)),
                                   _p(alone_max_frames=0))
    assert left.detection is None and right.detection is not None


def test_the_fired_rules_become_the_steps_trace_names():
    """What the transitions say fired is what ``track --trace`` writes for the step."""
    from badminton_gui.core.flight.guide import StepGuide
    from badminton_gui.core.step import Step

    step = Step(0.0, 0.0, (None, None), StepGuide(None, 0.0), trace=[])
    _, _, _, fired = _hold(REMEMBERED, SHOE, LYING)
    step.fired_all(fired)
    step.fired_all((("landed_other_anchor", 1), ("caught", None)))
    assert step.trace == ["landed_hold:left", "landed_shoe_past:left", "landed_other_anchor:right", "caught"]
    untraced = Step(0.0, 0.0, (None, None), StepGuide(None, 0.0))
    untraced.fired_all(fired)
    assert untraced.trace is None

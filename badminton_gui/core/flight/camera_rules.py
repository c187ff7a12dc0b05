"""The phase's rules for each camera's readout: a landed shuttle held, a caught one withheld, a
report one camera makes alone limited.

Why this file exists: what a camera reports depends on the shuttle's phase
(:mod:`~badminton_gui.core.flight.phase`) and on that camera's own recent readout. That memory
is one frozen :class:`ReadoutState` (a :class:`CameraReadoutState` per camera), advanced by two
pure transitions, each returning (new state, decision, the rules that fired as (name, camera)):

- :func:`hold_transition`, before the step's 3D point is measured: the landed hold may give a
  camera's report back to the lying shuttle, which drops the pair made without it, and says
  which reports the next frame's mask keeps (``HoldDecision``);
- :func:`readout_transition`, after the phase: the caught shuttle withheld, the hold's anchors
  and the tracks seen in the air noted, reports alone limited (the cameras' new results).

The rules, each switched by its parameter (the trace names them by the first column)::

    rule (switch)                       state before            on this step                                     after
    hold_transition, per camera with a new image:
    landed_hold (landed_frames > 0,     any                     a report on a track                              remembered: its track and spot, 0 frames held
      a court pose)                     any                     a predicted or untracked report                  nothing remembered
                                        remembered, 0 held      no report; anchored, phase landed, the track     HOLDING: its candidate (or an untracked blob)
                                                                flown within flown_memory s                      within landed_step px reported, 1 held
                                        HOLDING, n held         no report; such a candidate, n < landed_frames   HOLDING, n + 1 held
                                        remembered              otherwise                                        nothing remembered
    landed_shoe_past                    remembered track        a report on another track never flown, no pair   the hold goes on as if no report (HOLDING);
                                                                above landed_max_height                          the pair's 3D point dropped
    (the mask)                          HOLDING, or the report  its track flown recently, phase landed, image    the report's pixels kept in the next mask
                                        on a track              speed ≤ VOUCH_WIDE_IMAGE_SPEED px/s
    readout_transition:
    caught (caught_frames)              caught on this step     —                                                each camera's caught spot forgotten
                                        phase caught            a report at the catch, or within caught_step     withheld; its spot remembered
                                                                px of the last withheld one
    landed anchor                       not HOLDING             a report with a 3D point                         anchored (else not)
    landed_other_anchor                 not HOLDING, anchored   a report without one, the other camera HOLDING   still anchored
    flown                               —                       a report with a 3D point above landed_max_height its track flown now (forgotten after flown_memory)
    alone_limit (+ alone_max_frames,    —                       a report, no 3D point, the other camera without  one more alone; withheld past alone_max_frames
      alone_anchor_gap)                                         one (or HOLDING, or before the serve with        unless it continues a 3D point's readout
                                                                stereo.serve_start)

Why each:

- ``stereo.landed_frames`` (LANDED): the association stops reporting a still track soon after it
  flew; a landed shuttle lies there longer and the labels mark it visible: keep reporting it.
- ``stereo.landed_shoe_past``: after a rally a player's white shoe walking past takes the
  association's readout from the lying shuttle; the shuttle is still there.
- ``stereo.landed_other_anchor``: one camera holding its landed shuttle leaves the frame without
  a pair; without this the camera whose report stops last is never held.
- ``stereo.caught_frames`` (CAUGHT): the shuttle in the hand that caught it is out of play:
  withhold it in both cameras while the hand carries it.
- ``stereo.alone_limit``: a report the other camera does not confirm is mostly not the shuttle,
  unless it continues a readout that had a 3D point (a flight the other camera lost). Before the
  serve (``stereo.serve_start``) a report beside the other camera's that makes no pair with it is
  not confirmed either (an LED board's dot in one camera, clutter in the other).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from ..params import TrackerParams
from ..stereo.vouch import VOUCH_WIDE_IMAGE_SPEED
from ..types import REJECT_STEREO, CameraResult, Candidate
from .phase import PhaseState

# (rule name, camera or None): what a transition says fired, for ``Step.fired``.
Fired = tuple[tuple[str, int | None], ...]
# One camera's last noted image-path entry: (t, x, y, image velocity or None).
PathEntry = tuple[float, float, float, tuple[float, float] | None]


@dataclass(frozen=True, slots=True)
class CameraReadoutState:
    """One camera's memory for the readout rules.

    Landed hold: ``hold_tracklet`` the tracklet of the last report (-1: none), ``hold_frames``
    the frames held since, ``hold_xy`` its last position, ``anchored`` whether that report may
    start a hold (it had a 3D point), ``holding`` whether a hold reports this step; ``flown``
    (tracklet, time) of its last report with a 3D point above the floor. Reports alone:
    ``alone_run`` in a row, ``unreported_run`` frames without a report in a row,
    ``continues_stereo`` the readout continues one that had a 3D point. Caught: ``caught_xy``
    the last withheld position of the caught shuttle."""

    hold_tracklet: int = -1
    hold_frames: int = 0
    hold_xy: tuple[float, float] = (0.0, 0.0)
    anchored: bool = False
    holding: bool = False
    flown: tuple[tuple[int, float], ...] = ()
    alone_run: int = 0
    unreported_run: int = 0
    continues_stereo: bool = False
    caught_xy: tuple[float, float] | None = None

    def flown_recently(self, tracklet: int, t: float, params: TrackerParams) -> bool:
        """This camera reported ``tracklet`` with a 3D point above the floor within
        ``stereo.flown_memory`` s: the track carried a flight down, it is not one that only ever
        moved along the floor (a shoe paired with the other camera's shoe after the rally)."""
        for k, when in self.flown:
            if k == tracklet:
                return t - when <= params.stereo.flown_memory
        return False


@dataclass(frozen=True, slots=True)
class ReadoutState:
    """Both cameras' memory for the readout rules (left, right)."""

    cams: tuple[CameraReadoutState, CameraReadoutState] = (CameraReadoutState(), CameraReadoutState())

    def holding(self, cam: int) -> bool:
        """Camera ``cam`` reports a held landed shuttle this step."""
        return self.cams[cam].holding

    def with_camera(self, cam: int, state: CameraReadoutState) -> ReadoutState:
        cams = list(self.cams)
        cams[cam] = state
        return ReadoutState((cams[0], cams[1]))


@dataclass(frozen=True, slots=True)
class HoldInputs:
    """What the hold reads: each camera's result and report (both cameras; only ``cameras``,
    those with a new image, are ruled on), the height above the court of the pair's 3D point
    (None: no pair), each camera's last noted image-path entry (``ImagePaths.last``), the
    shuttle's phase, and whether the rig has a court pose (heights mean the floor)."""

    t: float
    results: tuple[CameraResult, CameraResult]
    reports: tuple[Candidate | None, Candidate | None]
    cameras: tuple[int, ...] = (0, 1)
    pair_height: float | None = None
    paths: tuple[PathEntry | None, PathEntry | None] = (None, None)
    phase: PhaseState = PhaseState()
    has_court_pose: bool = True


@dataclass(frozen=True, slots=True)
class HoldDecision:
    """Each camera's result and report after the hold; ``drop_point``: the pair's 3D point is no
    point any more (a report was given back to the landed shuttle); ``protect``: per camera the
    report whose pixels the next frame's mask keeps (a landed shuttle lying still), or None."""

    results: tuple[CameraResult, CameraResult]
    reports: tuple[Candidate | None, Candidate | None]
    drop_point: bool = False
    protect: tuple[Candidate | None, Candidate | None] = (None, None)


@dataclass(frozen=True, slots=True)
class ReadoutInputs:
    """What the readout rules read after the phase: each camera's result, ``reports`` each
    camera's report for the hold's anchor and the tracks seen in the air (a pair step: its
    reports as paired; None: the results' detections after the caught rule, a one-camera step),
    ``cameras`` those with a new image, whether the step reports a 3D point and its court
    height, whether the phase withholds the shuttle (caught), the phase, and whether the step
    came before the serve (``stereo.serve_start``: then a report without a 3D point is alone
    even beside the other camera's)."""

    t: float
    results: tuple[CameraResult, CameraResult]
    reports: tuple[Candidate | None, Candidate | None] | None = None
    cameras: tuple[int, ...] = (0, 1)
    has_point: bool = False
    height: float | None = None
    caught: bool = False
    phase: PhaseState = PhaseState()
    before_serve: bool = False


def reject_report(result: CameraResult) -> CameraResult:
    """``result`` with its detection withheld: no detection, the candidate marked
    ``REJECT_STEREO`` (the association, the flight and the look-ahead's tracklets untouched)."""
    det = result.detection
    return dataclasses.replace(
        result, detection=None,
        candidates=tuple(dataclasses.replace(c, rejected_by=REJECT_STEREO) if c is det else c
                         for c in result.candidates))


# ---- the landed hold ---------------------------------------------------------------------------
def hold_transition(state: ReadoutState, inputs: HoldInputs, params: TrackerParams
                    ) -> tuple[ReadoutState, HoldDecision, Fired]:
    """The landed hold for the cameras with a new image (pure: ``state`` is left as it was).

    The association reports a still track only for ``association.pause_frames`` after it flew;
    a shuttle that has just landed lies there longer, and the NYCU labels mark it visible for
    another ≈ 0.3–0.8 s. When a camera's report stops, its last report had a 3D point, the 3D
    flight's last point (within ``landed_recent`` s) lay near the floor, the track it followed
    was reported with a 3D point above the floor (``flown_recently``: on the NYCU rallies a
    player's shoe paired across the cameras after the rally was held otherwise) and still has a
    candidate where the last report was (within ``landed_step`` px a frame), that candidate is
    reported, for at most ``landed_frames`` frames. A shuttle held before the serve has no low 3D
    point before it; one picked up moves off. A stereo pair counts as the shuttle in the air only
    above the floor: a shoe paired with the lying shuttle (rally_11-47-21 986: 1.7 m below the
    court) is not one.
    """
    sp = params.stereo
    results, reports = list(inputs.results), list(inputs.reports)
    fired: list[tuple[str, int | None]] = []
    for cam in inputs.cameras:
        state = state.with_camera(cam, dataclasses.replace(state.cams[cam], holding=False))
    on = sp.landed_frames > 0 and inputs.has_court_pose
    if on:
        paired = inputs.pair_height is not None and inputs.pair_height > sp.landed_max_height
        for cam in inputs.cameras:
            cam_state, results[cam], reports[cam], shoe = _hold_camera(
                state.cams[cam], results[cam], reports[cam], inputs.t, inputs.phase, paired, params)
            state = state.with_camera(cam, cam_state)
            if cam_state.holding:
                fired.append(("landed_hold", cam))
            if shoe:
                fired.append(("landed_shoe_past", cam))
    changed = any(reports[cam] is not inputs.reports[cam] for cam in inputs.cameras)
    protect = [None, None]
    for cam in inputs.cameras:
        if _lying_landed(state.cams[cam], reports[cam], inputs, cam, on, params):
            protect[cam] = reports[cam]
    decision = HoldDecision((results[0], results[1]), (reports[0], reports[1]),
                            drop_point=inputs.pair_height is not None and changed,
                            protect=(protect[0], protect[1]))
    return state, decision, tuple(fired)


def _hold_camera(state: CameraReadoutState, result: CameraResult, det: Candidate | None, t: float,
                 phase: PhaseState, paired: bool, params: TrackerParams
                 ) -> tuple[CameraReadoutState, CameraResult, Candidate | None, bool]:
    """One camera through the hold: (its state, result and report after it, whether the hold
    took the report back from a new track, ``landed_shoe_past``)."""
    sp = params.stereo
    if (sp.landed_shoe_past and det is not None and not paired and not det.predicted
            and 0 <= state.hold_tracklet != det.tracklet and not state.flown_recently(det.tracklet, t, params)):
        # The readout leaves the landed shuttle for a track never seen in the air, with no
        # stereo partner above the floor: after a rally, a player's white shoe walking past
        # (rally_11-47-21 left 986, rally_11-48-00 right 630). The shuttle, still lying
        # there, stays the report while the hold's conditions last; else the new track is.
        held_state, held_result, held, _ = _hold_camera(state, result, None, t, phase, paired, params)
        if held is not None:
            return held_state, held_result, held, True
    if det is not None:
        if det.predicted or det.tracklet < 0:
            return dataclasses.replace(state, hold_tracklet=-1), result, det, False
        return (dataclasses.replace(state, hold_tracklet=det.tracklet, hold_frames=0, hold_xy=(det.x, det.y)),
                result, det, False)
    if state.hold_tracklet < 0:
        return state, result, None, False
    forget = dataclasses.replace(state, hold_tracklet=-1)
    if state.hold_frames >= sp.landed_frames or (
            state.hold_frames == 0 and not (state.anchored and phase.landed(t, params)
                                            and state.flown_recently(state.hold_tracklet, t, params))):
        return forget, result, None, False
    step = sp.landed_step * result.image_size[0] / 1280.0
    hx, hy = state.hold_xy
    for c in result.candidates:
        # Its own track's candidate, or a blob no track took (tracklet -1) at the same spot:
        # a lying shuttle dims and its look changes, and a classifier may then refuse it
        # before association (rally_11-48-00 right 641 with the coarse patch classifier).
        if ((c.tracklet == state.hold_tracklet or c.tracklet < 0) and not c.predicted
                and math.hypot(c.x - hx, c.y - hy) <= step):
            held = dataclasses.replace(c, rejected_by=None)
            held_result = dataclasses.replace(result, candidates=tuple(held if k is c else k
                                                                       for k in result.candidates))
            return (dataclasses.replace(state, hold_frames=state.hold_frames + 1, hold_xy=(c.x, c.y), holding=True),
                    held_result, held, False)
    return forget, result, None, False


def _lying_landed(state: CameraReadoutState, det: Candidate | None, inputs: HoldInputs, cam: int,
                  on: bool, params: TrackerParams) -> bool:
    """Whether this camera's report is a landed shuttle lying still, whose pixels the next
    frame's mask should keep: held, or still reported by its own track when that track carried
    the flight down (``flown_recently``), the flight's last point lay near the floor and the
    track barely moves (``VOUCH_WIDE_IMAGE_SPEED``). Without the second case a lying shuttle
    whose track the association kept reporting — its classifier score high — was never held, so
    never protected, and the quarter-scale model lost it when it dimmed (rally_11-48-00 right
    636–664 with the coarse preset's patch classifier). Off with the hold."""
    if det is None or det.predicted:
        return False
    if state.holding:
        return True
    if not on or det.tracklet < 0 or not inputs.phase.landed(inputs.t, params):
        return False
    if not state.flown_recently(det.tracklet, inputs.t, params):
        return False
    # The track's image velocity as noted for this very report (a later stage may have
    # replaced the report noted then).
    last = inputs.paths[cam]
    velocity = last[3] if last is not None and (last[1], last[2]) == (det.x, det.y) else None
    width = inputs.results[cam].image_size[0]
    return velocity is not None and math.hypot(*velocity) <= VOUCH_WIDE_IMAGE_SPEED * width / 1280.0


# ---- after the phase: caught, anchors, tracks in the air, reports alone --------------------------
def readout_transition(state: ReadoutState, inputs: ReadoutInputs, params: TrackerParams
                       ) -> tuple[ReadoutState, tuple[CameraResult, CameraResult], Fired]:
    """The readout rules after the phase (pure): the caught shuttle withheld (when
    ``inputs.caught``), then each camera's hold anchor and the tracks seen in the air, then the
    limit on reports alone. Returns (new state, each camera's result, the rules that fired)."""
    results = list(inputs.results)
    fired: list[tuple[str, int | None]] = []
    if inputs.caught:
        state, results = _withhold_caught(state, results, inputs, params)
        fired.append(("caught", None))
    reports = inputs.reports
    if reports is None:
        reports = (results[0].detection, results[1].detection)
    for cam in inputs.cameras:
        cam_state, kept = _note_anchor(state.cams[cam], state.cams[1 - cam], reports[cam], inputs.has_point, params)
        det = reports[cam]
        if (det is not None and not det.predicted and inputs.height is not None
                and inputs.height > params.stereo.landed_max_height):
            cam_state = _note_flown(cam_state, det.tracklet, inputs.t, params)
        state = state.with_camera(cam, cam_state)
        if kept:
            fired.append(("landed_other_anchor", cam))
    present = [r.detection is not None for r in results]
    for cam in inputs.cameras:
        other_present = present[1 - cam] and not inputs.before_serve
        cam_state, limited = _limit_alone(state.cams[cam], state.cams[1 - cam], results[cam], present[cam],
                                          other_present, inputs.has_point, params)
        state = state.with_camera(cam, cam_state)
        if limited is not results[cam]:
            fired.append(("alone_limit", cam))
            results[cam] = limited
    return state, (results[0], results[1]), tuple(fired)


def _withhold_caught(state: ReadoutState, results: list[CameraResult], inputs: ReadoutInputs,
                     params: TrackerParams) -> tuple[ReadoutState, list[CameraResult]]:
    """Each camera's report of the caught shuttle withheld (``reject_report``): the report at
    the catch, then each report within ``stereo.caught_step`` px a frame of the last one
    withheld (the hand carrying it)."""
    caught_new = inputs.phase.caught_new
    if caught_new:
        state = ReadoutState(tuple(dataclasses.replace(c, caught_xy=None) for c in state.cams))
    for cam in inputs.cameras:
        det = results[cam].detection
        if det is None or det.predicted:
            continue
        last = state.cams[cam].caught_xy
        step = params.stereo.caught_step * results[cam].image_size[0] / 1280.0
        if (last is None and not caught_new) or (
                last is not None and math.hypot(det.x - last[0], det.y - last[1]) > step):
            continue
        state = state.with_camera(cam, dataclasses.replace(state.cams[cam], caught_xy=(det.x, det.y)))
        results[cam] = reject_report(results[cam])
    return state, results


def _note_anchor(state: CameraReadoutState, other: CameraReadoutState, det: Candidate | None,
                 has_point: bool, params: TrackerParams) -> tuple[CameraReadoutState, bool]:
    """Whether this camera's report, if it stops next, may start a landed hold: it had a 3D
    point — or (``stereo.landed_other_anchor``) the other camera is holding its landed shuttle
    now, which leaves the frame without a pair and so without a 3D point, and this camera's
    report was anchored before. Without the second case the camera whose report stops last is
    never held (rally_11-46-22 right 1623–1670, rally_11-47-21 right 987–1020). Returns (the
    state, whether the second case kept the anchor)."""
    if state.holding:
        return state, False
    kept = (det is not None and not has_point and params.stereo.landed_other_anchor
            and other.holding and state.anchored)
    anchored = det is not None and (has_point or kept)
    if anchored != state.anchored:
        state = dataclasses.replace(state, anchored=anchored)
    return state, kept


def _note_flown(state: CameraReadoutState, tracklet: int, t: float, params: TrackerParams) -> CameraReadoutState:
    """This camera reported ``tracklet`` with a 3D point above the floor at ``t``; tracks not
    seen so for ``stereo.flown_memory`` s are forgotten."""
    memory = params.stereo.flown_memory
    flown = tuple((k, when) for k, when in state.flown if k != tracklet and t - when <= memory)
    return dataclasses.replace(state, flown=flown + ((tracklet, t),))


def _limit_alone(state: CameraReadoutState, other: CameraReadoutState, result: CameraResult,
                 present: bool, other_present: bool, has_point: bool, params: TrackerParams
                 ) -> tuple[CameraReadoutState, CameraResult]:
    """Withhold a camera's report the other camera has not confirmed (``stereo.alone_limit``).

    On the NYCU rallies most detections reported by one camera while the other reports nothing
    and no 3D point exists are not the shuttle (the labels say none is in view): a shuttle held
    or lying still, a racket, a white shoe, which one camera's association followed on its own.
    A real shuttle seen by one camera only is mostly a flight the other camera lost (out of its
    view, behind a player), and then this camera's readout runs on from frames that had a 3D
    point. So a one-camera report is kept when this camera's readout has continued, with no
    break longer than ``alone_anchor_gap`` frames, since a frame with a 3D point; otherwise at
    most ``alone_max_frames`` such reports in a row are kept. Only the readout changes
    (``reject_report``). ``present`` / ``other_present``: whether this camera and the other
    report now (the other's readout: its last one when it brought no new image). Before the
    serve (``stereo.serve_start``) the caller passes ``other_present`` False: two reports that
    make no pair then confirm nothing (an LED board's dot in one camera, clutter in the other).
    """
    sp = params.stereo
    if not present or state.holding:
        # No report; or a landed shuttle held on, reported, but no flight goes on: what this
        # camera reports after it does not continue the stereo readout, and the other camera's
        # report beside it is a report alone.
        unreported = state.unreported_run + 1
        return dataclasses.replace(state, alone_run=0, unreported_run=unreported,
                                   continues_stereo=state.continues_stereo and unreported <= sp.alone_anchor_gap
                                   ), result
    if has_point:
        return dataclasses.replace(state, unreported_run=0, alone_run=0, continues_stereo=True), result
    if other_present and not other.holding:
        return dataclasses.replace(state, unreported_run=0, alone_run=0), result
    alone = state.alone_run + 1
    if sp.alone_limit and not state.continues_stereo and alone > sp.alone_max_frames:
        result = reject_report(result)
    return dataclasses.replace(state, unreported_run=0, alone_run=alone), result

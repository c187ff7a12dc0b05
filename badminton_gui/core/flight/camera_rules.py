"""The phase's rules for each camera's readout: a landed shuttle held, a caught one withheld, a
report one camera makes alone limited.

Why this file exists: what a camera reports depends on the shuttle's phase
(:mod:`~badminton_gui.core.flight.phase`) and on that camera's own recent readout. Each rule is
switched by its parameter and keeps its per-camera memory in one named
:class:`CameraReadoutState`, instead of positional lists spread over the tracker:

- ``stereo.landed_frames`` (LANDED): the association stops reporting a still track soon after it
  flew; a landed shuttle lies there longer and the labels mark it visible: keep reporting it.
- ``stereo.caught_frames`` (CAUGHT): the shuttle in the hand that caught it is out of play:
  withhold it in both cameras while the hand carries it.
- ``stereo.alone_limit``: a report the other camera does not confirm is mostly not the shuttle,
  unless it continues a readout that had a 3D point (a flight the other camera lost).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from ..params import TrackerParams
from ..rig import StereoRig
from ..step import Step
from ..stereo.look import ImagePaths
from ..stereo.vouch import VOUCH_WIDE_IMAGE_SPEED
from ..types import REJECT_STEREO, CameraResult, Candidate
from .phase import PhaseState

# px at 1280 px width: how far a held landed shuttle's candidate may move from one frame to the
# next (it slides or rolls a little; a hand picking it up moves more).
LANDED_STEP = 4.0
# s: how long ago the held track may last have been reported with a 3D point above the floor
# (``flown_recently``): a landed shuttle slides and lies still for up to ~1.5 s before the hold
# starts; a shoe walked along the floor after the rally was never seen in the air.
FLOWN_MEMORY = 5.0
# px at 1280 px width: how far a caught shuttle's report may move from one frame to the next and
# still be the shuttle in the hand that caught it (a hand carrying it walks, it does not fly).
CAUGHT_STEP = 12.0


@dataclass(slots=True)
class CameraReadoutState:
    """One camera's memory for the readout rules.

    Landed hold: ``hold_tracklet`` the tracklet of the last report (-1: none), ``hold_frames``
    the frames held since, ``hold_x``/``hold_y`` its last position, ``anchored`` whether that
    report may start a hold (it had a 3D point), ``holding`` whether a hold reports this step;
    ``flown`` tracklet → time of its last report with a 3D point above the floor. Reports alone:
    ``alone_run`` in a row, ``unreported_run`` frames without a report in a row,
    ``continues_stereo`` the readout continues one that had a 3D point. Caught:
    ``caught_xy`` the last withheld position of the caught shuttle."""

    hold_tracklet: int = -1
    hold_frames: int = 0
    hold_x: float = 0.0
    hold_y: float = 0.0
    anchored: bool = False
    holding: bool = False
    flown: dict[int, float] = field(default_factory=dict)
    alone_run: int = 0
    unreported_run: int = 0
    continues_stereo: bool = False
    caught_xy: tuple[float, float] | None = None


def reject_report(result: CameraResult) -> CameraResult:
    """``result`` with its detection withheld: no detection, the candidate marked
    ``REJECT_STEREO`` (the association, the flight and the look-ahead's tracklets untouched)."""
    det = result.detection
    return dataclasses.replace(
        result, detection=None,
        candidates=tuple(dataclasses.replace(c, rejected_by=REJECT_STEREO) if c is det else c
                         for c in result.candidates))


class CameraRules:
    """The per-camera readout rules of the shuttle's phase, and their state."""

    def __init__(self, rig: StereoRig, params: TrackerParams) -> None:
        self.rig = rig
        self.params = params
        self.cams = (CameraReadoutState(), CameraReadoutState())

    def holding(self, cam: int) -> bool:
        """Camera ``cam`` reports a held landed shuttle this step."""
        return self.cams[cam].holding

    # ---- landed ----------------------------------------------------------------------------
    def hold_both(self, left: tuple[CameraResult, Candidate | None],
                  right: tuple[CameraResult, Candidate | None], point_left: np.ndarray | None,
                  epi: float | None, t: float, phase: PhaseState):
        """Both cameras through ``hold_landed``: ((result, report) left, right, 3D point, its
        epipolar error). When a hold gives a camera's report back to the landed shuttle (the shoe
        walking past), the pair made with the shoe, below the floor, is no 3D point any more."""
        self.cams[0].holding = self.cams[1].holding = False
        sp = self.params.stereo
        if sp.landed_frames <= 0 or not self.rig.has_court_pose:
            return left, right, point_left, epi
        # A stereo pair counts as the shuttle in the air only above the floor: a shoe paired
        # with the lying shuttle (rally_11-47-21 986: 1.7 m below the court) is not one.
        paired = (point_left is not None
                  and float(self.rig.to_output(point_left)[0][2]) > sp.landed_max_height)
        held_left = self.hold_landed(0, left[0], left[1], t, phase, paired)
        held_right = self.hold_landed(1, right[0], right[1], t, phase, paired)
        if point_left is not None and (held_left[1] is not left[1] or held_right[1] is not right[1]):
            point_left, epi = None, None
        return held_left, held_right, point_left, epi

    def hold_landed(self, cam: int, result: CameraResult, det: Candidate | None, t: float,
                    phase: PhaseState, paired: bool = False) -> tuple[CameraResult, Candidate | None]:
        """Keep reporting a shuttle that landed and lies still (``stereo.landed_frames``).

        The association reports a still track only for ``association.pause_frames`` after it
        flew; a shuttle that has just landed lies there longer, and the NYCU labels mark it
        visible for another ≈ 0.3–0.8 s. When this camera's report stops, its last report had a
        3D point, the 3D flight's last point (within ``LANDED_RECENT`` s) lay near the floor, the
        track it followed was reported with a 3D point above the floor (``flown_recently``: on
        the NYCU rallies a player's shoe paired across the cameras after the rally was held
        otherwise) and still has a candidate where the last report was (within ``LANDED_STEP``
        px a frame), that candidate is reported, for at most ``landed_frames`` frames. A shuttle
        held before the serve has no low 3D point before it; one picked up moves off.
        """
        sp = self.params.stereo
        state = self.cams[cam]
        if (det is not None and not paired and not det.predicted and 0 <= state.hold_tracklet != det.tracklet
                and not self.flown_recently(cam, det.tracklet, t)):
            # The readout leaves the landed shuttle for a track never seen in the air, with no
            # stereo partner above the floor: after a rally, a player's white shoe walking past
            # (rally_11-47-21 left 986, rally_11-48-00 right 630). The shuttle, still lying
            # there, stays the report while the hold's conditions last; else the new track is.
            held_result, held = self.hold_landed(cam, result, None, t, phase, paired)
            if held is not None:
                return held_result, held
        if det is not None:
            if det.predicted or det.tracklet < 0:
                state.hold_tracklet = -1
            else:
                state.hold_tracklet, state.hold_frames = det.tracklet, 0
                state.hold_x, state.hold_y = det.x, det.y
            return result, det
        if state.hold_tracklet < 0:
            return result, None
        if state.hold_frames >= sp.landed_frames or (
                state.hold_frames == 0 and not (state.anchored and phase.landed(t, self.params)
                                                and self.flown_recently(cam, state.hold_tracklet, t))):
            state.hold_tracklet = -1
            return result, None
        step = LANDED_STEP * result.image_size[0] / 1280.0
        for c in result.candidates:
            # Its own track's candidate, or a blob no track took (tracklet -1) at the same spot:
            # a lying shuttle dims and its look changes, and a classifier may then refuse it
            # before association (rally_11-48-00 right 641 with the coarse patch classifier).
            if ((c.tracklet == state.hold_tracklet or c.tracklet < 0) and not c.predicted
                    and math.hypot(c.x - state.hold_x, c.y - state.hold_y) <= step):
                state.hold_frames += 1
                state.hold_x, state.hold_y = c.x, c.y
                state.holding = True
                held = dataclasses.replace(c, rejected_by=None)
                return dataclasses.replace(result, candidates=tuple(held if k is c else k
                                                                    for k in result.candidates)), held
        state.hold_tracklet = -1
        return result, None

    def hold_one(self, step: Step, cam: int, phase: PhaseState) -> None:
        """``hold_landed`` for a step with camera ``cam``'s image only (no pair to drop)."""
        self.cams[cam].holding = False
        if self.params.stereo.landed_frames > 0 and self.rig.has_court_pose:
            step.results[cam], step.dets[cam] = self.hold_landed(cam, step.results[cam], step.dets[cam],
                                                                 step.t, phase)
            if self.cams[cam].holding:
                step.fired("landed_hold", cam)

    def lying_landed(self, cam: int, det: Candidate | None, t: float, width: int,
                     phase: PhaseState, paths: ImagePaths) -> bool:
        """Whether this camera's report is a landed shuttle lying still, whose pixels the next
        frame's mask should keep: held (``hold_landed``), or still reported by its own track
        when that track carried the flight down (``flown_recently``), the flight's last point
        lay near the floor and the track barely moves (``VOUCH_WIDE_IMAGE_SPEED``). Without the
        second case a lying shuttle whose track the association kept reporting — its classifier
        score high — was never held, so never protected, and the quarter-scale model lost it
        when it dimmed (rally_11-48-00 right 636–664 with the coarse preset's patch classifier)."""
        if det is None or det.predicted:
            return False
        if self.cams[cam].holding:
            return True
        # As for the hold itself (``hold_both``): off with it, and only where heights mean the floor.
        if self.params.stereo.landed_frames <= 0 or not self.rig.has_court_pose:
            return False
        if det.tracklet < 0 or not phase.landed(t, self.params) or not self.flown_recently(cam, det.tracklet, t):
            return False
        # The track's image velocity as noted for this very report (a later stage may have
        # replaced the report noted then).
        last = paths.last(cam)
        velocity = last[3] if last is not None and (last[1], last[2]) == (det.x, det.y) else None
        return (velocity is not None
                and math.hypot(*velocity) <= VOUCH_WIDE_IMAGE_SPEED * width / 1280.0)

    def note_anchor(self, cam: int, det: Candidate | None, has_point: bool) -> None:
        """Whether this camera's report, if it stops next, may start a landed hold: it had a 3D
        point — or the other camera is holding its landed shuttle now, which leaves the frame
        without a pair and so without a 3D point, and this camera's report was anchored before.
        Without the second case the camera whose report stops last is never held (rally_11-46-22
        right 1623–1670, rally_11-47-21 right 987–1020)."""
        state = self.cams[cam]
        if state.holding:
            return
        state.anchored = det is not None and (has_point or (self.cams[1 - cam].holding and state.anchored))

    def note_flown(self, cam: int, tracklet: int, t: float) -> None:
        """This camera reported ``tracklet`` with a 3D point above the floor at ``t``."""
        flown = self.cams[cam].flown
        flown[tracklet] = t
        for k in [k for k, when in flown.items() if t - when > FLOWN_MEMORY]:
            del flown[k]

    def flown_recently(self, cam: int, tracklet: int, t: float) -> bool:
        """This camera reported ``tracklet`` with a 3D point above the floor within
        ``FLOWN_MEMORY`` s: the track carried a flight down, it is not one that only ever moved
        along the floor (a shoe paired with the other camera's shoe after the rally)."""
        when = self.cams[cam].flown.get(tracklet)
        return when is not None and t - when <= FLOWN_MEMORY

    # ---- caught ----------------------------------------------------------------------------
    def withhold_caught(self, results: list[CameraResult], phase: PhaseState,
                        cameras: tuple[int, ...] = (0, 1)) -> list[CameraResult]:
        """Each camera's report of the caught shuttle withheld (``reject_report``): the report at
        the catch, then each report within ``CAUGHT_STEP`` px a frame of the last one withheld
        (the hand carrying it). ``cameras``: those with a new image this step."""
        results = list(results)
        if phase.caught_new:
            for state in self.cams:
                state.caught_xy = None
        for cam in cameras:
            det = results[cam].detection
            if det is None or det.predicted:
                continue
            last = self.cams[cam].caught_xy
            step = CAUGHT_STEP * results[cam].image_size[0] / 1280.0
            if (last is None and not phase.caught_new) or (
                    last is not None and math.hypot(det.x - last[0], det.y - last[1]) > step):
                continue
            self.cams[cam].caught_xy = (det.x, det.y)
            results[cam] = reject_report(results[cam])
        return results

    # ---- after the phase: what the next steps' rules remember -------------------------------
    def note_step(self, step: Step, has_point: bool, height: float | None) -> None:
        """This pair step's reports (``step.dets``) with or without a 3D point (``height``: its
        court height): the landed hold's anchors and the tracks seen in the air, then the limit
        on reports alone."""
        for cam, det in enumerate(step.dets):
            self.note_anchor(cam, det, has_point)
            if (det is not None and not det.predicted and height is not None
                    and height > self.params.stereo.landed_max_height):
                self.note_flown(cam, det.tracklet, step.t)
        self.limit_alone_step(step, has_point, (0, 1))

    def limit_alone_step(self, step: Step, has_point: bool, cameras: tuple[int, ...]) -> None:
        """``limit_alone`` on the step's results, naming the cameras it withheld."""
        limited = self.limit_alone(step.results, has_point, cameras)
        for cam in cameras:
            if limited[cam] is not step.results[cam]:
                step.fired("alone_limit", cam)
        step.results = limited

    # ---- reports alone ---------------------------------------------------------------------
    def limit_alone(self, results: list[CameraResult], has_point: bool,
                    cameras: tuple[int, ...] = (0, 1)) -> list[CameraResult]:
        """Withhold a camera's report the other camera has not confirmed (``stereo.alone_limit``).

        On the NYCU rallies most detections reported by one camera while the other reports
        nothing and no 3D point exists are not the shuttle (the labels say none is in view): a
        shuttle held or lying still, a racket, a white shoe, which one camera's association
        followed on its own. A real shuttle seen by one camera only is mostly a flight the other
        camera lost (out of its view, behind a player), and then this camera's readout runs on
        from frames that had a 3D point. So a one-camera report is kept when this camera's
        readout has continued, with no break longer than ``alone_anchor_gap`` frames, since a
        frame with a 3D point; otherwise at most ``alone_max_frames`` such reports in a row are
        kept. Only the readout changes (``reject_report``). ``cameras``: those with a new image
        this step (the other's readout is its last one).
        """
        results = list(results)
        present = [r.detection is not None for r in results]
        for cam in cameras:
            results[cam] = self._limit_alone_camera(cam, results[cam], present, has_point)
        return results

    def _limit_alone_camera(self, cam: int, result: CameraResult, present: list[bool],
                            has_point: bool) -> CameraResult:
        """``limit_alone`` for one camera; ``present``: whether each camera reports now."""
        sp = self.params.stereo
        state = self.cams[cam]
        if not present[cam] or state.holding:
            # No report; or a landed shuttle held on (``hold_landed``), reported, but no flight
            # goes on: what this camera reports after it does not continue the stereo readout,
            # and the other camera's report beside it is a report alone.
            state.alone_run = 0
            state.unreported_run += 1
            if state.unreported_run > sp.alone_anchor_gap:
                state.continues_stereo = False
            return result
        state.unreported_run = 0
        if has_point:
            state.alone_run, state.continues_stereo = 0, True
        elif present[1 - cam] and not self.cams[1 - cam].holding:
            state.alone_run = 0
        else:
            state.alone_run += 1
            if sp.alone_limit and not state.continues_stereo and state.alone_run > sp.alone_max_frames:
                result = reject_report(result)
        return result

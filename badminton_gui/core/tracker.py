"""The pure stereo tracker: a pair of frames in, a frozen :class:`TrackResult` out.

Why this file exists: it is the one object that the GUI worker, the CLI and the tests all drive.
A pair step runs these stages, in this order (``StereoTracker.process``):

1. segmentation and candidates, per camera (:class:`CameraDetector`, the two cameras side by
   side on two threads);
2. stereo vouch and pairing (``stereo/vouch.py``, ``stereo/pairing.py``): a young track the other
   camera confirms passes; the stereo-consistent pair is chosen, else each camera's own choice;
   each detector commits its report;
3. the flight's look (``flight/look.py``, ``stereo/look.py``): a camera that lost the shuttle
   looks where the flight projects, or where its own image path continues on the other
   detection's epipolar line; two reports just off the gate pair when the flight or the last
   pair vouches for them; a report is dropped when the shuttle has left that camera's view;
4. the landed hold (``flight/camera_rules.py``) and each camera's readout at the cork;
5. the 3D measurement (``stereo/cork.py``): the pair's point moved to the cork, its noise shape;
6. the 3D flight filter (:class:`Trajectory`), or one camera's line of sight when there is no
   pair (``flight/sight.py``);
7. the shuttle's phase (``flight/phase.py``) and its readout rules: a caught shuttle withheld,
   reports one camera makes alone limited.

The 3D point reported is the trajectory filter's estimate whenever the measured point extended
a flight (a single triangulation is several times less sure in depth than across); a point the
followed flight refuses is not reported as the shuttle, the raw triangulation stays in
``measured_point``.

Cameras without a common trigger (``process_frame``): a step may bring one camera's image only
(``StereoFrame.fresh_left`` / ``fresh_right``); only that camera runs, and no 3D point is
measured. In a pair whose images were taken apart, the right detection is moved along its track
to the left image's time before the two are paired (``stereo.align_pairs``).

``StereoTracker.trace = True`` makes each result name the rules that fired on its step
(``TrackResult.trace``).

Usage::

    rig = StereoRig.load("calibration/rig.yaml")
    tracker = StereoTracker(rig)
    result = tracker.process(left_bgr, right_bgr, timestamp)
    result = tracker.process_frame(source.read())   # a FrameSource's steps
"""

from __future__ import annotations

import dataclasses
import math
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import cv2
import numpy as np
import numpy.ma  # noqa: F401  np.median imports it on its first call: 17 ms in the middle of a rally

from .detector import CameraDetector
from .flight.camera_rules import CameraRules
from .flight.guide import StepGuide
from .flight.look import FlightLook
from .flight.phase import PhaseObservation, PhaseState, transition, withheld
from .flight.sight import PAIRED_SIGHT_NOISE, SightOfCamera
from .params import TrackerParams
from .rig import StereoRig
from .stereo.cork import CorkCorrection
from .stereo.epipolar import EpipolarGate
from .stereo.look import ImagePaths, stereo_look
from .stereo.pairing import StereoPairing
from .stereo.vouch import StereoVouch
from .trajectory import Trajectory
from .types import CameraResult, Candidate, FlightInfo, StereoFrame, TrackResult

# What the readout and the robot are told while the shuttle is caught (``FlightInfo.withheld_reason``).
CAUGHT_REASON = "caught: out of play"
SIDES = ("left", "right")


@dataclass(slots=True)
class _Step:
    """One step's work in progress, handed from stage to stage: each camera's result and report,
    the pair's 3D point (left-camera frame) and epipolar error, and the rules that fired."""

    t: float
    t_right: float
    frames: tuple[np.ndarray, np.ndarray]
    guide: StepGuide
    results: list[CameraResult] = field(default_factory=list)
    dets: list[Candidate | None] = field(default_factory=lambda: [None, None])
    point: np.ndarray | None = None
    epi: float | None = None
    trace: list[str] | None = None

    def fired(self, rule: str, cam: int | None = None) -> None:
        if self.trace is not None:
            self.trace.append(rule if cam is None else f"{rule}:{SIDES[cam]}")

    def add(self, cam: int, found: Candidate) -> None:
        """``found`` becomes camera ``cam``'s report and joins its candidates."""
        self.dets[cam] = found
        self.results[cam] = dataclasses.replace(self.results[cam],
                                                candidates=self.results[cam].candidates + (found,))


class StereoTracker:
    """Tracks the shuttle with two calibrated cameras."""

    def __init__(self, rig: StereoRig, params: TrackerParams | None = None,
                 parallel: bool = True) -> None:
        self.rig = rig
        self._params = params or TrackerParams()
        self.left = CameraDetector(self.params)
        self.right = CameraDetector(self.params)
        # ``window.stagger``: the right camera's scheduled whole frames half a period after the left's.
        self.right.set_window_phase(0.5)
        # OpenCV releases the GIL: the two cameras run side by side on two cores.
        self._pool = ThreadPoolExecutor(max_workers=2, thread_name_prefix="camera") if parallel else None
        self._trajectory = Trajectory(self.params.trajectory, rig.has_court_pose)
        self._checked_size = False
        # Each result names the rules that fired on its step (``TrackResult.trace``).
        self.trace = False
        self._new_state()

    def _new_state(self) -> None:
        """The stages and their memory, as at the start (``__init__`` and ``reset``)."""
        detectors = (self.left, self.right)
        self.gate = EpipolarGate(self.params)
        self.pairing = StereoPairing(self.rig, self.params, self.gate, detectors)
        self.vouch = StereoVouch(self.rig, self.params, self.gate, detectors)
        self.paths = ImagePaths()
        self.look = FlightLook(self.rig, self.params, detectors)
        self.cork = CorkCorrection(self.rig, self.params, detectors, self.pairing.right_xy)
        self.sight = SightOfCamera(self.rig, self.params, self._trajectory)
        self.rules = CameraRules(self.rig, self.params)
        self.phase = PhaseState()
        # Each camera's last image (the guided look's motion check) and last readout (what a
        # step that brings no new image from that camera reports for it).
        self._previous: list[np.ndarray | None] = [None, None]
        self._last_results: list[CameraResult | None] = [None, None]

    # ---- configuration ---------------------------------------------------------------------
    @property
    def params(self) -> TrackerParams:
        """The parameters the stereo stages read (``set_params`` also hands them to the cameras'
        detectors and the flight filter)."""
        return self._params

    @params.setter
    def params(self, params: TrackerParams) -> None:
        self._params = params
        for stage in (self.gate, self.pairing, self.vouch, self.look, self.cork, self.sight, self.rules):
            stage.params = params

    def set_params(self, params: TrackerParams) -> None:
        """Apply a new parameter snapshot (the GUI sends whole snapshots)."""
        self.params = params
        self.left.set_params(params)
        self.right.set_params(params)
        self._trajectory.set_params(params.trajectory)

    def reset(self) -> None:
        self.left.reset()
        self.right.reset()
        self._trajectory.reset()
        self._new_state()

    def epipolar_tolerance(self) -> float:
        """The epipolar gate in use: the configured one, widened to the rig's measured error."""
        return self.gate.tolerance()

    @property
    def rig_epipolar_px(self) -> float | None:
        """How far the rig really misses: the median epipolar error (px) of the sure pairs
        learnt so far, or None before enough of them. A chessboard-calibrated rig stays at a few
        px; the NYCU rig imported from its ``.cfg`` files misses by ≈ 30 px."""
        return self.gate.rig_error_px()

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None

    @property
    def trajectory(self):
        """The trajectory model (current flight, predicted path), or None."""
        return self._trajectory

    # ---- the pipeline ----------------------------------------------------------------------
    def process_frame(self, frame: StereoFrame, keep_masks: bool = True) -> TrackResult:
        """One step of a source: a pair of new images (``process``), or a new image from one
        camera only (cameras without a common trigger, ``VideoPair``'s timestamps: ``_process_one``)."""
        if frame.fresh_left and frame.fresh_right:
            return self.process(frame.left, frame.right, frame.t_left, frame.index,
                                frame.index_right, keep_masks, t_right=frame.t_right)
        if frame.fresh_right:
            return self._process_one(1, frame.right, frame.t_right, frame.index, frame.index_right,
                                     keep_masks)
        return self._process_one(0, frame.left, frame.t_left, frame.index, frame.index_right, keep_masks)

    def process(self, left_bgr: np.ndarray, right_bgr: np.ndarray, timestamp: float,
                index: int = -1, index_right: int = -1, keep_masks: bool = True,
                t_right: float | None = None) -> TrackResult:
        """Track one pair of images; ``timestamp`` is the pair's (the left image's) time, and
        ``t_right`` the right image's when it differs (the right detector follows its own clock;
        None: the same)."""
        start = time.perf_counter()
        t_r = timestamp if t_right is None else t_right
        self._check_sizes(left_bgr, right_bgr)
        self.pairing.set_times(timestamp, t_r)
        step = _Step(timestamp, t_r, (left_bgr, right_bgr), StepGuide(self._trajectory, timestamp),
                     trace=[] if self.trace else None)
        self._segment(step, keep_masks)
        self._pair(step)
        self._guided_look(step)
        self._stereo_look(step)
        self._vouched_by_flight(step)
        self._note_paths(step)
        self._exits(step)
        self._hold_and_readout(step)
        measured, noise_shape, head_var = self._measure(step)
        flight, sight_cam = self._follow_flight(step, measured, noise_shape, head_var)
        accepted = measured is not None and not self._trajectory.point_rejected
        point, flight = self._readout_point(step, measured, flight, sight_cam)
        point, flight = self._phase_step(step, measured, accepted, point, flight)
        self._last_results = list(step.results)
        return self._result(step, index, index_right, point, flight, measured, start)

    def _check_sizes(self, left_bgr: np.ndarray, right_bgr: np.ndarray) -> None:
        if not self._checked_size:
            h, w = left_bgr.shape[:2]
            self.rig.check_image_size(w, h, "the left frames")
            hr, wr = right_bgr.shape[:2]
            self.rig.check_image_size(wr, hr, "the right frames")
            self._checked_size = True

    # ---- stage 1: segmentation and candidates, per camera ----------------------------------
    def _segment(self, step: _Step, keep_masks: bool) -> None:
        """Each camera's candidates. A windowed frame is mostly Python holding the GIL: when both
        cameras process this frame in a window they run faster in turn on this thread than side
        by side; a pair with a whole frame, mostly image work that releases the GIL, runs side by
        side. The windows are chosen first, so a camera's periodic whole frame is never run in
        turn with the other's."""
        (left_bgr, right_bgr), t, t_r = step.frames, step.t, step.t_right
        self.left.keep_whole, self.right.keep_whole = self.rules.holding(0), self.rules.holding(1)
        in_turn = self.left.plan_window(left_bgr, t) & self.right.plan_window(right_bgr, t_r)
        if self._pool is not None and not in_turn:
            # Only the image half runs side by side (CameraDetector.segment); the measuring
            # half, many small calls each of which hands the GIL over, runs on this thread,
            # the left camera's while the right camera's image half may still be running.
            fut = self._pool.submit(self.right.segment, right_bgr, t_r)
            res_left = self.left.candidates_from(left_bgr, t, self.left.segment(left_bgr, t), keep_masks)
            res_right = self.right.candidates_from(right_bgr, t_r, fut.result(), keep_masks)
        else:
            res_left = self.left.find_candidates(left_bgr, t, keep_masks)
            res_right = self.right.find_candidates(right_bgr, t_r, keep_masks)
        step.results = [res_left, res_right]

    # ---- stage 2: stereo vouch, pairing, each camera's commit ------------------------------
    def _pair(self, step: _Step) -> None:
        res = step.results
        if self.params.stereo.stereo_vouch:
            vouched = self.vouch.apply(res[0], res[1])
            for cam in (0, 1):
                if vouched[cam] is not res[cam]:
                    step.fired("stereo_vouch", cam)
            res[0], res[1] = vouched
        self.pairing.learn(res[0], res[1])
        pair = self.pairing.choose_pair(res[0], res[1])
        step.dets, step.point, step.epi = [pair.left, pair.right], pair.point, pair.epipolar_error
        if step.point is None:
            # No stereo pair: each camera keeps its own best guess for the 2D readout.
            step.dets = [self.left.choose(res[0].candidates), self.right.choose(res[1].candidates)]
        self.left.commit(step.dets[0], step.t, res[0].candidates)
        self.right.commit(step.dets[1], step.t_right, res[1].candidates)

    # ---- stage 3: the flight's look, and the shuttle leaving a camera's view ---------------
    def _guided_look(self, step: _Step) -> None:
        """Look where the flight projects for a camera with no detection, or a weak lone one
        (the flight's RK4 prediction is skipped when both cameras have a sure one)."""
        sp = self.params.stereo
        unseen = [det is None or det.predicted for det in step.dets]
        weak = [self.look.weak_lone(det, step.point is not None) for det in step.dets]
        if not (sp.guided_search and (sp.guided_override or any(unseen) or any(weak))):
            return
        guide = step.guide.get()
        if guide is None:
            return
        found = [self.look.guided(cam, step.frames[cam], self._previous[cam], step.dets[cam], guide, weak[cam])
                 for cam in (0, 1)]
        if found[0] is not None or found[1] is not None:
            for cam in (0, 1):
                if found[cam] is not None:
                    step.add(cam, found[cam])
                    step.fired("guided_search", cam)
            step.point, step.epi = self.pairing.pair_point(step.dets[0], step.dets[1])
        if sp.guided_coast:
            for cam in (0, 1):
                before = step.dets[cam]
                step.results[cam], step.dets[cam] = self.look.coast(cam, step.frames[cam], step.results[cam],
                                                                    before, guide)
                if step.dets[cam] is not before:
                    step.fired("guided_coast", cam)

    def _stereo_look(self, step: _Step) -> None:
        """Neither the pair nor the flight found the shuttle in one camera: the other's sure
        detection puts it on an epipolar line, this camera's own image path near a point."""
        sp = self.params.stereo
        if not sp.stereo_look or step.point is not None:
            return
        for cam in (0, 1):
            own, other = step.dets[cam], step.dets[1 - cam]
            if ((own is None or own.predicted) and other is not None
                    and not other.predicted and other.score >= sp.stereo_look_min_score):
                found = stereo_look(self.rig, self.params, self.gate, self.paths, cam, step.frames[cam],
                                    self._previous[cam], other, step.t)
                if found is not None:
                    step.add(cam, found)
                    step.fired("stereo_look", cam)
                    step.point, step.epi = self.pairing.pair_point(step.dets[0], step.dets[1])
                    return

    def _vouched_by_flight(self, step: _Step) -> None:
        """Two reports off the epipolar gate pair when the flight puts the shuttle where they
        triangulate, or when they continue the last step's pair."""
        left, right = step.dets
        if step.point is not None or left is None or right is None:
            return
        step.point, step.epi = self.pairing.flight_vouched_pair(left, right, step.guide.get())
        if step.point is not None:
            step.fired("flight_vouch")
            return
        step.point, step.epi = self.pairing.continued_pair(left, right, step.t)
        if step.point is not None:
            step.fired("pair_continuity")

    def _note_paths(self, step: _Step, cameras: tuple[int, ...] = (0, 1)) -> None:
        detectors = (self.left, self.right)
        for cam in cameras:
            det = step.dets[cam]
            if det is not None and not det.predicted:
                self.paths.note(cam, step.t, det.x, det.y, detectors[cam].tracklet_velocity(det))

    def _exits(self, step: _Step, cameras: tuple[int, ...] = (0, 1)) -> None:
        """No report where the shuttle has left the camera's view: a detection at the border
        (its clipped skirt: a pair made with it is biased too), or a weak lone one while the
        flight is out of this camera's view."""
        sp = self.params.stereo
        if not (sp.exit_margin > 0 or (sp.out_of_view_weak and step.point is None)):
            return
        for cam in cameras:
            det, frame = step.dets[cam], step.frames[cam]
            border = self.look.near_border(det, frame) and (step.point is None or sp.exit_by_path)
            weak_now = sp.out_of_view_weak and self.look.weak_lone(det, step.point is not None)
            if not (border or weak_now):
                continue
            guide = step.guide.get()
            if ((border and sp.exit_by_path and self.paths.leaves(cam, frame, step.t))
                    or (guide is not None
                        and ((border and self.look.gone_out(cam, det, frame, guide[0]))
                             or (weak_now and self.look.out_of_view(cam, frame, guide[0]))))):
                step.dets[cam] = None
                step.point, step.epi = None, None
                step.fired("exit", cam)

    # ---- stage 4: the landed hold, each camera's readout at the cork -----------------------
    def _hold_and_readout(self, step: _Step) -> None:
        res, dets = step.results, step.dets
        (res[0], dets[0]), (res[1], dets[1]), step.point, step.epi = self.rules.hold_both(
            (res[0], dets[0]), (res[1], dets[1]), step.point, step.epi, step.t, self.phase)
        for cam in (0, 1):
            if self.rules.holding(cam):
                step.fired("landed_hold", cam)
        self._protect_and_show(step, (0, 1))

    def _protect_and_show(self, step: _Step, cameras: tuple[int, ...]) -> None:
        """A landed shuttle lying still stays in its camera's mask; the 2D readout is the cork,
        not the trailing bright centroid (the 3D point is still triangulated from the measured
        centroids: each camera's lead is estimated on its own and their disagreement would be a
        disparity error; the same bias is removed in 3D, ``stereo/cork.py``)."""
        detectors = (self.left, self.right)
        for cam in cameras:
            det, width = step.dets[cam], step.frames[cam].shape[1]
            lying = self.rules.lying_landed(cam, det, step.t, width, self.phase, self.paths)
            detectors[cam].protect_report(det if lying else None, width)
            # The sources hand out a new array per frame: keeping the reference costs no copy.
            self._previous[cam] = step.frames[cam]
        for cam in cameras:
            result, shown = detectors[cam].lead_to_head(step.results[cam], step.dets[cam])
            step.results[cam] = CameraDetector.finalise(result, shown)

    # ---- stage 5: the 3D measurement -------------------------------------------------------
    def _measure(self, step: _Step):
        """(measured point in the output frame, its noise shape, the cork correction's variance)
        of the step's pair, or (None, None, 0)."""
        head_var = 0.0
        blob = step.point
        left, right = step.dets
        if blob is not None and self.params.stereo.head_offset > 0:
            step.point = self.cork.to_head(left, right, blob)
            head_var = self.cork.variance(step.t, blob, step.point - blob)
        self.cork.note_blob(step.t, blob)
        if step.point is None:
            return None, None, head_var
        if step.epi is not None:
            self.pairing.note_pair(step.t, left, right, step.epi)
        measured = tuple(float(v) for v in self.rig.to_output(step.point)[0])
        noise_shape = self.rig.noise_shape([[left.x, left.y]], [list(self.pairing.right_xy(right))])[0]
        if step.epi is not None:
            noise_shape = noise_shape * self.gate.inflation(step.epi)
        return measured, noise_shape, head_var

    # ---- stage 6: the 3D flight filter -----------------------------------------------------
    def _follow_flight(self, step: _Step, measured, noise_shape, head_var: float):
        """The flight after this step: the measured point, or, with no pair, the sight of the one
        camera that sees the shuttle (hidden, merged with a player, lost by the other camera's
        detector, or that camera's readout on something else): the robot keeps a 3D point."""
        sight_cam = None
        if measured is None and self.params.stereo.one_camera_rays and self.rig.has_court_pose:
            sight_cam = self.sight.camera(step.dets[0], step.dets[1], step.t)
        if sight_cam is None:
            return self._trajectory.update(step.t, measured, noise_shape,
                                           np.eye(3) * head_var if head_var > 0 else None), None
        # The right image's own time when its clock lags (``align_pairs``), never earlier
        # than the last step (the trajectory would take that for a replay and reset).
        last = self._trajectory.last_time
        t_sight = step.t if sight_cam == 0 or (last is not None and step.t_right <= last) else step.t_right
        step.fired("one_camera_sight", sight_cam)
        return self.sight.feed(sight_cam, step.dets[sight_cam], t_sight, PAIRED_SIGHT_NOISE), sight_cam

    def _readout_point(self, step: _Step, measured, flight: FlightInfo, sight_cam: int | None):
        """The 3D point to report (output frame) and the flight, before the phase's rules."""
        point = measured
        filtered = self._trajectory.filtered_position()
        left, right = step.dets
        if filtered is not None and step.point is not None and self.params.stereo.one_camera_rays:
            blob = self.cork.last_blob_point()
            self.sight.note_pair(step.t, self.rig.to_output(blob),
                                 ((left.x, left.y), self.pairing.right_xy(right)))
        if filtered is not None and sight_cam is not None and self.params.stereo.guided_other:
            blind = 1 - sight_cam
            shown = self.sight.projected_readout(blind, filtered, step.t, step.results[blind],
                                                 step.frames[blind])
            if shown is not None:
                step.results[blind] = shown
                step.fired("guided_other", blind)
        if filtered is not None:
            point = filtered
        elif self._trajectory.point_rejected:
            # An outlier to the followed flight: no point, unless it is the next shot's already.
            point = self._trajectory.tentative_position()
        elif measured is not None and self.rig.has_court_pose:
            point = self._resting_cork(measured)
        return point, flight

    # ---- stage 7: the shuttle's phase and its readout rules --------------------------------
    def _phase_step(self, step: _Step, measured, accepted: bool, point, flight: FlightInfo):
        speed = _speed(flight)
        self.phase = transition(self.phase, PhaseObservation(
            step.t, measured, accepted, speed, None if point is None else float(point[2])),
            self.params, self.rig.has_court_pose)
        if withheld(self.phase, step.t, self.params):
            point, flight = None, _withheld_flight(flight)
            step.results = self.rules.withhold_caught(step.results, self.phase)
            step.fired("caught")
        for cam, det in enumerate(step.dets):
            self.rules.note_anchor(cam, det, point is not None)
            if (det is not None and not det.predicted and point is not None
                    and float(point[2]) > self.params.stereo.landed_max_height):
                self.rules.note_flown(cam, det.tracklet, step.t)
        self._limit_alone(step, point is not None, (0, 1))
        return point, flight

    def _limit_alone(self, step: _Step, has_point: bool, cameras: tuple[int, ...]) -> None:
        limited = self.rules.limit_alone(step.results, has_point, cameras)
        for cam in cameras:
            if limited[cam] is not step.results[cam]:
                step.fired("alone_limit", cam)
        step.results = limited

    def _result(self, step: _Step, index: int, index_right: int, point, flight: FlightInfo,
                measured, start: float) -> TrackResult:
        distance = predicted_distance = None
        if point is not None:
            distance = float(np.linalg.norm(self.rig.to_left([point])[0]))
        elif flight.in_flight:
            # The guide a stage asked for, before the flight took this step; else the flight's now.
            guide = step.guide.known
            if guide is None:
                guide = self._trajectory.guide(step.t)
            predicted_distance = None if guide is None else float(np.linalg.norm(self.rig.to_left([guide[0]])[0]))
        if step.trace is not None:
            step.trace.append(f"phase:{self.phase.phase.name.lower()}")
        return TrackResult(
            index=index, timestamp=step.t, left=step.results[0], right=step.results[1], point=point,
            in_court_frame=self.rig.has_court_pose, distance=distance, speed=_speed(flight),
            epipolar_error=step.epi, index_right=index_right,
            measured_point=measured, predicted_distance=predicted_distance,
            processing_ms=(time.perf_counter() - start) * 1000.0, flight=flight,
            trace=() if step.trace is None else tuple(step.trace))

    # ---- a step with one camera's image ----------------------------------------------------
    def _process_one(self, cam: int, frame_bgr: np.ndarray, t: float, index: int, index_right: int,
                     keep_masks: bool) -> TrackResult:
        """A step that brings a new image from camera ``cam`` only (the other camera, free-running,
        had none near this time): that camera's detector runs on it at its own time, the other
        camera's readout is its last one, and no 3D point is measured (a pair of images taken
        apart would triangulate the shuttle's motion between them). The one-camera rules of a
        pair step apply to this camera as they would without a partner: the flight's guided
        look, the exits from view, the landed hold, the caught shuttle, the limit on reports
        alone; none of them counts this step for the other camera. The flight takes this
        camera's line of sight to the shuttle (``stereo.one_camera_rays``, corrected by
        ``SightOfCamera.offset``) and, when it does, its position is the step's 3D point."""
        start = time.perf_counter()
        detector = (self.left, self.right)[cam]
        sp = self.params.stereo
        h, w = frame_bgr.shape[:2]
        if not self._checked_size:
            self.rig.check_image_size(w, h, "the left frames" if cam == 0 else "the right frames")
        other = self._last_results[1 - cam] or CameraResult(detection=None, image_size=(w, h))
        frames = [self._previous[0], self._previous[1]]
        frames[cam] = frame_bgr
        step = _Step(t, t, (frames[0], frames[1]), StepGuide(self._trajectory, t),
                     trace=[] if self.trace else None)
        detector.keep_whole = self.rules.holding(cam)
        detector.plan_window(frame_bgr, t)
        result = detector.find_candidates(frame_bgr, t, keep_masks)
        step.results = [other, other]
        step.results[cam] = result
        step.dets[cam] = detector.choose(result.candidates)
        detector.commit(step.dets[cam], t, result.candidates)
        self._guided_look_one(step, cam)
        self._note_paths(step, (cam,))
        self._exits(step, (cam,))
        self.rules.cams[cam].holding = False
        if sp.landed_frames > 0 and self.rig.has_court_pose:
            step.results[cam], step.dets[cam] = self.rules.hold_landed(cam, step.results[cam], step.dets[cam],
                                                                       t, self.phase)
            if self.rules.holding(cam):
                step.fired("landed_hold", cam)
        self._protect_and_show(step, (cam,))
        det, result = step.dets[cam], step.results[cam]
        if (sp.one_camera_rays and det is not None and not det.predicted
                and result.detection is not None and self.rig.has_court_pose):
            flight = self.sight.feed(cam, det, t)
            step.fired("one_camera_sight", cam)
        else:
            flight = self._trajectory.update(t, None)
        point = self._trajectory.filtered_position()
        if withheld(self.phase, t, self.params):
            point, flight = None, _withheld_flight(flight)
            step.results = self.rules.withhold_caught(step.results, self.phase, cameras=(cam,))
            step.fired("caught")
        self.rules.note_anchor(cam, step.results[cam].detection, False)
        self._limit_alone(step, False, (cam,))
        self.phase = transition(self.phase, PhaseObservation(
            t, point_height=None if point is None else float(point[2]), paired=False),
            self.params, self.rig.has_court_pose)
        self._last_results[cam] = step.results[cam]
        return self._result(step, index, index_right, point, flight, None, start)

    def _guided_look_one(self, step: _Step, cam: int) -> None:
        """``_guided_look`` for a step with camera ``cam``'s image only."""
        sp = self.params.stereo
        det = step.dets[cam]
        weak = self.look.weak_lone(det, False)
        if not (sp.guided_search and (det is None or det.predicted or weak)):
            return
        guide = step.guide.get()
        if guide is None:
            return
        found = self.look.guided(cam, step.frames[cam], self._previous[cam], det, guide, weak)
        if found is not None:
            step.add(cam, found)
            step.fired("guided_search", cam)
        if sp.guided_coast:
            before = step.dets[cam]
            step.results[cam], step.dets[cam] = self.look.coast(cam, step.frames[cam], step.results[cam],
                                                                before, guide)
            if step.dets[cam] is not before:
                step.fired("guided_coast", cam)

    def _resting_cork(self, point: tuple[float, float, float]) -> tuple[float, float, float]:
        """A shuttle lying where the last flight landed: move the blob's point to the cork."""
        direction = self._trajectory.resting_direction(point)
        if direction is None:
            return point
        sp = self.params.stereo
        return (point[0] + sp.rest_cork_ahead * direction[0], point[1] + sp.rest_cork_ahead * direction[1],
                point[2] - sp.rest_cork_below)


def _speed(flight: FlightInfo) -> float | None:
    if flight.velocity is None:
        return None
    return float(math.sqrt(sum(v * v for v in flight.velocity)))


def _withheld_flight(flight: FlightInfo) -> FlightInfo:
    """The flight as told while the shuttle is caught: out of play, no position, speed or landing
    for the robot to chase (the flight filter itself runs on, for the next serve)."""
    return dataclasses.replace(flight, velocity=None, prediction=None, in_flight=False,
                               withheld_reason=CAUGHT_REASON, confirmed=(), confirmed_path=())


def configure_opencv_threads() -> None:
    """One OpenCV thread: the tracker's two camera threads already fill two cores.

    OpenCV's own pool on top of them costs CPU and time: at 2048 px on 2 cores
    (``benchmarks/speed.py --process-bound``, two runs) 51–63 → 60–74 pairs/s and 26–29 → 20–23 ms
    of CPU a pair. A process-wide setting, so it is the entry points (``badminton-track track``,
    the GUI) that call it, not the tracker.
    """
    cv2.setNumThreads(1)

"""The pure stereo tracker: a pair of frames in, a frozen :class:`TrackResult` out.

Why this file exists: it is the one object that the GUI worker, the CLI and the tests all drive.
A pair step runs these stages, in this order (``StereoTracker.process``):

1. segmentation and candidates, per camera (:class:`CameraDetector`, the two cameras side by
   side on two threads, or each in a process of its own: ``core/execution.py``);
2. stereo vouch and pairing (``stereo/vouch.py``, ``stereo/pairing.py``): a young track the other
   camera confirms passes; the stereo-consistent pair is chosen (within the followed flight's
   reach with ``stereo.flight_reach``), else each camera's own choice; each detector commits
   its report;
3. the flight's look (``flight/look.py``, ``stereo/look.py``): a camera that lost the shuttle
   looks where the flight projects, or where its own image path continues on the other
   detection's epipolar line; two reports just off the gate pair when the flight or the last
   pair vouches for them; a report is dropped when the shuttle has left that camera's view;
4. the landed hold (``flight/camera_rules.py``) and each camera's readout at the cork;
5. the 3D measurement (``stereo/measure.py``, ``stereo/cork.py``): the pair's point moved to the
   cork, its noise shape;
6. the 3D flight filter (``flight/follow.py``, :class:`Trajectory`), or one camera's line of
   sight when there is no pair (``flight/sight.py``), and the 3D point to report;
7. the shuttle's phase (``flight/phase.py``, a pure transition) and its readout rules
   (``flight/camera_rules.py``): a caught shuttle withheld, reports one camera makes alone limited.

Each stage hands the next one :class:`~badminton_gui.core.step.Step` (each camera's result and
report, the pair's point); each keeps its own memory, rebuilt from one place by ``reset``.

The 3D point reported is the trajectory filter's estimate whenever the measured point extended
a flight (a single triangulation is several times less sure in depth than across); a point the
followed flight refuses is not reported as the shuttle, the raw triangulation stays in
``measured_point``.

Cameras without a common trigger (``process_frame``): a step may bring one camera's image only
(``StereoFrame.fresh_left`` / ``fresh_right``); only that camera runs, and no 3D point is
measured. In a pair whose images were taken apart, the right detection is moved along its track
to the left image's time before the two are paired (``stereo.align_pairs``).

``StereoTracker.adaptation`` (``core/court_adaptation.py``, ``adapt`` parameters, off by default)
learns the court's shuttle from the flights both cameras agree on and swaps each camera's
classifier between two steps.

``StereoTracker.trace = True`` makes each result name the rules that fired on its step
(``TrackResult.trace``).

Usage::

    rig = StereoRig.load("calibration/rig.yaml")
    tracker = StereoTracker(rig)
    result = tracker.process(left_bgr, right_bgr, timestamp)
    result = tracker.process_frame(source.read())   # a FrameSource's steps
"""

from __future__ import annotations

import math
import time

import cv2
import numpy as np
import numpy.ma  # noqa: F401  np.median imports it on its first call: 17 ms in the middle of a rally

from .court_adaptation import CourtAdaptation
from .detector import CameraDetector
from .execution import ProcessCameras, ThreadCameras
from .frame_checks import InputChecks
from .flight.camera_rules import HoldInputs, ReadoutInputs, ReadoutState, hold_transition, readout_transition
from .flight.guide import StepGuide
from .flight.look import FlightLook
from .flight.follow import FlightFollower
from .flight.phase import PhaseObservation, PhaseState, caught_flight, transition, withheld
from .flight.sight import SightOfCamera
from .params import TrackerParams
from .rig import StereoRig
from .step import Step
from .stereo.cork import CorkCorrection
from .stereo.epipolar import EpipolarGate
from .stereo.look import ImagePaths, look_on_epipolar_lines
from .stereo.measure import measure
from .stereo.pairing import StereoPairing
from .stereo.vouch import StereoVouch
from .flight.trajectory import Trajectory
from .types import CameraResult, FlightInfo, StereoFrame, TrackResult



class StereoTracker:
    """Tracks the shuttle with two calibrated cameras."""

    def __init__(self, rig: StereoRig, params: TrackerParams | None = None,
                 parallel: bool = True, processes: bool = False) -> None:
        """``parallel``: the cameras' image work on two threads; ``processes``: each camera's
        detector in a process of its own instead (``core/execution.py``; the same results)."""
        self.rig = rig
        self._params = params or TrackerParams()
        geometry = tuple((rig, cam) if rig.has_court_pose else None for cam in (0, 1))
        self.cameras = (ProcessCameras(self.params, geometry) if processes
                        else ThreadCameras(self.params, geometry, parallel))
        self.left, self.right = self.cameras.detectors
        # ``window.stagger``: the right camera's scheduled whole frames half a period after the left's.
        self.right.set_window_phase(0.5)
        self._trajectory = Trajectory(self.params.trajectory, rig.has_court_pose)
        self._input_checks = InputChecks(rig.image_size)
        self._checked_size = False
        # Each result names the rules that fired on its step (``TrackResult.trace``).
        self.trace = False
        self.adaptation = CourtAdaptation(self.params.adapt)
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
        self.follower = FlightFollower(self.rig, self.params, self._trajectory, self.sight, self.cork,
                                       self.pairing.right_xy)
        self.readout = ReadoutState()
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
        for stage in (self.gate, self.pairing, self.vouch, self.look, self.cork, self.sight, self.follower):
            stage.params = params

    def set_params(self, params: TrackerParams) -> None:
        """Apply a new parameter snapshot (the GUI sends whole snapshots)."""
        self.params = params
        self.left.set_params(params)
        self.right.set_params(params)
        self._trajectory.set_params(params.trajectory)

    def reset(self) -> None:
        self._input_checks.reset()
        self.left.reset()
        self.right.reset()
        self._trajectory.reset()
        self._new_state()

    def epipolar_tolerance(self) -> float:
        """The epipolar gate in use: the configured one, widened to the rig's measured error."""
        return self.gate.tolerance()

    @property
    def rig_epipolar_px(self) -> float | None:
        """How far the rig really misses: the median epipolar error (px) of the sure pairs learnt so
        far (None: too few yet); a chessboard rig a few px, the NYCU rig from its ``.cfg`` ≈ 30 px."""
        return self.gate.rig_error_px()

    @property
    def rig_swapped_px(self) -> float | None:
        """The median epipolar error (px) the same sure pairs have with the left and right images
        exchanged (None: too few yet; measured only on pairs that miss as given): far below ``rig_epipolar_px`` when the inputs are swapped
        (``rig.inputs_look_swapped``)."""
        return self.gate.swapped_error_px()

    def close(self) -> None:
        self.adaptation.close()
        self.cameras.close()

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
        None: the same). Raises ``TrackerInputError`` for images or times it cannot use."""
        left_bgr, right_bgr = self._input_checks.check_pair(left_bgr, right_bgr, timestamp, t_right)
        start = time.perf_counter()
        t_r = timestamp if t_right is None else t_right
        self._check_sizes(left_bgr, right_bgr)
        self.pairing.set_times(timestamp, t_r)
        step = Step(timestamp, t_r, (left_bgr, right_bgr), StepGuide(self._trajectory, timestamp),
                    trace=[] if self.trace else None)
        self._segment(step, keep_masks)
        self._pair(step)
        self.look.look(step, self._previous, self.pairing.pair_point)
        look_on_epipolar_lines(step, self.rig, self.params, self.gate, self.paths, self._previous,
                               self.pairing.pair_point)
        self.pairing.pair_off_gate(step)
        self._note_paths(step)
        self.look.exits(step, self.paths)
        self._hold_and_readout(step)
        m = measure(step, self.rig, self.params, self.gate, self.pairing, self.cork)
        flight, sight_cam = self.follower.follow(step, m)
        accepted = m.point is not None and not self._trajectory.point_rejected
        point = self.follower.point_to_report(step, m.point, sight_cam)
        point, flight = self._phase_step(step, m.point, accepted, point, flight)
        self._last_results = list(step.results)
        return self._result(step, index, index_right, point, flight, m.point, start)

    def _check_sizes(self, left_bgr: np.ndarray, right_bgr: np.ndarray) -> None:
        if not self._checked_size:
            for image, name in ((left_bgr, "the left frames"), (right_bgr, "the right frames")):
                self.rig.check_image_size(image.shape[1], image.shape[0], name)
            self._checked_size = True

    # ---- stage 1: segmentation and candidates, per camera ----------------------------------
    def _segment(self, step: Step, keep_masks: bool) -> None:
        """Each camera's candidates (``core/execution.py``: on threads or in processes)."""
        self.left.keep_whole, self.right.keep_whole = self.readout.holding(0), self.readout.holding(1)
        step.results = self.cameras.find_candidates(step.frames, (step.t, step.t_right), keep_masks)

    # ---- stage 2: stereo vouch, pairing, each camera's commit ------------------------------
    def _pair(self, step: Step) -> None:
        res = step.results
        if self.params.stereo.stereo_vouch:
            step.take("stereo_vouch", self.vouch.apply(res[0], res[1]))
        step.take("off_volume", self.pairing.reject_off_volume(res[0], res[1], step.t, step.guide))
        if self.params.stereo.serve_start and self.rig.has_court_pose:
            step.before_serve = self.pairing.serve_start.before_serve(step.t, step.guide, self.phase, self.params)
            step.take("serve_start", self.pairing.reject_before_serve(res[0], res[1], step.t, step.before_serve,
                                                                     self._trajectory.resting_direction))
        self.pairing.learn(res[0], res[1])
        self.pairing.pair(step)
        self.left.commit(step.dets[0], step.t, res[0].candidates)
        self.right.commit(step.dets[1], step.t_right, res[1].candidates)

    # ---- stage 3: the flight's look, and the shuttle leaving a camera's view ---------------
    def _note_paths(self, step: Step, cameras: tuple[int, ...] = (0, 1)) -> None:
        detectors = (self.left, self.right)
        for cam in cameras:
            det = step.dets[cam]
            if det is not None and not det.predicted:
                self.paths.note(cam, step.t, det.x, det.y, detectors[cam].tracklet_velocity(det))

    # ---- stage 4: the landed hold, each camera's readout at the cork -----------------------
    def _hold_and_readout(self, step: Step, cameras: tuple[int, ...] = (0, 1)) -> None:
        """The landed hold; a landed shuttle lying still stays in its camera's mask; the 2D
        readout is the cork, not the trailing bright centroid (the 3D point is still triangulated
        from the measured centroids: each camera's lead is estimated on its own and their
        disagreement would be a disparity error; the same bias is removed in 3D, ``stereo/cork.py``)."""
        height = None if step.point is None else float(self.rig.to_output(step.point)[0][2])
        self.readout, hold, fired = hold_transition(self.readout, HoldInputs(
            step.t, tuple(step.results), tuple(step.dets), cameras, height, (self.paths.last(0), self.paths.last(1)),
            self.phase, self.rig.has_court_pose), self.params)
        step.results, step.dets = list(hold.results), list(hold.reports)
        if hold.drop_point:
            step.point, step.epi = None, None
        step.fired_all(fired)
        detectors = (self.left, self.right)
        for cam in cameras:
            detectors[cam].protect_report(hold.protect[cam], step.frames[cam].shape[1])
            # The sources hand out a new array per frame: keeping the reference costs no copy.
            self._previous[cam] = step.frames[cam]
        for cam in cameras:
            result, shown = detectors[cam].lead_to_head(step.results[cam], step.dets[cam])
            step.results[cam] = CameraDetector.finalise(result, shown)

    # ---- stage 7: the shuttle's phase and its readout rules --------------------------------
    def _phase_step(self, step: Step, measured, accepted: bool, point, flight: FlightInfo):
        self.phase = transition(self.phase, PhaseObservation(
            step.t, measured, accepted, _speed(flight), None if point is None else float(point[2])),
            self.params, self.rig.has_court_pose)
        if self.phase.net_stop:
            step.fired("caught_net_exception")
        caught = withheld(self.phase, step.t, self.params)
        self.pairing.serve_start.note_flight(flight)
        if caught:
            point, flight = None, caught_flight(flight)
        self._readout_rules(step, ReadoutInputs(step.t, tuple(step.results), tuple(step.dets), (0, 1), point is not None,
                                                None if point is None else float(point[2]), caught, self.phase,
                                                step.before_serve))
        return point, flight

    def _readout_rules(self, step: Step, inputs: ReadoutInputs) -> None:
        self.readout, results, fired = readout_transition(self.readout, inputs, self.params)
        step.results = list(results)
        step.fired_all(fired)

    def _result(self, step: Step, index: int, index_right: int, point, flight: FlightInfo,
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
        result = TrackResult(
            index=index, timestamp=step.t, left=step.results[0], right=step.results[1], point=point,
            in_court_frame=self.rig.has_court_pose, distance=distance, speed=_speed(flight),
            epipolar_error=step.epi, index_right=index_right,
            measured_point=measured, predicted_distance=predicted_distance,
            processing_ms=(time.perf_counter() - start) * 1000.0, flight=flight,
            trace=() if step.trace is None else tuple(step.trace), pair_in_flight=step.in_flight)
        self.adaptation.observe(self, result)
        return result

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
        step = Step(t, t, (frames[0], frames[1]), StepGuide(self._trajectory, t),
                    trace=[] if self.trace else None)
        detector.keep_whole = self.readout.holding(cam)
        detector.plan_window(frame_bgr, t)
        result = detector.find_candidates(frame_bgr, t, keep_masks)
        step.results = [other, other]
        step.results[cam] = result
        step.dets[cam] = detector.choose(result.candidates)
        detector.commit(step.dets[cam], t, result.candidates)
        self.look.look_one(step, cam, self._previous[cam])
        self._note_paths(step, (cam,))
        self.look.exits(step, self.paths, (cam,))
        self._hold_and_readout(step, (cam,))
        det, result = step.dets[cam], step.results[cam]
        if (sp.one_camera_rays and det is not None and not det.predicted
                and result.detection is not None and self.rig.has_court_pose):
            flight = self.sight.feed(cam, det, t)
            step.fired("one_camera_sight", cam)
        else:
            flight = self._trajectory.update(t, None)
        point = self._trajectory.filtered_position()
        caught = withheld(self.phase, t, self.params)
        if caught:
            point, flight = None, caught_flight(flight)
        self._readout_rules(step, ReadoutInputs(t, tuple(step.results), None, (cam,), caught=caught, phase=self.phase))
        self.phase = transition(self.phase, PhaseObservation(
            t, point_height=None if point is None else float(point[2]), paired=False),
            self.params, self.rig.has_court_pose)
        self._last_results[cam] = step.results[cam]
        return self._result(step, index, index_right, point, flight, None, start)


def _speed(flight: FlightInfo) -> float | None:
    if flight.velocity is None:
        return None
    return float(math.sqrt(sum(v * v for v in flight.velocity)))


def configure_opencv_threads() -> None:
    """One OpenCV thread: the tracker's two camera threads already fill two cores.

    OpenCV's own pool on top of them costs CPU and time: at 2048 px on 2 cores
    (``benchmarks/speed.py --process-bound``, two runs) 51–63 → 60–74 pairs/s and 26–29 → 20–23 ms
    of CPU a pair. A process-wide setting, so it is the entry points (``badminton-track track``,
    the GUI) that call it, not the tracker.
    """
    cv2.setNumThreads(1)

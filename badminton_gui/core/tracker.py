"""The pure stereo tracker: a pair of frames in, a frozen :class:`TrackResult` out.

Why this file exists: it is the one object that the GUI worker, the CLI and the tests all drive
(GUIDE §2). It owns one :class:`CameraDetector` per camera, chooses a stereo-consistent pair of
detections (epipolar check), triangulates, and hands the 3D point to the trajectory module for
speed and landing prediction.

The 3D point it reports is the trajectory filter's estimate whenever the measured point extended
a flight: a single triangulation is several times less sure in depth than across (≈ 12 cm per px
of disparity at 5 m on the demo rig), and the drag-model filter, weighing each point by its own
stereo noise shape, removes most of that. A point the followed flight refuses (a wrong pair, a
racket) is not reported as the shuttle; the raw triangulation stays in ``measured_point``.

Each camera's 2D readout uses the other camera and the flight too: a candidate its association
held back passes when the other camera agrees on the epipolar line (``_vouch``); a camera that
lost the shuttle looks where the flight projects (``_guided``) or, before the flight is known,
where its own image path continues on the other detection's epipolar line (``_stereo_look``);
nothing is reported where the shuttle has left the camera's view (``stereo.exit_margin``,
``exit_by_path``, ``out_of_view_weak``), nor, in either camera, while a shuttle whose flight
stopped dead in mid-air is held in the hand that caught it (``stereo.caught_frames``). When one
camera alone has the shuttle, its line of sight moves the flight (``_feed_sight``), the robot
keeps a 3D point, and the camera that lost it shows the flight's projection where its image shows
something there (``stereo.guided_other``).

Cameras without a common trigger (``process_frame``): a step may bring one camera's image only
(``StereoFrame.fresh_left`` / ``fresh_right``, io/video.py ``pairing_schedule``); only that camera
runs, and no 3D point is measured. In a pair whose images were taken apart, the right detection
is moved along its track to the left image's time before the two are paired
(``stereo.align_pairs``).

Usage::

    rig = StereoRig.load("calibration/rig.yaml")
    tracker = StereoTracker(rig)
    result = tracker.process(left_bgr, right_bgr, timestamp)
    result = tracker.process_frame(source.read())   # a FrameSource's steps
"""

from __future__ import annotations

import bisect
import dataclasses
import math
import time
from collections import deque
from concurrent.futures import ThreadPoolExecutor

import cv2
import numpy as np
import numpy.ma  # noqa: F401  np.median imports it on its first call: 17 ms in the middle of a rally

from .court import NET_HEIGHT_POSTS
from .detector import CameraDetector
from .frame_checks import InputChecks
from .guided import bright_near, find_spot, white_near
from .params import TrackerParams
from .rig import StereoRig
from .trajectory import Trajectory
from .types import REJECT_STEREO, CameraResult, Candidate, StereoFrame, TrackResult


# Time step (s) over which the tracklets' image velocities are followed back to find the
# flight direction for the cork correction: long enough to resolve the direction, short
# enough that the image path is still straight.
HEAD_DIRECTION_DT = 0.01
# px: the least epipolar error taken as typical of a good pair (see _epipolar_inflation)
EPIPOLAR_TYPICAL_MIN = 0.5
# The cork correction's direction is checked against the 3D step from the previous blob point
# when that point is at most this old (s) and the step at least this many head offsets long
# (shorter steps are mostly the points' noise): see _head_variance.
HEAD_CHECK_DT = 0.02
HEAD_CHECK_STEPS = 4.0
# px at 1280 px width: how near the flight's projection a white pixel must show for a shuttle
# merged with a larger blob (wider, a shoulder's edge next to a hidden cork passed on the demo).
MERGED_WHITE_RADIUS = 2.0
# s: how far back the two tracks' image velocities are followed to check that a held-back pair
# moves consistently in 3D (``_vouch``): a few frames at 120 fps, long enough for a slow shuttle
# to move a few px.
VOUCH_DT = 0.02
# px at 1280 px width: how near an unpaired detection at the border the flight's projection
# outside the image must lie for the detection to be taken as the shuttle leaving (``_gone_out``).
EXIT_NEAR = 20.0
# s: how old this camera's last report may be for ``_stereo_look`` to follow its image path
# (three frames at 120 fps).
STEREO_LOOK_AGE = 0.03
# px² at 1280 px width: the largest spot ``_stereo_look`` takes (a shuttle near the rig is
# ~10 px across; a player's white shirt is larger).
STEREO_LOOK_MAX_AREA = 150.0
# px/s at 1280 px width: how fast both tracks of a vouched pair must move in the image for the
# gate widened to the rig's error (``stereo.vouch_rig_factor``): 2 px a frame at 119 fps; a
# shuttle lying on the floor, a light, a still shoe move less.
VOUCH_WIDE_IMAGE_SPEED = 250.0
# m/s: the fastest 3D motion a vouched pair may show (smashes leave the racket at ≤ ~157 m/s).
VOUCH_MAX_SPEED = 160.0
# s: how recent the flight's last low 3D point must be when a camera's followed track stops
# being reported for ``stereo.landed_frames`` to hold it (a shuttle lands and comes to rest in
# a fraction of a second; the pause allowance runs out 40 frames later at 119 fps).
LANDED_RECENT = 1.0
# px at 1280 px width: how far a held landed shuttle's candidate may move from one frame to the
# next (it slides or rolls a little; a hand picking it up moves more).
LANDED_STEP = 4.0
# Sure pairs (``_learn_epipolar``) before the learnt epipolar tolerance replaces
# ``stereo.cold_epipolar_error``.
EPIPOLAR_LEARNT_SAMPLES = 20
# s: how long ago the held track may last have been reported with a 3D point above the floor
# (``_flown_recently``): a landed shuttle slides and lies still for up to ~1.5 s before the hold
# starts; a shoe walked along the floor after the rally was never seen in the air.
FLOWN_MEMORY = 5.0
# m/s: how fast the flight must have been followed just before its 3D points stopped dead for
# ``stereo.caught_frames`` to call it caught (a shuttle held before the serve had no flight).
CAUGHT_MIN_FLIGHT_SPEED = 3.0
# s: how long before the first stopped point the flight's last accepted point may lie.
CAUGHT_FLIGHT_GAP = 0.05
# m: how near the net's plane (court Y = 0) and above its top a stop counts as the net's, not a
# hand's: the shuttle hangs in the mesh or falls off the tape in full view.
CAUGHT_NET_MARGIN = 0.3
# What the readout and the robot are told while the shuttle is caught (``FlightInfo.withheld_reason``).
CAUGHT_REASON = "caught: out of play"
# px at 1280 px width: how far a caught shuttle's report may move from one frame to the next and
# still be the shuttle in the hand that caught it (a hand carrying it walks, it does not fly).
CAUGHT_STEP = 12.0
# s: the least time between a pair's two images for the right camera's detections to be moved
# along their tracks to the left image's time before they are paired (free-running cameras,
# ``_right_xy``); the NYCU cameras' pairs are 0.05 ms apart, launcher-stereo's up to 25 ms.
ALIGN_MIN_LAG = 0.0005
# s: how recent a pair's reprojection miss must be to correct a one-camera step's line of sight
# (``_sight_offset``); the rig's miss changes slowly with where the shuttle is in the image, so an
# older pair's miss still serves, up to SIGHT_OFFSET_MEMORY, while the shuttle is within
# SIGHT_OFFSET_REACH (× image width) of where that pair saw it (a slow flight one camera lost).
SIGHT_OFFSET_AGE = 0.1
SIGHT_OFFSET_PAIRS = 5       # ... averaged over this many recent pairs (one pair's is its detection noise)
SIGHT_OFFSET_MEMORY = 0.5
SIGHT_OFFSET_REACH = 0.05
# × image width: with both cameras' detections and no pair, the one off the flight's projection
# by more than this is taken for something else, and the other camera's sight moves the flight.
SIGHT_PICK_FAR = 0.05
# × the points' pixel noise: a sight on a pair step whose other camera lost the shuttle is less
# sure than a free-running camera's lone image (the shuttle half hidden, merging with a player):
# at 1 the demo court's 3D RMS within 6 m went 0.91 → 0.98 cm, at 2 0.94, at 3 0.93 cm.
PAIRED_SIGHT_NOISE = 3.0
# A pair of reports off the epipolar gate that the followed flight vouches for (``_flight_vouched_pair``):
FLIGHT_VOUCH_GATE = 1.5      # × the epipolar gate: how far off its line it may be
FLIGHT_VOUCH_SLACK = 0.1     # m: ... and how near the flight's prediction (+ 3σ of it) it must lie
# The last step's pair continued off the epipolar gate (``_continued_pair``):
PAIR_CONTINUITY_AGE = 0.03   # s: the last pair at most this old (a frame or two)
PAIR_CONTINUITY_STEP = 0.005  # × image width: its epipolar error moved by at most this since (10 px at 2048)
PAIR_CONTINUITY_GATE = 2.0   # × the epipolar gate: and is at most this


class StereoTracker:
    """Tracks the shuttle with two calibrated cameras."""

    def __init__(self, rig: StereoRig, params: TrackerParams | None = None,
                 parallel: bool = True) -> None:
        self.rig = rig
        self.params = params or TrackerParams()
        self.left = CameraDetector(self.params)
        self.right = CameraDetector(self.params)
        # ``window.stagger``: the right camera's scheduled whole frames half a period after the left's.
        self.right.set_window_phase(0.5)
        # OpenCV releases the GIL: the two cameras run side by side on two cores (GUIDE §4).
        self._pool = ThreadPoolExecutor(max_workers=2, thread_name_prefix="camera") if parallel else None
        self._trajectory = Trajectory(self.params.trajectory, rig.has_court_pose)
        self._input_checks = InputChecks(rig.image_size)
        self._checked_size = False
        self._previous: tuple[np.ndarray | None, np.ndarray | None] = (None, None)
        # Per camera, its last reported measured detections: [(t, x, y, image velocity or None)]
        # (``_stereo_look`` follows the camera's own image path from them).
        self._reports: tuple[deque, deque] = (deque(maxlen=2), deque(maxlen=2))
        # Epipolar errors of long, confident tracklets seen by both cameras: what the rig
        # really achieves (a rig calibrated by clicking court points is off by tens of px).
        self._epipolar_samples: deque[float] = deque(maxlen=600)
        # The same samples kept sorted (and how many are NaN, which np.median would return):
        # their median is read several times a pair (the gate, the noise inflation) and changes
        # with each new sample, and np.median of 600 values costs ≈ 0.05 ms a call.
        self._epipolar_sorted: list[float] = []
        self._epipolar_nans = 0
        # The last frame's triangulated blob point (left-camera frame) and its time: the 3D step
        # checks the direction of the cork correction (see _head_variance).
        self._last_blob: tuple[float, np.ndarray] | None = None
        # Per camera, the last pairs' (time, detection − projection of its triangulated point, px):
        # a rig whose cameras' rays miss each other (the NYCU rig imported from its .cfg files,
        # ≈ 10° off) puts each camera's sight of the shuttle centimetres off the triangulated
        # flight; a one-camera step's sight is moved back by it (``_sight_offset``).
        self._sight_miss: tuple[deque, deque] = (deque(maxlen=SIGHT_OFFSET_PAIRS), deque(maxlen=SIGHT_OFFSET_PAIRS))
        # The last measured pair: (time, left tracklet, right tracklet, epipolar error px), for
        # ``_continued_pair``.
        self._last_pair: tuple[float, int, int, float] | None = None
        # Per camera, for ``stereo.alone_limit``: [reports alone in a row, frames without a
        # report in a row, the readout continues one that had a 3D point].
        self._alone = ([0, 0, False], [0, 0, False])
        # Per camera, for ``stereo.landed_frames``: [tracklet of the last report (-1: none),
        # frames held since, its last x, y, that report had a 3D point]; and (t, court height)
        # of the last 3D point.
        self._held = ([-1, 0, 0.0, 0.0, False], [-1, 0, 0.0, 0.0, False])
        self._held_now = [False, False]
        self._last_point: tuple[float, float] | None = None
        # Per camera, for ``stereo.landed_frames``: tracklet -> time of its last report with a
        # 3D point above ``landed_max_height`` (within ``FLOWN_MEMORY`` s).
        self._flown: tuple[dict[int, float], dict[int, float]] = ({}, {})
        # Each camera's readout of the last step: what a step that brings no new image from that
        # camera reports for it (``process_frame``).
        self._last_results: list[CameraResult | None] = [None, None]
        # s: the left image's time minus the right one's in the pair being processed (``_right_xy``).
        self._right_lag = 0.0
        self._reset_caught()

    # ---- configuration ---------------------------------------------------------------------
    def set_params(self, params: TrackerParams) -> None:
        """Apply a new parameter snapshot (the GUI sends whole snapshots, GUIDE §3.2)."""
        self.params = params
        self.left.set_params(params)
        self.right.set_params(params)
        self._trajectory.set_params(params.trajectory)

    def reset(self) -> None:
        self._input_checks.reset()
        self.left.reset()
        self.right.reset()
        self._trajectory.reset()
        self._epipolar_samples.clear()
        self._epipolar_sorted.clear()
        self._epipolar_nans = 0
        self._previous = (None, None)
        self._reports[0].clear()
        self._reports[1].clear()
        self._last_blob = None
        self._last_pair = None
        self._sight_miss[0].clear()
        self._sight_miss[1].clear()
        self._alone = ([0, 0, False], [0, 0, False])
        self._held = ([-1, 0, 0.0, 0.0, False], [-1, 0, 0.0, 0.0, False])
        self._held_now = [False, False]
        self._last_point = None
        self._flown = ({}, {})
        self._last_results = [None, None]
        self._reset_caught()

    def _reset_caught(self) -> None:
        """State of ``stereo.caught_frames``: the measured 3D points stopped since the flight's
        last accepted one [(t, court point)], that flight's (time, speed), and, once the shuttle
        is caught, each camera's last position of it ([x, y] or None) — None when not caught."""
        self._stopped: list[tuple[float, tuple[float, float, float]]] = []
        self._last_flown: tuple[float, float] | None = None
        self._caught: list[list[float] | None] | None = None
        self._caught_now = False
        self._caught_at = 0.0

    def epipolar_tolerance(self) -> float:
        """The epipolar gate in use: the configured one, widened to the rig's measured error."""
        sp = self.params.stereo
        tol = float(sp.max_epipolar_error)
        if sp.adaptive_epipolar:
            if len(self._epipolar_samples) >= EPIPOLAR_LEARNT_SAMPLES:
                learnt = sp.adaptive_factor * self._epipolar_median()
                tol = max(tol, min(learnt, sp.max_learnt_tolerance))
            else:
                # Nothing learnt yet (a fresh start): the rig may be off by tens of px, and the
                # 6 px gate left rally_11-47-02's serve unpaired in both cameras, then withheld
                # as one-camera reports (coarse, 33 frames).
                tol = max(tol, float(sp.cold_epipolar_error))
        return tol

    @property
    def rig_epipolar_px(self) -> float | None:
        """How far the rig really misses: the median epipolar error (px) of the sure pairs
        learnt so far (``_learn_epipolar``), or None before EPIPOLAR_LEARNT_SAMPLES of them.
        A chessboard-calibrated rig stays at a few px; the NYCU rig imported from its ``.cfg``
        files misses by ≈ 30 px (its relative pose is ≈ 10° off, benchmarks/README.md)."""
        if len(self._epipolar_samples) < EPIPOLAR_LEARNT_SAMPLES:
            return None
        median = self._epipolar_median()
        return None if math.isnan(median) else median

    def _add_epipolar_sample(self, err: float) -> None:
        """Append a sample to the deque and to its sorted copy (the oldest leaves both)."""
        samples = self._epipolar_samples
        if len(samples) == samples.maxlen:
            old = samples[0]
            if math.isnan(old):
                self._epipolar_nans -= 1
            else:
                ordered = self._epipolar_sorted
                del ordered[bisect.bisect_left(ordered, old)]
        samples.append(err)
        if math.isnan(err):
            self._epipolar_nans += 1
        else:
            bisect.insort(self._epipolar_sorted, err)

    def _epipolar_median(self) -> float:
        """``float(np.median(self._epipolar_samples))`` bit for bit (non-empty), from the sorted
        copy: the middle value, or the two middle values' sum halved as numpy's mean does."""
        if self._epipolar_nans:
            return float(np.median(self._epipolar_samples))
        ordered = self._epipolar_sorted
        n = len(ordered)
        if n % 2:
            return ordered[n // 2]
        return (ordered[n // 2 - 1] + ordered[n // 2]) / 2.0

    def _learn_epipolar(self, res_left: CameraResult, res_right: CameraResult) -> None:
        sp = self.params.stereo
        if not sp.adaptive_epipolar:
            return
        own_left = self.left.choose(res_left.candidates)
        own_right = self.right.choose(res_right.candidates)
        if own_left is None or own_right is None or own_left.predicted or own_right.predicted:
            return
        if min(self.left.tracklet_hits(own_left), self.right.tracklet_hits(own_right)) < sp.confident_hits:
            return
        err = float(self.rig.epipolar_errors([[own_left.x, own_left.y]], [list(self._right_xy(own_right))])[0, 0])
        self._add_epipolar_sample(err)

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
        None: the same). Raises ``TrackerInputError`` for images or times it cannot use."""
        left_bgr, right_bgr = self._input_checks.check_pair(left_bgr, right_bgr, timestamp, t_right)
        start = time.perf_counter()
        t_r = timestamp if t_right is None else t_right
        self._right_lag = (timestamp - t_r if self.params.stereo.align_pairs
                           and abs(timestamp - t_r) >= ALIGN_MIN_LAG else 0.0)
        if not self._checked_size:
            h, w = left_bgr.shape[:2]
            self.rig.check_image_size(w, h, "the left frames")
            hr, wr = right_bgr.shape[:2]
            self.rig.check_image_size(wr, hr, "the right frames")
            self._checked_size = True

        # A windowed frame is mostly Python holding the GIL: when both cameras process this
        # frame in a window they run faster in turn on this thread than side by side (coarse,
        # in play: 179–222 against 169–172 pairs/s, README Speed); a pair with a whole frame,
        # mostly image work that releases the GIL, runs side by side. The windows are chosen
        # first, so a camera's periodic whole frame is never run in turn with the other's.
        self.left.keep_whole, self.right.keep_whole = self._held_now
        in_turn = (self.left.plan_window(left_bgr, timestamp)
                   & self.right.plan_window(right_bgr, t_r))
        if self._pool is not None and not in_turn:
            # Only the image half runs side by side (CameraDetector.segment); the measuring
            # half, many small calls each of which hands the GIL over, runs on this thread,
            # the left camera's while the right camera's image half may still be running.
            fut = self._pool.submit(self.right.segment, right_bgr, t_r)
            res_left = self.left.candidates_from(left_bgr, timestamp,
                                                 self.left.segment(left_bgr, timestamp), keep_masks)
            res_right = self.right.candidates_from(right_bgr, t_r, fut.result(), keep_masks)
        else:
            res_left = self.left.find_candidates(left_bgr, timestamp, keep_masks)
            res_right = self.right.find_candidates(right_bgr, t_r, keep_masks)

        if self.params.stereo.stereo_vouch:
            res_left, res_right = self._vouch(res_left, res_right)
        self._learn_epipolar(res_left, res_right)
        det_left, det_right, point_left, epi = self._choose_pair(res_left, res_right)
        if point_left is None:
            # No stereo pair: each camera keeps its own best guess for the 2D readout.
            det_left = self.left.choose(res_left.candidates)
            det_right = self.right.choose(res_right.candidates)
        self.left.commit(det_left, timestamp, res_left.candidates)
        self.right.commit(det_right, t_r, res_right.candidates)
        sp = self.params.stereo
        # Without override the guided look only serves a camera with no detection: when both
        # have one, skip predicting the flight (an RK4 propagation per frame on the hot path).
        unseen = [det is None or det.predicted for det in (det_left, det_right)]
        # Without a stereo pair, a detection of little merit (a track that slid onto a player
        # when the shuttle's own track was lost) is looked past too, at the flight's projection.
        weak = [self._weak_lone(det, point_left is not None) for det in (det_left, det_right)]
        guide = None
        guide_tried = False
        if sp.guided_search and (sp.guided_override or any(unseen) or any(weak)):
            guide, guide_tried = self._trajectory.guide(timestamp), True
            if guide is not None:
                found_left = self._guided(0, left_bgr, det_left, guide, weak[0])
                found_right = self._guided(1, right_bgr, det_right, guide, weak[1])
                if found_left is not None or found_right is not None:
                    if found_left is not None:
                        det_left = found_left
                        res_left = dataclasses.replace(res_left, candidates=res_left.candidates + (found_left,))
                    if found_right is not None:
                        det_right = found_right
                        res_right = dataclasses.replace(res_right, candidates=res_right.candidates + (found_right,))
                    point_left, epi = self._pair_point(det_left, det_right)
                if sp.guided_coast:
                    res_left, det_left = self._coast_on_flight(0, left_bgr, res_left, det_left, guide)
                    res_right, det_right = self._coast_on_flight(1, right_bgr, res_right, det_right, guide)
        if sp.stereo_look and point_left is None:
            # Neither the pair nor the flight found the shuttle in one camera: the other's sure
            # detection puts it on an epipolar line, this camera's own image path near a point.
            dets = [det_left, det_right]
            results = [res_left, res_right]
            for cam, frame in ((0, left_bgr), (1, right_bgr)):
                other = dets[1 - cam]
                if ((dets[cam] is None or dets[cam].predicted) and other is not None
                        and not other.predicted and other.score >= sp.stereo_look_min_score):
                    found = self._stereo_look(cam, frame, other, timestamp)
                    if found is not None:
                        dets[cam] = found
                        results[cam] = dataclasses.replace(results[cam], candidates=results[cam].candidates + (found,))
                        point_left, epi = self._pair_point(dets[0], dets[1])
                        break
            det_left, det_right = dets
            res_left, res_right = results
        if point_left is None and det_left is not None and det_right is not None:
            if not guide_tried:
                guide, guide_tried = self._trajectory.guide(timestamp), True
            point_left, epi = self._flight_vouched_pair(det_left, det_right, guide)
            if point_left is None:
                point_left, epi = self._continued_pair(det_left, det_right, timestamp)
        for cam, det in ((0, det_left), (1, det_right)):
            if det is not None and not det.predicted:
                velocity = (self.left if cam == 0 else self.right).tracklet_velocity(det)
                self._reports[cam].append((timestamp, det.x, det.y, velocity))
        if sp.exit_margin > 0 or (sp.out_of_view_weak and point_left is None):
            # A detection at the border while the shuttle has left the view (its clipped skirt: a
            # pair made with it is biased too), or a weak lone one while the flight is out of
            # this camera's view.
            dets = [det_left, det_right]
            for cam, frame in ((0, left_bgr), (1, right_bgr)):
                border = self._near_border(dets[cam], frame) and (point_left is None or sp.exit_by_path)
                weak_now = sp.out_of_view_weak and self._weak_lone(dets[cam], point_left is not None)
                if not (border or weak_now):
                    continue
                if guide is None and not guide_tried:
                    guide, guide_tried = self._trajectory.guide(timestamp), True
                if ((border and sp.exit_by_path and self._path_leaves(cam, frame, timestamp))
                        or (guide is not None
                            and ((border and self._gone_out(cam, dets[cam], frame, guide[0]))
                                 or (weak_now and self._out_of_view(cam, frame, guide[0]))))):
                    dets[cam] = None
                    point_left, epi = None, None
            det_left, det_right = dets
        (res_left, det_left), (res_right, det_right), point_left, epi = self._hold_both(
            (res_left, det_left), (res_right, det_right), point_left, epi, timestamp)
        # A landed shuttle lying still stays in its camera's mask (``CameraDetector.protect_report``).
        self.left.protect_report(det_left if self._lying_landed(0, det_left, timestamp, left_bgr.shape[1])
                                 else None, left_bgr.shape[1])
        self.right.protect_report(det_right if self._lying_landed(1, det_right, timestamp, right_bgr.shape[1])
                                  else None, right_bgr.shape[1])
        # The sources hand out a new array per frame: keeping the reference costs no copy.
        self._previous = (left_bgr, right_bgr)
        # The 2D readout is the cork, not the trailing bright centroid. The 3D point is still
        # triangulated from the measured centroids: each camera's lead is estimated on its own
        # and their small disagreement would be a disparity error, ≈ 12 cm of depth per px at
        # 5 m on the demo rig; the same bias is removed in 3D instead (``_to_head``).
        res_left, shown_left = self.left.lead_to_head(res_left, det_left)
        res_right, shown_right = self.right.lead_to_head(res_right, det_right)
        res_left = CameraDetector.finalise(res_left, shown_left)
        res_right = CameraDetector.finalise(res_right, shown_right)

        head_var = 0.0
        blob = point_left
        if point_left is not None and self.params.stereo.head_offset > 0:
            point_left = self._to_head(det_left, det_right, point_left)
            head_var = self._head_variance(timestamp, blob, point_left - blob)
        self._last_blob = None if blob is None else (timestamp, blob)

        measured = None
        noise_shape = None
        if point_left is not None:
            if epi is not None and det_left.tracklet >= 0 and det_right.tracklet >= 0:
                self._last_pair = (timestamp, det_left.tracklet, det_right.tracklet, float(epi))
            measured = tuple(float(v) for v in self.rig.to_output(point_left)[0])
            noise_shape = self.rig.noise_shape([[det_left.x, det_left.y]], [list(self._right_xy(det_right))])[0]
            if epi is not None:
                noise_shape = noise_shape * self._epipolar_inflation(epi)

        sight_cam = None
        if measured is None and self.params.stereo.one_camera_rays and self.rig.has_court_pose:
            sight_cam = self._sight_camera(det_left, det_right, timestamp)
        if sight_cam is not None:
            # One camera sees the shuttle, the other not (hidden, merged with a player, lost by
            # its detector, or its readout on something else): that camera's sight moves the
            # flight as a lone image's does (``_process_one``), and the robot keeps a 3D point.
            cam = sight_cam
            # The right image's own time when its clock lags (``align_pairs``), never earlier
            # than the last step (the trajectory would take that for a replay and reset).
            last = self._trajectory.last_time
            t_sight = timestamp if cam == 0 or (last is not None and t_r <= last) else t_r
            flight = self._feed_sight(cam, det_left if cam == 0 else det_right, t_sight, PAIRED_SIGHT_NOISE)
        else:
            flight = self._trajectory.update(timestamp, measured, noise_shape,
                                             np.eye(3) * head_var if head_var > 0 else None)
        speed = None
        if flight.velocity is not None:
            speed = float(math.sqrt(sum(v * v for v in flight.velocity)))
        point_out = measured
        caught = self._note_caught(timestamp, measured, speed)
        filtered = self._trajectory.filtered_position()
        if filtered is not None and blob is not None and self.params.stereo.one_camera_rays:
            # A pair the flight took: where each camera saw it against where the point projects.
            seen_at = self.rig.to_output(blob)
            for cam, (x, y) in ((0, (det_left.x, det_left.y)), (1, self._right_xy(det_right))):
                u, v = (float(c) for c in self.rig.project(cam, seen_at)[0])
                self._sight_miss[cam].append((timestamp, x, y, x - u, y - v))
        if filtered is not None and sight_cam is not None and sp.guided_other:
            blind = 1 - sight_cam
            shown = self._projected_readout(blind, filtered, timestamp, res_left if blind == 0 else res_right,
                                            left_bgr if blind == 0 else right_bgr)
            if shown is not None:
                if blind == 0:
                    res_left = shown
                else:
                    res_right = shown
        if filtered is not None:
            point_out = filtered
        elif self._trajectory.point_rejected:
            # An outlier to the followed flight: no point, unless it is the next shot's already.
            point_out = self._trajectory.tentative_position()
        elif measured is not None and self.rig.has_court_pose:
            point_out = self._resting_cork(measured)
        if caught:
            # Out of play: no position, speed or landing for the robot to chase (the flight
            # filter itself runs on, for the next serve).
            point_out = speed = None
            flight = dataclasses.replace(flight, velocity=None, prediction=None, in_flight=False,
                                         withheld_reason=CAUGHT_REASON, confirmed=(),
                                         confirmed_path=())
            res_left, res_right = self._withhold_caught(res_left, res_right)
        if point_out is not None:
            self._last_point = (timestamp, float(point_out[2]))
        for cam, det in ((0, det_left), (1, det_right)):
            self._note_anchor(cam, det, point_out is not None)
            if (det is not None and not det.predicted and point_out is not None
                    and float(point_out[2]) > self.params.stereo.landed_max_height):
                self._note_flown(cam, det.tracklet, timestamp)
        res_left, res_right = self._limit_alone(res_left, res_right, point_out is not None)
        distance = predicted_distance = None
        if point_out is not None:
            distance = float(np.linalg.norm(self.rig.to_left([point_out])[0]))
        elif flight.in_flight:
            predicted_distance = self._predicted_distance(timestamp, guide)
        self._last_results = [res_left, res_right]

        return TrackResult(
            index=index, timestamp=timestamp, left=res_left, right=res_right, point=point_out,
            in_court_frame=self.rig.has_court_pose, distance=distance, speed=speed,
            epipolar_error=epi, index_right=index_right, measured_point=measured,
            predicted_distance=predicted_distance,
            processing_ms=(time.perf_counter() - start) * 1000.0, flight=flight)

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
        ``_sight_offset``) and, when it does, its position is the step's 3D point."""
        start = time.perf_counter()
        detector = self.left if cam == 0 else self.right
        sp = self.params.stereo
        h, w = frame_bgr.shape[:2]
        if not self._checked_size:
            self.rig.check_image_size(w, h, "the left frames" if cam == 0 else "the right frames")
        other = self._last_results[1 - cam] or CameraResult(detection=None, image_size=(w, h))

        detector.keep_whole = self._held_now[cam]
        detector.plan_window(frame_bgr, t)
        result = detector.find_candidates(frame_bgr, t, keep_masks)
        det = detector.choose(result.candidates)
        detector.commit(det, t, result.candidates)
        guide = None
        weak = self._weak_lone(det, False)
        if sp.guided_search and (det is None or det.predicted or weak):
            guide = self._trajectory.guide(t)
            if guide is not None:
                found = self._guided(cam, frame_bgr, det, guide, weak)
                if found is not None:
                    det = found
                    result = dataclasses.replace(result, candidates=result.candidates + (found,))
                if sp.guided_coast:
                    result, det = self._coast_on_flight(cam, frame_bgr, result, det, guide)
        if det is not None and not det.predicted:
            self._reports[cam].append((t, det.x, det.y, detector.tracklet_velocity(det)))
        if (sp.exit_margin > 0 or sp.out_of_view_weak) and det is not None:
            border = self._near_border(det, frame_bgr)
            weak_now = sp.out_of_view_weak and self._weak_lone(det, False)
            if border or weak_now:
                if guide is None:
                    guide = self._trajectory.guide(t)
                if ((border and sp.exit_by_path and self._path_leaves(cam, frame_bgr, t))
                        or (guide is not None
                            and ((border and self._gone_out(cam, det, frame_bgr, guide[0]))
                                 or (weak_now and self._out_of_view(cam, frame_bgr, guide[0]))))):
                    det = None
        self._held_now[cam] = False
        if sp.landed_frames > 0 and self.rig.has_court_pose:
            result, det = self._hold_landed(cam, result, det, t)
        detector.protect_report(det if self._lying_landed(cam, det, t, w) else None, w)
        previous = list(self._previous)
        previous[cam] = frame_bgr
        self._previous = (previous[0], previous[1])
        result, shown = detector.lead_to_head(result, det)
        result = CameraDetector.finalise(result, shown)

        if (sp.one_camera_rays and det is not None and not det.predicted
                and result.detection is not None and self.rig.has_court_pose):
            flight = self._feed_sight(cam, det, t)
        else:
            flight = self._trajectory.update(t, None)
        point_out = self._trajectory.filtered_position()
        speed = None
        if flight.velocity is not None:
            speed = float(math.sqrt(sum(v * v for v in flight.velocity)))
        if (self._caught is not None and sp.caught_frames > 0
                and t - self._caught_at <= sp.caught_hold):
            point_out = speed = None
            flight = dataclasses.replace(flight, velocity=None, prediction=None, in_flight=False,
                                         withheld_reason=CAUGHT_REASON, confirmed=(),
                                         confirmed_path=())
            pair = [other, other]
            pair[cam] = result
            result = self._withhold_caught(*pair, cameras=(cam,))[cam]
        self._note_anchor(cam, result.detection, False)
        present = [other.detection is not None] * 2
        present[cam] = result.detection is not None
        result = self._limit_alone_camera(cam, result, present, False)
        distance = predicted_distance = None
        if point_out is not None:
            self._last_point = (t, float(point_out[2]))
            distance = float(np.linalg.norm(self.rig.to_left([point_out])[0]))
        elif flight.in_flight:
            predicted_distance = self._predicted_distance(t, guide)
        self._last_results[cam] = result
        left, right = (result, other) if cam == 0 else (other, result)
        return TrackResult(
            index=index, timestamp=t, left=left, right=right, point=point_out,
            in_court_frame=self.rig.has_court_pose, distance=distance, speed=speed,
            epipolar_error=None, index_right=index_right, measured_point=None,
            predicted_distance=predicted_distance,
            processing_ms=(time.perf_counter() - start) * 1000.0, flight=flight)

    def _sight_camera(self, det_left: Candidate | None, det_right: Candidate | None, t: float) -> int | None:
        """The camera whose sight may move the flight on a step with no pair: the one camera
        with a measured detection; with two (their pair refused), the one whose detection lies
        nearer the flight's projection, the other's being off it by more than SIGHT_PICK_FAR ×
        the image width (the detector took something else, the shuttle lost against a
        player); else None."""
        real = [det is not None and not det.predicted for det in (det_left, det_right)]
        if real[0] != real[1]:
            return 0 if real[0] else 1
        if not real[0]:
            return None
        guide = self._trajectory.guide(t)
        if guide is None:
            return None
        at = guide[0][None]
        off = []
        for cam, det in ((0, det_left), (1, det_right)):
            if float(self.rig.depth(cam, at)[0]) <= 0.1:
                return None
            u, v = self.rig.project(cam, at)[0]
            off.append(math.hypot(det.x - float(u), det.y - float(v)))
        far = SIGHT_PICK_FAR * self.rig.image_size[0]
        if max(off) <= far:
            return None
        return 0 if off[0] < off[1] else 1

    def _feed_sight(self, cam: int, det: Candidate, t: float, noise_scale: float = 1.0):
        """Feed the flight this camera's line of sight to ``det`` at ``t`` (``update_ray``).

        The blob's centroid is used, as the pairs are triangulated; the cork leads it along the
        flight by ``head_offset`` (``_to_head``), which the flight applies to the ray; the sight is
        first moved by where this camera's recent detections lay from the pairs' points."""
        sp = self.params.stereo
        dx, dy = self._sight_offset(cam, t, det.x, det.y)
        centre, direction = self.rig.rays(cam, [[det.x - dx, det.y - dy]])
        m = self.rig.M1 if cam == 0 else self.rig.M2
        return self._trajectory.update_ray(t, centre, direction[0], noise_scale / float(m[0, 0]),
                                           lead=sp.head_offset, lead_min_speed=sp.head_min_speed)

    def _projected_readout(self, cam: int, position, t: float, result: CameraResult,
                           frame: np.ndarray) -> CameraResult | None:
        """This camera's readout at the flight's ``position`` (court frame, the cork), which the
        other camera's sight has just moved while this camera found nothing: the projection moved
        by where this camera's last pairs' detections lay from their points (``_sight_offset``),
        flagged ``predicted`` (drawn dashed, never triangulated). None when the camera has a
        detection, when the projection is behind it or outside its image (the shuttle out of
        view), or when nothing brighter than its surroundings lies there (``bright_near``: the
        shuttle hidden, which the labels call not visible; one lost against a player's shirt or
        in the detector's mask still shows)."""
        if result.detection is not None:
            return None
        at = np.asarray(position, dtype=float)[None]
        if float(self.rig.depth(cam, at)[0]) <= 0.1:
            return None
        u, v = (float(c) for c in self.rig.project(cam, at)[0])
        dx, dy = self._sight_offset(cam, t, u, v)
        u, v = u + dx, v + dy
        w, h = result.image_size
        if not (0 <= u < w and 0 <= v < h):
            return None
        if not bright_near(frame, u, v, MERGED_WHITE_RADIUS * w / 1280.0, self.params.stereo.guided_min_contrast):
            return None
        shown = Candidate(u, v, math.nan, math.nan, math.nan, math.nan, 0.0, 0.0, None, predicted=True)
        return dataclasses.replace(result, detection=shown, candidates=result.candidates + (shown,))

    def _sight_offset(self, cam: int, t: float, x: float, y: float) -> tuple[float, float]:
        """How far (px) this camera's detections lay from where the triangulated points project, over
        the last pairs the flight took (``SIGHT_OFFSET_PAIRS`` within ``SIGHT_OFFSET_AGE``, or older,
        up to ``SIGHT_OFFSET_MEMORY``, when seen near (x, y), the detection now); else (0, 0). On
        an exact rig it is the detection noise (a fraction of a px on the demo court); on
        launcher-stereo, whose rig is the NYCU one imported from the .cfg files, a single
        camera's sight missed the triangulated flight by 5–23 cm and the flight refused every one."""
        reach = SIGHT_OFFSET_REACH * self.rig.image_size[0]
        recent = [(dx, dy) for t_pair, x_pair, y_pair, dx, dy in self._sight_miss[cam]
                  if 0.0 <= t - t_pair <= SIGHT_OFFSET_AGE
                  or (t - t_pair <= SIGHT_OFFSET_MEMORY and math.hypot(x - x_pair, y - y_pair) <= reach)]
        if not recent:
            return 0.0, 0.0
        dx, dy = np.mean(recent, axis=0)
        return float(dx), float(dy)

    def _predicted_distance(self, t: float, guide: tuple[np.ndarray, np.ndarray] | None) -> float | None:
        """Distance (m) from the left camera to where the followed flight puts the shuttle at
        ``t`` (``guide``: that flight's guide at ``t`` when already asked), or None."""
        if guide is None:
            guide = self._trajectory.guide(t)
        return None if guide is None else float(np.linalg.norm(self.rig.to_left([guide[0]])[0]))

    def _hold_both(self, left: tuple[CameraResult, Candidate | None],
                   right: tuple[CameraResult, Candidate | None], point_left: np.ndarray | None,
                   epi: float | None, t: float):
        """Both cameras through ``_hold_landed``: ((result, report) left, right, 3D point, its
        epipolar error). When a hold gives a camera's report back to the landed shuttle (the shoe
        walking past), the pair made with the shoe, below the floor, is no 3D point any more."""
        self._held_now = [False, False]
        sp = self.params.stereo
        if sp.landed_frames <= 0 or not self.rig.has_court_pose:
            return left, right, point_left, epi
        # A stereo pair counts as the shuttle in the air only above the floor: a shoe paired
        # with the lying shuttle (rally_11-47-21 986: 1.7 m below the court) is not one.
        paired = (point_left is not None
                  and float(self.rig.to_output(point_left)[0][2]) > sp.landed_max_height)
        held_left = self._hold_landed(0, left[0], left[1], t, paired)
        held_right = self._hold_landed(1, right[0], right[1], t, paired)
        if point_left is not None and (held_left[1] is not left[1] or held_right[1] is not right[1]):
            point_left, epi = None, None
        return held_left, held_right, point_left, epi

    def _hold_landed(self, cam: int, result: CameraResult, det: Candidate | None, t: float,
                     paired: bool = False) -> tuple[CameraResult, Candidate | None]:
        """Keep reporting a shuttle that landed and lies still (``stereo.landed_frames``).

        The association reports a still track only for ``association.pause_frames`` after it
        flew; a shuttle that has just landed lies there longer, and the NYCU labels mark it
        visible for another ≈ 0.3–0.8 s. When this camera's report stops, its last report had a
        3D point, the 3D flight's last point (within ``LANDED_RECENT`` s) lay near the floor, the
        track it followed was reported with a 3D point above the floor (``_flown_recently``: on
        the NYCU rallies a player's shoe paired across the cameras after the rally was held
        otherwise) and still has
        a candidate where the last report was (within ``LANDED_STEP`` px a frame), that candidate
        is reported, for at most ``landed_frames`` frames. A shuttle held before the serve has
        no low 3D point before it; one picked up moves off.
        """
        sp = self.params.stereo
        state = self._held[cam]
        if (det is not None and not paired and not det.predicted and 0 <= state[0] != det.tracklet
                and not self._flown_recently(cam, det.tracklet, t)):
            # The readout leaves the landed shuttle for a track never seen in the air, with no
            # stereo partner above the floor: after a rally, a player's white shoe walking past
            # (rally_11-47-21 left 986, rally_11-48-00 right 630). The shuttle, still lying
            # there, stays the report while the hold's conditions last; else the new track is.
            held_result, held = self._hold_landed(cam, result, None, t, paired)
            if held is not None:
                return held_result, held
        if det is not None:
            if det.predicted or det.tracklet < 0:
                state[0] = -1
            else:
                state[:4] = [det.tracklet, 0, det.x, det.y]
            return result, det
        if state[0] < 0:
            return result, None
        if state[1] >= sp.landed_frames or (state[1] == 0 and not (state[4] and self._landed(t)
                                                                   and self._flown_recently(cam, state[0], t))):
            state[0] = -1
            return result, None
        step = LANDED_STEP * result.image_size[0] / 1280.0
        for c in result.candidates:
            # Its own track's candidate, or a blob no track took (tracklet -1) at the same spot:
            # a lying shuttle dims and its look changes, and a classifier may then refuse it
            # before association (rally_11-48-00 right 641 with the coarse patch classifier).
            if ((c.tracklet == state[0] or c.tracklet < 0) and not c.predicted
                    and math.hypot(c.x - state[2], c.y - state[3]) <= step):
                state[1] += 1
                state[2], state[3] = c.x, c.y
                self._held_now[cam] = True
                held = dataclasses.replace(c, rejected_by=None)
                return dataclasses.replace(result, candidates=tuple(held if k is c else k
                                                                    for k in result.candidates)), held
        state[0] = -1
        return result, None

    def _lying_landed(self, cam: int, det: Candidate | None, t: float, width: int) -> bool:
        """Whether this camera's report is a landed shuttle lying still, whose pixels the next
        frame's mask should keep: held (``_hold_landed``), or still reported by its own track
        when that track carried the flight down (``_flown_recently``), the flight's last point
        lay near the floor (``_landed``) and the track barely moves (``VOUCH_WIDE_IMAGE_SPEED``).
        Without the second case a lying shuttle whose track the association kept reporting —
        its classifier score high — was never held, so never protected, and the quarter-scale
        model lost it when it dimmed (rally_11-48-00 right 636–664 with the coarse preset's
        patch classifier)."""
        if det is None or det.predicted:
            return False
        if self._held_now[cam]:
            return True
        # As for the hold itself (``_hold_both``): off with it, and only where heights mean the floor.
        if self.params.stereo.landed_frames <= 0 or not self.rig.has_court_pose:
            return False
        if det.tracklet < 0 or not self._landed(t) or not self._flown_recently(cam, det.tracklet, t):
            return False
        # The track's image velocity as noted for this very report (a later stage may have
        # replaced the report noted then).
        last = self._reports[cam][-1] if self._reports[cam] else None
        velocity = last[3] if last is not None and (last[1], last[2]) == (det.x, det.y) else None
        return (velocity is not None
                and math.hypot(*velocity) <= VOUCH_WIDE_IMAGE_SPEED * width / 1280.0)

    def _note_caught(self, t: float, measured: tuple[float, float, float] | None,
                     speed: float | None) -> bool:
        """Whether the shuttle is caught, out of play (``stereo.caught_frames``), after this
        frame's 3D point went to the flight.

        A shuttle in flight never stops in mid-air. When the flight was followed at
        ``CAUGHT_MIN_FLIGHT_SPEED`` or more and its next measured 3D points are refused by it and
        stay within ``caught_radius`` of each other above the floor for ``caught_frames`` frames,
        a hand or a racket caught it (rally_11-47-02 172: from 5 m/s to still at 0.9 m); the
        labellers stop marking a shuttle held in the hand, and the robot has nothing to chase. It
        stays caught until the flight follows a point at ``caught_release_speed`` or more (a
        serve). An apex is no stop (the flight accepts its points), nor is a hit (its points
        move fast), nor a shuttle held before a serve with no flight before it.
        """
        sp = self.params.stereo
        if sp.caught_frames <= 0 or not self.rig.has_court_pose:
            self._caught = None
            return False
        if self._caught is not None and t - self._caught_at > sp.caught_hold:
            self._caught = None
        accepted = measured is not None and not self._trajectory.point_rejected
        if accepted:
            self._stopped.clear()
            if speed is not None:
                if self._caught is not None and speed >= sp.caught_release_speed:
                    self._caught = None
                if self._caught is None:
                    self._last_flown = (t, speed)
            return self._caught is not None
        if self._caught is not None:
            return True
        if measured is None:
            self._stopped.clear()
            return False
        flown = self._last_flown
        if not self._stopped and (flown is None or t - flown[0] > CAUGHT_FLIGHT_GAP + 1e-9
                                  or flown[1] < CAUGHT_MIN_FLIGHT_SPEED):
            return False
        self._stopped.append((t, measured))
        if len(self._stopped) < sp.caught_frames:
            return False
        points = np.array([p for _, p in self._stopped[-sp.caught_frames:]])
        centre = points.mean(axis=0)
        self._stopped.clear()
        if (float(np.max(np.linalg.norm(points - centre, axis=1))) > sp.caught_radius
                or centre[2] <= sp.landed_max_height
                or (abs(centre[1]) <= CAUGHT_NET_MARGIN and centre[2] <= NET_HEIGHT_POSTS + CAUGHT_NET_MARGIN)):
            # Not caught: lying on the floor (the landed hold's case), or stopped by the net,
            # where it hangs in the mesh or on the tape in view (rally_11-47-21 879, labelled).
            return False
        self._caught, self._caught_now, self._caught_at = [None, None], True, t
        return True

    def _withhold_caught(self, res_left: CameraResult, res_right: CameraResult,
                         cameras: tuple[int, ...] = (0, 1)) -> tuple[CameraResult, CameraResult]:
        """Each camera's report of the caught shuttle withheld (marked ``REJECT_STEREO``, the
        association and the flight untouched): the report at the catch, then each report within
        ``CAUGHT_STEP`` px a frame of the last one withheld (the hand carrying it). ``cameras``:
        those with a new image this step."""
        results = [res_left, res_right]
        for cam in cameras:
            det = results[cam].detection
            if det is None or det.predicted:
                continue
            last = self._caught[cam]
            step = CAUGHT_STEP * results[cam].image_size[0] / 1280.0
            if (last is None and not self._caught_now) or (
                    last is not None and math.hypot(det.x - last[0], det.y - last[1]) > step):
                continue
            self._caught[cam] = [det.x, det.y]
            results[cam] = dataclasses.replace(
                results[cam], detection=None,
                candidates=tuple(dataclasses.replace(c, rejected_by=REJECT_STEREO) if c is det else c
                                 for c in results[cam].candidates))
        self._caught_now = False
        return results[0], results[1]

    def _note_anchor(self, cam: int, det: Candidate | None, has_point: bool) -> None:
        """Whether this camera's report, if it stops next, may start a landed hold: it had a 3D
        point — or the other camera is holding its landed shuttle now, which leaves the frame
        without a pair and so without a 3D point, and this camera's report was anchored before.
        Without the second case the camera whose report stops last is never held (rally_11-46-22
        right 1623–1670, rally_11-47-21 right 987–1020)."""
        if self._held_now[cam]:
            return
        state = self._held[cam]
        state[4] = det is not None and (has_point or (self._held_now[1 - cam] and state[4]))

    def _note_flown(self, cam: int, tracklet: int, t: float) -> None:
        """This camera reported ``tracklet`` with a 3D point above the floor at ``t``."""
        flown = self._flown[cam]
        flown[tracklet] = t
        for k in [k for k, when in flown.items() if t - when > FLOWN_MEMORY]:
            del flown[k]

    def _flown_recently(self, cam: int, tracklet: int, t: float) -> bool:
        """This camera reported ``tracklet`` with a 3D point above the floor within
        ``FLOWN_MEMORY`` s: the track carried a flight down, it is not one that only ever moved
        along the floor (a shoe paired with the other camera's shoe after the rally)."""
        when = self._flown[cam].get(tracklet)
        return when is not None and t - when <= FLOWN_MEMORY

    def _landed(self, t: float) -> bool:
        """The 3D flight's last point, within ``LANDED_RECENT`` s, lay near the floor."""
        last = self._last_point
        return (last is not None and t - last[0] <= LANDED_RECENT
                and last[1] <= self.params.stereo.landed_max_height)

    def _limit_alone(self, res_left: CameraResult, res_right: CameraResult, has_point: bool
                     ) -> tuple[CameraResult, CameraResult]:
        """Withhold a camera's report the other camera has not confirmed (``stereo.alone_limit``).

        On the NYCU rallies most detections reported by one camera while the other reports
        nothing and no 3D point exists are not the shuttle (the labels say none is in view): a
        shuttle held or lying still, a racket, a white shoe, which one camera's association
        followed on its own. A real shuttle seen by one camera only is mostly a flight the other
        camera lost (out of its view, behind a player), and then this camera's readout runs on
        from frames that had a 3D point. So a one-camera report is kept when this camera's
        readout has continued, with no break longer than ``alone_anchor_gap`` frames, since a
        frame with a 3D point; otherwise at most ``alone_max_frames`` such reports in a row are
        kept. Only the readout changes (the detection is marked ``REJECT_STEREO``): the
        association, the flight and the look-ahead's tracklets are left as they were.
        """
        results = [res_left, res_right]
        present = [r.detection is not None for r in results]
        for cam in (0, 1):
            results[cam] = self._limit_alone_camera(cam, results[cam], present, has_point)
        return results[0], results[1]

    def _limit_alone_camera(self, cam: int, result: CameraResult, present: list[bool],
                            has_point: bool) -> CameraResult:
        """``_limit_alone`` for one camera; ``present``: whether each camera reports now."""
        sp = self.params.stereo
        state = self._alone[cam]
        if present[cam] and self._held_now[cam]:
            # A landed shuttle held on (``_hold_landed``) is reported, but no flight goes on:
            # what this camera reports after it does not continue the stereo readout, and
            # the other camera's report beside it is a report alone.
            state[0] = 0
            state[1] += 1
            if state[1] > sp.alone_anchor_gap:
                state[2] = False
            return result
        if not present[cam]:
            state[0] = 0
            state[1] += 1
            if state[1] > sp.alone_anchor_gap:
                state[2] = False
            return result
        state[1] = 0
        if has_point:
            state[0], state[2] = 0, True
        elif present[1 - cam] and not self._held_now[1 - cam]:
            state[0] = 0
        else:
            state[0] += 1
            if sp.alone_limit and not state[2] and state[0] > sp.alone_max_frames:
                det = result.detection
                result = dataclasses.replace(
                    result, detection=None,
                    candidates=tuple(dataclasses.replace(c, rejected_by=REJECT_STEREO) if c is det else c
                                     for c in result.candidates))
        return result

    def _vouch(self, res_left: CameraResult, res_right: CameraResult
               ) -> tuple[CameraResult, CameraResult]:
        """Let through a candidate the association held back when the other camera agrees.

        One camera alone needs ``association.min_hits`` frames and ``min_travel`` px to tell a
        shuttle from clutter: a serve's or a hit's first frames, a shuttle coming back slowly into
        view from the top after a clear, are lost (about half the demo court's online errors).
        The other camera is evidence that camera lacks: a partner on the epipolar line (a tight
        fixed tolerance, ``stereo.vouch_max_epipolar``, widened to ``vouch_rig_factor`` × the
        rig's measured error for two tracks that both move in the image: on the roughly
        calibrated NYCU rig sure pairs miss by ~30 px and the fixed gate never fired) whose track moves the same way — the two
        image velocities, followed back ``VOUCH_DT``, meet their epipolar lines too and
        triangulate to a 3D velocity of at least ``vouch_min_speed`` (a light, a shuttle at rest
        do not move; two unrelated blobs rarely move consistently). Only a camera with no
        surviving candidate is helped; its partner is the other camera's survivor, or, when
        neither has one, a held-back candidate of the other camera (both pass); the partner
        survivor is the other camera's own choice. The candidate
        keeps its own quality as its score, below any confirmed track's merit.

        ``stereo.vouch_lone``: a camera whose survivors have no stereo partner among the other
        camera's (within the epipolar tolerance in use) is helped too, its partner being the other
        camera's own choice: the shuttle's own track held back at a racket contact while a
        clutter track passes. ``stereo.vouch_position_quality``: a held-back candidate scoring
        at least this by its looks is vouched for by position alone when the two tracks'
        smoothed velocities disagree (they mix the old and the new flight just after a hit).
        """
        sp = self.params.stereo
        # A camera coasting through a blind spot (a predicted candidate) is not helped: its
        # followed track still knows where the shuttle is.
        survivors = [[c for c in res.candidates if c.rejected_by is None] for res in (res_left, res_right)]
        need = [not s for s in survivors]
        results = [res_left, res_right]
        if any(need):
            pair = self._vouch_pair(results, need)
            if pair is not None:
                for cam in (0, 1):
                    if need[cam]:
                        results[cam] = self._pass_vouched(cam, results[cam], pair[cam])
        elif sp.vouch_lone and all(not any(c.predicted for c in s) for s in survivors):
            pl = np.array([[c.x, c.y] for c in survivors[0]])
            pr = np.array([[c.x, c.y] for c in survivors[1]])
            if not (self.rig.epipolar_errors(pl, pr) <= self.epipolar_tolerance()).any():
                picks = [self._vouch_pair(results, [cam == 0, cam == 1]) for cam in (0, 1)]
                for cam in (0, 1):
                    if picks[cam] is not None:
                        results[cam] = self._pass_vouched(cam, results[cam], picks[cam][cam])
        return results[0], results[1]

    def _vouch_tolerance(self) -> float:
        """The vouch's epipolar gate: ``stereo.vouch_max_epipolar``, widened to
        ``vouch_rig_factor`` × the rig's measured median epipolar error of sure pairs."""
        sp = self.params.stereo
        tol = float(sp.vouch_max_epipolar)
        if sp.vouch_rig_factor > 0 and len(self._epipolar_samples) >= EPIPOLAR_LEARNT_SAMPLES:
            tol = max(tol, sp.vouch_rig_factor * self._epipolar_median())
        return tol

    def _pass_vouched(self, cam: int, result: CameraResult, pick: Candidate) -> CameraResult:
        """``result`` with the held-back ``pick`` let through (it keeps its own score)."""
        passed = (self.left if cam == 0 else self.right).vouch(pick, pick.score)
        return dataclasses.replace(result, candidates=tuple(passed if c is pick else c
                                                            for c in result.candidates))

    def _vouch_pair(self, results: list[CameraResult], need: list[bool]
                    ) -> tuple[Candidate, Candidate] | None:
        """The best (left, right) pair for ``_vouch``: held-back candidates of the cameras in
        ``need``, the other camera's own choice otherwise; None when no pair agrees."""
        sp = self.params.stereo
        detectors = (self.left, self.right)
        first_floor = min(sp.vouch_first_quality, sp.vouch_first_partner_quality)
        pools = []
        for cam in (0, 1):
            pool = []
            if need[cam]:
                for c in results[cam].candidates:
                    v = detectors[cam].vouchable(c, sp.vouch_min_quality)
                    # (candidate, velocity, by position alone if need be, a weak first
                    # sighting, sure enough to partner a weak first sighting)
                    strong = c.score >= sp.vouch_first_quality
                    if v is not None:
                        pool.append((c, v, c.score >= sp.vouch_position_quality, False, strong))
                    elif sp.vouch_first_quality < 1.0 and detectors[cam].first_sighting(c, first_floor):
                        pool.append((c, None, True, not strong, strong))
            else:
                # The partner is that camera's own choice (its best track), nothing else.
                own = detectors[cam].choose(results[cam].candidates)
                v = None if own is None or own.predicted else detectors[cam].tracklet_velocity(own)
                if v is not None:
                    pool.append((own, v, True, False, True))
            if not pool:
                return None
            pools.append(pool)
        left, right = pools
        now_l = np.array([[e[0].x, e[0].y] for e in left])
        now_r = np.array([[e[0].x, e[0].y] for e in right])
        tol = self._vouch_tolerance()
        fixed = float(sp.vouch_max_epipolar)
        wide_speed = VOUCH_WIDE_IMAGE_SPEED * results[0].image_size[0] / 1280.0
        epi = self.rig.epipolar_errors(now_l, now_r)
        if not (epi <= tol).any():
            return None
        back_l = now_l - VOUCH_DT * np.array([(0.0, 0.0) if e[1] is None else e[1] for e in left])
        back_r = now_r - VOUCH_DT * np.array([(0.0, 0.0) if e[1] is None else e[1] for e in right])
        best = None
        for i, j in zip(*np.nonzero(epi <= tol)):
            # A first sighting has no velocity: its pair is checked by position alone, and
            # one that looks little like a shuttle needs a partner that does.
            if (left[i][3] and not right[j][4]) or (right[j][3] and not left[i][4]):
                continue
            moving = left[i][1] is not None and right[j][1] is not None
            if moving and float(self.rig.epipolar_errors(back_l[i:i + 1], back_r[j:j + 1])[0, 0]) > 2.0 * tol:
                if not (left[i][2] and right[j][2]):
                    continue
                moving = False      # two shuttle-like blobs: by position alone
            if epi[i, j] > fixed and not (moving and min(math.hypot(*left[i][1]), math.hypot(*right[j][1]))
                                           >= wide_speed):
                # Beyond the fixed gate only two tracks that both move in the image: on a
                # roughly calibrated rig the widened gate lets chance alignments through (a
                # lying shuttle beside a shoe, a noisy 3D speed from still blobs).
                continue
            pts = self.rig.triangulate(np.stack([now_l[i], back_l[i]]), np.stack([now_r[j], back_r[j]]))
            dist = float(np.linalg.norm(pts[0]))
            if pts[0][2] <= 0 or not (sp.min_distance <= dist <= sp.max_distance):
                continue
            if self.rig.depth(1, self.rig.to_output(pts[:1]))[0] <= 0:
                continue
            speed = float(np.linalg.norm(pts[0] - pts[1])) / VOUCH_DT
            if moving and not (sp.vouch_min_speed <= speed <= VOUCH_MAX_SPEED):
                continue
            merit = left[i][0].score + right[j][0].score - float(epi[i, j]) / tol
            if best is None or merit > best[0]:
                best = (merit, i, j)
        if best is None:
            return None
        _, i, j = best
        return left[i][0], right[j][0]

    def _choose_pair(self, res_left: CameraResult, res_right: CameraResult
                     ) -> tuple[Candidate | None, Candidate | None, np.ndarray | None, float | None]:
        """The most plausible stereo-consistent pair of surviving candidates, if any."""
        sp = self.params.stereo
        tolerance = self.epipolar_tolerance()
        k = int(sp.max_candidates)
        # A coasting prediction is no measurement: it is never triangulated.
        left = sorted((c for c in res_left.candidates if c.rejected_by is None and not c.predicted),
                      key=lambda c: -c.score)[:k]
        right = sorted((c for c in res_right.candidates if c.rejected_by is None and not c.predicted),
                       key=lambda c: -c.score)[:k]
        if not left or not right:
            return None, None, None, None
        pl = np.array([[c.x, c.y] for c in left])
        pr = np.array([self._right_xy(c) for c in right])
        epi = self.rig.epipolar_errors(pl, pr)
        best = None
        order = np.argsort(epi, axis=None)
        for flat in order:
            i, j = np.unravel_index(flat, epi.shape)
            if epi[i, j] > tolerance:
                break
            point = self.rig.triangulate(pl[i:i + 1], pr[j:j + 1])[0]
            dist = float(np.linalg.norm(point))
            depth_ok = point[2] > 0 and self.rig.depth(1, self.rig.to_output(point))[0] > 0
            if not depth_ok or not (sp.min_distance <= dist <= sp.max_distance):
                continue
            # Prefer shuttle-like blobs; the epipolar error breaks near ties.
            merit = left[i].score + right[j].score - epi[i, j] / max(tolerance, 1e-6)
            # Each camera's own choice (index 0: best score, hysteresis included) wins
            # whenever it is stereo-consistent: the pair overrides it only to reject a
            # candidate that has no partner on the other camera.
            merit += sp.own_choice_bonus * ((i == 0) + (j == 0))
            if best is None or merit > best[0]:
                best = (merit, i, j, point, float(epi[i, j]))
        if best is None:
            return None, None, None, None
        _, i, j, point, err = best
        return left[i], right[j], point, err

    def _epipolar_inflation(self, epi: float) -> float:
        """How much less to trust a pair whose epipolar error is large for this rig.

        Two detections of one point meet their epipolar lines to a fraction of a pixel on a good
        rig; a pair several times further off has one centroid pulled aside (by a court line, the
        net's tape, a player's blob): the pair's 3D point is then biased, so the flight filter gets
        it with its noise scaled by 1 + (error / typical)².
        """
        samples = self._epipolar_samples
        typical = (max(EPIPOLAR_TYPICAL_MIN, 1.5 * self._epipolar_median())
                   if len(samples) >= EPIPOLAR_LEARNT_SAMPLES else EPIPOLAR_TYPICAL_MIN)
        return 1.0 + (epi / typical) ** 2

    def _weak_lone(self, detection: Candidate | None, paired: bool) -> bool:
        """A detection with no stereo partner scoring below ``stereo.guided_weak_score``: the
        guided look may replace it by a spot at the flight's projection (a confirmed track
        followed with its hysteresis scores ≥ ~3 on the demo court; one that slid onto a player
        after the shuttle's own track was lost, 0.2–2)."""
        sp = self.params.stereo
        return (not paired and sp.guided_weak_score > 0 and detection is not None
                and not detection.predicted and detection.score < sp.guided_weak_score)

    def _stereo_look(self, camera: int, frame: np.ndarray, other: Candidate, t: float) -> Candidate | None:
        """A white spot where this camera's own image path continues, on the epipolar line of
        the other camera's detection (``stereo.stereo_look``), or None.

        After a hit the 3D flight is not known yet for some frames, and a small or dim shuttle
        (the far court, a drive low over the net) gives no blob that passes the contour filters
        in one camera while the other follows it. This camera's last report (within
        ``STEREO_LOOK_AGE`` s), moved on by its track's image velocity (or the step from the
        report before), says where to look (``stereo.stereo_look_radius``); the spot must lie
        within ``vouch_max_epipolar`` of the other detection's epipolar line.
        """
        sp = self.params.stereo
        path = self._path_point(camera, t)
        if path is None:
            return None
        u, v = path
        h, w = frame.shape[:2]
        if not (0 <= u < w and 0 <= v < h):
            return None
        scale = w / 1280.0
        spot = find_spot(frame, u, v, sp.stereo_look_radius * scale, sp.guided_min_contrast,
                         STEREO_LOOK_MAX_AREA * scale * scale, self._previous[camera])
        if spot is None:
            return None
        x, y, contrast, area = spot
        pair = ([[other.x, other.y]], [[x, y]]) if camera == 1 else ([[x, y]], [[other.x, other.y]])
        if float(self.rig.epipolar_errors(*pair)[0, 0]) > self._vouch_tolerance():
            return None
        return Candidate(x=x, y=y, length=float("nan"), short_side=float("nan"), whiteness=contrast,
                         area=area, motion=math.hypot(x - u, y - v), score=0.0)

    def _path_point(self, camera: int, t: float) -> tuple[float, float] | None:
        """Where this camera's own image path puts the shuttle at ``t``: its last report before
        ``t`` (within ``STEREO_LOOK_AGE`` s) moved on by its track's image velocity, or by the
        step from the report before; None without such reports."""
        hist = [r for r in self._reports[camera] if r[0] < t]
        if not hist:
            return None
        t2, x2, y2, vel = hist[-1]
        if t - t2 > STEREO_LOOK_AGE:
            return None
        if vel is None:
            if len(hist) < 2:
                return None
            t1, x1, y1, _ = hist[-2]
            if not (0.0 < t2 - t1 <= STEREO_LOOK_AGE):
                return None
            vel = ((x2 - x1) / (t2 - t1), (y2 - y1) / (t2 - t1))
        return x2 + vel[0] * (t - t2), y2 + vel[1] * (t - t2)

    def _path_leaves(self, camera: int, frame: np.ndarray, t: float) -> bool:
        """This camera's own image path has left the image by now (``stereo.exit_by_path``)."""
        path = self._path_point(camera, t)
        if path is None:
            return False
        h, w = frame.shape[:2]
        return not (0 <= path[0] < w and 0 <= path[1] < h)

    def _out_of_view(self, camera: int, frame: np.ndarray, position: np.ndarray) -> bool:
        """The 3D flight's position projects outside this camera's image (or behind it)."""
        if float(self.rig.depth(camera, position[None])[0]) <= 0.1:
            return True
        u, v = (float(c) for c in self.rig.project(camera, position[None])[0])
        h, w = frame.shape[:2]
        return not (0 <= u < w and 0 <= v < h)

    def _near_border(self, detection: Candidate | None, frame: np.ndarray) -> bool:
        """The detection lies within ``stereo.exit_margin`` px of the image's border."""
        m = float(self.params.stereo.exit_margin)
        if detection is None or m <= 0:
            return False
        h, w = frame.shape[:2]
        return min(detection.x, detection.y, w - 1 - detection.x, h - 1 - detection.y) <= m

    def _gone_out(self, camera: int, detection: Candidate, frame: np.ndarray, position: np.ndarray) -> bool:
        """The 3D flight puts the shuttle outside this camera's image, just past the unpaired
        detection at its border (within ``EXIT_NEAR`` px): the blob is the skirt's end, clipped
        by the border, or a prediction coasting out; the cork itself is out of view."""
        if float(self.rig.depth(camera, position[None])[0]) <= 0.1:
            return False
        u, v = (float(c) for c in self.rig.project(camera, position[None])[0])
        h, w = frame.shape[:2]
        if 0 <= u < w and 0 <= v < h:
            return False
        return math.hypot(detection.x - u, detection.y - v) <= EXIT_NEAR * w / 1280.0

    def _guided(self, camera: int, frame: np.ndarray, detection: Candidate | None,
                guide: tuple[np.ndarray, np.ndarray], override: bool = False) -> Candidate | None:
        """A spot found where the flight projects, when this camera's detection is not there
        (a detection is looked past with ``guided_override``, or ``override``: a weak one)."""
        sp = self.params.stereo
        position, covariance = guide
        depth = float(self.rig.depth(camera, position[None])[0])
        if depth <= 0.1:
            return None
        u, v = self.rig.project(camera, position[None])[0]
        h, w = frame.shape[:2]
        if not (0 <= u < w and 0 <= v < h):
            return None
        focal = float((self.rig.M1 if camera == 0 else self.rig.M2)[0, 0])
        sigma_px = focal * math.sqrt(max(float(np.trace(covariance)) / 3.0, 0.0)) / depth
        radius = min(3.0 * sigma_px + 3.0 * w / 1280.0, 0.02 * w)
        if detection is not None and (not (sp.guided_override or override)
                                      or math.hypot(detection.x - u, detection.y - v) <= radius):
            return None
        skirt_px = focal * 0.065 / depth            # a shuttle's skirt is 6.5 cm across
        max_area = 4.0 * skirt_px * skirt_px + 12.0
        spot = find_spot(frame, u, v, radius, sp.guided_min_contrast, max_area, self._previous[camera])
        if spot is None:
            return None
        x, y, contrast, area = spot
        return Candidate(x=x, y=y, length=float("nan"), short_side=float("nan"), whiteness=contrast,
                         area=area, motion=math.hypot(x - u, y - v), score=0.0)

    def _coast_on_flight(self, camera: int, frame: np.ndarray, result: CameraResult,
                         detection: Candidate | None, guide: tuple[np.ndarray, np.ndarray]
                         ) -> tuple[CameraResult, Candidate | None]:
        """Where the 3D flight projects, for a camera that cannot see the shuttle there.

        A camera's own coasting (``motion.coast_blind``) carries its tracklet on a straight image
        path at constant speed; the 3D flight (drag and gravity, fed by both cameras) knows the
        curve, so a coasting prediction is moved to the flight's projection. A camera with no
        detection at all whose flight projection lies in its blind spot (a light, a white line:
        the mask cannot show the shuttle there) reports that projection too — the followed
        tracklet may have been taken by clutter, or the blind stretch outlasted ``coast_blind``
        — and so does one whose projection falls on a blob too large for a shuttle where a white
        pixel shows (``stereo.guided_merged``: the shuttle crossing a player's arm or a racket
        merges with it; one hidden behind the player shows no white). Both are flagged
        ``predicted`` (never triangulated); a projection outside the image, or on plain
        background with no detection, gives nothing (nothing is invented where the detector
        could have seen the shuttle).
        """
        if detection is not None and not detection.predicted:
            return result, detection
        position = guide[0][None]
        if float(self.rig.depth(camera, position)[0]) <= 0.1:
            return result, detection
        u, v = (float(c) for c in self.rig.project(camera, position)[0])
        w, h = result.image_size
        if not (0 <= u < w and 0 <= v < h):
            return result, detection
        detector = self.left if camera == 0 else self.right
        if detection is None:
            sp = self.params.stereo
            merged = (sp.guided_merged and detector.is_merged(u, v)
                      and white_near(frame, u, v, MERGED_WHITE_RADIUS * w / 1280.0, sp.guided_min_contrast))
            if not (merged or detector.is_blind(u, v)):
                return result, None
            moved = Candidate(u, v, math.nan, math.nan, math.nan, math.nan, 0.0, 0.0, None, predicted=True)
            return dataclasses.replace(result, candidates=result.candidates + (moved,)), moved
        moved = dataclasses.replace(detection, x=u, y=v)
        candidates = tuple(moved if c is detection else c for c in result.candidates)
        return dataclasses.replace(result, candidates=candidates), moved

    def _pair_point(self, det_left: Candidate | None, det_right: Candidate | None
                    ) -> tuple[np.ndarray | None, float | None]:
        """Triangulate a pair of detections if they are stereo-consistent (else None)."""
        if det_left is None or det_right is None or det_left.predicted or det_right.predicted:
            return None, None
        sp = self.params.stereo
        pl, pr = [[det_left.x, det_left.y]], [list(self._right_xy(det_right))]
        err = float(self.rig.epipolar_errors(pl, pr)[0, 0])
        if err > self.epipolar_tolerance():
            return None, None
        point = self.rig.triangulate(pl, pr)[0]
        dist = float(np.linalg.norm(point))
        if point[2] <= 0 or not (sp.min_distance <= dist <= sp.max_distance):
            return None, None
        return point, err

    def _flight_vouched_pair(self, det_left: Candidate, det_right: Candidate,
                             guide: tuple[np.ndarray, np.ndarray] | None
                             ) -> tuple[np.ndarray | None, float | None]:
        """The two cameras' reports as a pair although they miss the epipolar gate by a little,
        when the followed flight puts the shuttle where they triangulate (else (None, None))."""
        if guide is None or det_left.predicted or det_right.predicted:
            return None, None
        pl, pr = [[det_left.x, det_left.y]], [list(self._right_xy(det_right))]
        err = float(self.rig.epipolar_errors(pl, pr)[0, 0])
        if err > FLIGHT_VOUCH_GATE * self.epipolar_tolerance():
            return None, None
        point = self.rig.triangulate(pl, pr)[0]
        position, covariance = guide
        reach = FLIGHT_VOUCH_SLACK + 3.0 * math.sqrt(max(float(np.trace(covariance)) / 3.0, 0.0))
        if float(np.linalg.norm(self.rig.to_output(point)[0] - position)) > reach:
            return None, None
        return point, err

    def _continued_pair(self, det_left: Candidate, det_right: Candidate, t: float
                        ) -> tuple[np.ndarray | None, float | None]:
        """The two cameras' reports as a pair although they miss the epipolar gate, when the
        same two tracklets were the last step's pair and their epipolar error has moved by at
        most PAIR_CONTINUITY_STEP (× image width) since, up to PAIR_CONTINUITY_GATE × the gate
        (else (None, None)).

        A rough rig's epipolar miss varies smoothly over the image: on rally_11-47-02 the
        labelled shuttle's went 6 → 151 → 7 px along one flight (the learnt gate ≈ 113 px), and
        the robot lost 50 frames of 3D points in the middle, with both cameras on the shuttle."""
        last = self._last_pair
        if (last is None or det_left.predicted or det_right.predicted or t - last[0] > PAIR_CONTINUITY_AGE
                or (det_left.tracklet, det_right.tracklet) != (last[1], last[2]) or det_left.tracklet < 0):
            return None, None
        pl, pr = [[det_left.x, det_left.y]], [list(self._right_xy(det_right))]
        err = float(self.rig.epipolar_errors(pl, pr)[0, 0])
        if (abs(err - last[3]) > PAIR_CONTINUITY_STEP * self.rig.image_size[0]
                or err > PAIR_CONTINUITY_GATE * self.epipolar_tolerance()):
            return None, None
        point = self.rig.triangulate(pl, pr)[0]
        dist = float(np.linalg.norm(point))
        sp = self.params.stereo
        if point[2] <= 0 or not (sp.min_distance <= dist <= sp.max_distance):
            return None, None
        return point, err

    def _right_xy(self, c: Candidate) -> tuple[float, float]:
        """Where the right camera's candidate ``c`` was at the left image's time: moved along its
        track's image velocity by the pair's time apart (free-running cameras; a pair taken
        together, or a candidate whose track has no velocity yet, stays where it was seen). Two
        images 5 ms apart see a 30 m/s shuttle 15 cm apart: paired as they are, the pair misses
        its epipolar line or triangulates off the flight."""
        lag = self._right_lag
        if lag == 0.0:
            return c.x, c.y
        v = self.right.tracklet_velocity(c)
        if v is None:
            return c.x, c.y
        return c.x + v[0] * lag, c.y + v[1] * lag

    def _resting_cork(self, point: tuple[float, float, float]) -> tuple[float, float, float]:
        """A shuttle lying where the last flight landed: move the blob's point to the cork."""
        direction = self._trajectory.resting_direction(point)
        if direction is None:
            return point
        sp = self.params.stereo
        return (point[0] + sp.rest_cork_ahead * direction[0], point[1] + sp.rest_cork_ahead * direction[1],
                point[2] - sp.rest_cork_below)

    def _head_variance(self, timestamp: float, blob: np.ndarray, moved: np.ndarray) -> float:
        """Variance (m², per axis) of the cork correction ``moved`` applied to the blob point.

        The correction follows the tracklets' image velocities, which are smoothed over several
        frames: for the first frames after a hit they still point along the old flight (on the
        demo court the correction was 90° off one frame after a smash and 55° off the next),
        and the first frames of a tracklet get no correction at all. Either way the point is off
        by up to twice ``head_offset`` across the flight, in the directions the stereo pair
        measures best, and a young flight bends to fit it. The 3D step from the last frame's
        blob point shows the real direction when it is long enough to be sure of
        (``HEAD_CHECK_STEPS`` × ``head_offset``): the mismatch between the correction made and
        the one that direction asks for is the variance. Without such a step, an uncorrected
        point gets ``head_offset``² (it may be moving), a corrected one nothing.
        """
        offset = float(self.params.stereo.head_offset)
        last = self._last_blob
        step = None
        if last is not None and 0.0 < timestamp - last[0] <= HEAD_CHECK_DT:
            step = blob - last[1]
            if float(np.linalg.norm(step)) < HEAD_CHECK_STEPS * offset:
                step = None
        if step is None:
            return 0.0 if float(np.linalg.norm(moved)) > 0.0 else offset * offset
        wanted = offset * step / float(np.linalg.norm(step))
        return float(np.sum((moved - wanted) ** 2))

    def _to_head(self, det_left: Candidate, det_right: Candidate, point: np.ndarray) -> np.ndarray:
        """Move the triangulated blob point forward along the flight to the cork (GUIDE §7).

        Each camera measures the centroid of the blob's bright part, which lies behind the
        cork because the skirt trails it. The bias is the same 3D offset in both views (it
        survives triangulation as a shift along the flight direction, not as a disparity
        error), so it is removed in 3D: the direction is the triangulation of the two
        tracklets' image velocities. Without a known image velocity in both cameras (the first
        frames of a tracklet, a shuttle at rest) the point is left as measured.
        """
        sp = self.params.stereo
        vl = self.left.tracklet_velocity(det_left)
        vr = self.right.tracklet_velocity(det_right)
        if vl is None or vr is None:
            return point
        xr, yr = self._right_xy(det_right)
        back = self.rig.triangulate([[det_left.x - vl[0] * HEAD_DIRECTION_DT,
                                      det_left.y - vl[1] * HEAD_DIRECTION_DT]],
                                    [[xr - vr[0] * HEAD_DIRECTION_DT,
                                      yr - vr[1] * HEAD_DIRECTION_DT]])[0]
        step = point - back
        norm = float(np.linalg.norm(step))
        if norm < sp.head_min_speed * HEAD_DIRECTION_DT:
            return point
        return point + sp.head_offset * step / norm


def configure_opencv_threads() -> None:
    """One OpenCV thread: the tracker's two camera threads already fill two cores.

    OpenCV's own pool on top of them costs CPU and time: at 2048 px on 2 cores
    (``benchmarks/speed.py --process-bound``, two runs) 51–63 → 60–74 pairs/s and 26–29 → 20–23 ms
    of CPU a pair. A process-wide setting, so it is the entry points (``badminton-track track``,
    the GUI) that call it, not the tracker.
    """
    cv2.setNumThreads(1)

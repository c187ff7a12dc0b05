"""Stereo pairing: which left and right detections are the same shuttle, and its 3D point.

Why this file exists: the pairing stage of the tracker. Among the surviving candidates of the two
cameras it chooses the stereo-consistent pair (epipolar gate, depth in front of both cameras,
distance in range, each camera's own choice preferred; with ``stereo.flight_reach`` within the
followed flight's reach, where it puts the shuttle first), triangulates it, and takes two reports
as a pair although they miss the gate when the followed flight puts the shuttle where they
triangulate (``stereo.flight_vouch``) or when the same two tracks were the last step's pair and
their miss moved little (``stereo.pair_continuity``). Free-running cameras' right detections are
first moved along their tracks to the left image's time (``stereo.align_pairs``). With
``stereo.play_volume`` a pair must lie inside the play volume, and what pairs only outside it
(an LED board's moving dot) is rejected in both cameras; with ``stereo.off_volume_radius`` also
what one camera keeps alone where such pairs were refused (``off_volume.py``). With
``stereo.serve_start``, before the serve a pair is taken only once its 3D track starts like a
serve (``serve_start.py``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..detect.shuttle_scale import play_volume
from ..detector import CameraDetector
from ..flight.guide import StepGuide
from ..params import TrackerParams
from ..rig import StereoRig, refine_threshold
from ..step import Step
from ..types import REJECT_STEREO, CameraResult, Candidate
from .epipolar import EpipolarGate
from .off_volume import OffVolumeMemory
from .serve_start import ServeRule, ServeStart

# s: the least time between a pair's two images for the right camera's detections to be moved
# along their tracks to the left image's time before they are paired (free-running cameras,
# ``right_xy``); the NYCU cameras' pairs are 0.05 ms apart, launcher-stereo's up to 25 ms.
ALIGN_MIN_LAG = 0.0005
# A pair of reports off the epipolar gate that the followed flight vouches for (``flight_vouched_pair``):
FLIGHT_VOUCH_GATE = 1.5      # × the epipolar gate: how far off its line it may be
FLIGHT_VOUCH_SLACK = 0.1     # m: ... and how near the flight's prediction (+ 3σ of it) it must lie
# The last step's pair continued off the epipolar gate (``continued_pair``):
PAIR_CONTINUITY_AGE = 0.03   # s: the last pair at most this old (a frame or two)
PAIR_CONTINUITY_STEP = 0.005  # × image width: its epipolar error moved by at most this since (10 px at 2048)
PAIR_CONTINUITY_GATE = 2.0   # × the epipolar gate: and is at most this


def in_play_volume(rig: StereoRig, params: TrackerParams, point) -> bool:
    """Could a triangulated point (left-camera frame) be the shuttle's by where it is? With a
    court pose and ``stereo.play_volume``, only inside the play volume (``shuttle_scale``'s
    court margin and height; not bounded below, where a lying shuttle's point scatters around
    the floor); without, anywhere.

    Both cameras see an object off the court where it is, so its pair meets the epipolar gate
    like the shuttle's: an LED board's moving dot beside the court, paired whenever the
    shuttle was out of one camera's view, took both cameras' reports for seconds."""
    if not params.stereo.play_volume or not rig.has_court_pose:
        return True
    _, hi = play_volume(params.shuttle_scale)
    x, y, z = (float(v) for v in rig.to_output(point)[0])
    return abs(x) <= hi[0] and abs(y) <= hi[1] and z <= hi[2]


@dataclass(frozen=True, slots=True)
class StereoPair:
    """The pairing stage's hand-off: each camera's report, and their 3D point (left-camera
    frame) with its epipolar error when they make a pair (else None, None)."""

    left: Candidate | None
    right: Candidate | None
    point: np.ndarray | None = None
    epipolar_error: float | None = None
    # A stereo-consistent pair was left out: beyond the followed flight's reach (``reach_level``).
    beyond_reach: bool = False


@dataclass(frozen=True, slots=True)
class _LastPair:
    """The last measured pair: its time, the two tracklets and its epipolar error (px)."""

    t: float
    left_tracklet: int
    right_tracklet: int
    epipolar_error: float


class StereoPairing:
    """Pairs the two cameras' detections; remembers the last pair for ``continued_pair``."""

    def __init__(self, rig: StereoRig, params: TrackerParams, gate: EpipolarGate,
                 detectors: tuple[CameraDetector, CameraDetector]) -> None:
        self.rig = rig
        self.params = params
        self.gate = gate
        self.detectors = detectors
        # s: the left image's time minus the right one's in the pair being processed.
        self.right_lag = 0.0
        self._last_pair: _LastPair | None = None
        # Where pairs were refused as off the play volume (``stereo.off_volume_radius``).
        self.off_volume = OffVolumeMemory()
        # The 3D tracks of the pairs seen before the serve (``stereo.serve_start``).
        self.serve_start = ServeStart()

    def set_times(self, t_left: float, t_right: float) -> None:
        """The pair being processed was taken at these times (``right_xy`` moves by their lag)."""
        self.right_lag = (t_left - t_right if self.params.stereo.align_pairs
                          and abs(t_left - t_right) >= ALIGN_MIN_LAG else 0.0)

    def right_xy(self, c: Candidate) -> tuple[float, float]:
        """Where the right camera's candidate ``c`` was at the left image's time: moved along its
        track's image velocity by the pair's time apart (free-running cameras; a pair taken
        together, or a candidate whose track has no velocity yet, stays where it was seen). Two
        images 5 ms apart see a 30 m/s shuttle 15 cm apart: paired as they are, the pair misses
        its epipolar line or triangulates off the flight."""
        lag = self.right_lag
        if lag == 0.0:
            return c.x, c.y
        v = self.detectors[1].tracklet_velocity(c)
        if v is None:
            return c.x, c.y
        return c.x + v[0] * lag, c.y + v[1] * lag

    def learn(self, res_left: CameraResult, res_right: CameraResult) -> None:
        """Add the epipolar error of the two cameras' own choices to the gate's samples when both
        are long, confident tracks (what the rig really achieves)."""
        sp = self.params.stereo
        if not sp.adaptive_epipolar:
            return
        left, right = self.detectors
        own_left = left.choose(res_left.candidates)
        own_right = right.choose(res_right.candidates)
        if own_left is None or own_right is None or own_left.predicted or own_right.predicted:
            return
        if min(left.tracklet_hits(own_left), right.tracklet_hits(own_right)) < sp.confident_hits:
            return
        err = float(self.rig.epipolar_errors([[own_left.x, own_left.y]], [list(self.right_xy(own_right))])[0, 0])
        # The error with the cameras exchanged only tells anything when this one is large (a good
        # rig's pairs are never called swapped): skipped otherwise, it costs ≈ 40 µs a pair.
        swapped = None
        if err > 0.5 * refine_threshold(self.rig.image_size[0]):
            swapped = float(self.rig.epipolar_errors([[own_right.x, own_right.y]], [[own_left.x, own_left.y]])[0, 0])
        self.gate.add_sample(err, swapped)

    def _best(self, result: CameraResult) -> list[Candidate]:
        """A camera's best ``stereo.max_candidates`` surviving candidates by score. A coasting
        prediction is no measurement: it is never triangulated."""
        k = int(self.params.stereo.max_candidates)
        return sorted((c for c in result.candidates if c.rejected_by is None and not c.predicted),
                      key=lambda c: -c.score)[:k]

    def _survivors(self, res_left: CameraResult, res_right: CameraResult):
        """Each camera's best surviving candidates (``_best``), their image points (the right
        camera's at the left image's time) and the epipolar errors of every combination; None
        when a camera has none."""
        left, right = self._best(res_left), self._best(res_right)
        if not left or not right:
            return None
        pl = np.array([[c.x, c.y] for c in left])
        pr = np.array([self.right_xy(c) for c in right])
        return left, right, pl, pr, self.rig.epipolar_errors(pl, pr)

    def _in_front_within_range(self, point: np.ndarray) -> bool:
        """A triangulated ``point`` lies in front of both cameras, within the stereo distance range."""
        sp = self.params.stereo
        dist = float(np.linalg.norm(point))
        return bool(point[2] > 0 and self.rig.depth(1, self.rig.to_output(point))[0] > 0
                    and sp.min_distance <= dist <= sp.max_distance)

    def reject_off_volume(self, res_left: CameraResult, res_right: CameraResult, t: float = 0.0,
                          guide: StepGuide | None = None) -> tuple[CameraResult, CameraResult]:
        """Each camera's surviving candidates that meet a partner on the other camera only
        outside the play volume (``in_play_volume``), both of them, rejected (``REJECT_STEREO``):
        both cameras see that object off the court, so neither is the shuttle, and a camera
        left without a pair would otherwise keep it as its own choice and follow it. With
        ``stereo.off_volume_radius``, the places of those pairs are remembered (``t``: the step's
        time) and a candidate with no partner inside the play volume whose line of sight passes
        near one is rejected too (``off_volume.py``); a candidate whose line of sight passes where
        the followed flight (``guide``) puts the shuttle neither marks a place nor is rejected at
        one (the shuttle paired by chance with clutter off the volume, then seen by one camera).
        Returns the two results (the same objects where nothing was rejected)."""
        sp = self.params.stereo
        if not sp.play_volume or not self.rig.has_court_pose:
            return res_left, res_right
        best = (self._best(res_left), self._best(res_right))
        gone: tuple[set[int], set[int]] = (set(), set())
        paired_inside: set[int] = set()
        if best[0] and best[1]:
            off, inside, points = self._off_volume_pairs(*best, guide)
            for cam, axis in ((0, 1), (1, 0)):
                gone[cam].update(id(best[cam][i]) for i in np.flatnonzero(off.any(axis=axis)))
                paired_inside.update(id(best[cam][i]) for i in np.flatnonzero(inside.any(axis=axis)))
            if sp.off_volume_radius > 0.0 and points:
                self.off_volume.remember(np.array(points), t, sp.off_volume_radius)
        if sp.off_volume_radius > 0.0:
            self.off_volume.forget_before(t - sp.off_volume_memory)
            for cam, res in enumerate((res_left, res_right)):
                gone[cam].update(id(c) for c in self._lone_at_refused_places(cam, res, paired_inside | gone[cam],
                                                                             guide))
        return (_rejected(res_left, gone[0]) if gone[0] else res_left,
                _rejected(res_right, gone[1]) if gone[1] else res_right)

    def reject_before_serve(self, res_left: CameraResult, res_right: CameraResult, t: float,
                            before_serve: bool, resting=None) -> tuple[CameraResult, CameraResult]:
        """Before the serve (``before_serve``: no shuttle in play; ``stereo.serve_start``), each
        camera's surviving candidate that meets partners on the other camera inside the play
        volume, none of whose pairs of tracks starts like a serve (``ServeStart.qualifies``), is
        rejected (``REJECT_STEREO``): a shuttle held before the serve, an LED board's dot inside
        the play volume's margin. A pair that ``resting`` (a court point → None or not) says lies
        where the last flight came down is the shuttle lying there and is left alone. A pair that starts like a serve
        puts the shuttle in play (``ServeStart.in_play``). Returns the two results (the same
        objects where nothing was rejected)."""
        sp = self.params.stereo
        if not sp.serve_start or not self.rig.has_court_pose:
            return res_left, res_right
        if not before_serve:
            self.serve_start.clear()
            return res_left, res_right
        rule = ServeRule(sp.serve_points, sp.serve_min_speed, sp.serve_min_climb, sp.serve_min_rise,
                         sp.serve_max_height, self.params.trajectory.max_gap)
        self.serve_start.forget_before(t - rule.max_gap)
        left, right = self._best(res_left), self._best(res_right)
        if not left or not right:
            return res_left, res_right
        pl = np.array([[c.x, c.y] for c in left])
        pr = np.array([self.right_xy(c) for c in right])
        epi = self.rig.epipolar_errors(pl, pr)
        paired = (np.zeros(len(left), dtype=bool), np.zeros(len(right), dtype=bool))
        started = (np.zeros(len(left), dtype=bool), np.zeros(len(right), dtype=bool))
        for i, j in zip(*np.nonzero(epi <= self.gate.tolerance())):
            point = self.rig.triangulate(pl[i:i + 1], pr[j:j + 1])[0]
            if not self._in_front_within_range(point) or not in_play_volume(self.rig, self.params, point):
                continue
            paired[0][i] = paired[1][j] = True
            court = self.rig.to_output(point[None])[0]
            if resting is not None and resting(court) is not None:
                started[0][i] = started[1][j] = True
                continue
            key = (left[i].tracklet, right[j].tracklet)
            if min(key) < 0:
                continue        # no track yet: nothing to tell a start by
            self.serve_start.observe(key, t, court, rule)
            if self.serve_start.qualifies(key, t, rule):
                started[0][i] = started[1][j] = True
                self.serve_start.in_play = True
        gone = ({id(c) for c, p, s in zip(left, paired[0], started[0]) if p and not s},
                {id(c) for c, p, s in zip(right, paired[1], started[1]) if p and not s})
        return (_rejected(res_left, gone[0]) if gone[0] else res_left,
                _rejected(res_right, gone[1]) if gone[1] else res_right)

    def _off_volume_pairs(self, left: list[Candidate], right: list[Candidate], guide: StepGuide | None):
        """Of the two cameras' best survivors: which pairs meet the epipolar gate only outside the
        play volume (neither candidate pairs inside it), which pair inside it, and the points (court
        frame) of the former whose candidates both lie off the followed flight (``_on_flight``)."""
        pl = np.array([[c.x, c.y] for c in left])
        pr = np.array([self.right_xy(c) for c in right])
        epi = self.rig.epipolar_errors(pl, pr)
        inside = np.zeros(epi.shape, dtype=bool)
        outside = np.zeros(epi.shape, dtype=bool)
        where: dict[tuple[int, int], np.ndarray] = {}
        for i, j in zip(*np.nonzero(epi <= self.gate.tolerance())):
            point = self.rig.triangulate(pl[i:i + 1], pr[j:j + 1])[0]
            if not self._in_front_within_range(point):
                continue
            if in_play_volume(self.rig, self.params, point):
                inside[i, j] = True
            else:
                outside[i, j] = True
                where[(int(i), int(j))] = point
        off = outside & ~inside.any(axis=1)[:, None] & ~inside.any(axis=0)[None, :]
        # The places only matter to the memory (``stereo.off_volume_radius``, off by default).
        points = [] if self.params.stereo.off_volume_radius <= 0.0 else [
            self.rig.to_output(where[(int(i), int(j))])[0] for i, j in zip(*np.nonzero(off))
            if not self._on_flight(0, left[i], guide) and not self._on_flight(1, right[j], guide)]
        return off, inside, points

    def _on_flight(self, cam: int, c: Candidate, guide: StepGuide | None) -> bool:
        """Does camera ``cam``'s line of sight through ``c`` pass where the followed flight puts the
        shuttle (within ``trajectory.outlier_distance`` and three of the flight's σ)? False
        without a flight to ask."""
        known = None if guide is None else guide.get()
        if known is None:
            return False
        position, covariance = known
        near = self.params.trajectory.outlier_distance + 3.0 * math.sqrt(max(float(np.trace(covariance)) / 3.0, 0.0))
        centre, dirs = self.rig.rays(cam, [[c.x, c.y]])
        offset = position - centre
        along = max(float(offset @ dirs[0]), 0.0)
        return float(np.linalg.norm(offset - along * dirs[0])) <= near

    def _lone_at_refused_places(self, cam: int, result: CameraResult, spared: set[int],
                                guide: StepGuide | None) -> list[Candidate]:
        """Camera ``cam``'s surviving candidates, other than ``spared`` (ids: those paired inside
        the play volume, those already rejected) and those on the followed flight (``_on_flight``),
        whose lines of sight pass within ``stereo.off_volume_radius`` of a place where a pair was
        refused as off the play volume."""
        if not len(self.off_volume):
            return []
        lone = [c for c in result.candidates if c.rejected_by is None and not c.predicted and id(c) not in spared]
        if not lone:
            return []
        centre, dirs = self.rig.rays(cam, [[c.x, c.y] for c in lone])
        radius = self.params.stereo.off_volume_radius
        return [c for c, d in zip(lone, dirs)
                if self.off_volume.near_sight(centre, d, radius) and not self._on_flight(cam, c, guide)]

    def choose_pair(self, res_left: CameraResult, res_right: CameraResult,
                    guide: StepGuide | None = None) -> StereoPair:
        """The most plausible stereo-consistent pair of surviving candidates within the followed
        flight's reach (``guide``, ``reach_level``), those where it puts the shuttle first, if any."""
        sp = self.params.stereo
        tolerance = self.gate.tolerance()
        survivors = self._survivors(res_left, res_right)
        if survivors is None:
            return StereoPair(None, None)
        left, right, pl, pr, epi = survivors
        best = None
        beyond = False
        order = np.argsort(epi, axis=None)
        for flat in order:
            i, j = np.unravel_index(flat, epi.shape)
            if epi[i, j] > tolerance:
                break
            point = self.rig.triangulate(pl[i:i + 1], pr[j:j + 1])[0]
            if not self._in_front_within_range(point) or not in_play_volume(self.rig, self.params, point):
                continue
            level = self.reach_level(point, guide)
            if level == 0:
                beyond = True
                continue
            # Prefer shuttle-like blobs; the epipolar error breaks near ties.
            merit = left[i].score + right[j].score - epi[i, j] / max(tolerance, 1e-6)
            # Each camera's own choice (index 0: best score, hysteresis included) wins
            # whenever it is stereo-consistent: the pair overrides it only to reject a
            # candidate that has no partner on the other camera.
            merit += sp.own_choice_bonus * ((i == 0) + (j == 0))
            # A pair where the followed flight puts the shuttle comes before any other.
            if best is None or (level, merit) > best[0]:
                best = ((level, merit), i, j, point, float(epi[i, j]))
        if best is None:
            return StereoPair(None, None, beyond_reach=beyond)
        _, i, j, point, err = best
        return StereoPair(left[i], right[j], point, err, beyond_reach=beyond)

    def reach_level(self, point: np.ndarray, guide: StepGuide | None) -> int:
        """Could the followed shuttle be at ``point`` (left-camera frame)? 1 without a flight to
        ask (``guide`` None, no guide now, or ``stereo.flight_reach`` 0); else 0 beyond the
        flight's reach (``StepGuide.reach``: the shuttle does not jump, and one hit since the
        flight's last point leaves from its path), 2 where the flight puts the shuttle (within
        ``trajectory.outlier_distance`` of it), 1 in between. An LED board's dot both cameras
        see pairs into a consistent 3D track metres from the flight; chosen over the shuttle for
        a frame (it scored higher, or the other camera had lost the shuttle), it became each
        camera's followed track and kept both cameras off the shuttle for the rest of the flight."""
        speed = self.params.stereo.flight_reach
        if guide is None or speed <= 0.0:
            return 1
        reach = guide.reach(speed)
        if reach is None:
            return 1
        position, radius = reach
        off = float(np.linalg.norm(self.rig.to_output(point[None])[0] - position))
        if off > radius:
            return 0
        return 2 if off <= self.params.trajectory.outlier_distance else 1

    def pair(self, step: Step) -> None:
        """The stage: the pair of the step's candidates (``choose_pair``) as its reports and
        point; without one, each camera's own choice within the followed flight's reach
        (``own_choices``) for the 2D readout."""
        res = step.results
        pair = self.choose_pair(res[0], res[1], step.guide)
        if pair.beyond_reach:
            step.fired("pair_beyond_reach")
        step.dets, step.point, step.epi = [pair.left, pair.right], pair.point, pair.epipolar_error
        if step.point is None:
            step.dets, moved = self.own_choices(res, step.guide)
            for cam in moved:
                step.fired("sight_beyond_reach", cam)

    def own_choices(self, results: list[CameraResult], guide: StepGuide | None
                    ) -> tuple[list[Candidate | None], list[int]]:
        """Each camera's own choice, when no pair was made; and the cameras whose choice gave way:
        a choice whose line of sight passes beyond the followed flight's reach (``sight_within_reach``)
        cannot be the shuttle, and that camera's best survivor within reach is its report
        instead, or none (the flight's look then searches where the flight projects)."""
        dets: list[Candidate | None] = []
        moved: list[int] = []
        for cam, (detector, res) in enumerate(zip(self.detectors, results)):
            choice = detector.choose(res.candidates)
            if choice is not None and not choice.predicted and not self.sight_within_reach(cam, choice, guide):
                within = [c for c in res.candidates if c.rejected_by is None and not c.predicted
                          and c is not choice and self.sight_within_reach(cam, c, guide)]
                choice = max(within, key=lambda c: c.score, default=None)
                moved.append(cam)
            dets.append(choice)
        return dets, moved

    def sight_within_reach(self, cam: int, c: Candidate, guide: StepGuide | None) -> bool:
        """Does camera ``cam``'s line of sight through ``c`` pass within the followed flight's reach
        (``reach_level``; True without a flight to ask)?"""
        speed = self.params.stereo.flight_reach
        if guide is None or speed <= 0.0:
            return True
        reach = guide.reach(speed)
        if reach is None:
            return True
        position, radius = reach
        centre, dirs = self.rig.rays(cam, [list(self.right_xy(c)) if cam == 1 else [c.x, c.y]])
        offset = position - centre
        along = max(float(offset @ dirs[0]), 0.0)
        return float(np.linalg.norm(offset - along * dirs[0])) <= radius

    def pair_point(self, det_left: Candidate | None, det_right: Candidate | None
                   ) -> tuple[np.ndarray | None, float | None]:
        """Triangulate a pair of detections if they are stereo-consistent (else None)."""
        if det_left is None or det_right is None or det_left.predicted or det_right.predicted:
            return None, None
        sp = self.params.stereo
        pl, pr = [[det_left.x, det_left.y]], [list(self.right_xy(det_right))]
        err = float(self.rig.epipolar_errors(pl, pr)[0, 0])
        if err > self.gate.tolerance():
            return None, None
        point = self.rig.triangulate(pl, pr)[0]
        dist = float(np.linalg.norm(point))
        if (point[2] <= 0 or not (sp.min_distance <= dist <= sp.max_distance)
                or not in_play_volume(self.rig, self.params, point)):
            return None, None
        return point, err

    def flight_vouched_pair(self, det_left: Candidate, det_right: Candidate,
                            guide: tuple[np.ndarray, np.ndarray] | None
                            ) -> tuple[np.ndarray | None, float | None]:
        """The two cameras' reports as a pair although they miss the epipolar gate by a little,
        when the followed flight puts the shuttle where they triangulate (else (None, None);
        ``stereo.flight_vouch``)."""
        if (not self.params.stereo.flight_vouch or guide is None or det_left.predicted
                or det_right.predicted):
            return None, None
        pl, pr = [[det_left.x, det_left.y]], [list(self.right_xy(det_right))]
        err = float(self.rig.epipolar_errors(pl, pr)[0, 0])
        if err > FLIGHT_VOUCH_GATE * self.gate.tolerance():
            return None, None
        point = self.rig.triangulate(pl, pr)[0]
        position, covariance = guide
        reach = FLIGHT_VOUCH_SLACK + 3.0 * math.sqrt(max(float(np.trace(covariance)) / 3.0, 0.0))
        if float(np.linalg.norm(self.rig.to_output(point)[0] - position)) > reach:
            return None, None
        return point, err

    def note_pair(self, t: float, det_left: Candidate, det_right: Candidate, epi: float) -> None:
        """The step at ``t`` measured this pair (``continued_pair`` may continue it)."""
        if det_left.tracklet >= 0 and det_right.tracklet >= 0:
            self._last_pair = _LastPair(t, det_left.tracklet, det_right.tracklet, float(epi))

    def continued_pair(self, det_left: Candidate, det_right: Candidate, t: float
                       ) -> tuple[np.ndarray | None, float | None]:
        """The two cameras' reports as a pair although they miss the epipolar gate, when the
        same two tracklets were the last step's pair and their epipolar error has moved by at
        most PAIR_CONTINUITY_STEP (× image width) since, up to PAIR_CONTINUITY_GATE × the gate
        (else (None, None); ``stereo.pair_continuity``).

        A rough rig's epipolar miss varies smoothly over the image: on rally_11-47-02 the
        labelled shuttle's went 6 → 151 → 7 px along one flight (the learnt gate ≈ 113 px), and
        the robot lost 50 frames of 3D points in the middle, with both cameras on the shuttle."""
        last = self._last_pair
        if not self.params.stereo.pair_continuity:
            return None, None
        if (last is None or det_left.predicted or det_right.predicted or t - last.t > PAIR_CONTINUITY_AGE
                or (det_left.tracklet, det_right.tracklet) != (last.left_tracklet, last.right_tracklet)
                or det_left.tracklet < 0):
            return None, None
        pl, pr = [[det_left.x, det_left.y]], [list(self.right_xy(det_right))]
        err = float(self.rig.epipolar_errors(pl, pr)[0, 0])
        if (abs(err - last.epipolar_error) > PAIR_CONTINUITY_STEP * self.rig.image_size[0]
                or err > PAIR_CONTINUITY_GATE * self.gate.tolerance()):
            return None, None
        point = self.rig.triangulate(pl, pr)[0]
        dist = float(np.linalg.norm(point))
        sp = self.params.stereo
        if (point[2] <= 0 or not (sp.min_distance <= dist <= sp.max_distance)
                or not in_play_volume(self.rig, self.params, point)):
            return None, None
        return point, err

    def pair_off_gate(self, step: Step) -> None:
        """The stage: two reports off the epipolar gate pair when the flight puts the shuttle where
        they triangulate, or when they continue the last step's pair."""
        left, right = step.dets
        if step.point is not None or left is None or right is None:
            return
        step.point, step.epi = self.flight_vouched_pair(left, right, step.guide.get())
        if step.point is not None:
            step.fired("flight_vouch")
            return
        step.point, step.epi = self.continued_pair(left, right, step.t)
        if step.point is not None:
            step.fired("pair_continuity")


def _rejected(result: CameraResult, gone: set[int]) -> CameraResult:
    """``result`` with the candidates whose ids are in ``gone`` rejected (``REJECT_STEREO``)."""
    return dataclasses.replace(result, candidates=tuple(
        dataclasses.replace(c, rejected_by=REJECT_STEREO) if id(c) in gone else c for c in result.candidates))

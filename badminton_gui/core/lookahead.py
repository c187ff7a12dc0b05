"""Look-ahead readout: each frame's 2D detection re-decided once the next K frames are known.

Why this file exists: the online pipeline must decide frame t with frames ≤ t only. A flight's
first frames are then lost (a tracklet may supply the detection only once it is confirmed,
``association.min_hits``), and after a racket hit the followed tracklet keeps its hysteresis on
the racket or the hand for a few frames before the shuttle's own tracklet wins. K frames later
both are plain to see: the tracklet the readout follows next is known, so its earlier
candidates are the shuttle too. Offline (the file CLI) that costs nothing; online it costs K
frames of latency (K / fps seconds). This module holds the readout back by K frames and
re-decides the oldest one from the tracklets' futures; it reads what the online pipeline
produced (candidates with their ``Candidate.tracklet`` ids, the online choice) and never feeds
back into it, so the online tracking, its 3D flight filter and the robot's live stream are
unchanged by it.

Two rules, per camera, for frame t with the online readouts of frames t+1 … t+K:

* **back-fill**: no online detection at t (or only the coasting prediction of a tracklet the
  readout does not follow again), and the next tracklet the readout follows (for at
  least ``lookahead.min_support`` of the K frames) had a candidate at t: that candidate is the
  detection (a flight's unconfirmed first frames; a frame where the followed tracklet's blob
  was refused for a moment; the shuttle's first frame after a hit while the racket's
  tracklet coasted).
* **switch**: the online detection at t is on tracklet A, the readout later hands over to
  tracklet B for good within the window (A is not followed again after B's first frame, and B
  is followed at least ``min_support`` frames), and B had a candidate at t: B's candidate is
  the detection (the racket or hand kept by hysteresis after a hit, while the shuttle left on
  B). The handover must be clean: a readout that hops back to A keeps A.

A candidate taken this way is led to the cork like the online readout (``colour.head_lead`` ×
its width along its tracklet's image velocity, measured on the tracklet's neighbouring
candidates). For the stereo tracker (:class:`StereoLookahead`) each camera is re-decided on its
own; a frame with no online 3D point whose two detections were both taken by the look-ahead gets
the triangulation of their centroids when epipolar-consistent (the online flight filter's point
stays everywhere else). A flight's first points have none online either: the flight filter
refuses a point no flight explains, and those points grow the track that becomes the next
flight a few frames later. When it does (``FlightInfo.confirmed``), the frames they came from get
the track's fitted path there, and so does a frame the track left out whose measured point lies
within ``CONFIRM_GATE_M`` of that path; likewise, when the followed flight takes a point again
after refusing a few, those frames whose measured point lies that close to its path
(``FlightInfo.confirmed_path``). The file readout holds its decided frames ``CONFIRM_HOLD_S``
longer for it (NYCU rallies: a 3D point on 92.3 -> 96.8 % of the frames in flight both cameras
report; twenty-ninth round, benchmarks/README.md).

A third rule, off unless ``lookahead.lead_in_run`` is set (the broadcast preset), runs on the
decided frames: **lead-in**. A run of that many detections on one tracklet is followed back from
its first frame through the earlier frames, each time to the nearest blob within
``lead_in_radius`` of the last one taken, whatever the filters said of it (not one too large for
a shuttle). On TV the shuttle held before the serve moves a few pixels a frame, is often shorter
than filter 1 allows and never travels, yet is labelled visible; the rally it starts is plain
to see once the serve flies. The chain stops at a gap and at a run of its own length on another
tracklet (an earlier flight); it goes on through a report it reaches (within the radius: the
held shuttle reported for a moment, kept as it is); a shorter report elsewhere (a hand, a shoe
the association followed for a few frames while the shuttle was held) is replaced. A run is
counted per tracklet, so that such a report just before the serve does not become the run's
first frames. A chain that would replace more than ``lead_in_max_replaced`` reports is dropped
whole: it ran beside a flight reported on short tracklets (bwf_00025 frames 13-73: a still blob
beside the serve, whose flight the chain would have replaced for 36 frames). With
``lead_in_through`` off the chain stops at any report and a run is any unbroken detections: the
adaptation's first pass (core/adaptation.py) leads in so, since the frames the chain replaces
are the least sure and its pseudo-labels must be sure. The lead-in
holds the decided frames back ``lead_in_frames`` + the run's frames more, so it is off with
``lookahead.frames`` 0 (the live readout). Not for the two-camera tracker (its labels call the
held shuttle not visible, and its 3D points are not re-made from a lead-in):
:class:`StereoLookahead` turns it off. Chosen leave-one-clip-out (benchmarks/README.md): runs of
10 frames, 12 px (twenty-sixth round); through shorter reports, runs per tracklet, not in the
adaptation's pass, at most 10 replaced (twenty-seventh: 81.60 -> 84.03 % mean over seeds 0/1/2).

The lead-in stage also **fills gaps** (``lookahead.gap_fill_frames``, the broadcast preset's 6):
as a result leaves it, a frame with no detection (or only a coasting prediction) between two
real detections at most that many frames apart takes the blob nearest the straight line between
them, within ``gap_fill_radius``, whatever the filters said of it — on TV mostly a far-court
shuttle too short for filter 1 for a frame or two, or one the association let go while another
tracklet held the readout. Off in the adaptation's pass (a point on a line is no sure label).
Leave-one-clip-out: 83.26 / 84.10 / 84.72 -> 83.99 / 84.82 / 84.82 % (twenty-seventh round).
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from typing import Callable

import numpy as np

from .params import TrackerParams
from .flight.shot_filter import position_on_path
from .types import REJECT_SCORE, CameraResult, Candidate, TrackResult


@dataclasses.dataclass(slots=True)
class _Frame:
    t: float
    result: CameraResult
    # tracklet id → the frame's (real, associated) candidate on it
    on: dict[int, Candidate]
    followed: int              # tracklet of the online detection (-1: none or on no tracklet)
    # A tracklet seen leaving the picture just after this frame, on it without a break since
    # (``CameraResult.left_picture``): it was the shuttle, whatever the readout followed.
    left: int = -1
    # Steps after this one that brought no new image from this camera (``StereoFrame.fresh_left``
    # / ``fresh_right``): each is handed out as this frame's decided result again.
    repeats: int = 0


class CameraLookahead:
    """Delays one camera's readout by ``lookahead.frames`` and re-decides it from the future."""

    def __init__(self, params: TrackerParams | None = None) -> None:
        self.params = params or TrackerParams()
        self._buffer: deque[_Frame] = deque()
        self._past: _Frame | None = None   # the last frame handed out (velocity of a back-fill)
        # The last online result pushed and the last decided one: a step that brought no new
        # image from this camera pushes its last result again (the same object).
        self._last_online: CameraResult | None = None
        self._last_decided: CameraResult | None = None
        # lead_in_over: frames the lead-in took in place of a shorter track's report;
        # lead_in_refused: chains dropped whole (``lookahead.lead_in_max_replaced``).
        self.changes = {"backfill": 0, "switch": 0, "exit": 0, "lead_in": 0, "lead_in_over": 0,
                        "lead_in_refused": 0, "gap_fill": 0}
        # id(decided CameraResult) → the taken candidate's measured centroid (before the lead to
        # the cork), for the stereo re-triangulation; read and removed by StereoLookahead.
        self.centroids: dict[int, tuple[float, float]] = {}
        self.keep_centroids = False
        # The lead-in stage: decided results held back, and the length of the run of real
        # detections that ends the held frames.
        self.lead_in = True
        self._held: deque[CameraResult] = deque()
        # Per held result: the length so far of its track segment (consecutive real detections
        # on one tracklet, counted from before the held window too; 0: no real detection).
        self._held_runs: deque[int] = deque()
        self._run = 0
        self._run_tracklet = -1
        # The gap fill: results released so far, and the last released real detection
        # (its index, x, y): a gap's start.
        self._released = 0
        self._last_real: tuple[int, float, float] | None = None

    @property
    def frames(self) -> int:
        return int(self.params.lookahead.frames)

    def reset(self) -> None:
        self._buffer.clear()
        self._past = None
        self._last_online = self._last_decided = None
        self._held.clear()
        self._held_runs.clear()
        self._run = 0
        self._run_tracklet = -1
        self._released = 0
        self._last_real = None

    def push(self, result: CameraResult, t: float) -> list[CameraResult]:
        """Add this frame's online result; return the results now decided, in order (one per
        push in the end). The same result pushed again (a step with no new image from this
        camera) is no new frame: it is handed out as that frame's decision, when it is made."""
        if result is self._last_online:
            if self._buffer:
                self._buffer[-1].repeats += 1
                return []
            return [self._last_decided]
        self._last_online = result
        det = result.detection
        on = {c.tracklet: c for c in result.candidates
              if c.tracklet >= 0 and not c.predicted and c is not det}
        if det is not None and det.tracklet >= 0 and not det.predicted:
            on[det.tracklet] = det
        followed = det.tracklet if det is not None else -1
        if result.left_picture >= 0:
            # The tracklet that left through the top edge was the shuttle (the online readout
            # may have followed a player meanwhile): its candidates of the held-back frames,
            # back to its last gap, are the detections.
            for f in reversed(self._buffer):
                if result.left_picture not in f.on:
                    break
                f.left = result.left_picture
        self._buffer.append(_Frame(t, result, on, followed))
        out = []
        while len(self._buffer) > self.frames:
            out.extend(self._decide())
        return self._lead_in(out)

    def flush(self) -> list[CameraResult]:
        """The frames still held back (end of the video), decided with what future there is."""
        out = []
        while self._buffer:
            out.extend(self._decide())
        out = self._lead_in(out)
        while self._held:
            out.append(self._release())
        return out

    # ---------------------------------------------------------------------------------------
    def _lead_in(self, decided: list[CameraResult]) -> list[CameraResult]:
        """The decided results through the lead-in stage (the module docstring): those now final."""
        lp = self.params.lookahead
        if lp.lead_in_run <= 0 or not self.lead_in or self.frames == 0:
            # (look-ahead 0 is the live readout, `detect --lookahead 0`: no delay at all)
            return decided
        out = []
        for result in decided:
            det = result.detection
            if det is None or det.predicted:
                self._run = 0
            elif self._run and (det.tracklet == self._run_tracklet or not lp.lead_in_through):
                self._run += 1
            else:
                # Another tracklet starts another segment: clutter reported just before the
                # serve must not become the first frames of the serve's run.
                self._run, self._run_tracklet = 1, det.tracklet
            self._held.append(result)
            self._held_runs.append(self._run)
            if self._run == lp.lead_in_run:
                self._follow_back(len(self._held) - self._run)
            while len(self._held) > lp.lead_in_run + lp.lead_in_frames:
                out.append(self._release())
        return out

    def _release(self) -> CameraResult:
        """The oldest held result, final: its gap filled when it lies in one (the module docstring)."""
        self._held_runs.popleft()
        result = self._held.popleft()
        index, self._released = self._released, self._released + 1
        det = result.detection
        if det is not None and not det.predicted:
            self._last_real = (index, det.x, det.y)
            return result
        lp = self.params.lookahead
        if lp.gap_fill_frames <= 0 or self._last_real is None:
            return result
        a, xa, ya = self._last_real
        for j, later in enumerate(self._held):
            b = index + 1 + j
            if b - a - 1 > lp.gap_fill_frames:
                return result                 # the gap is too long (or has no end in sight)
            d = later.detection
            if d is not None and not d.predicted:
                break
        else:
            return result
        f = (index - a) / (b - a)
        x, y = xa + f * (d.x - xa), ya + f * (d.y - ya)
        best = self._nearest_blob(result, x, y, lp.gap_fill_radius * (result.image_size[0] or 1280) / 1280.0)
        if best is None:
            return result
        self.changes["gap_fill"] += 1
        return self._taken(result, best)

    def _in_long_segment(self, k: int) -> bool:
        """The held result k's detection is part of a segment of at least ``lead_in_run``."""
        runs, end = self._held_runs, k
        while end + 1 < len(runs) and runs[end + 1] == runs[end] + 1 and runs[end] > 0:
            end += 1
        return runs[end] >= self.params.lookahead.lead_in_run

    def _follow_back(self, start: int) -> None:
        """Give the held frames before ``start`` (a run's first) the blobs that lead to it."""
        lp = self.params.lookahead
        first = self._held[start]
        x, y = first.detection.x, first.detection.y
        width = first.image_size[0] or 1280
        radius = lp.lead_in_radius * width / 1280.0
        taken: list[tuple[int, Candidate, Candidate | None]] = []   # (held index, blob, report replaced)
        for k in range(start - 1, max(start - 1 - lp.lead_in_frames, -1), -1):
            result = self._held[k]
            old = result.detection
            if old is not None:
                if not lp.lead_in_through or self._in_long_segment(k):
                    break                    # an earlier flight, a run of its own
                if math.hypot(old.x - x, old.y - y) <= radius:
                    # The held shuttle reported already (a still blob the association let
                    # through, a short tracklet on it): kept, and the chain goes on from it.
                    x, y = old.x, old.y
                    continue
            best = self._nearest_blob(result, x, y, radius)
            if best is None:
                break
            taken.append((k, best, old))
            x, y = best.x, best.y
        replaced = sum(old is not None for _, _, old in taken)
        if replaced > lp.lead_in_max_replaced:
            # A still blob beside a flight whose reports are on short tracklets each: the chain
            # would replace the flight, not a hand's few frames. Not a lead-in.
            self.changes["lead_in_refused"] += 1
            return
        for k, best, _ in taken:
            self._held[k] = self._taken(self._held[k], best)
        self.changes["lead_in"] += len(taken)
        self.changes["lead_in_over"] += replaced

    def _nearest_blob(self, result: CameraResult, x: float, y: float, radius: float) -> Candidate | None:
        """The frame's blob nearest (x, y) within ``radius`` px, whatever the filters said of it
        — but never one too large for a shuttle (a player, a racket)."""
        p = self.params
        best, best_d = None, radius
        for c in result.candidates:
            if (c.predicted or c.length > p.contour_length.max_length
                    or c.short_side > p.tilted_rect.max_short_side):
                continue
            d = math.hypot(c.x - x, c.y - y)
            if d <= best_d:
                best, best_d = c, d
        return best

    @staticmethod
    def _taken(result: CameraResult, blob: Candidate) -> CameraResult:
        """The result with ``blob`` as its detection; the report it replaces marked as a loser."""
        old = result.detection
        chosen = dataclasses.replace(blob, rejected_by=None)
        return dataclasses.replace(result, detection=chosen, candidates=tuple(
            chosen if c is blob else dataclasses.replace(c, rejected_by=REJECT_SCORE) if c is old else c
            for c in result.candidates))

    # ---------------------------------------------------------------------------------------
    def _decide(self) -> list[CameraResult]:
        frame = self._buffer[0]
        future = [f.followed for f in list(self._buffer)[1:]]
        chosen = self._choice(frame, future)
        result = frame.result
        if chosen is not None:
            raw = frame.on[chosen.tracklet]
            result = _with_detection(result, chosen)
            if self.keep_centroids:
                self.centroids[id(result)] = (raw.x, raw.y)
        self._buffer.popleft()
        # Back-fills of the next frames measure their velocity on this frame's candidates.
        self._past = dataclasses.replace(frame, result=result)
        self._last_decided = result
        return [result] * (1 + frame.repeats)

    def _choice(self, frame: _Frame, future: list[int]) -> Candidate | None:
        """The candidate that replaces frame's online detection, or None to keep it."""
        lp = self.params.lookahead
        det = frame.result.detection
        if frame.left >= 0 and (det is None or det.tracklet != frame.left):
            self.changes["exit"] += 1
            return self._lead(frame, frame.on[frame.left])
        if not future or (det is not None and det.tracklet < 0):
            # Nothing to look at, or the online readout came from the 3D flight (a guided spot):
            # the stereo tracker knew something the tracklets do not.
            return None
        # A coasting prediction of a tracklet the readout never follows again was a guess
        # that did not come true (the racket's track after a hit, 1_02_01 130): as no detection.
        lost_guess = det is not None and det.predicted and det.tracklet not in future
        if det is None or lost_guess:
            if not lp.backfill:
                return None
            # The next tracklet the readout follows.
            nxt = next((tr for tr in future if tr >= 0), -1)
            if nxt < 0 or nxt not in frame.on or sum(tr == nxt for tr in future) < lp.min_support:
                return None
            if not self._flies(nxt, future.index(nxt) + 1):
                return None
            self.changes["backfill"] += 1
            return self._lead(frame, frame.on[nxt])
        if not lp.switch:
            return None
        # The online readout is on tracklet A (a coasting prediction counts as A): does the
        # readout leave A for good within the window, and for which tracklet?
        current = det.tracklet
        after = len(future) - future[::-1].index(current) if current in future else 0
        nxt = next((tr for tr in future[after:] if tr >= 0), -1)
        if nxt < 0 or nxt not in frame.on:
            return None
        first = after + future[after:].index(nxt)
        if first >= lp.max_switch_delay or sum(tr == nxt for tr in future) < lp.min_support:
            return None
        frames = list(self._buffer)
        if lp.switch_needs_alive and current not in frames[first + 1].on:
            # A was lost (not handed over while still seen: the shuttle's own tracklet ending
            # at a hit or a hiding place), so B is no proof that A was something else.
            return None
        if not self._flies(nxt, first + 1):
            return None
        if lp.switch_needs_alive:
            # After a hit the shuttle leaves the racket: B moves away from A. A racket (or a
            # player) closing in on the shuttle that then keeps its tracklet moves towards it.
            a_now, b_now = frame.on.get(current, det), frame.on[nxt]
            a_then, b_then = frames[first + 1].on[current], frames[first + 1].on.get(nxt)
            if b_then is not None and (math.hypot(a_now.x - b_now.x, a_now.y - b_now.y)
                                       > math.hypot(a_then.x - b_then.x, a_then.y - b_then.y)):
                return None
        self.changes["switch"] += 1
        return self._lead(frame, frame.on[nxt])

    def _flies(self, ident: int, until: int) -> bool:
        """Tracklet ``ident`` moves from the oldest frame on, on a smooth path up to ``until``.

        A tracklet that later holds the shuttle may have been something else before: the
        shuttle held still in the hand before the serve (labelled invisible), or a racket's
        tracklet that the shuttle took over by a jump off its path. Neither is the shuttle.
        """
        lp = self.params.lookahead
        path = []
        for f in list(self._buffer)[:until + 1]:
            c = f.on.get(ident)
            if c is not None:
                path.append((f.t, c.x, c.y))
        if len(path) < 2:
            return False
        (t0, x0, y0), (t1, x1, y1) = path[0], path[1]
        if math.hypot(x1 - x0, y1 - y0) < lp.min_speed * (t1 - t0):
            return False
        jump = self.params.association.jump_residual
        if jump <= 0:
            return True
        for (ta, xa, ya), (tb, xb, yb), (tc, xc, yc) in zip(path, path[1:], path[2:]):
            r = (tc - tb) / max(tb - ta, 1e-9)
            if math.hypot(xc - (xb + (xb - xa) * r), yc - (yb + (yb - ya) * r)) > jump:
                return False
        return True

    def _lead(self, frame: _Frame, cand: Candidate) -> Candidate:
        """The candidate moved forward along its tracklet to the cork (see ``lead_to_head``)."""
        c = self.params.colour
        if c.head_lead <= 0 or not math.isfinite(cand.short_side):
            return dataclasses.replace(cand, rejected_by=None)
        points = []
        neighbours = [self._past] + list(self._buffer)[1:2]
        for other in neighbours:
            if other is None:
                continue
            o = other.on.get(cand.tracklet)
            if o is not None and other.t != frame.t:
                points.append((other.t, o.x, o.y))
        if not points:
            return dataclasses.replace(cand, rejected_by=None)
        points.append((frame.t, cand.x, cand.y))
        points.sort()
        (t0, x0, y0), (t1, x1, y1) = points[0], points[-1]
        vx, vy = (x1 - x0) / (t1 - t0), (y1 - y0) / (t1 - t0)
        speed = math.hypot(vx, vy)
        if speed < c.head_lead_min_speed:
            return dataclasses.replace(cand, rejected_by=None)
        lead = c.head_lead * cand.short_side / speed
        w, h = frame.result.image_size
        x, y = cand.x + lead * vx, cand.y + lead * vy
        if w > 0 and not (-0.5 <= x < w - 0.5 and -0.5 <= y < h - 0.5):
            return dataclasses.replace(cand, rejected_by=None)
        return dataclasses.replace(cand, x=x, y=y, rejected_by=None)


def _with_detection(result: CameraResult, chosen: Candidate) -> CameraResult:
    """The result with ``chosen`` as its detection (the old one marked as a loser)."""
    old = result.detection
    cands = []
    replaced = False
    for c in result.candidates:
        if c is old:
            c = dataclasses.replace(c, rejected_by=REJECT_SCORE)
        elif not replaced and c.tracklet == chosen.tracklet and not c.predicted and old is not c:
            c, replaced = chosen, True
        cands.append(c)
    if not replaced:
        cands.append(chosen)
    return dataclasses.replace(result, detection=chosen, candidates=tuple(cands))


# s: how long the file readout holds its decided frames for a flight's first points (``_confirm``;
# 1.0 s gave the same points on the NYCU tuned-on rallies).
CONFIRM_HOLD_S = 0.25
# m: a held frame the new flight's track left out (a point it dropped as inconsistent, one
# measured just before it) takes the flight's path where its own measured point lies this close
# to it, from CONFIRM_BEFORE_S (s) before the track's first point on. At 0.10 m one of the NYCU
# tuned-on rallies' 65 such points was a wrong 2D pair 51 cm off; at 0.05 m, 41 points, all
# within 9 cm of the triangulated labels (twenty-ninth round).
CONFIRM_GATE_M = 0.05
CONFIRM_BEFORE_S = 0.05


class StereoLookahead:
    """Both cameras' readouts of :class:`TrackResult` delayed and re-decided (``track``).

    ``rig`` triangulates a rewritten pair; ``tolerance()`` is the epipolar gate in force
    (``StereoTracker.epipolar_tolerance``).
    """

    def __init__(self, rig, params: TrackerParams | None = None,
                 tolerance: Callable[[], float] | None = None,
                 confirm_hold: float | None = None) -> None:
        self.rig = rig
        self.params = params or TrackerParams()
        self.left = CameraLookahead(self.params)
        self.right = CameraLookahead(self.params)
        self.left.keep_centroids = self.right.keep_centroids = True
        # Per camera, a lead-in would give 2D points with no 3D (module docstring).
        self.left.lead_in = self.right.lead_in = False
        self._tolerance = tolerance or (lambda: float(self.params.stereo.max_epipolar_error))
        self._results: deque[TrackResult] = deque()
        # Each camera's decided results not yet zipped: with steps that bring one camera's image
        # only, the two cameras' decisions come out at different pushes.
        self._lefts: deque[CameraResult] = deque()
        self._rights: deque[CameraResult] = deque()
        self.retriangulated = 0
        self.confirmed = 0   # held frames given a point a later flight took up (``_confirm``)
        # Decided frames held on a while longer (look-ahead on only: the file readout), for a
        # flight that begins from points older than the look-ahead's window. ``confirm_hold``
        # given: that long instead (the GUI's delayed view gives 0: its display waits for the
        # readout, so it holds exactly the look-ahead's frames and no more).
        if confirm_hold is None:
            confirm_hold = CONFIRM_HOLD_S if self.frames > 0 else 0.0
        self.confirm_hold = float(confirm_hold)
        self._decided: deque[TrackResult] = deque()

    @property
    def frames(self) -> int:
        return self.left.frames

    def push(self, result: TrackResult) -> list[TrackResult]:
        out = []
        if self._decided and result.timestamp < self._decided[-1].timestamp:
            # The clock went back (another recording): what was held goes out now, and no point
            # of the new one is matched with a frame of the old by its time.
            out += self._decided
            self._decided.clear()
        self._results.append(result)
        if result.flight.confirmed or result.flight.confirmed_path:
            self._confirm(result.flight.confirmed, result.flight.confirmed_path)
        self._decided.extend(self._zip(self.left.push(result.left, result.timestamp),
                                       self.right.push(result.right, result.timestamp)))
        while self._decided and self._decided[0].timestamp <= result.timestamp - self.confirm_hold:
            out.append(self._decided.popleft())
        return out

    def flush(self) -> list[TrackResult]:
        self._decided.extend(self._zip(self.left.flush(), self.right.flush()))
        out = list(self._decided)
        self._decided.clear()
        return out

    def _zip(self, lefts: list[CameraResult], rights: list[CameraResult]) -> list[TrackResult]:
        self._lefts.extend(lefts)
        self._rights.extend(rights)
        out = []
        while self._lefts and self._rights:
            left, right = self._lefts.popleft(), self._rights.popleft()
            online = self._results.popleft()
            if left is online.left and right is online.right:
                out.append(online)
                continue
            out.append(self._rewrite(online, left, right))
        return out

    def _confirm(self, points: tuple, path: tuple = ()) -> None:
        """A flight began at the newest frame from a track of points the online readout had
        refused (``FlightInfo.confirmed``): each held frame with no 3D point whose time is one of
        them gets the track's path there, and so does one whose measured point lies within
        ``CONFIRM_GATE_M`` of the path (``path``: ``FlightInfo.confirmed_path``). Without
        ``points`` (the followed flight took the newest frame's point), only the frames since
        the last one with a point are looked at. Online the robot got nothing there (the flight
        filter cannot vouch for a flight's first points before it is one); a moment later it can."""
        at = {round(p[0], 9): p[1:4] for p in points}
        # A new flight: from a moment before its first point. A point the flight took: the frames
        # since the last one with a point.
        first = min(p[0] for p in points) - CONFIRM_BEFORE_S if points else None
        held = [(frames, k) for frames in (self._decided, self._results) for k in range(len(frames))]
        for frames, k in reversed(held[:-1]):   # (the newest is the step that brought them)
            frame = frames[k]
            if frame.point is not None:
                if first is None:
                    break
                continue
            if first is not None and frame.timestamp < first:
                continue
            xyz = at.get(round(frame.timestamp, 9))
            if xyz is None and path and frame.measured_point is not None:
                on_path = position_on_path(path, frame.timestamp)
                if math.dist(on_path, frame.measured_point) <= CONFIRM_GATE_M:
                    xyz = on_path
            if xyz is None:
                continue
            frames[k] = dataclasses.replace(
                frame, point=tuple(xyz), predicted_distance=None,
                distance=float(np.linalg.norm(self.rig.to_left([xyz])[0])))
            self.confirmed += 1

    def _rewrite(self, online: TrackResult, left: CameraResult, right: CameraResult) -> TrackResult:
        dl, dr = left.detection, right.detection
        point, distance, epi = online.point, online.distance, online.epipolar_error
        # The measured centroids of taken candidates (the online pipeline also triangulates the
        # centroids, not the cork-led points: two leads disagree by a disparity error).
        cl = self.left.centroids.pop(id(left), None)
        cr = self.right.centroids.pop(id(right), None)
        if point is None and cl is not None and cr is not None:
            # Only where the online pipeline had no point (its flight filter's point, with the
            # drag model and the cork correction, beats one raw triangulation: demo court seed 0,
            # 3D RMS 1.00 → 1.44 cm when every rewritten frame was re-triangulated), and only a
            # pair both of whose halves the look-ahead took: a taken candidate paired with the
            # other camera's online detection met its epipolar line by chance on the demo court
            # (seed 2 frame 889: 1.5 px off the line, 1.6 m off the shuttle).
            pl, pr = [list(cl)], [list(cr)]
            err = float(self.rig.epipolar_errors(pl, pr)[0, 0])
            if err <= self._tolerance():
                p = self.rig.triangulate(pl, pr)[0]
                dist = float(np.linalg.norm(p))
                sp = self.params.stereo
                if p[2] > 0 and sp.min_distance <= dist <= sp.max_distance:
                    point = tuple(float(v) for v in self.rig.to_output(p)[0])
                    distance, epi = dist, err
                    self.retriangulated += 1
        return dataclasses.replace(online, left=left, right=right, point=point, distance=distance,
                                   epipolar_error=epi,
                                   predicted_distance=None if point is not None else online.predicted_distance)


class MonoLookahead:
    """One camera's :class:`TrackResult` readout (``MonoTracker``: a TV clip played in the GUI)
    delayed and re-decided by :class:`CameraLookahead` — the rules ``detect`` applies to a file,
    lead-in and gap fill included, so the desktop tool shows the command line's rows."""

    def __init__(self, params: TrackerParams | None = None) -> None:
        self.camera = CameraLookahead(params)
        self._online: deque[TrackResult] = deque()

    @property
    def params(self) -> TrackerParams:
        return self.camera.params

    @property
    def frames(self) -> int:
        return self.camera.frames

    def push(self, result: TrackResult) -> list[TrackResult]:
        """This step's online result in; the results now decided out, in order (one per push in
        the end)."""
        self._online.append(result)
        return self._zip(self.camera.push(result.left, result.timestamp))

    def flush(self) -> list[TrackResult]:
        return self._zip(self.camera.flush())

    def _zip(self, decided: list[CameraResult]) -> list[TrackResult]:
        out = []
        for camera in decided:
            online = self._online.popleft()
            out.append(online if camera is online.left else dataclasses.replace(online, left=camera))
        return out


class DelayedReadout:
    """The look-ahead readout with what came with each frame: a display shows a frame only with
    its decided result, so it keeps the frame (its image, labels, arrival time: ``payload``) until
    the look-ahead hands that frame's result out.

    ``frames`` 0 passes every result straight through (the live view). Else a one-camera
    readout (``rig`` None) goes through :class:`MonoLookahead`, a stereo one through
    :class:`StereoLookahead` without the file readout's extra hold (``confirm_hold`` 0), so a
    display waits exactly ``frames`` steps. The look-ahead's other rules come from ``params``."""

    def __init__(self, params: TrackerParams, frames: int, rig=None,
                 tolerance: Callable[[], float] | None = None) -> None:
        self.frames = max(0, int(frames))
        self._payloads: deque = deque()
        self._lookahead: StereoLookahead | MonoLookahead | None = None
        if self.frames > 0:
            params = params.with_value("lookahead.frames", self.frames)
            self._lookahead = (MonoLookahead(params) if rig is None
                               else StereoLookahead(rig, params, tolerance, confirm_hold=0.0))

    def push(self, result: TrackResult, payload) -> list[tuple[TrackResult, object]]:
        """This step's online result and its payload in; (decided result, its payload) out for
        every frame now decided, oldest first."""
        if self._lookahead is None:
            return [(result, payload)]
        self._payloads.append(payload)
        return self._paired(self._lookahead.push(result))

    def flush(self) -> list[tuple[TrackResult, object]]:
        """Every frame still held, decided with the future there is (the source ended, the
        settings changed)."""
        if self._lookahead is None:
            return []
        return self._paired(self._lookahead.flush())

    @property
    def params(self) -> TrackerParams | None:
        """The parameters the look-ahead decides with (None: the live view, nothing decided)."""
        return None if self._lookahead is None else self._lookahead.params

    def set_params(self, params: TrackerParams) -> None:
        """Decide with these parameters from now on, the frames held included (a filter tuned
        while watching). The look-ahead's own group must not change: another look-ahead is a
        new readout."""
        if self._lookahead is None:
            return
        params = params.with_value("lookahead.frames", self.frames)
        if params.lookahead != self._lookahead.params.lookahead:
            raise ValueError("other look-ahead rules need a new DelayedReadout")
        if isinstance(self._lookahead, MonoLookahead):
            self._lookahead.camera.params = params
        else:
            self._lookahead.params = self._lookahead.left.params = self._lookahead.right.params = params

    @property
    def held(self) -> int:
        """Frames pushed and not yet handed out."""
        return len(self._payloads)

    def _paired(self, decided: list[TrackResult]) -> list[tuple[TrackResult, object]]:
        # Both look-aheads hand out one result per result pushed, in order (a stereo step that
        # brought one camera's image only included), so the payloads pair first in, first out.
        return [(result, self._payloads.popleft()) for result in decided]

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
report).

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
:class:`StereoLookahead` turns it off. Chosen leave-one-clip-out: runs of 10 frames, 12 px;
through shorter reports, runs per tracklet, not in the adaptation's pass, at most 10 replaced
(81.60 -> 84.03 % mean over seeds 0/1/2).

The lead-in stage also **fills gaps** (``lookahead.gap_fill_frames``, the broadcast preset's 6):
as a result leaves it, a frame with no detection (or only a coasting prediction) between two
real detections at most that many frames apart takes the blob nearest the straight line between
them, within ``gap_fill_radius``, whatever the filters said of it — on TV mostly a far-court
shuttle too short for filter 1 for a frame or two, or one the association let go while another
tracklet held the readout. Off in the adaptation's pass (a point on a line is no sure label).
Leave-one-clip-out: 83.26 / 84.10 / 84.72 -> 83.99 / 84.82 / 84.82 % at seeds 0 / 1 / 2.

Where the parts live: this module re-decides one camera's readout (:class:`CameraLookahead`);
``track_lookahead.py`` pairs two of them into :class:`TrackResult` rows (:class:`StereoLookahead`,
:class:`MonoLookahead`) with the flight's confirmed points, and holds the GUI's
``DelayedReadout``.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque

from .params import TrackerParams
from .types import REJECT_SCORE, CameraResult, Candidate


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

"""Multi-frame association: candidates of successive frames joined into smooth image paths.

Why this file exists: on real courts most blobs that pass the paper's three shape/colour filters
are *not* the shuttle (hands, rackets, shoes, flickering lights, a shuttle lying on the floor).
What sets the shuttle apart is its motion over several frames: it moves on a smooth, nearly
ballistic image path and never stays put for long while in play. The paper's filter 4 ("distance
from the previous frame's shuttle") is the one-frame version of that idea; here every candidate
can start a *tracklet*, tracklets are extended by speed-aware gating (the gate grows with the
tracklet's own image speed, so a smash is not lost), and only tracklets that are confirmed (hit
in enough frames, smooth, and actually travelling) may supply the detection. The choice between
confirmed tracklets has hysteresis: the one being followed keeps the lead while it is hit.

Everything is causal: a tracklet is confirmed after ``min_hits`` frames (one fewer when its
candidates look clearly like a shuttle), which costs those first frames of each flight (no
look-ahead, no latency). A step far off the predicted path breaks the tracklet's travel record,
so a tracklet that hopped onto a static glint cannot claim the flight's travel to "pause" there;
the followed tracklet survives a blind spot (a light, a white line) for ``motion.coast_blind``
frames.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from typing import Callable

import numpy as np

from .params import AssociationParams, MotionParams


@dataclasses.dataclass(slots=True)
class Tracklet:
    """One hypothesis of an object moving on a smooth image path."""

    ident: int
    x: float
    y: float
    t: float
    start_x: float
    start_y: float
    vx: float = 0.0
    vy: float = 0.0
    hits: int = 1
    misses: int = 0            # consecutive frames without a candidate
    residual: float = 0.0      # running mean of |measured - predicted| (px)
    quality: float = 0.0       # running mean of the candidates' own scores
    travel: float = 0.0        # largest distance from the start point (px)
    hit_now: bool = True
    velocity_known: bool = False
    still_for: int = 0         # hits since the tracklet last travelled min_travel in the window
    recent: deque = dataclasses.field(default_factory=lambda: deque(maxlen=64))

    def recent_travel(self, frames: int) -> float:
        """Net displacement (px) over the last ``frames`` hits: static clutter stays near 0."""
        if len(self.recent) < 2:
            return 0.0
        k = min(frames, len(self.recent) - 1)
        x0, y0 = self.recent[-1 - k]
        return math.hypot(self.x - x0, self.y - y0)

    @property
    def speed(self) -> float:
        return math.hypot(self.vx, self.vy)

    def predict(self, t: float) -> tuple[float, float]:
        dt = t - self.t
        return self.x + self.vx * dt, self.y + self.vy * dt


class TrackletAssociator:
    """Keeps the tracklets of one camera and says which candidates lie on a confirmed one."""

    def __init__(self, motion: MotionParams, association: AssociationParams) -> None:
        self.motion = motion
        self.params = association
        self.tracklets: list[Tracklet] = []
        self.selected: int | None = None
        # The followed tracklet after it was dropped (hidden by the racket or a player):
        # a candidate near it may still inherit its history for ``motion.lost_after`` s.
        self._ghost: Tracklet | None = None
        self._next_id = 0
        # The pixel values of the gates grow or shrink with the shuttle's image scale where a
        # tracklet is (``shuttle_scale.enabled``; set per frame by the detector; None: as given).
        self.scale = None

    def factor(self, tr: Tracklet) -> float:
        """The factor of the pixel values of the gates at the tracklet's image position."""
        return 1.0 if self.scale is None else self.scale.at1(tr.x, tr.y)

    def set_params(self, motion: MotionParams, association: AssociationParams) -> None:
        self.motion = motion
        self.params = association

    def reset(self) -> None:
        self.tracklets = []
        self.selected = None
        self._ghost = None

    # ---------------------------------------------------------------------------------------
    def gate(self, tr: Tracklet, dt: float) -> float:
        """Speed-aware gate radius (px): grows with the tracklet's own speed and the time step."""
        m = self.motion
        f = self.factor(tr)
        if not tr.velocity_known:
            # Unknown velocity: anything up to the fastest plausible image speed (with the
            # camera's geometry: the shuttle's top speed seen at its nearest from there).
            if self.scale is None:
                return m.base_radius + m.max_image_speed * dt
            return m.base_radius * f + self.scale.speed_at1(tr.x, tr.y) * dt
        return (m.base_radius * f + self.params.speed_gate_gain * tr.speed * dt
                + self.params.acceleration_px * f * (1 + tr.misses))

    def live_predictions(self, t: float) -> np.ndarray:
        """(N, 3) predicted x, y and gate of the tracklets seen at least twice."""
        rows = [(*tr.predict(t), self.gate(tr, max(t - tr.t, 1e-3)))
                for tr in self.tracklets if tr.hits >= 2]
        return np.asarray(rows, dtype=float).reshape(-1, 3)

    def match_costs(self, t: float, positions: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(tracklets × candidates distances to the predictions, gates, matching costs) of the
        live tracklets at ``t`` against ``positions`` (N, 2); changes nothing."""
        # Per tracklet: predicted x, y, gate and hits, in one pass (hits are small integers:
        # exact as floats).
        # ``history_needs_motion``: still clutter (a shoe, the crowd) claims by distance alone,
        # its age must not take the blob of a shuttle passing over it from the shuttle's
        # younger tracklet.
        p = self.params
        any_age = not p.history_needs_motion
        rows = np.array([(*tr.predict(t), self.gate(tr, max(t - tr.t, 1e-3)),
                          tr.hits if (any_age or tr.ident == self.selected
                                      or tr.recent_travel(p.travel_window) >= p.min_travel) else 0)
                         for tr in self.tracklets])
        gates = rows[:, 2]
        d = np.hypot(rows[:, None, 0] - positions[None, :, 0],
                     rows[:, None, 1] - positions[None, :, 1])
        cost = d / gates[:, None]
        # Established tracklets claim their candidates first (greedy by normalised cost,
        # with a bonus for history), so a new blob cannot steal a long track's point.
        cost = cost - 0.5 * np.minimum(rows[:, 3], 20)[:, None] / 20
        return d, gates, cost

    def update(self, t: float, positions: np.ndarray, scores: np.ndarray,
               blind: Callable[[float, float], bool] | None = None
               ) -> list[tuple[int, float, float]]:
        """Associate this frame's candidates; return per candidate (tracklet id, motion, merit).

        ``merit`` is ≥ 0 when the candidate continues a confirmed, travelling tracklet (the
        larger the better) and negative otherwise; ``motion`` is its distance from the
        tracklet's prediction (nan for a new tracklet). ``blind(x, y)`` (full-resolution px)
        says where the detector cannot see the shuttle: the followed tracklet survives there
        for ``motion.coast_blind`` frames instead of ``max_misses``.

        In steps: match the candidates to the tracklets' predictions → drop the lost tracklets
        → start new ones from the candidates left (one may inherit the followed tracklet's
        history) → each candidate's merit.
        """
        for tr in self.tracklets:
            tr.hit_now = False
        assigned, motion = self._match(t, positions, scores, blind)
        self._drop_lost(t, blind)
        ids = self._start_new(t, positions, scores, assigned)
        p = self.params
        if len(self.tracklets) > p.max_tracklets:
            self.tracklets.sort(key=lambda tr: (tr.hit_now, tr.hits), reverse=True)
            self.tracklets = self.tracklets[:p.max_tracklets]
        by_id = {tr.ident: tr for tr in self.tracklets}
        out = []
        for j in range(len(positions)):
            tr = by_id.get(ids[j])
            merit = self.merit(tr, float(scores[j])) if tr is not None else -1.0
            if merit >= 0 and p.candidate_weight > 0:
                # The running quality remembers ~5 frames: a followed tracklet that slid from
                # the shuttle onto a player's shoe keeps its good mean for a while; this
                # frame's own score tells sooner which candidate looks like the shuttle now.
                merit += p.candidate_weight * float(scores[j])
            out.append((ids[j], motion[j], merit))
        return out

    def _match(self, t: float, positions: np.ndarray, scores: np.ndarray,
               blind: Callable[[float, float], bool] | None) -> tuple[list[int], list[float]]:
        """Greedy matching by normalised cost inside the gates; each matched tracklet is
        extended. Returns per candidate (the tracklet ident it went to or -1, its distance
        from that tracklet's prediction or nan)."""
        n = len(positions)
        assigned = [-1] * n
        motion = [math.nan] * n
        if not (self.tracklets and n):
            return assigned, motion
        d, gates, cost = self.match_costs(t, positions)
        if self.params.followed_swap_margin < 1.0:
            self._favour_shuttle_like(d, gates, cost, scores)
        if self.params.blind_gate > 0 and blind is not None and self.selected is not None:
            self._narrow_blind_gate(gates, t, blind)
        order = np.argsort(cost, axis=None)
        # Only pairs inside the tracklet's gate can be taken: drop the others before the
        # Python loop (it used to visit all tracklets × candidates, ~800 pairs a frame, to
        # take a dozen), keeping the cost order; stop once either side is used up.
        in_gate = (d <= gates[:, None]).ravel()[order]
        used_t = set()
        used_c = set()
        n_tracklets = len(self.tracklets)
        for flat in order[in_gate].tolist():
            i, j = divmod(flat, n)
            if i in used_t or j in used_c:
                continue
            used_t.add(i)
            used_c.add(j)
            assigned[j] = self.tracklets[i].ident
            motion[j] = float(d[i, j])
            self._extend(self.tracklets[i], t, positions[j], scores[j], float(d[i, j]))
            if len(used_t) == n_tracklets or len(used_c) == n:
                break
        return assigned, motion

    def _favour_shuttle_like(self, d: np.ndarray, gates: np.ndarray, cost: np.ndarray,
                             scores: np.ndarray) -> None:
        """``followed_swap_margin``: after a hit the nearest blob to the followed path is often
        the racket or the hand that struck (larger, less white: a low quality) while the
        shuttle leaves on a path of its own inside the same gate: the followed tracklet takes
        the blob that looks far more like a shuttle (its cost is lowered in place)."""
        p = self.params
        for i, tr in enumerate(self.tracklets):
            if tr.ident != self.selected:
                continue
            if tr.quality < p.followed_swap_track_quality:
                return
            inside = np.flatnonzero(d[i] <= gates[i])
            if len(inside) < 2:
                return
            nearest = inside[np.argmin(cost[i, inside])]
            best = inside[np.argmax(scores[inside])]
            if scores[best] - scores[nearest] >= p.followed_swap_margin:
                cost[i, best] = cost[i, nearest] - 1e-3
            return

    def _narrow_blind_gate(self, gates: np.ndarray, t: float, blind: Callable[[float, float], bool]) -> None:
        """``blind_gate``: the followed shuttle predicted where the detector is blind (a light, a
        white line) cannot show there: a blob far from the prediction is something else (a
        hand, a racket) that would take the track over; the track coasts instead (its gate is
        narrowed in place)."""
        p = self.params
        for i, tr in enumerate(self.tracklets):
            if (tr.ident == self.selected and tr.velocity_known and tr.hits >= p.min_hits
                    and blind(*tr.predict(t))):
                gates[i] = min(gates[i], p.blind_gate * self.factor(tr))
                return

    def _drop_lost(self, t: float, blind: Callable[[float, float], bool] | None) -> None:
        """Count a miss for every tracklet not hit this frame and drop the lost ones; the
        followed one dropped becomes the ghost a candidate may still inherit from."""
        kept = []
        for tr in self.tracklets:
            if not tr.hit_now:
                tr.misses += 1
            if tr.misses <= self.params.max_misses or self._coasts(tr, t, blind):
                kept.append(tr)
            elif tr.ident == self.selected:
                self._ghost = tr
        self.tracklets = kept
        if self._ghost is not None and t - self._ghost.t > self.motion.lost_after:
            self._ghost = None

    def _start_new(self, t: float, positions: np.ndarray, scores: np.ndarray,
                   assigned: list[int]) -> list[int]:
        """Each candidate's tracklet ident: its match, or a new tracklet (the followed one's
        heir inherits its history, ``_heir``)."""
        heir = self._heir(t, positions, assigned, scores)
        ids = []
        for j in range(len(positions)):
            if assigned[j] >= 0:
                ids.append(assigned[j])
            elif j == heir:
                ids.append(self._inherit(t, positions[j], float(scores[j])))
            else:
                tr = Tracklet(self._next_id, float(positions[j, 0]), float(positions[j, 1]), t,
                              float(positions[j, 0]), float(positions[j, 1]),
                              quality=float(scores[j]))
                tr.recent.append((tr.x, tr.y))
                self._next_id += 1
                self.tracklets.append(tr)
                ids.append(tr.ident)
        return ids

    def _coasts(self, tr: Tracklet, t: float, blind) -> bool:
        """The followed, confirmed tracklet is predicted inside a blind spot: keep it."""
        return (blind is not None and tr.ident == self.selected and not tr.hit_now
                and tr.velocity_known and tr.hits >= self.params.min_hits
                and tr.misses <= self.motion.coast_blind and blind(*tr.predict(t)))

    def coasting(self, t: float, blind: Callable[[float, float], bool] | None
                 ) -> tuple[Tracklet, float] | None:
        """(followed tracklet, merit) when it was missed this frame inside a blind spot."""
        tr = self.followed
        if tr is None or tr not in self.tracklets or not self._coasts(tr, t, blind):
            return None
        p = self.params
        if tr.quality < p.min_track_quality:
            return None
        merit = (min(tr.hits, p.hits_saturation) / p.hits_saturation + p.quality_weight * tr.quality
                 - tr.residual / max(p.residual_scale * self.factor(tr), 1e-6) + p.hysteresis)
        return tr, max(merit, 0.0)

    @property
    def followed(self) -> Tracklet | None:
        """The followed tracklet: alive, or its ghost while a candidate may still inherit its
        history (``motion.lost_after``); None when nothing is followed."""
        for tr in self.tracklets:
            if tr.ident == self.selected:
                return tr
        if self._ghost is not None and self._ghost.ident == self.selected:
            return self._ghost
        return None

    @property
    def ghost(self) -> Tracklet | None:
        """The followed tracklet after it was dropped, while a candidate may still inherit it."""
        return self._ghost

    def tracklet(self, ident: int) -> Tracklet | None:
        """The live tracklet ``ident`` (a candidate's ``tracklet`` field), or None."""
        for tr in self.tracklets:
            if tr.ident == ident:
                return tr
        return None

    @property
    def next_ident(self) -> int:
        """The ident the next new tracklet will get: every tracklet born from now on has an
        ident at least this."""
        return self._next_id

    def _heir(self, t: float, positions: np.ndarray, assigned: list[int],
              scores: np.ndarray) -> int | None:
        """The unassigned candidate that continues the followed tracklet after a hit.

        A racket contact changes the velocity abruptly, so the followed tracklet misses; the
        nearest free candidate close to where it was inherits its history instead of
        waiting ``min_hits`` frames to be confirmed again.
        """
        old = self.followed
        if old is None or old.hit_now or not len(positions) or self.params.rebirth_radius <= 0:
            return None
        # The radius grows with the frames the followed tracklet has been missing.
        best, best_d = None, self.params.rebirth_radius * self.factor(old) * (1 + 0.5 * old.misses)
        for j, (x, y) in enumerate(positions):
            if assigned[j] >= 0 or scores[j] < self.params.min_track_quality:
                continue
            d = math.hypot(x - old.x, y - old.y)
            if d <= best_d:
                best, best_d = j, d
        return best

    def _inherit(self, t: float, pos: np.ndarray, score: float) -> int:
        old = self.followed
        tr = Tracklet(self._next_id, float(pos[0]), float(pos[1]), t, old.start_x, old.start_y,
                      hits=old.hits, quality=0.5 * (old.quality + score), travel=old.travel)
        tr.recent.extend(old.recent)
        tr.recent.append((tr.x, tr.y))
        self._next_id += 1
        self.tracklets.append(tr)
        if old in self.tracklets:
            self.tracklets.remove(old)
        self._ghost = None
        self.selected = tr.ident
        return tr.ident

    def _extend(self, tr: Tracklet, t: float, pos: np.ndarray, score: float, dist: float) -> None:
        dt = t - tr.t
        x, y = float(pos[0]), float(pos[1])
        predicted = tr.velocity_known
        if predicted:   # the prediction meant something: a smoothness measurement
            tr.residual = 0.8 * tr.residual + 0.2 * dist
        if dt > 1e-6:
            vx, vy = (x - tr.x) / dt, (y - tr.y) / dt
            a = self.params.velocity_smoothing if tr.velocity_known else 1.0
            tr.vx = a * vx + (1 - a) * tr.vx
            tr.vy = a * vy + (1 - a) * tr.vy
            tr.velocity_known = True
        # Plain mean over the first hits, then an exponential memory of ~5 frames.
        tr.quality += (score - tr.quality) * max(0.2, 1.0 / (tr.hits + 1))
        tr.x, tr.y, tr.t = x, y, t
        f = self.factor(tr)
        if predicted and self.params.jump_residual > 0 and dist > self.params.jump_residual * f:
            # The step left the predicted path (a racket hit, or a tracklet hopping between
            # clutter blobs inside its wide gates): the travel before it says nothing about
            # what the tracklet follows now, so the travel and pause rules start afresh.
            anchor = tr.recent[-1] if tr.recent else None
            tr.start_x, tr.start_y, tr.travel = x, y, 0.0
            tr.recent.clear()
            if (anchor is not None and tr.ident == self.selected
                    and score >= self.params.jump_anchor_quality):
                # The followed shuttle struck by the racket: the new path starts where the old
                # one ended (the contact), not at its first point after it, so the flight counts
                # as moving at once instead of after min_travel px more.
                tr.start_x, tr.start_y = anchor
                tr.recent.append(anchor)
            if self.params.jump_resets_residual:
                # ... and so does its smoothness record: after a racket contact the shuttle may
                # take over a clutter tracklet (the racket head's, a hand's), whose old
                # residual would cost the new path its merit for ~10 frames.
                tr.residual = 0.0
        tr.hits += 1
        tr.misses = 0
        tr.hit_now = True
        tr.travel = max(tr.travel, math.hypot(x - tr.start_x, y - tr.start_y))
        tr.recent.append((x, y))
        if tr.recent_travel(self.params.travel_window) >= self.params.min_travel:
            tr.still_for = 0
        else:
            tr.still_for += 1

    def merit(self, tr: Tracklet, quality: float | None = None) -> float:
        """How shuttle-like a tracklet is; negative when it may not supply a detection.

        ``quality``: this frame's candidate's own score; the followed tracklet keeps its
        hysteresis only while it is at least ``hysteresis_min_quality``.
        """
        p = self.params
        # A tracklet is confirmed after min_hits frames, or one frame earlier when every
        # candidate on it so far looked clearly like a shuttle (a flight's first frames
        # are otherwise lost to the confirmation).
        confirmed = tr.hits >= p.min_hits or (p.early_confirm_quality < 1.0
                                               and tr.hits >= max(p.min_hits - 1, 2)
                                               and tr.quality >= p.early_confirm_quality)
        if not tr.hit_now or not confirmed or tr.quality < p.min_track_quality:
            return -1.0
        # Moving now, or a shuttle that flew far and slows down for a moment (apex, the far
        # court); clutter (lights, screens) never flies far, a shuttle on the floor stays
        # still for longer than the allowance.
        # The travel thresholds stay in pixels with the camera's geometry: they tell motion from
        # the jitter of a still blob (a hand, a held shuttle), which is a pixel or two of the
        # mask whatever the shuttle's scale (scaled down with it on the demo court at 640×360,
        # clutter passed as moving: seed 1 left 96.5 → 91.2 %).
        f = self.factor(tr)
        moving = tr.recent_travel(p.travel_window) >= p.min_travel
        allowance = p.pause_frames
        if p.followed_pause_frames > 0 and tr.ident == self.selected:
            # The shuttle being followed may rest for long (held before the serve, lying after
            # the rally: TV labels mark it visible), other tracklets only for a moment.
            allowance = p.followed_pause_frames
        pausing = tr.travel >= p.flight_travel and tr.still_for <= allowance
        if not (moving or pausing):
            return -1.0
        merit = (min(tr.hits, p.hits_saturation) / p.hits_saturation
                 + p.quality_weight * tr.quality
                 - tr.residual / max(p.residual_scale * f, 1e-6))
        if tr.ident == self.selected and (quality is None or quality >= p.hysteresis_min_quality):
            # Not when this frame's blob does not look like a shuttle at all: after a racket
            # contact the followed tracklet goes on with the racket (or a hand), whose running
            # quality still remembers the shuttle for ~5 frames, while the shuttle leaves on a
            # tracklet of its own.
            merit += p.hysteresis
        return max(merit, 0.0)

    def select(self, ident: int | None) -> None:
        self.selected = ident

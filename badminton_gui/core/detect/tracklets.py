"""Filter 4, motion over frames: the scored blobs joined into image tracklets, and the candidates
that come out of them.

Why this file exists: the paper's fourth filter ("distance from the previous frame's shuttle")
grew into a multi-frame stage — the association (``core/association.py``) keeps the tracklets;
this stage hands it the blobs that passed filters 1–3 and the score, turns its answer into
candidates that carry their tracklet's ident (``Candidate.tracklet``), and adds the rules that
decide what may be reported from the tracklets: the followed shuttle coasting through a blind
spot, a lone sure blob passing when nothing travels, and the hold while the shuttle is out of the
picture (``ExitHold``). It also remembers each tracklet's recent blob sizes, which the readout
(``CameraDetector.lead_to_head``) reads.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from typing import Callable

import numpy as np

from ..association import Tracklet, TrackletAssociator
from ..params import TrackerParams
from ..types import REJECT_MOTION, Candidate, make_candidate
from .diagnostics import TrackletReport
from .scoring import ScoredBlobs

Link = tuple[int, float, float]   # (tracklet ident, distance from its prediction, merit) per blob


def near_edge(x: float, y: float, w: int, h: int, margin: float) -> bool:
    """True when (x, y) lies within ``margin`` px of any image edge."""
    return min(x + 0.5, y + 0.5, w - 0.5 - x, h - 0.5 - y) < margin


def came_in(tr: Tracklet, first: int, hits_then: dict[int, int], w: int, h: int, entry: float) -> bool:
    """Has tracklet ``tr`` been within ``entry`` px of an edge since the shuttle left?

    A track born after the exit (ident ≥ ``first``): any of its points. An older one: only
    the points it gained since (its hits then, ``hits_then``), for an old clutter track
    (a player's, a line's) can take the returning shuttle's blob into its gate (bwf_00001
    90 with the gate slack at 30 px: a track that had sat at (733, 317) for 52 frames).
    """
    points = list(tr.recent)
    if tr.ident < first:
        gained = tr.hits - hits_then.get(tr.ident, tr.hits)
        points = points[len(points) - gained:] if gained > 0 else []
    return any(near_edge(x, y, w, h, entry) for x, y in points)


class ExitHold:
    """Hold every report back while the shuttle is out of the picture (``association.exit_margin``).

    A track that could supply the detection last frame, seen within the margin of the top
    edge while rising and now missing with its prediction above the image, is the shuttle
    leaving the picture (on TV: a clear or a lob; players and rackets cross the other
    edges, not this one). Out there it cannot be seen, so whatever the association offers
    meanwhile (a player in white, a shoe, a logo) is not the shuttle; it can only come back
    across an edge. So until a track that has come within ``entry_margin`` of an edge since the
    exit may supply the detection (the shuttle coming back in; its first frames back may be
    missed, so its track can start some way inside; ``came_in``), or ``exit_timeout`` has
    passed (a new shuttle brought into play), every candidate is held back (``merit`` -1). Any
    point of a track born after the exit counts, not only its first: a young clutter track's
    wide gate (its velocity barely known) can take the returning shuttle's first blob over
    (1_02_01 111 with filter 1 at 18 px: a track born at (992, 173) took the shuttle at (847,
    6), and its first point held it back for 17 frames). The hold starts only while the
    followed track is not seen in the frame.
    """

    def __init__(self) -> None:
        # (time the shuttle left the picture, first tracklet ident born after that, {ident: hits}
        # of the tracklets alive then) while it is out, else None
        self.outside: tuple[float, int, dict[int, int]] | None = None
        self._eligible: set[int] = set()   # the tracklets that could supply the detection last frame
        self.left_picture = -1             # the tracklet that left the picture this frame (-1: none)

    @property
    def holding(self) -> bool:
        """The shuttle is out of the picture: nothing is reported."""
        return self.outside is not None

    def _note_exit(self, a: TrackletAssociator, t: float, margin: float) -> None:
        """Start the hold when the followed shuttle leaves through the top edge this frame."""
        # The followed track seen in this frame is the shuttle in the picture: another track
        # leaving through the top is clutter (bwf_00001 242 with the speed gate gain at 0.75:
        # a track at the top edge that could have supplied the detection left while the
        # followed shuttle flew on below, and the shuttle was held back for 3 s).
        followed_here = any(tr.ident == a.selected and tr.hit_now for tr in a.tracklets)
        for tr in a.tracklets:
            # Through the top edge only: players, rackets and shoes cross the side and bottom
            # edges of a TV picture, never its top (they stand on the court below it).
            if (not tr.hit_now and tr.misses == 1 and tr.ident in self._eligible and not followed_here
                    and tr.velocity_known and tr.vy < 0 and tr.y + 0.5 < margin):
                if tr.predict(t)[1] < -0.5:
                    # The followed shuttle is the one that left: no clutter keeps the hysteresis.
                    self.outside = (t, a.next_ident, {other.ident: other.hits for other in a.tracklets})
                    a.select(tr.ident)
                    self.left_picture = tr.ident
                    break

    def apply(self, a: TrackletAssociator, params: TrackerParams, t: float, w: int, h: int,
              links: list[Link]) -> list[Link]:
        """This frame's links, with every merit set to -1 while the shuttle is out."""
        ap = params.association
        self.left_picture = -1
        margin = ap.exit_margin * w / 1280.0
        entry = max(ap.entry_margin, ap.exit_margin) * w / 1280.0
        self._note_exit(a, t, margin)
        self._eligible = {ident for ident, _, merit in links if merit >= 0}
        if self.outside is None:
            return links
        t_exit, first, hits_then = self.outside
        if t - t_exit > ap.exit_timeout:
            self.outside = None
            return links
        by_id = {tr.ident: tr for tr in a.tracklets}
        out, entered = [], False
        for ident, motion, merit in links:
            tr = by_id.get(ident)
            if merit >= 0 and not (tr is not None and came_in(tr, first, hits_then, w, h, entry)):
                merit = -1.0
            entered = entered or merit >= 0
            out.append((ident, motion, merit))
        if entered:
            self.outside = None
        return out


class TrackletLooks:
    """Each tracklet's recent blob widths (``colour.head_lead_width_frames``) and areas
    (``colour.edge_exit``), for the readout: a shuttle merged with a racket is wider than the
    shuttle, and one clipped by the edge it leaves through has lost part of its usual area."""

    def __init__(self) -> None:
        self._widths: dict[int, deque] = {}
        self._areas: dict[int, deque] = {}

    def note(self, ident: int, short_side: float, area: float, width_frames: int, area_frames: int) -> None:
        """Tracklet ``ident``'s blob this frame; ``area_frames``: how many of its areas to keep
        (``colour.edge_exit_frames``; 0: none, the edge exit off)."""
        if width_frames > 1:
            widths = self._widths.get(ident)
            if widths is None or widths.maxlen != width_frames:
                widths = self._widths[ident] = deque(widths or (), maxlen=width_frames)
            widths.append(short_side)
        if area_frames > 0:
            areas = self._areas.get(ident)
            if areas is None or areas.maxlen != area_frames:
                areas = self._areas[ident] = deque(areas or (), maxlen=area_frames)
            areas.append(area)

    def forget_dead(self, tracklets: list[Tracklet], width_frames: int, edge_exit: bool) -> None:
        """Drop the memories of dead tracklets once they outnumber the live ones well."""
        if width_frames > 1 and len(self._widths) > 2 * len(tracklets) + 16:
            alive = {tr.ident for tr in tracklets}
            self._widths = {k: v for k, v in self._widths.items() if k in alive}
        if edge_exit and len(self._areas) > 2 * len(tracklets) + 16:
            alive = {tr.ident for tr in tracklets}
            self._areas = {k: v for k, v in self._areas.items() if k in alive}

    def widths(self, ident: int) -> deque | None:
        """The recent short sides of tracklet ``ident``'s blobs (None: none remembered)."""
        return self._widths.get(ident)

    def areas(self, ident: int) -> deque | None:
        """The recent areas of tracklet ``ident``'s blobs (None: none remembered)."""
        return self._areas.get(ident)


class TrackletStage:
    """Filter 4 for one camera: the scored blobs → candidates on tracklets."""

    def __init__(self, associator: TrackletAssociator, params: TrackerParams) -> None:
        self.associator = associator
        self.params = params
        self.exit_hold = ExitHold()
        self.looks = TrackletLooks()

    def link(self, t: float, blobs: ScoredBlobs, w: int, h: int,
             blind: Callable[[float, float], bool] | None) -> tuple[list[Candidate], TrackletReport]:
        """This frame's candidates from the scored blobs, in their order (plus the coasting
        prediction last), and what this stage did. Only candidates on a confirmed, travelling,
        smooth tracklet pass (the speed-aware gate lives in the associator); the others are
        rejected by motion."""
        p = self.params
        live = [k for k, reason in enumerate(blobs.rejected_by) if reason is None]
        positions = np.asarray([(blobs.x[k], blobs.y[k]) for k in live], dtype=float).reshape(-1, 2)
        qualities = np.asarray([blobs.quality[k] for k in live], dtype=float)
        links = self.associator.update(t, positions, qualities, blind)
        self.exit_hold.left_picture = -1
        if p.association.exit_margin > 0:
            links = self.exit_hold.apply(self.associator, p, t, w, h, links)
        candidates, refused = self._candidates(blobs, links)
        # The followed shuttle crossing a light or a white line leaves no blob: its track's
        # prediction stands in (flagged, never triangulated) until it shows again.
        coast = self.associator.coasting(t, blind) if not self.exit_hold.holding else None
        lone = False
        if coast is not None:
            tr, merit = coast
            px, py = tr.predict(t)
            candidates.append(Candidate(px, py, math.nan, math.nan, math.nan, math.nan, 0.0, merit,
                                        None, predicted=True, tracklet=tr.ident))
        elif refused and not self.exit_hold.holding:
            accept_lone(candidates, refused)
            lone = True
        held = sum(1 for _, _, merit in links if merit < 0) - lone
        report = TrackletReport(len(live), held, len(live) - held, self.exit_hold.holding,
                                coast is not None, lone)
        return candidates, report

    def _candidates(self, blobs: ScoredBlobs, links: list[Link]) -> tuple[list[Candidate], list[int] | None]:
        """(a candidate per blob, the indices of those the association refused while none
        passed, each of quality ≥ ``association.lone_quality``: ``accept_lone``)."""
        p = self.params
        width_frames = int(p.colour.head_lead_width_frames)
        area_frames = int(p.colour.edge_exit_frames) if p.colour.edge_exit > 0 else 0
        lone = p.association.lone_quality < 1.0
        refused: list[int] | None = [] if lone else None
        candidates: list[Candidate] = []
        k = 0
        for x, y, length, short_side, whiteness, area, quality, reason in zip(
                blobs.x, blobs.y, blobs.length, blobs.short_side, blobs.whiteness, blobs.area,
                blobs.quality, blobs.rejected_by):
            motion, score, ident = math.nan, quality, -1
            if reason is None:
                ident, motion, merit = links[k]
                k += 1
                if merit < 0:
                    reason = REJECT_MOTION
                    if refused is not None and quality >= p.association.lone_quality:
                        refused.append(len(candidates))
                else:
                    score = merit
                    refused = None
                self.looks.note(ident, short_side, area, width_frames, area_frames)
            candidates.append(make_candidate(x, y, length, short_side, whiteness, area, motion, score,
                                             reason, tracklet=ident))
        self.looks.forget_dead(self.associator.tracklets, width_frames, area_frames > 0)
        return candidates, refused


def accept_lone(candidates: list[Candidate], refused: list[int]) -> None:
    """No candidate lies on a confirmed, travelling tracklet: the most shuttle-like one the
    association refused (``refused``: indices into ``candidates``, each of quality ≥
    ``association.lone_quality``) passes after all, scored by its own quality.

    The shuttle held for the serve, or lying after a rally, never travels, and TV labels
    mark it visible; with nothing else to report, a blob the classifier is sure of is more
    often that shuttle than anything (``lone_quality`` in params.py). Not while the shuttle
    is out of the picture (``ExitHold`` holds every candidate back then) nor while the
    followed track coasts through a blind spot.
    """
    best = max(refused, key=lambda i: candidates[i].score)
    candidates[best] = dataclasses.replace(candidates[best], rejected_by=None)

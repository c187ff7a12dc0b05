"""What the stereo stage asks a camera's detector about its candidates during a step, answered
from the detector's live state or from a snapshot of it.

Why this file exists: the stereo stage (pairing, the vouch, the cork correction, the readout's
lead to the cork) asks each camera's detector about the tracklets behind its candidates
(``tracklet_velocity``, ``tracklet_hits``, ``vouchable``, ``first_sighting``, ``lead_to_head``)
while it decides a step. In one process the detector answers from its own tracklets
(:class:`~badminton_gui.core.detector.CameraDetector`); a detector running in a process of its
own (``core/camera_process.py``) returns with each frame's result a :class:`DetectorSnapshot`
of the same tracklets, and its stand-in answers from that. Both answer through the one class
here, :class:`TrackletQueries`, so the two cannot disagree.

Between a frame's candidates and the end of its step the stereo stage changes only which
tracklet the detector follows (``commit``); the snapshot therefore holds every tracklet a
candidate of the frame lies on, the followed one and its ghost, and the stand-in applies the
same ``select`` to it.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..association import Tracklet
from ..types import REJECT_MOTION, REJECT_SCORE, CameraResult, Candidate
from .diagnostics import DetectionDiagnostics


class TrackletQueries:
    """The questions about a frame's candidates that need the camera's tracklets.

    A subclass provides ``params`` (``TrackerParams``), ``_associator`` (``tracklet(ident)``,
    ``followed``) and ``_looks`` (``widths(ident)``, ``areas(ident)``)."""

    def tracklet_hits(self, candidate: Candidate) -> int:
        """Frames the candidate's tracklet has been seen (0 when it is on none)."""
        tr = self._associator.tracklet(candidate.tracklet)
        return 0 if tr is None else tr.hits

    def vouchable(self, candidate: Candidate, min_quality: float) -> tuple[float, float] | None:
        """Image velocity (px/s) of a candidate the association held back (filter 4: its tracklet
        is not confirmed yet, or not travelling far enough) while the tracklet is seen this frame,
        has a known velocity and a running quality of at least ``min_quality``; else None.

        The stereo tracker lets such a candidate through when the other camera sees a partner
        on its epipolar line moving the same way in 3D (``stereo/vouch.py``): the flight's
        first frames after a serve or a hit, a shuttle coming back slowly into view.
        """
        if candidate.rejected_by != REJECT_MOTION or candidate.predicted:
            return None
        tr = self._associator.tracklet(candidate.tracklet)
        if (tr is not None and tr.hit_now and tr.velocity_known and tr.quality >= min_quality
                and len(tr.recent) >= 2
                and math.hypot(tr.x - tr.recent[-2][0], tr.y - tr.recent[-2][1]) >= self.params.stereo.vouch_min_step):
            return tr.vx, tr.vy
        return None

    def first_sighting(self, candidate: Candidate, min_quality: float) -> bool:
        """The held-back candidate starts a track this frame (no velocity yet) and scores at
        least ``min_quality`` by its looks: the other camera may vouch for it by position alone."""
        if candidate.rejected_by != REJECT_MOTION or candidate.predicted or candidate.score < min_quality:
            return False
        tr = self._associator.tracklet(candidate.tracklet)
        return tr is not None and tr.hit_now and tr.hits == 1

    def vouch(self, candidate: Candidate, score: float) -> Candidate:
        """The held-back candidate let through with ``score`` (it keeps its tracklet)."""
        return dataclasses.replace(candidate, rejected_by=None, score=score)

    def tracklet_velocity(self, candidate: Candidate) -> tuple[float, float] | None:
        """Image velocity (px/s) of the candidate's tracklet, or None when not yet known."""
        tr = self._associator.tracklet(candidate.tracklet)
        return (tr.vx, tr.vy) if tr is not None and tr.velocity_known else None

    def _velocity_of(self, ident: int) -> tuple[float, float] | None:
        """Image velocity (px/s) of the tracklet ``ident`` (or of the followed one's ghost)."""
        if ident < 0:
            return None
        tr = self._associator.tracklet(ident)
        if tr is not None:
            return (tr.vx, tr.vy) if tr.velocity_known else None
        ghost = self._associator.followed
        if ghost is not None and ghost.ident == ident and ghost.velocity_known:
            return ghost.vx, ghost.vy
        return None

    def lead_to_head(self, result: CameraResult, chosen: Candidate | None
                     ) -> tuple[CameraResult, Candidate | None]:
        """Move a moving detection forward along its tracklet to the cork (``colour.head_lead``).

        The bright centroid of a moving shuttle trails its cork: the skirt is behind it and the
        motion blur smears the white backwards too. The lead is proportional to the blob's width
        (the shuttle's apparent size, which blur does not stretch). Call after ``commit`` (the
        tracklet's velocity then includes this frame); the associator keeps the measured
        position, only the reported one moves. Returns the result with the moved candidate in
        place of the old one, and the moved candidate; no candidate (None) when the cork is led
        out of the image.
        """
        c = self.params.colour
        w, h = result.image_size
        if chosen is not None and chosen.predicted:
            # A coasting prediction (no blob) at the edge its track leaves through: the blob is
            # missing because the shuttle has left the image, not because it is hidden.
            velocity = self._velocity_of(chosen.tracklet)
            if (c.edge_exit > 0 and w > 0 and velocity is not None
                    and _leaving_edge(chosen.x, chosen.y, velocity, w, h, c.edge_exit * w / 1280.0)):
                return result, None
            return result, chosen
        if (chosen is None or (c.head_lead <= 0 and c.edge_exit <= 0)
                or not math.isfinite(chosen.short_side)):
            return result, chosen
        velocity = self.tracklet_velocity(chosen)
        if velocity is None:
            return result, chosen
        moved = chosen
        speed = math.hypot(*velocity)
        if c.head_lead > 0 and speed >= c.head_lead_min_speed:
            width = chosen.short_side
            widths = self._looks.widths(chosen.tracklet)
            if c.head_lead_width_frames > 1 and widths:
                # A shuttle merged with a racket or an arm: the blob is wider than the shuttle,
                # whose own width shows in the tracklet's recent frames.
                width = min(width, min(widths))
            lead = c.head_lead * width / speed
            moved = dataclasses.replace(chosen, x=chosen.x + lead * velocity[0],
                                        y=chosen.y + lead * velocity[1])
            if w > 0 and not (-0.5 <= moved.x < w - 0.5 and -0.5 <= moved.y < h - 0.5):
                # The cork has left the image (only the skirt's end still shows at the border):
                # no point inside the frame is the shuttle's, and none outside it can be reported.
                return result, None
        if (c.edge_exit > 0 and w > 0
                and _leaving_edge(moved.x, moved.y, velocity, w, h, c.edge_exit * w / 1280.0)):
            # A shuttle clipped by the edge it is leaving through: its visible part's bright
            # centroid stays inside while the cork is already out (``colour.edge_exit``). The
            # cork leads, so it is out once the blob has lost a good part of its usual area.
            areas = self._looks.areas(chosen.tracklet)
            if areas is not None and len(areas) >= 3:
                usual = float(np.median(list(areas)[:-1]))
                if chosen.area < c.edge_exit_area * usual:
                    return result, None
        if moved is chosen:
            return result, chosen
        candidates = tuple(moved if cand is chosen else cand for cand in result.candidates)
        return dataclasses.replace(result, candidates=candidates), moved

    def choose(self, candidates: tuple[Candidate, ...]) -> Candidate | None:
        """The best candidate that passed every filter, or None."""
        best = None
        for c in candidates:
            if c.rejected_by is None and (best is None or c.score > best.score):
                best = c
        return best

    @staticmethod
    def finalise(result: CameraResult, chosen: Candidate | None,
                 losers_reason: str = REJECT_SCORE) -> CameraResult:
        """Mark the chosen candidate, and the other survivors as rejected by ``losers_reason``."""
        cands = []
        for c in result.candidates:
            if c.rejected_by is None and c is not chosen:
                c = dataclasses.replace(c, rejected_by=losers_reason)
            cands.append(c)
        return dataclasses.replace(result, detection=chosen, candidates=tuple(cands))


def _leaving_edge(x: float, y: float, velocity: tuple[float, float], w: int, h: int,
                  margin: float) -> bool:
    """True when (x, y) lies within ``margin`` px of an image edge that ``velocity`` moves
    towards (pixel centres are integers: the image spans -0.5 … w - 0.5)."""
    vx, vy = velocity
    return ((vx < 0 and x + 0.5 < margin) or (vx > 0 and w - 0.5 - x < margin)
            or (vy < 0 and y + 0.5 < margin) or (vy > 0 and h - 0.5 - y < margin))


class TrackletFacts(NamedTuple):
    """What a query reads of a :class:`Tracklet` (the same names): a snapshot's tracklet."""

    ident: int
    x: float
    y: float
    vx: float
    vy: float
    hits: int
    hit_now: bool
    velocity_known: bool
    quality: float
    recent: tuple       # the last two of its recent positions

    @staticmethod
    def row(tr: Tracklet | None) -> tuple | None:
        """``tr``'s facts as a plain tuple (quick to pickle; ``TrackletFacts._make`` reads it)."""
        if tr is None:
            return None
        recent = tr.recent
        last = tuple(recent[k] for k in range(max(len(recent) - 2, 0), len(recent)))
        return (tr.ident, tr.x, tr.y, tr.vx, tr.vy, tr.hits, tr.hit_now, tr.velocity_known,
                tr.quality, last)


@dataclass(frozen=True, slots=True)
class DetectorSnapshot:
    """One frame's answers of a camera's detector: the tracklets its candidates lie on (None:
    not live), the followed tracklet's ident and its ghost, each such tracklet's recent widths
    and areas (``TrackletLooks``), and the frame's ``last_diagnostics`` / ``last_scored``."""

    tracklets: dict[int, tuple | None]      # TrackletFacts rows
    ghost: tuple | None
    selected: int | None
    widths: dict[int, tuple[float, ...] | None]
    areas: dict[int, tuple[float, ...] | None]
    diagnostics: DetectionDiagnostics | None = None
    scored: tuple[np.ndarray, np.ndarray] | None = None

    @classmethod
    def of(cls, associator, looks, result: CameraResult, diagnostics: DetectionDiagnostics | None,
           scored: tuple[np.ndarray, np.ndarray] | None) -> DetectorSnapshot:
        """The snapshot of a detector's ``associator`` and ``looks`` after ``result``
        (``scored``: the frame's ``last_scored``, when someone reads it)."""
        idents = {c.tracklet for c in result.candidates if c.tracklet >= 0}
        if associator.selected is not None:
            idents.add(associator.selected)
        live = {tr.ident: tr for tr in associator.tracklets if tr.ident in idents}

        widths, areas = {}, {}
        for ident in idents:
            widths[ident] = None if looks.widths(ident) is None else tuple(looks.widths(ident))
            areas[ident] = None if looks.areas(ident) is None else tuple(looks.areas(ident))
        row = TrackletFacts.row
        return cls({i: row(live.get(i)) for i in idents}, row(associator.ghost),
                   associator.selected, widths, areas, diagnostics, scored)


class SnapshotTracklets:
    """A :class:`DetectorSnapshot` read as a detector's associator and tracklet looks are read
    (``tracklet``, ``followed``, ``select``; ``widths``, ``areas``)."""

    def __init__(self, snapshot: DetectorSnapshot | None = None) -> None:
        self.snapshot = snapshot
        self.selected = None if snapshot is None else snapshot.selected

    def tracklet(self, ident: int) -> TrackletFacts | None:
        if ident < 0 or self.snapshot is None:
            return None
        try:
            row = self.snapshot.tracklets[ident]
        except KeyError:
            raise LookupError(f"tracklet {ident} is not in this frame's snapshot") from None
        return None if row is None else TrackletFacts._make(row)

    @property
    def followed(self) -> TrackletFacts | None:
        if self.selected is None or self.snapshot is None:
            return None
        live = self.snapshot.tracklets.get(self.selected)
        if live is not None:
            return TrackletFacts._make(live)
        ghost = self.snapshot.ghost
        return TrackletFacts._make(ghost) if ghost is not None and ghost[0] == self.selected else None

    def select(self, ident: int | None) -> None:
        self.selected = ident

    def widths(self, ident: int) -> tuple[float, ...] | None:
        return None if self.snapshot is None else self.snapshot.widths.get(ident)

    def areas(self, ident: int) -> tuple[float, ...] | None:
        return None if self.snapshot is None else self.snapshot.areas.get(ident)

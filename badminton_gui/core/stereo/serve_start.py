"""Before the serve, a pair is the shuttle only once its 3D track starts like a serve.

Why this file exists: the product reports the shuttle in play, from its first motion at the
serve; a shuttle held before the serve is at rest and not reported. Before any flight has
started there is no flight to ask where the shuttle is (``stereo.flight_reach``), and an LED
board's moving dot standing inside the play volume's margin (or a chance pair of clutter
triangulated into it) pairs like the shuttle: both cameras reported it until the serve. A
serve leaves a hand or racket at most at a player's reach and climbs (it must clear the net),
fast, towards the net; a dot slides along its board at about the same height, and a chance
pair jumps. So while no shuttle is in play, each pair of the two cameras' tracklets keeps its
recent 3D points here, and the pairing takes a pair only when its track qualifies
(``ServeStart.qualifies``); the shuttle is in play from then until its flight lands, or no 3D
point was reported for a while with no flight in the air (``ServeStart.in_play``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..flight.guide import StepGuide
from ..flight.phase import PhaseState, ShuttlePhase
from ..params import TrackerParams
from ..types import FlightInfo


@dataclass(frozen=True, slots=True)
class ServeRule:
    """What a track of pairs must show to start like a serve (``stereo.serve_*``): from one of
    its points to its last, at least ``points`` points at most ``max_gap`` s apart each and
    ``max_gap`` s in all, the first at most ``max_height`` m high, moving on average at
    ``min_speed`` m/s or more, climbing at ``min_climb`` m/s or more and by ``min_rise`` m or
    more, towards the net (court frame: z up, the net along y = 0; a serve crosses the net from
    the server's half). The rise is what a few centimetres of triangulation noise between two
    frames cannot fake; a fast serve has it within two frames, a slow one within a few more."""

    points: int
    min_speed: float
    min_climb: float
    min_rise: float
    max_height: float
    max_gap: float


class ServeStart:
    """The recent 3D points (court frame) of each pair of tracklets (left, right) seen before
    the serve; ``in_play``: a pair started like a serve since the shuttle was last out of play;
    ``airborne_until``: the followed flight's predicted landing time (s; a flight lost in the air
    is still in play until then)."""

    def __init__(self) -> None:
        self._tracks: dict[tuple[int, int], list[tuple[float, np.ndarray]]] = {}
        self.in_play = False
        self.airborne_until = -np.inf

    def before_serve(self, t: float, guide: StepGuide, phase: PhaseState, params: TrackerParams) -> bool:
        """Is no shuttle in play at ``t``? Not since a pair started like a serve, until no flight
        is followed (``guide``) nor in the air by its last landing prediction (``note_flight``)
        and the shuttle landed (``phase``) or no 3D point was reported for the trajectory's
        ``max_gap``. A flight lost in the air is still in play: the shot that comes back into
        view may be going down, and would never start like a serve."""
        last = phase.last_point
        if self.in_play and t > self.airborne_until and guide.get() is None and (
                phase.phase is ShuttlePhase.LANDED or last is None
                or t - last[0] > params.trajectory.max_gap):
            self.in_play = False
        return not self.in_play

    def note_flight(self, flight: FlightInfo) -> None:
        """A step's flight: while it predicts a landing, the shuttle is in the air until then."""
        if flight.prediction is not None:
            self.airborne_until = flight.prediction.t

    def __len__(self) -> int:
        return len(self._tracks)

    def observe(self, key: tuple[int, int], t: float, point, rule: ServeRule) -> None:
        """The tracklets ``key`` paired at ``t`` into ``point``; a track broken for more than
        ``rule.max_gap`` starts again, and keeps its points of the last ``rule.max_gap`` s."""
        track = self._tracks.get(key)
        if track is None or t - track[-1][0] > rule.max_gap or t <= track[-1][0]:
            track = []
            self._tracks[key] = track
        track.append((float(t), np.asarray(point, dtype=float).reshape(3)))
        while track[0][0] < t - rule.max_gap:
            del track[0]

    def qualifies(self, key: tuple[int, int], t: float, rule: ServeRule) -> bool:
        """Does the track of ``key``, observed at ``t``, start like a serve (``ServeRule``)?"""
        track = self._tracks.get(key)
        n = max(int(rule.points), 2)
        if track is None or len(track) < n or track[-1][0] != t:
            return False
        t1, p1 = track[-1]
        for t0, p0 in track[:len(track) - n + 1]:
            if t1 <= t0 or p0[2] > rule.max_height or p1[2] - p0[2] < rule.min_rise:
                continue
            velocity = (p1 - p0) / (t1 - t0)
            if (np.linalg.norm(velocity) >= rule.min_speed and velocity[2] >= rule.min_climb
                    and velocity[1] * p0[1] < 0.0):
                return True
        return False

    def forget_before(self, t: float) -> None:
        """Drop the tracks not observed since ``t``."""
        self._tracks = {k: v for k, v in self._tracks.items() if v[-1][0] >= t}

    def clear(self) -> None:
        self._tracks.clear()

"""Look-ahead of whole tracker results: both cameras' (or one camera's) delayed readouts as ``TrackResult``.

Why this module exists: :class:`~badminton_gui.core.lookahead.CameraLookahead` re-decides one
camera's detections; the ``track`` CLI, the demo evaluation and the GUI need the same for a
:class:`TrackResult` — the two cameras' re-decided frames zipped back together, a re-decided pair
re-triangulated when epipolar-consistent, and a new flight's first points (and those the followed
flight refused just before it took them again) given the flight's fitted path
(``FlightInfo.confirmed``, ``CONFIRM_GATE_M``, ``CONFIRM_HOLD_S``). :class:`MonoLookahead` does the
same for one camera, and :class:`DelayedReadout` pairs the delayed results with the GUI's
payloads. The rules themselves are documented in ``core/lookahead.py``.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from typing import Callable

import numpy as np

from .flight.shot_filter import position_on_path
from .lookahead import CameraLookahead
from .params import TrackerParams
from .stereo.pairing import in_play_volume
from .types import CameraResult, TrackResult


# s: how long the file readout holds its decided frames for a flight's first points (``_confirm``;
# 1.0 s gave the same points on the NYCU tuned-on rallies).
CONFIRM_HOLD_S = 0.25
# m: a held frame the new flight's track left out (a point it dropped as inconsistent, one
# measured just before it) takes the flight's path where its own measured point lies this close
# to it, from CONFIRM_BEFORE_S (s) before the track's first point on. At 0.10 m one of the NYCU
# tuned-on rallies' 65 such points was a wrong 2D pair 51 cm off; at 0.05 m, 41 points, all
# within 9 cm of the triangulated labels.
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
                if (p[2] > 0 and sp.min_distance <= dist <= sp.max_distance
                        and in_play_volume(self.rig, self.params, p)):
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

"""The shuttle's phase: in play, stopped in mid-air, caught, landed, or unseen.

Why this file exists: several readout rules hold only in one phase of the shuttle's life — a
landed shuttle lying still is kept reported (``stereo.landed_frames``), a caught one is withheld
from the readout and the robot (``stereo.caught_frames``). The phase is one frozen
:class:`PhaseState`, advanced once a step by the pure :func:`transition`, so the rules read a
named state instead of flags scattered over the tracker.

Transitions (``t``: the step's time; "the point": the step's reported 3D point in the court
frame; "accepted": the flight filter took the step's measured point)::

    from            on                                                           to
    any             caught rule off (caught_frames 0, or no court pose)          (not caught)
    CAUGHT          caught_hold s passed since the catch                         (not caught)
    CAUGHT          accepted point, flight speed ≥ caught_release_speed          IN_PLAY
    not CAUGHT      accepted point                                               IN_PLAY / LANDED
    not CAUGHT      refused point within caught_flight_gap s of a flight         STOPPED
                    ≥ caught_min_flight_speed (or already STOPPED)
    STOPPED         caught_frames refused points within caught_radius,           CAUGHT
                    above landed_max_height and not at the net
    STOPPED         those points spread, or lie on the floor                     UNSEEN / LANDED
    STOPPED         they hang at the net (caught_net_exception; within           UNSEEN / LANDED,
                    caught_net_margin of its plane, not above its top)           net_stop
    STOPPED         a step with no measured point                                UNSEEN / LANDED
    (not caught)    a reported point above landed_max_height                     IN_PLAY
    (not caught)    the last point, within landed_recent s, at most              LANDED
                    landed_max_height high
    (not caught)    otherwise                                                    UNSEEN

A step that brings one camera's image only (cameras without a common trigger) measures no 3D
point: it neither starts nor releases a catch, and a catch still within ``caught_hold`` holds.
"""

from __future__ import annotations

import dataclasses
import enum
from dataclasses import dataclass

import numpy as np

from ..court import NET_HEIGHT_POSTS
from ..params import TrackerParams
from ..types import FlightInfo

# What the readout and the robot are told while the shuttle is caught (``FlightInfo.withheld_reason``).
CAUGHT_REASON = "caught: out of play"


class ShuttlePhase(enum.Enum):
    """Where the shuttle is in its life, as the 3D flight shows it."""

    UNSEEN = "unseen"        # no recent 3D point
    IN_PLAY = "in play"      # a 3D point above the floor this step
    STOPPED = "stopped"      # the flight refuses points that stopped in mid-air: caught, maybe
    CAUGHT = "caught"        # stopped dead above the floor: in a hand, out of play
    LANDED = "landed"        # the last 3D point, recent, near the floor


@dataclass(frozen=True, slots=True)
class PhaseObservation:
    """What one step tells the phase.

    ``measured``: the step's measured 3D point (court frame) or None; ``accepted``: the flight
    filter took it; ``speed``: the flight's speed after the step (m/s) or None; ``point_height``:
    the height of the 3D point the step would report if the shuttle is in play, or None;
    ``paired``: a step with both cameras' images (False: one camera's image only)."""

    t: float
    measured: tuple[float, float, float] | None = None
    accepted: bool = False
    speed: float | None = None
    point_height: float | None = None
    paired: bool = True


@dataclass(frozen=True, slots=True)
class PhaseState:
    """The shuttle's phase and what the transitions remember.

    ``stopped``: the measured points the flight refused since its last accepted one, (t, court
    point); ``last_flown``: (t, speed) of the flight's last accepted point before a catch;
    ``caught_at``: the time of the catch (None: not caught); ``caught_new``: caught on this very
    step; ``last_point``: (t, court height) of the last reported 3D point; ``net_stop``: on this
    very step a stop met the catch's conditions but lay at the net (``caught_net_exception``)."""

    phase: ShuttlePhase = ShuttlePhase.UNSEEN
    stopped: tuple[tuple[float, tuple[float, float, float]], ...] = ()
    last_flown: tuple[float, float] | None = None
    caught_at: float | None = None
    caught_new: bool = False
    last_point: tuple[float, float] | None = None
    net_stop: bool = False

    @property
    def caught(self) -> bool:
        return self.caught_at is not None

    def landed(self, t: float, params: TrackerParams) -> bool:
        """The 3D flight's last point, within ``stereo.landed_recent`` s of ``t``, lay near the floor."""
        last = self.last_point
        return (last is not None and t - last[0] <= params.stereo.landed_recent
                and last[1] <= params.stereo.landed_max_height)


def _catch(state: PhaseState, obs: PhaseObservation, params: TrackerParams
           ) -> tuple[tuple, tuple[float, float] | None, float | None, bool, bool]:
    """The caught rule on a pair step: (stopped, last_flown, caught_at, caught_new, net_stop) after it."""
    sp = params.stereo
    t = obs.t
    stopped, flown, caught_at = state.stopped, state.last_flown, state.caught_at
    if caught_at is not None and t - caught_at > sp.caught_hold:
        caught_at = None
    if obs.measured is not None and obs.accepted:
        if obs.speed is not None:
            if caught_at is not None and obs.speed >= sp.caught_release_speed:
                caught_at = None
            if caught_at is None:
                flown = (t, obs.speed)
        return (), flown, caught_at, False, False
    if caught_at is not None:
        return stopped, flown, caught_at, False, False
    if obs.measured is None:
        return (), flown, None, False, False
    if not stopped and (flown is None or t - flown[0] > sp.caught_flight_gap + 1e-9
                        or flown[1] < sp.caught_min_flight_speed):
        return stopped, flown, None, False, False
    stopped = stopped + ((t, obs.measured),)
    if len(stopped) < sp.caught_frames:
        return stopped, flown, None, False, False
    points = np.array([p for _, p in stopped[-sp.caught_frames:]])
    centre = points.mean(axis=0)
    if (float(np.max(np.linalg.norm(points - centre, axis=1))) > sp.caught_radius
            or centre[2] <= sp.landed_max_height):
        # Not caught: lying on the floor (the landed hold's case).
        return (), flown, None, False, False
    margin = sp.caught_net_margin
    if sp.caught_net_exception and abs(centre[1]) <= margin and centre[2] <= NET_HEIGHT_POSTS + margin:
        # Not caught: stopped by the net, where it hangs in the mesh or on the tape in view
        # (rally_11-47-21 879, labelled).
        return (), flown, None, False, True
    return (), flown, t, True, False


def transition(state: PhaseState, obs: PhaseObservation, params: TrackerParams,
               has_court_pose: bool = True) -> PhaseState:
    """The phase after one step (pure: ``state`` is left as it was).

    The caught rule (``stereo.caught_frames``): a shuttle in flight never stops in mid-air. When
    the flight was followed at ``caught_min_flight_speed`` or more and its next measured 3D
    points are refused by it and stay within ``caught_radius`` of each other above the floor for
    ``caught_frames`` frames, a hand or a racket caught it (rally_11-47-02 172: from 5 m/s to
    still at 0.9 m); the labellers stop marking a shuttle held in the hand, and the robot has
    nothing to chase. It stays caught until the flight follows a point at
    ``caught_release_speed`` or more (a serve), or ``caught_hold`` s have passed. An apex is no
    stop (the flight accepts its points), nor is a hit (its points move fast), nor a shuttle held
    before a serve with no flight before it.
    """
    sp = params.stereo
    stopped, flown, caught_at, new, net = state.stopped, state.last_flown, state.caught_at, False, False
    if sp.caught_frames <= 0 or not has_court_pose:
        caught_at = None
    elif obs.paired:
        stopped, flown, caught_at, new, net = _catch(state, obs, params)
    # A one-camera step reads the catch without ending it: the next pair step does.
    caught = caught_at is not None and sp.caught_frames > 0 and obs.t - caught_at <= sp.caught_hold
    last_point = state.last_point
    if not caught and obs.point_height is not None:
        last_point = (obs.t, obs.point_height)
    if caught:
        phase = ShuttlePhase.CAUGHT
    elif stopped:
        phase = ShuttlePhase.STOPPED
    elif obs.point_height is not None and obs.point_height > sp.landed_max_height:
        phase = ShuttlePhase.IN_PLAY
    elif (last_point is not None and obs.t - last_point[0] <= sp.landed_recent
          and last_point[1] <= sp.landed_max_height):
        phase = ShuttlePhase.LANDED
    else:
        phase = ShuttlePhase.UNSEEN
    return PhaseState(phase, stopped, flown, caught_at, new, last_point, net)


def withheld(state: PhaseState, t: float, params: TrackerParams) -> bool:
    """The shuttle is caught at ``t``: its readout is withheld."""
    return (state.caught_at is not None and params.stereo.caught_frames > 0
            and t - state.caught_at <= params.stereo.caught_hold)


def caught_flight(flight: FlightInfo) -> FlightInfo:
    """The flight as told while the shuttle is caught: out of play, no position, speed or landing
    for the robot to chase (the flight filter itself runs on, for the next serve)."""
    return dataclasses.replace(flight, velocity=None, prediction=None, in_flight=False,
                               withheld_reason=CAUGHT_REASON, confirmed=(), confirmed_path=())

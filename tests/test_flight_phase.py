"""The shuttle's phase as a pure state machine (core/flight/phase.py): each row of the transition
table in its docstring, driven with hand-made observations.

A row gives the state before, what one step observes, and the phase (and catch) after; the
transition must leave the state it was given as it was, and a one-camera step must neither start
nor end a catch.
"""

from __future__ import annotations

import dataclasses

import pytest

from badminton_gui.core.flight.phase import PhaseObservation, PhaseState, ShuttlePhase, transition, withheld
from badminton_gui.core.params import TrackerParams

P = TrackerParams()
SP = P.stereo
DT = 1.0 / 120.0
STILL = (0.5, -2.5, 0.9)        # court frame, m: in mid-air, away from the net


NET = (0.5, 0.1, 1.2)            # ... hanging in the net's mesh


def _stopping(n: int, t0: float = 1.0, at: tuple = STILL) -> PhaseState:
    """A flight followed at 5 m/s up to ``t0``, then ``n`` refused points at ``at``."""
    state = PhaseState(last_flown=(t0, 5.0), last_point=(t0, 0.9))
    for k in range(n):
        state = transition(state, PhaseObservation(t0 + (k + 1) * DT, at, accepted=False), P)
    return state


CAUGHT_AT = 1.0 + SP.caught_frames * DT
CAUGHT = _stopping(SP.caught_frames)

# (why, state before, observation, params, phase after, caught after)
TABLE = [
    ("a point above the floor is in play",
     PhaseState(), PhaseObservation(1.0, (0, 0, 2.0), True, 8.0, point_height=2.0), P, ShuttlePhase.IN_PLAY, False),
    ("a point on the floor is landed",
     PhaseState(), PhaseObservation(1.0, (0, 0, 0.05), True, 1.0, point_height=0.05), P, ShuttlePhase.LANDED, False),
    ("landed stays landed without points for landed_recent s",
     PhaseState(last_point=(1.0, 0.05)), PhaseObservation(1.0 + 0.9 * SP.landed_recent), P, ShuttlePhase.LANDED, False),
    ("... then unseen",
     PhaseState(last_point=(1.0, 0.05)), PhaseObservation(1.0 + 1.1 * SP.landed_recent), P, ShuttlePhase.UNSEEN, False),
    ("a refused point just after a fast flight starts a stop",
     PhaseState(last_flown=(1.0, 5.0)), PhaseObservation(1.0 + DT, STILL, False), P, ShuttlePhase.STOPPED, False),
    ("... not after a slow one (a shuttle held before the serve)",
     PhaseState(last_flown=(1.0, 2.0)), PhaseObservation(1.0 + DT, STILL, False), P, ShuttlePhase.UNSEEN, False),
    ("... nor long after the flight",
     PhaseState(last_flown=(1.0, 5.0)), PhaseObservation(1.0 + 2 * SP.caught_flight_gap, STILL, False), P,
     ShuttlePhase.UNSEEN, False),
    ("caught_frames stopped points in mid-air: caught",
     _stopping(SP.caught_frames - 1), PhaseObservation(CAUGHT_AT, STILL, False), P, ShuttlePhase.CAUGHT, True),
    ("... not at the net (caught_net_exception)",
     _stopping(SP.caught_frames - 1, at=NET), PhaseObservation(CAUGHT_AT, NET, False), P, ShuttlePhase.UNSEEN, False),
    ("... at the net too with caught_net_exception off",
     _stopping(SP.caught_frames - 1, at=NET), PhaseObservation(CAUGHT_AT, NET, False),
     P.with_value("stereo.caught_net_exception", False), ShuttlePhase.CAUGHT, True),
    ("... at the net's top with a smaller caught_net_margin",
     _stopping(SP.caught_frames - 1, at=NET), PhaseObservation(CAUGHT_AT, NET, False),
     P.with_value("stereo.caught_net_margin", 0.05), ShuttlePhase.CAUGHT, True),
    ("a stop after a slower flight with caught_min_flight_speed lowered",
     PhaseState(last_flown=(1.0, 2.0)), PhaseObservation(1.0 + DT, STILL, False),
     P.with_value("stereo.caught_min_flight_speed", 1.5), ShuttlePhase.STOPPED, False),
    ("... not when they lie on the floor",
     _stopping(SP.caught_frames - 1), PhaseObservation(CAUGHT_AT, STILL, False),
     P.with_value("stereo.landed_max_height", 1.0), ShuttlePhase.LANDED, False),
    ("a step with no measured point ends a stop",
     _stopping(3), PhaseObservation(1.0 + 4 * DT), P, ShuttlePhase.UNSEEN, False),
    ("caught holds while the hand moves it slowly",
     CAUGHT, PhaseObservation(CAUGHT_AT + DT, STILL, True, 2.0, point_height=0.9), P, ShuttlePhase.CAUGHT, True),
    ("a fast flight releases the catch",
     CAUGHT, PhaseObservation(CAUGHT_AT + DT, STILL, True, 6.0, point_height=0.9), P, ShuttlePhase.IN_PLAY, False),
    ("caught_hold s after the catch it ends",
     CAUGHT, PhaseObservation(CAUGHT_AT + SP.caught_hold + DT), P, ShuttlePhase.UNSEEN, False),
    ("a one-camera step holds the catch",
     CAUGHT, PhaseObservation(CAUGHT_AT + DT, paired=False), P, ShuttlePhase.CAUGHT, True),
    ("a one-camera step starts no stop",
     _stopping(SP.caught_frames - 1), PhaseObservation(CAUGHT_AT, paired=False), P, ShuttlePhase.STOPPED, False),
    ("the rule off: no catch",
     CAUGHT, PhaseObservation(CAUGHT_AT + DT), P.with_value("stereo.caught_frames", 0), ShuttlePhase.UNSEEN, False),
]


@pytest.mark.parametrize("why, before, obs, params, phase, caught", TABLE, ids=[row[0] for row in TABLE])
def test_the_transition_table(why, before, obs, params, phase, caught):
    kept = dataclasses.replace(before)
    after = transition(before, obs, params)
    assert before == kept, "the transition changed the state it was given"
    assert after.phase is phase, why
    assert withheld(after, obs.t, params) is caught, why


def test_the_caught_table_rows_start_where_they_say():
    assert CAUGHT.caught and CAUGHT.caught_at == pytest.approx(CAUGHT_AT) and CAUGHT.phase is ShuttlePhase.CAUGHT
    assert CAUGHT.caught_new
    assert not transition(CAUGHT, PhaseObservation(CAUGHT_AT + DT), P).caught_new


def test_a_caught_shuttles_point_is_not_the_last_point():
    """While caught, the step's point (the hand) is not remembered as the flight's last point:
    the landed hold must not start from a hand at 0.9 m."""
    after = transition(CAUGHT, PhaseObservation(CAUGHT_AT + DT, STILL, True, 2.0, point_height=0.9), P)
    assert after.last_point == CAUGHT.last_point
    free = transition(PhaseState(), PhaseObservation(2.0, point_height=0.05), P)
    assert free.last_point == (2.0, 0.05) and free.landed(2.5, P) and not free.landed(3.5, P)


def test_no_court_pose_no_catch():
    assert not transition(_stopping(SP.caught_frames - 1), PhaseObservation(CAUGHT_AT, STILL, False), P,
                          has_court_pose=False).caught


def test_a_stop_at_the_net_is_named_on_its_step():
    """``PhaseState.net_stop`` marks the step whose stop the net exception excused (the
    tracker's trace names it ``caught_net_exception``); never when the rule is off or the stop
    was a catch."""
    at_net = transition(_stopping(SP.caught_frames - 1, at=NET), PhaseObservation(CAUGHT_AT, NET, False), P)
    assert at_net.net_stop and not at_net.caught
    assert not transition(at_net, PhaseObservation(CAUGHT_AT + DT), P).net_stop
    off = P.with_value("stereo.caught_net_exception", False)
    assert not transition(_stopping(SP.caught_frames - 1, at=NET), PhaseObservation(CAUGHT_AT, NET, False), off).net_stop
    assert not CAUGHT.net_stop

"""The drag-model Kalman filter of one shot, and the drag model's propagation it stands on.

Why this module exists: :class:`~badminton_gui.core.flight.trajectory.Trajectory` decides *which*
points make a flight and when a shot starts or ends; the numerics of following one shot — the
quadratic-drag model ``a = g − k |v| v`` integrated in plain floats (RK4, adaptive step, cached
step chains), its linearisation (state-transition matrices), and the extended Kalman filter on
``(position, velocity, k)`` with its tests (χ², "surely moving", "velocity sure enough to show") —
live here, apart from those rules, so each can be read (and timed) on its own.
"""

from __future__ import annotations

import math
import struct
import threading
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np

from .. import physics

MIN_FLIGHT_SPEED = 1.0      # m/s: slower "tracks" are shuttles lying on the floor or held in a hand
VELOCITY_SIGMA_MIN = 0.5     # m/s: a velocity this uncertain (or 10 % of the speed) is not shown
VELOCITY_SIGMA_FRACTION = 0.10
K_MIN = 1.0 / physics.AERO_LENGTH_BOUNDS[1]
K_MAX = 1.0 / physics.AERO_LENGTH_BOUNDS[0]
_G = physics.GRAVITY
_I7 = np.eye(7)


# ---------------------------------------------------------------------------------------------
# The drag model in plain floats: per-frame work on 3-vectors is several times faster this way
# than with numpy arrays (call overhead dominates at this size).
# ---------------------------------------------------------------------------------------------
def _rk4(px, py, pz, vx, vy, vz, k, h):
    """One RK4 step of a = g − k|v|v; returns the new (px, py, pz, vx, vy, vz)."""
    s1 = math.sqrt(vx * vx + vy * vy + vz * vz) * k
    a1x, a1y, a1z = -s1 * vx, -s1 * vy, -_G - s1 * vz
    hh = 0.5 * h
    wx, wy, wz = vx + hh * a1x, vy + hh * a1y, vz + hh * a1z
    s2 = math.sqrt(wx * wx + wy * wy + wz * wz) * k
    a2x, a2y, a2z = -s2 * wx, -s2 * wy, -_G - s2 * wz
    ux, uy, uz = vx + hh * a2x, vy + hh * a2y, vz + hh * a2z
    s3 = math.sqrt(ux * ux + uy * uy + uz * uz) * k
    a3x, a3y, a3z = -s3 * ux, -s3 * uy, -_G - s3 * uz
    qx, qy, qz = vx + h * a3x, vy + h * a3y, vz + h * a3z
    s4 = math.sqrt(qx * qx + qy * qy + qz * qz) * k
    a4x, a4y, a4z = -s4 * qx, -s4 * qy, -_G - s4 * qz
    h6 = h / 6.0
    return (px + h6 * (vx + 2 * wx + 2 * ux + qx),
            py + h6 * (vy + 2 * wy + 2 * uy + qy),
            pz + h6 * (vz + 2 * wz + 2 * uz + qz),
            vx + h6 * (a1x + 2 * a2x + 2 * a3x + a4x),
            vy + h6 * (a1y + 2 * a2y + 2 * a3y + a4y),
            vz + h6 * (a1z + 2 * a2z + 2 * a3z + a4z))


def _step_size(vx, vy, vz, k, h_max):
    """A step of a tenth of the drag time constant 1/(k|v|), at most h_max (RK4 is then exact to
    well under a millimetre over a whole flight)."""
    s = math.sqrt(vx * vx + vy * vy + vz * vz) * k
    return h_max if s * h_max <= 0.12 else 0.12 / s


def _propagate(state, k, duration, h_max=0.01):
    """The state ``(px, py, pz, vx, vy, vz)`` after ``duration`` seconds (may be negative).

    Steps of ``_step_size`` each, the last one cut to what remains. The full steps from a
    state do not depend on the duration, so they are kept (``_CHAINS``, keyed on the state's,
    k's, the direction's and h_max's bits) and a later call from the same state replays them:
    the flight's ``predicted`` at 17 instants in ``_continuous``, the tentative track at each
    of its points in ``_consistent``, every frame a refused track is re-tried (4–5 ms spikes in
    play). Only the cut last step is integrated anew; the remaining time is subtracted
    step by step as before, so the result is the plain loop's, bit for bit
    (tests/test_speed_oracles.py keeps the plain loop as the reference).
    """
    if duration == 0.0:
        return state
    sign = 1.0 if duration > 0 else -1.0
    remaining = abs(duration)
    key = _CHAIN_KEY(*state, k, sign, h_max)
    with _CHAINS_LOCK:
        chain = _CHAINS.get(key)
        if chain is None:
            chain = _CHAINS[key] = ([state], [])
            if len(_CHAINS) > _CHAINS_MAX:
                _CHAINS.popitem(last=False)
        else:
            _CHAINS.move_to_end(key)
        states, steps = chain      # len(states) == len(steps) + 1
        s = state
        i = 0
        for h in steps:
            if not remaining > 1e-12:
                return s
            if remaining < h:
                # min(step, remaining) is the remaining time: the last, cut step.
                return _rk4(*s, k, sign * remaining)
            i += 1
            s = states[i]
            remaining -= h
        while remaining > 1e-12:
            h = _step_size(s[3], s[4], s[5], k, h_max)
            if remaining < h:
                return _rk4(*s, k, sign * remaining)
            s = _rk4(*s, k, sign * h)
            steps.append(h)
            states.append(s)
            remaining -= h
        return s


# ``_propagate``'s full steps from recent start states: key → ([state, after 1 step, ...],
# [step 0, step 1, ...]); the least recently used chain goes first.
_CHAINS: OrderedDict[bytes, tuple[list, list]] = OrderedDict()
_CHAINS_MAX = 32
_CHAINS_LOCK = threading.Lock()
_CHAIN_KEY = struct.Struct("9d").pack


def position_on_path(path: tuple, t: float) -> tuple[float, float, float]:
    """Where the drag-model path ``(t0, x, y, z, vx, vy, vz, k)`` puts the shuttle at ``t``
    (``FlightInfo.confirmed_path``)."""
    return tuple(float(v) for v in _propagate(tuple(path[1:7]), float(path[7]), t - path[0])[:3])


def _jacobians(vel: np.ndarray, k: np.ndarray | float) -> np.ndarray:
    """Continuous-time Jacobians F (n, 7, 7) of d(p, v, k)/dt at velocities ``vel`` (n, 3)."""
    vel = np.atleast_2d(vel)
    n = vel.shape[0]
    speed = np.maximum(np.linalg.norm(vel, axis=1), 1e-9)
    k = np.broadcast_to(np.asarray(k, dtype=float), (n,))
    f = np.zeros((n, 7, 7))
    f[:, 0, 3] = f[:, 1, 4] = f[:, 2, 5] = 1.0
    # ∂a/∂v = −k (|v| I + v vᵀ/|v|);  ∂a/∂k = −|v| v
    f[:, 3:6, 3:6] = -(k[:, None, None] * (speed[:, None, None] * np.eye(3)
                                            + vel[:, :, None] * vel[:, None, :] / speed[:, None, None]))
    f[:, 3:6, 6] = -speed[:, None] * vel
    return f


def _transitions(vel: np.ndarray, k: float, steps: np.ndarray) -> np.ndarray:
    """Discrete transition matrices I + FΔ + (FΔ)²/2 for each (velocity, step) pair, (n, 7, 7)."""
    fd = _jacobians(vel, k) * steps[:, None, None]
    return _I7 + fd + 0.5 * (fd @ fd)


def _chain(phis: np.ndarray) -> np.ndarray:
    """Product Φn ··· Φ2 Φ1 of a stack of matrices by pairwise (tree) reduction."""
    while phis.shape[0] > 1:
        if phis.shape[0] % 2:
            phis = np.concatenate([phis, _I7[None]], axis=0)
        phis = phis[1::2] @ phis[0::2]
    return phis[0]


# ---------------------------------------------------------------------------------------------
@dataclass(slots=True)
class _Filter:
    """Extended Kalman filter on (p, v, k) for one flight (mutable, private)."""

    x: np.ndarray          # (7,) state at time t
    P: np.ndarray          # (7, 7) covariance
    t: float
    k_prior: tuple[float, float]   # (mean, variance) of k when the filter started
    points: list           # accepted measurements (t, x, y, z)
    start_t: float
    noises: list           # the (3, 3) noise covariance each accepted point was given
    track: list = field(default_factory=list)   # the filtered position after each update (t, x, y, z)


    @classmethod
    def from_two_points(cls, t1, p1, r1, t2, p2, r2, k_prior):
        """A filter started from two points with noise covariances ``r1``, ``r2`` (3×3, m²)."""
        dt = t2 - t1
        p1 = np.asarray(p1, dtype=float)
        p2 = np.asarray(p2, dtype=float)
        v_mid = (p2 - p1) / dt
        k = k_prior[0]
        # The chord gives the velocity at mid-interval; carry it to t2 with the model.
        speed = float(np.linalg.norm(v_mid))
        acc = physics.GRAVITY_VECTOR - k * speed * v_mid
        v2 = v_mid + acc * (0.5 * dt)
        x = np.concatenate([p2, v2, [k]])
        P = np.zeros((7, 7))
        r1 = np.asarray(r1, dtype=float)
        r2 = np.asarray(r2, dtype=float)
        # Velocity: chord noise, the model's change of acceleration over the interval, and the
        # unknown k (a smash decelerates at ~2000 m/s²) — generous, the next points settle it.
        var_v = ((0.5 * float(np.linalg.norm(acc)) * dt) ** 2
                 + (0.5 * speed * speed * dt) ** 2 * k_prior[1] + 0.25)
        P[0:3, 0:3] = r2
        P[3:6, 3:6] = (r1 + r2) / (dt * dt) + np.eye(3) * var_v
        P[0:3, 3:6] = P[3:6, 0:3] = r2 / dt
        P[6, 6] = k_prior[1]
        return cls(x=x, P=P, t=t2, k_prior=k_prior,
                   points=[(t1, *p1.tolist()), (t2, *p2.tolist())], start_t=t1, noises=[r1, r2],
                   track=[(t2, *p2.tolist())])

    # ---- prediction -----------------------------------------------------------------------
    def predicted(self, t: float) -> tuple[float, float, float, float, float, float]:
        return _propagate(tuple(self.x[:6].tolist()), float(self.x[6]), t - self.t)

    def predict(self, t: float, accel_noise: float) -> None:
        """Move the state and covariance to time t."""
        dt = t - self.t
        if dt <= 0.0:
            return
        k = float(self.x[6])
        s = tuple(self.x[:6].tolist())
        # Sub-steps short enough for the linearisation (a smash changes speed fast).
        vels, steps = [], []
        remaining = dt
        while remaining > 1e-12:
            h = min(_step_size(s[3], s[4], s[5], k, 0.01), remaining)
            vels.append(s[3:6])
            steps.append(h)
            s = _rk4(*s, k, h)
            remaining -= h
        phi = _chain(_transitions(np.asarray(vels), k, np.asarray(steps)))
        self.x = np.array([*s, k])
        P = phi @ self.P @ phi.T
        if accel_noise > 0.0:
            # White acceleration noise (model mismatch: flipping after a hit, spin, air currents).
            q = accel_noise * accel_noise
            P[0:3, 0:3] += np.eye(3) * (q * dt ** 3 / 3.0)
            P[0:3, 3:6] += np.eye(3) * (q * dt ** 2 / 2.0)
            P[3:6, 0:3] += np.eye(3) * (q * dt ** 2 / 2.0)
            P[3:6, 3:6] += np.eye(3) * (q * dt)
        self.P = P
        self.t = t

    # ---- measurement ----------------------------------------------------------------------
    def innovation(self, z: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """(innovation, its covariance S, squared Mahalanobis distance) of a point at self.t
        whose noise covariance is ``r`` (3×3)."""
        nu = z - self.x[:3]
        S = self.P[0:3, 0:3] + r
        d2 = float(nu @ np.linalg.solve(S, nu))
        return nu, S, d2

    def correct(self, t: float, z: np.ndarray, nu: np.ndarray, S: np.ndarray, r: np.ndarray) -> None:
        PHt = self.P[:, 0:3]
        K = np.linalg.solve(S, PHt.T).T          # (7, 3), S is symmetric
        self.x = self.x + K @ nu
        IKH = _I7.copy()
        IKH[:, 0:3] -= K
        # Joseph form: stays positive definite whatever the rounding.
        self.P = IKH @ self.P @ IKH.T + K @ r @ K.T
        self.x[6] = min(max(self.x[6], K_MIN), K_MAX)
        self.points.append((t, float(z[0]), float(z[1]), float(z[2])))
        self.noises.append(r)
        self.track.append((t, float(self.x[0]), float(self.x[1]), float(self.x[2])))

    def correct_across(self, t: float, basis: np.ndarray, nu: np.ndarray, S: np.ndarray,
                       r: np.ndarray) -> None:
        """A measurement of the position across a line of sight only: ``basis`` (2, 3) spans the
        plane across it, ``nu`` (2,) the innovation there, ``r`` (2, 2) its noise. No point is
        recorded (the shot's points are the triangulated ones)."""
        PHt = self.P[:, 0:3] @ basis.T           # (7, 2)
        K = np.linalg.solve(S, PHt.T).T
        self.x = self.x + K @ nu
        IKH = _I7.copy()
        IKH[:, 0:3] -= K @ basis
        self.P = IKH @ self.P @ IKH.T + K @ r @ K.T
        self.x[6] = min(max(self.x[6], K_MIN), K_MAX)
        self.t = t
        self.track.append((t, float(self.x[0]), float(self.x[1]), float(self.x[2])))

    @property
    def speed(self) -> float:
        return float(np.linalg.norm(self.x[3:6]))


def _chi2_999(dof: int) -> float:
    """99.9 % quantile of χ² with ``dof`` degrees of freedom (Wilson–Hilferty, within ~1 %)."""
    a = 2.0 / (9.0 * dof)
    return dof * (1.0 - a + 3.090 * math.sqrt(a)) ** 3


def _points_travel(f: _Filter) -> bool:
    """The track's points, first to last, moved at least MIN_FLIGHT_SPEED on average."""
    if len(f.points) < 2:
        return False
    (t0, *p0), (t1, *p1) = f.points[0], f.points[-1]
    return t1 > t0 and math.dist(p0, p1) >= MIN_FLIGHT_SPEED * (t1 - t0)


def _velocity_is_sure(f: _Filter) -> bool:
    """Is the filter's velocity known well enough to be shown as the speed (σ ≤ 10 %, or 0.5 m/s)?"""
    var = float(f.P[3, 3] + f.P[4, 4] + f.P[5, 5]) / 3.0
    limit = max(VELOCITY_SIGMA_MIN, VELOCITY_SIGMA_FRACTION * f.speed)
    return var <= limit * limit

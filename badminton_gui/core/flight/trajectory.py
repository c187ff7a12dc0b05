"""From 3D points to a flight: smoothing, speed, shot segmentation and landing prediction.

Why this file exists: the stereo tracker stops at one 3D point per frame pair; the robot needs the
shuttle's velocity and, above all, *where and when it will land*, early and exact. This module
turns the stream of (noisy, sometimes wrong, sometimes missing) points into that, once per frame,
within a budget of about a millisecond (it runs inside the tracker at 120 fps).

How (court frame, Z up):

* Each shot is followed by an extended Kalman filter on the state ``(position, velocity, k)``
  of the quadratic-drag model of ``core/physics.py``, ``a = g − k |v| v`` with ``k = 1/L``.
  The aerodynamic length is part of the state, so every shot *fits* its own L; the filter is the
  recursive form of the Gauss–Newton fit of (p0, v0, L) to the shot's points (one linearisation
  per point around the current estimate, exact for the linear measurement), at a fraction of the
  cost of refitting the whole shot every frame. L is kept inside ``physics.AERO_LENGTH_BOUNDS``.
* The session prior on L: when a shot ends, the information its points carried about L (its
  posterior minus the prior it started with) is added to a session estimate, which is the prior of
  the next shot. A variance floor keeps it adaptable (feathers wear, shuttles are changed).
* Outliers: a point whose innovation is beyond ``outlier_sigma`` standard deviations (or farther
  than ``outlier_distance``) is not used. Rejected points seed a *tentative* track. It replaces
  the flight when at least ``CONFIRM_POINTS`` consecutive rejected points lie on one drag path
  (χ² test), are surely moving (speed − 2σ ≥ 1 m/s) and start above the floor. While a flight is
  being followed it takes more: ``TAKEOVER_POINTS`` points, and a path that meets the flight's
  where the shuttle could have been hit (the shuttle does not jump), so a few wrong points in a
  row (a racket, a shoe) cannot replace a good flight. If the new track's velocity differs from
  the flight's by more than ``hit_acceleration`` × the time step, that is a hit: a new shot
  starts. Otherwise the flight was only re-synchronised (model mismatch) and keeps its shot
  number and its L.
* The points' noise: ``measurement_noise`` is a floor; the filter measures the real scatter from
  the innovations of established flights (robust median) and uses the larger of the two, so a
  rig noisier than declared does not get its good points rejected and its shots chopped up.
* A flight ends when the shuttle reaches the floor (a point, or the model's landing time, says
  so), or after ``max_gap`` seconds without a usable point; its last landing prediction stays
  available (``in_flight`` False) until the next shot starts.
* The landing point is the drag model integrated (RK4, adaptive step) from the current state down
  to Z = 0; its uncertainty is the filter covariance carried along that path by the linearised
  dynamics (state-transition matrices) and projected onto the floor. The in/out call uses
  ``court.is_in``.

Without a court pose (points in the left-camera frame) gravity's direction is unknown, so there is
no drag model: velocity comes from a local quadratic fit of the last few points, and landing
predictions are withheld with a reason.
"""

from __future__ import annotations

import math
import struct
import threading
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np

from .. import court, physics
from ..params import TrajectoryParams
from ..types import FlightInfo, LandingPrediction

NO_COURT_POSE = "no court pose: calibrate the court pose to get landing predictions"
CONFIRM_POINTS = 4          # consecutive agreeing points that start a flight
TAKEOVER_POINTS = 6         # ... that replace a flight being followed (a hit, or a re-synchronisation):
                            # the demo pipeline makes runs of 4 wrong points (centroid on the skirt
                            # or a racket for a few frames) that had replaced a good flight 230 ms
                            # before landing and cost its prediction
MIN_FLIGHT_SPEED = 1.0      # m/s: slower "tracks" are shuttles lying on the floor or held in a hand
LANDED_HEIGHT = 0.03        # m: a flight whose estimate is this low has landed (cork radius ≈ 1.3 cm)
MIN_START_HEIGHT = 0.15     # m: no flight starts lower (a shuttle rolling or picked up off the floor;
                            # with noisy points its 4-point "speed" easily exceeds MIN_FLIGHT_SPEED)
VELOCITY_SIGMA_MIN = 0.5     # m/s: a velocity this uncertain (or 10 % of the speed) is not shown
VELOCITY_SIGMA_FRACTION = 0.10
REST_MAX_HEIGHT = 0.10      # m: a point this low next to the last landing is the shuttle lying there
REST_RADIUS = 0.6           # m: ... within this distance of the predicted landing (it may bounce)
LANDING_GRACE_S = 0.03      # s: a flight past its predicted landing time by this much has landed
NOISE_WINDOW = 120          # innovations kept for the measured-noise estimate (~1 s at 120 fps)
NOISE_MIN_SAMPLES = 30      # before that many, the parameter alone sets the noise
COAST_VELOCITY_S = 0.1     # s: no speed shown after this long without a point (a hidden hit, seen in
                            # the demo: a shuttle behind a player for 190 ms, hit meanwhile)
TENTATIVE_FLOOR = 0.01      # m: noise added to the points of a tentative track at ≥ STARVED_MIN_SPEED: right
                            # after a hit the shuttle turns over and its points scatter by 1–6 cm
                            # about the new path (rally_11-46-22 429–432) where the stereo noise
                            # model says ≈ 2 mm, and the tentative track restarted at each
MIN_SHOT_TIME = 0.1         # s: no two hits closer together (a flight younger is re-synchronised)
TENTATIVE_REPORT_POINTS = 4  # a tentative track this long, consistent and fast, gives the robot its
                            # position while the old flight still refuses its points
                            # (``tentative_position``); at 3 the demo court's short runs of wrong
                            # points were reported too (one 90 cm off: 3D RMS 0.90 → 1.08 cm)
HIT_SLACK = 0.05            # m: at a hit the blob's centroid swaps sides of the cork (skirt lag ~2 cm)
STARVED_MIN_SPEED = 5.0     # m/s: a track that takes over a starved flight (``starved_takeover``) is a
                            # shot; a hand carrying a caught shuttle moves slower (≤ 2.6 m/s: the
                            # tracker's caught rule needs the flight to refuse those points)
MAX_RADIUS = 2.0            # m: a landing this uncertain is withheld (a fresh, poorly fixed track)
MAX_FLIGHT_TIME = 6.0       # s: the landing search stops here
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
    play, benchmarks/README.md). Only the cut last step is integrated anew; the remaining time
    is subtracted step by step as before, so the result is the plain loop's, bit for bit
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


@dataclass(frozen=True, slots=True)
class _Landing:
    """A landing computed from a filter state (cached until the next accepted point)."""

    prediction: LandingPrediction
    path: np.ndarray           # (M, 3) predicted positions from now to the floor


class Trajectory:
    """Per-frame flight model: call :meth:`update` once per frame pair with the 3D point or None.

    ``court_frame`` says whether the points are in court coordinates (Z up); without it there are
    no landing predictions (see the module docstring).
    """

    def __init__(self, params: TrajectoryParams, court_frame: bool) -> None:
        self.params = params
        self.court_frame = bool(court_frame)
        self.reset()

    # ---- configuration ---------------------------------------------------------------------
    def set_params(self, params: TrajectoryParams) -> None:
        """Apply a new parameter snapshot; the current flight continues."""
        self.params = params
        self._noise_dirty = True

    def reset(self) -> None:
        """Forget every flight and the session's estimate of L."""
        k0 = 1.0 / physics.DEFAULT_AERO_LENGTH
        sigma_k0 = self._sigma_k(self.params.aero_length_sigma)
        self._session_k = (k0, sigma_k0 * sigma_k0)
        self._flight: _Filter | None = None
        self._tentative: _Filter | None = None
        self._seed: tuple[float, np.ndarray, np.ndarray] | None = None  # last unexplained point, its noise
        # Consecutive promotions of the tentative track refused only because it does not meet the
        # followed flight's path (``params.starved_takeover``).
        self._apart = 0
        self._shot_index = -1
        self._peak_speed: float | None = None
        self._launch_speed: float | None = None
        self._landing: _Landing | None = None
        # Where the last flight came down and its horizontal direction there: a shuttle lying
        # on the floor lies along it, cork ahead (see resting_direction).
        self._rest_anchor: tuple[float, float, float, float] | None = None
        self._last_t: float | None = None
        self._ended_points: np.ndarray | None = None
        self._ended_track: np.ndarray | None = None
        self._recent: list[tuple[float, float, float, float]] = []   # camera-frame mode
        self._velocity_no_model: tuple[float, float, float] | None = None
        self._misses_no_model = 0     # consecutive points off the local fit (camera-frame mode)
        # Per point of an established flight: (|w|², state variance along w) with w the innovation
        # whitened by the point's noise shape (see measurement_noise_matrix).
        self._noise_samples: list[tuple[float, float]] = []
        self._noise_count = 0
        self._noise_dirty = True
        self._sigma_cache = self.params.measurement_noise
        self._stereo_noise = False    # the points come with their stereo noise shape (px units)
        self._accepted_now = False    # the last update's point extended the flight
        self._rejected_now = False    # ... was refused by a flight being followed
        self._extended_tentative = False  # ... extended the tentative track (not a restart)
        # (t, x, y, z) for each point a flight took up from its tentative track at the last
        # update, on that track's fitted path: earlier frames' points, refused then, which the
        # flight now vouches for (``FlightInfo.confirmed``).
        self._confirmed_now: tuple = ()
        # ... and that track's state then, or the flight's when it took the last update's point:
        # (t, x, y, z, vx, vy, vz, k) (``FlightInfo.confirmed_path``).
        self._confirmed_path: tuple = ()
        self.shots_ended = 0

    # ---- read-only views for plots and tests ------------------------------------------------
    def current_flight(self) -> np.ndarray:
        """Accepted points of the current (or just ended) shot, (N, 4): t, x, y, z."""
        if not self.court_frame:
            return np.asarray(self._recent, dtype=float).reshape(-1, 4)
        if self._flight is not None:
            return np.asarray(self._flight.points, dtype=float).reshape(-1, 4)
        if self._ended_points is not None:
            return self._ended_points
        return np.zeros((0, 4))

    def current_track(self) -> np.ndarray:
        """The filtered positions of the current (or just ended) shot after each of its updates,
        (N, 4): t, x, y, z — the path the robot was given, where ``current_flight`` has the raw
        points (several centimetres of scatter at 7 m on the demo court)."""
        if not self.court_frame:
            return self.current_flight()
        if self._flight is not None:
            return np.asarray(self._flight.track, dtype=float).reshape(-1, 4)
        if self._ended_track is not None:
            return self._ended_track
        return np.zeros((0, 4))

    def predicted_path(self) -> np.ndarray:
        """Predicted positions from the current state to the floor, (M, 3) (empty if none)."""
        if self._landing is None or self._flight is None:
            return np.zeros((0, 3))
        return self._landing.path

    @property
    def session_aero_length(self) -> float:
        """The session's estimate of L (the prior of the next shot), m."""
        return 1.0 / self._session_k[0]

    @property
    def current_aero_length(self) -> float | None:
        """The current shot's fitted L, m, or None without a flight."""
        return None if self._flight is None else 1.0 / float(self._flight.x[6])

    # ---- the per-frame entry point ------------------------------------------------------------
    def update(self, t: float, point: tuple | None, noise_shape: np.ndarray | None = None,
               extra_noise: np.ndarray | None = None) -> FlightInfo:
        """Feed one frame pair's 3D point (or None) at time t (s); returns the flight state.

        ``noise_shape`` (3×3, m² per px²) is the point's covariance for 1 px of noise on each
        image coordinate (``StereoTracker`` computes it from the rig): a triangulated point is
        several times less sure in depth than across, and far points less than near ones, so the
        filter weighs each point by its own geometry and the scale (px) is measured from the
        flight's innovations. Without it the noise is isotropic (``measurement_noise``, m).
        ``extra_noise`` (3×3, m²) is added to that: an error the point may carry that its image
        noise does not explain (the tracker's cork correction made in a doubtful direction).
        """
        self._begin_step(t)
        if not self.court_frame:
            return self._update_no_model(t, point)
        self._end_stale(t)

        accepted = False
        if point is not None:
            z = np.asarray(point, dtype=float)
            if np.all(np.isfinite(z)):
                following = self._flight is not None
                extra = None if extra_noise is None else np.asarray(extra_noise, dtype=float)
                accepted = self._feed(t, z, self._noise_matrix(noise_shape), extra)
                self._rejected_now = following and not accepted
        if accepted and not self._confirmed_path and self._flight is not None:
            # The flight took this point: its path now, for frames just before it that it
            # refused (``FlightInfo.confirmed_path``).
            f = self._flight
            self._confirmed_path = (float(f.t), *(float(v) for v in f.x[:7]))
        self._accepted_now = accepted
        return self._info(t, accepted)

    def update_ray(self, t: float, centre, direction, pixel_angle: float, lead: float = 0.0,
                   lead_min_speed: float = 0.0) -> FlightInfo:
        """Feed one camera's sight of the shuttle at time t (s): the line through ``centre`` along
        the unit ``direction`` (court frame) on which it lies, from a step that brought this camera's
        image only (cameras without a common trigger). ``pixel_angle`` (rad) is one image pixel
        seen from the camera (1 / focal length in px). ``lead`` (m): the shuttle the flight
        follows lies this far ahead of the seen point along its flight (the cork ahead of the
        blob's centroid, as the tracker's triangulated points are moved) when the flight is at
        least ``lead_min_speed`` (m/s) fast.

        Only an established flight (``guide``'s condition) takes it, gated as a point is: the
        filter moves across the line of sight, by the points' measured pixel scale at the
        flight's range, and learns nothing along it. Returns the flight state; the filtered
        position is then ``filtered_position`` as after a point.
        """
        self._begin_step(t)
        if not self.court_frame:
            return self._update_no_model(t, None)
        self._end_stale(t)
        flight = self._flight
        if (flight is None or not self._stereo_noise or t <= flight.t
                or len(flight.points) < self.params.min_points):
            return self._info(t, False)
        p = self.params
        d = np.asarray(direction, dtype=float)
        d = d / np.linalg.norm(d)
        # Two unit vectors across the line of sight.
        helper = np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        e1 = np.cross(d, helper)
        e1 /= np.linalg.norm(e1)
        basis = np.stack([e1, np.cross(d, e1)])
        saved = (flight.x, flight.P, flight.t)
        flight.predict(t, p.model_noise)
        offset = flight.x[:3] - np.asarray(centre, dtype=float)
        speed = float(np.linalg.norm(flight.x[3:6]))
        if lead > 0.0 and speed >= max(lead_min_speed, 1e-9):
            offset = offset - lead * flight.x[3:6] / speed
        rng = float(np.linalg.norm(offset))
        sigma = self.measurement_sigma * pixel_angle * rng          # m across the ray at that range
        r = np.eye(2) * (sigma * sigma)
        nu = -(basis @ offset)                                      # the ray passes through 0 across
        S = basis @ flight.P[0:3, 0:3] @ basis.T + r
        d2 = float(nu @ np.linalg.solve(S, nu))
        if d2 > p.outlier_sigma ** 2 or float(np.linalg.norm(nu)) > p.outlier_distance:
            flight.x, flight.P, flight.t = saved
            return self._info(t, False)
        robust = p.robust_sigma
        if robust > 0.0 and d2 > robust * robust:
            # As for a point (``_feed``): beyond robust_sigma σ, the farther the less it pulls.
            r = r * (d2 / (robust * robust))
            S = basis @ flight.P[0:3, 0:3] @ basis.T + r
        flight.correct_across(t, basis, nu, S, r)
        self._after_flight_update()
        self._apart = 0           # the followed flight is seen: it does not starve
        self._accepted_now = True
        return self._info(t, True)

    def _begin_step(self, t: float) -> None:
        """The start of every update: a clock that went back resets, the last step's flags clear."""
        if self._last_t is not None and t < self._last_t - 1e-9:
            self.reset()        # the clock went back: a new video / replay
        self._last_t = t
        self._accepted_now = self._rejected_now = self._extended_tentative = False
        self._confirmed_now = ()
        self._confirmed_path = ()

    def _end_stale(self, t: float) -> None:
        """End a flight past its landing or unseen for ``max_gap``; forget an old tentative track."""
        p = self.params
        if self._flight is not None:
            if self._landing is not None and t > self._landing.prediction.t + LANDING_GRACE_S:
                # The model says it is on the floor by now even if the last points were not usable.
                self._end_flight(keep_landing=True)
            elif t - self._flight.t > p.max_gap:
                self._end_flight(keep_landing=True)   # lost: the robot keeps the last prediction
        if self._tentative is not None and t - self._tentative.t > p.max_gap:
            self._tentative = None
        if self._seed is not None and t - self._seed[0] > p.max_gap:
            self._seed = None

    def filtered_position(self) -> tuple[float, float, float] | None:
        """The flight's filtered position at the last update's time, when that update's point
        extended a flight (``update`` returned accepted); else None."""
        if not self._accepted_now or self._flight is None:
            return None
        return tuple(float(v) for v in self._flight.x[:3])

    def tentative_position(self) -> tuple[float, float, float] | None:
        """The tentative track's position at the last update's time when that update's point,
        refused by the flight being followed, extended a track that is surely a new shot: at
        least ``TENTATIVE_REPORT_POINTS`` points on one drag-model path (``_consistent``; or its
        latest that many — all but its first when it has just that many — refitted alone),
        moving at ``STARVED_MIN_SPEED`` or more; else None.

        After a hit the new shot's points are refused by the old flight until the new track has
        ``TAKEOVER_POINTS`` of them (and longer when its first points are off): ≈ 50 ms at
        119 fps in which the robot got no 3D point although both cameras saw the shuttle. The
        track does not take the flight over any sooner (a run of a few wrong points must not
        replace a good flight's landing), but its position is the shuttle's. A hand carrying a
        caught shuttle is slower than ``STARVED_MIN_SPEED``, a racket's few frames no path.
        """
        tent = self._tentative
        if not self._extended_tentative or tent is None or len(tent.points) < TENTATIVE_REPORT_POINTS:
            return None
        if not self._consistent(tent):
            # Its first point is often the hit itself (the blob merged with the racket): the
            # track's latest points alone may still lie on one path — all but its first when
            # it has just that many.
            n = min(TENTATIVE_REPORT_POINTS, len(tent.points) - 1)
            tent = self._refit(tent.points[-n:], tent.noises[-n:])
            if tent is None or len(tent.points) < n or not self._consistent(tent):
                return None
        if tent.speed < STARVED_MIN_SPEED:
            return None
        return tuple(float(v) for v in tent.x[:3])

    def guide(self, t: float) -> tuple[np.ndarray, np.ndarray] | None:
        """Where the followed flight puts the shuttle at time t: (position (3,), its covariance
        (3, 3)), or None when there is no established flight to trust (fewer than ``min_points``
        points, lost for longer than ``max_gap``, or a new track is being confirmed: a hit)."""
        f = self._flight
        p = self.params
        tent = self._tentative
        if (p.guide_tentative_points > 0 and tent is not None
                and len(tent.points) >= p.guide_tentative_points and t - tent.t <= p.max_gap):
            # A new shot being confirmed after a hit: the old flight is wrong there, but the
            # new track's points already agree on a path; without a guide the cameras lose a
            # shuttle that merges with a player right after the hit, and the track never gets
            # the points that would confirm it.
            if not _points_travel(tent):
                # A track whose points do not move is no shot: a shuttle lying on the floor
                # (never promoted, its points go on for as long as it lies there) or held.
                # Carried on, its state falls through the floor, and once the shuttle was taken
                # away the cameras' coasting reported that fall under a player walking past
                # (demo court seed 0 1020–1030, seed 2 1235–1236: up to max_gap after its last
                # point). Its points, not its state: a drag-and-gravity fit to still points
                # settles on a sinking velocity (≈ 1 m/s on the demo court, MIN_FLIGHT_SPEED).
                return None
            f = tent
        elif (f is None or len(f.points) < p.min_points or t - f.t > p.max_gap
                or (tent is not None and len(tent.points) >= 3)):
            return None
        saved = (f.x, f.P, f.t)
        f.predict(t, p.model_noise)
        position, covariance = f.x[:3].copy(), f.P[0:3, 0:3].copy()
        f.x, f.P, f.t = saved
        return position, covariance

    def resting_direction(self, point) -> tuple[float, float] | None:
        """The horizontal direction (unit x, y) of the flight that came down next to ``point``, when
        the point is a shuttle lying on the floor there (no flight followed, at floor height,
        within ``REST_RADIUS`` of the last landing); else None."""
        if self._flight is not None or self._rest_anchor is None or point is None:
            return None
        x, y, dx, dy = self._rest_anchor
        if point[2] > REST_MAX_HEIGHT or math.hypot(point[0] - x, point[1] - y) > REST_RADIUS:
            return None
        return dx, dy

    @property
    def last_time(self) -> float | None:
        """The time (s) of the last update, or None before the first (a later update may not be
        earlier: a clock that goes back resets the trajectory)."""
        return self._last_t

    @property
    def point_rejected(self) -> bool:
        """The last update's point was refused by the flight being followed (an outlier: a wrong
        pair, a racket) and did not start a new one."""
        return self._rejected_now

    # ---- measurement noise ------------------------------------------------------------------
    def _noise_matrix(self, shape: np.ndarray | None) -> np.ndarray:
        """The 3×3 covariance of a point: its stereo shape × (px scale)², or isotropic (m)."""
        stereo = shape is not None
        if stereo != self._stereo_noise:
            # The units of the measured scale change (px vs m): start measuring afresh.
            self._stereo_noise = stereo
            self._noise_samples.clear()
            self._noise_dirty = True
        sigma = self.measurement_sigma
        if stereo:
            return np.asarray(shape, dtype=float) * (sigma * sigma)
        return np.eye(3) * (sigma * sigma)

    # ---- court-frame machinery ---------------------------------------------------------------
    def _feed(self, t: float, z: np.ndarray, r: np.ndarray, extra: np.ndarray | None = None) -> bool:
        """Use one point with noise covariance ``r``; True when it extended the current flight.

        ``extra`` (m²) is added to ``r`` for weighing the point, not for gating it: the doubt it
        stands for (a cork correction in the wrong direction, right after a hit) is also a sign
        that the point may not belong to the flight, and must not widen the gate.
        """
        p = self.params
        flight = self._flight
        if flight is not None and t > flight.t:
            # Gate against a copy of the prediction: a rejected point must leave the flight as it was.
            saved = (flight.x, flight.P, flight.t)
            flight.predict(t, p.model_noise)
            nu, S, d2 = flight.innovation(z, r)
            if len(flight.points) >= p.min_points:
                self._observe_noise(nu, flight.P, r)
            if d2 <= p.outlier_sigma ** 2 and float(np.linalg.norm(nu)) <= p.outlier_distance:
                weigh = r if extra is None else r + extra
                robust = p.robust_sigma
                if robust > 0.0 and d2 > robust * robust:
                    # Beyond robust_sigma σ the point's noise is scaled by (d / robust_sigma)²
                    # (an iteratively-reweighted, redescending weight: once the flight is surer
                    # than the point, the farther the point the less it moves the flight). A
                    # blob merged with a line or a racket for a frame passes the 5σ gate of a
                    # young flight and had dragged it by centimetres for ten frames.
                    weigh = weigh * (d2 / (robust * robust))
                if weigh is not r:
                    nu, S, _ = flight.innovation(z, weigh)
                flight.correct(t, z, nu, S, weigh)
                self._after_flight_update()
                self._tentative = None
                self._seed = None
                self._apart = 0
                return True
            flight.x, flight.P, flight.t = saved
        self._feed_tentative(t, z, r, extra)
        return self._flight is not None and self._flight.t == t

    def _observe_noise(self, nu: np.ndarray, P: np.ndarray, r: np.ndarray) -> None:
        """Collect one innovation of an established flight for the measured-noise estimate.

        The innovation is whitened by the point's noise shape (``r`` / σ²), so the samples
        measure the one scale σ whatever the point's range and direction.
        """
        if float(nu @ nu) > self.params.outlier_distance ** 2:
            return
        sigma2 = self.measurement_sigma ** 2
        if self._stereo_noise:
            chol = np.linalg.cholesky(r / sigma2)
            w = np.linalg.solve(chol, nu)
            Pw = np.linalg.solve(chol, np.linalg.solve(chol, P[0:3, 0:3]).T)
            sample = (float(w @ w), float(np.trace(Pw)) / 3.0)
        else:
            sample = (float(nu @ nu), float(P[0, 0] + P[1, 1] + P[2, 2]) / 3.0)
        self._noise_samples.append(sample)
        if len(self._noise_samples) > NOISE_WINDOW:
            del self._noise_samples[:-NOISE_WINDOW]
        self._noise_count += 1
        if self._noise_count % 8 == 0:       # re-estimate every few points: a median costs
            self._noise_dirty = True

    @property
    def measurement_sigma(self) -> float:
        """σ of the points used by the filter: the parameter, or more if the points say so.

        In metres for isotropic points, in image pixels for points with a stereo noise shape.
        The points' real scatter is estimated from recent (whitened) innovations of established
        flights: |w|² ~ (σ² + state variance) χ²₃, whose median is 2.366 (σ² + state variance).
        The parameter is a floor: a rig worse than declared (wide range, short baseline) must not
        see its good points rejected as outliers and its shots chopped into pieces.
        """
        if self._noise_dirty:
            self._noise_dirty = False
            floor = self.params.pixel_noise if self._stereo_noise else self.params.measurement_noise
            if len(self._noise_samples) >= NOISE_MIN_SAMPLES:
                arr = np.asarray(self._noise_samples)
                var = float(np.median(arr[:, 0])) / 2.366 - float(np.median(arr[:, 1]))
                self._sigma_cache = max(floor, math.sqrt(max(var, 0.0)))
            else:
                self._sigma_cache = floor
        return self._sigma_cache

    def _feed_tentative(self, t: float, z: np.ndarray, r: np.ndarray, extra: np.ndarray | None = None) -> None:
        """A point the flight could not explain: grow (or restart) the tentative track."""
        p = self.params
        tent = self._tentative
        if tent is not None and tent.speed >= STARVED_MIN_SPEED:
            r = r + TENTATIVE_FLOOR ** 2 * np.eye(3)
        if extra is not None:
            r_gate, r = r, r + extra
        else:
            r_gate = r
        if tent is not None and t > tent.t:
            saved = (tent.x, tent.P, tent.t)
            tent.predict(t, p.model_noise)
            _, _, d2 = tent.innovation(z, r_gate)
            nu, S, _ = tent.innovation(z, r)
            if d2 <= p.outlier_sigma ** 2 and float(np.linalg.norm(nu)) <= p.outlier_distance:
                tent.correct(t, z, nu, S, r)
                self._extended_tentative = True
                needed = CONFIRM_POINTS if self._flight is None else TAKEOVER_POINTS
                if len(tent.points) >= needed:
                    self._promote(tent)
                return
            tent.x, tent.P, tent.t = saved
        # Start a tentative track from the previous unexplained point and this one.
        if self._seed is not None and t > self._seed[0]:
            t0, z0, r0 = self._seed
            self._tentative = _Filter.from_two_points(t0, z0, r0, t, z, r, self._session_k)
            self._apart = 0
        self._seed = (t, z, r)

    def _promote(self, tent: _Filter) -> None:
        """The tentative track becomes the flight: a new shot, or a re-synchronised one."""
        sigma_v = math.sqrt(max(float(tent.P[3, 3] + tent.P[4, 4] + tent.P[5, 5]) / 3.0, 0.0))
        if tent.speed - 2.0 * sigma_v < MIN_FLIGHT_SPEED or tent.x[2] < MIN_START_HEIGHT:
            # Not (yet) surely moving: a shuttle lying on the floor or held in a hand, or a track
            # too short to tell. It keeps growing and is promoted once it is sure.
            return
        old = self._flight
        if not self._consistent(tent):
            # Its points do not lie on one drag-model path (the 2-point start took an outlier, or
            # the first point after a hit is the racket's blob): keep the flight, drop the
            # track's oldest point and refit the rest.
            self._apart = 0
            self._drop_oldest(tent)
            return
        if old is not None and not self._continuous(old, tent):
            # It is not where the followed shuttle is or could have been hit (a racket, a shoe,
            # the skirt for a few frames): the same, until it has gone on as a flight for
            # ``starved_takeover`` more points while the followed flight took none — a flight
            # does not starve while its shuttle is seen, and a racket's or a shoe's track is no
            # drag-model path for that long. After a hit whose first points are off (the blob
            # merged with the racket: rally_11-46-04 549–555) the new shot otherwise waited
            # for the old flight to run out (``max_gap``), 27 frames without a 3D point.
            self._apart += 1
            limit = self.params.starved_takeover
            if limit <= 0 or self._apart < limit or tent.speed < STARVED_MIN_SPEED:
                self._drop_oldest(tent)
                return
        self._apart = 0
        # Its own points' times, before a re-synchronised shot takes the old flight's in front of
        # them, each with where the track's path puts the shuttle then (its final state carried
        # back by the drag model: the fit through all its points, steadier than each point).
        self._confirmed_path = (float(tent.t), *(float(v) for v in tent.x[:7]))
        self._confirmed_now = tuple((float(point[0]), *position_on_path(self._confirmed_path, point[0]))
                                    for point in tent.points)
        new_shot = True
        if old is not None:
            t_first = tent.points[0][0]
            old_v = np.asarray(old.predicted(t_first)[3:6])
            new_v = np.asarray(_propagate(tuple(tent.x[:6].tolist()), float(tent.x[6]),
                                          t_first - tent.t)[3:6])
            frame_dt = max(t_first - old.t, 1e-3)
            # No racket hits the shuttle twice within ``MIN_SHOT_TIME``: a track that replaces a
            # flight younger than that is the same shot re-synchronised (a young flight promoted
            # from the points that scatter right after a hit, ``TENTATIVE_FLOOR``).
            new_shot = (float(np.linalg.norm(new_v - old_v)) / frame_dt >= self.params.hit_acceleration
                        and t_first - old.start_t >= MIN_SHOT_TIME)
            if not new_shot:
                # Same shot, the model had drifted: keep what the shot knew about L.
                tent.x[6] = old.x[6]
                tent.P[6, :] = tent.P[:, 6] = 0.0
                tent.P[6, 6] = old.P[6, 6]
                tent.k_prior = old.k_prior
                tent.points = old.points + tent.points
                tent.track = old.track + tent.track
                tent.noises = old.noises + tent.noises
                tent.start_t = old.start_t
            else:
                self._end_flight()
        self._flight = tent
        self._tentative = None
        self._seed = None
        self._rest_anchor = None
        if new_shot:
            self._shot_index += 1
            self._peak_speed = None
            self._launch_speed = None
        self._after_flight_update()

    def _drop_oldest(self, tent: _Filter) -> None:
        """The tentative track without its oldest point, refitted; its last point seeds the next."""
        self._tentative = self._refit(tent.points[1:], tent.noises[1:])
        last = tent.points[-1]
        self._seed = (last[0], np.asarray(last[1:], dtype=float), tent.noises[-1])

    def _refit(self, points: list, noises: list) -> _Filter | None:
        """A tentative track fitted to ``points`` (t, x, y, z) with their noise covariances afresh;
        points it rejects are left out."""
        if len(points) < 2:
            return None
        p = self.params
        (t0, *z0), (t1, *z1) = points[0], points[1]
        tent = _Filter.from_two_points(t0, z0, noises[0], t1, z1, noises[1], self._session_k)
        for (t_i, *z_i), r in zip(points[2:], noises[2:]):
            saved = (tent.x, tent.P, tent.t)
            tent.predict(t_i, p.model_noise)
            z = np.asarray(z_i, dtype=float)
            nu, S, d2 = tent.innovation(z, r)
            if d2 <= p.outlier_sigma ** 2 and float(np.linalg.norm(nu)) <= p.outlier_distance:
                tent.correct(t_i, z, nu, S, r)
            else:
                tent.x, tent.P, tent.t = saved
        return tent

    def _continuous(self, old: _Filter, tent: _Filter) -> bool:
        """Does the new track meet the followed flight's path between the flight's last point and
        its own first one (where a hit, or the model's drift, must have happened)?

        The shuttle cannot jump: both paths pass through it at the moment of a hit. The gate is
        ``outlier_sigma`` standard deviations of the two position estimates and the point noise,
        plus ``HIT_SLACK``.
        """
        t_first = tent.points[0][0]
        t_from = min(old.t, t_first)
        var = (float(np.trace(tent.noises[0])) / 3.0 + float(np.trace(old.P[0:3, 0:3])) / 3.0
               + float(np.trace(tent.P[0:3, 0:3])) / 3.0)
        gate = self.params.outlier_sigma * math.sqrt(var) + HIT_SLACK
        new_state = tuple(tent.x[:6].tolist())
        k_new = float(tent.x[6])
        n = min(16, max(1, math.ceil((t_first - t_from) / 0.004)))
        best = math.inf
        for i in range(n + 1):
            ts = t_from + (t_first - t_from) * i / n
            po = old.predicted(ts)
            pn = _propagate(new_state, k_new, ts - tent.t)
            best = min(best, math.sqrt((po[0] - pn[0]) ** 2 + (po[1] - pn[1]) ** 2 + (po[2] - pn[2]) ** 2))
        return best <= gate

    def _consistent(self, tent: _Filter) -> bool:
        """Do the track's points lie on the path its final state implies (χ² test at 99.9 %)?

        A 2-point start can take an outlier and the filter then compromises between it and the
        good points; each point may pass the gate while together they do not fit one path.
        """
        state = tuple(tent.x[:6].tolist())
        k = float(tent.x[6])
        limit2 = self.params.outlier_sigma ** 2
        total = 0.0
        for (t_i, x_i, y_i, z_i), r in zip(tent.points, tent.noises):
            px, py, pz = _propagate(state, k, t_i - tent.t)[:3]
            res = np.array([px - x_i, py - y_i, pz - z_i])
            m2 = float(res @ np.linalg.solve(r, res))    # squared Mahalanobis distance
            if m2 > limit2:
                return False
            total += m2
        dof = max(3 * len(tent.points) - 6, 1)
        return total <= _chi2_999(dof)

    def _after_flight_update(self) -> None:
        """Bookkeeping after the flight took a point: landing, peak speed, end on the floor."""
        f = self._flight
        assert f is not None
        n = len(f.points)
        speed = f.speed
        if n >= 3:
            self._peak_speed = speed if self._peak_speed is None else max(self._peak_speed, speed)
        # The launch speed: the current state carried back to the shot's first point. Cheap while
        # the shot is young, and by then the estimate is as good as it gets for fast shots.
        if n <= 3 * self.params.min_points:
            back = _propagate(tuple(f.x[:6].tolist()), float(f.x[6]), f.start_t - f.t)
            self._launch_speed = math.sqrt(back[3] ** 2 + back[4] ** 2 + back[5] ** 2)
        if f.x[2] <= LANDED_HEIGHT and f.x[5] <= 0.0:
            self._landing = self._compute_landing(f) if n >= self.params.min_points else None
            self._end_flight(keep_landing=True)
            return
        self._landing = self._compute_landing(f) if n >= self.params.min_points else None

    def _end_flight(self, keep_landing: bool = False) -> None:
        """Close the current shot and fold what it learnt about L into the session prior."""
        f = self._flight
        if f is None:
            return
        self._ended_points = np.asarray(f.points, dtype=float).reshape(-1, 4)
        self._ended_track = np.asarray(f.track, dtype=float).reshape(-1, 4)
        k_post, var_post = float(f.x[6]), float(f.P[6, 6])
        k_pri, var_pri = f.k_prior
        # Information the shot's own points carried about k = posterior − prior information.
        info = 1.0 / max(var_post, 1e-12) - 1.0 / max(var_pri, 1e-12)
        if info > 1e-6 and K_MIN < k_post < K_MAX:
            k_shot = (k_post / var_post - k_pri / var_pri) / info
            if K_MIN <= k_shot <= K_MAX:
                s_k, s_var = self._session_k
                new_info = 1.0 / s_var + info
                new_k = (s_k / s_var + k_shot * info) / new_info
                floor = self._sigma_k(self.params.aero_length_floor, 1.0 / new_k) ** 2
                self._session_k = (new_k, max(1.0 / new_info, floor))
        self._flight = None
        self.shots_ended += 1
        if not keep_landing:
            self._landing = None
        elif self._landing is not None:
            vx, vy = float(f.x[3]), float(f.x[4])
            norm = math.hypot(vx, vy)
            if norm > 1e-6:
                pred = self._landing.prediction
                self._rest_anchor = (pred.x, pred.y, vx / norm, vy / norm)

    def _sigma_k(self, sigma_length: float, length: float = physics.DEFAULT_AERO_LENGTH) -> float:
        """σ of k = 1/L for a σ of L (first order)."""
        return sigma_length / (length * length)

    def _compute_landing(self, f: _Filter) -> _Landing:
        """Integrate the model to the floor and carry the covariance along (module docstring)."""
        k = float(f.x[6])
        s = tuple(f.x[:6].tolist())
        path = [s[:3]]
        vels, steps = [], []
        elapsed = 0.0
        if s[2] > 0.0:
            while elapsed < MAX_FLIGHT_TIME:
                h = _step_size(s[3], s[4], s[5], k, 0.025)
                nxt = _rk4(*s, k, h)
                if nxt[2] <= 0.0:
                    # Land exactly: two secant refinements of the last step's length.
                    lo, hi, z_lo, z_hi = 0.0, h, s[2], nxt[2]
                    for _ in range(2):
                        frac = lo + (hi - lo) * z_lo / max(z_lo - z_hi, 1e-12)
                        trial = _rk4(*s, k, frac)
                        if trial[2] > 0.0:
                            lo, z_lo = frac, trial[2]
                        else:
                            hi, z_hi = frac, trial[2]
                    h = lo + (hi - lo) * z_lo / max(z_lo - z_hi, 1e-12)
                    nxt = _rk4(*s, k, h)
                    vels.append(s[3:6])
                    steps.append(h)
                    elapsed += h
                    s = nxt
                    path.append(s[:3])
                    break
                vels.append(s[3:6])
                steps.append(h)
                elapsed += h
                s = nxt
                path.append(s[:3])
        x_land, y_land = s[0], s[1]
        # Uncertainty: δ(landing) = [I2, −v_xy/v_z] · Φ[0:3, :] δstate (moving along the path to Z=0).
        if steps:
            phi = _chain(_transitions(np.asarray(vels), k, np.asarray(steps)))
        else:
            phi = _I7
        vz = s[5] if s[5] < -1e-3 else -1e-3
        J = np.zeros((2, 3))
        J[0, 0] = J[1, 1] = 1.0
        J[0, 2] = -s[3] / vz
        J[1, 2] = -s[4] / vz
        Jx = J @ phi[0:3, :]
        cov = Jx @ f.P @ Jx.T
        radius = math.sqrt(max(float(cov[0, 0] + cov[1, 1]), 0.0))
        call = "in" if court.is_in(x_land, y_land, self.params.doubles) else "out"
        pred = LandingPrediction(x=float(x_land), y=float(y_land), t=f.t + elapsed, radius=radius,
                                 call=call, aero_length=1.0 / k)
        return _Landing(pred, np.asarray(path, dtype=float))

    def _info(self, t: float, accepted: bool) -> FlightInfo:
        f = self._flight
        if f is None:
            reason = "no shuttle in flight"
            pred = self._landing.prediction if self._landing is not None else None
            return FlightInfo(shot_index=self._shot_index, velocity=None,
                              peak_speed=self._peak_speed_value(), prediction=pred,
                              withheld_reason="" if pred is not None else reason,
                              in_flight=False)
        tent = self._tentative
        vel: tuple[float, float, float] | None
        if accepted or t <= f.t:
            vel = tuple(float(v) for v in f.x[3:6]) if _velocity_is_sure(f) else None
        elif tent is not None and tent.t == t and len(tent.points) >= 3:
            # The flight no longer explains the points but a new track does: probably a hit being
            # confirmed. Neither velocity can be trusted yet: better no speed than a wrong one.
            vel = None
        elif _velocity_is_sure(f) and t - f.t <= COAST_VELOCITY_S:
            vel = tuple(float(v) for v in f.predicted(t)[3:6])   # coasting through a short gap
        else:
            vel = None
        pred = self._landing.prediction if self._landing is not None else None
        reason = ""
        if pred is None:
            reason = f"collecting points: {len(f.points)}/{self.params.min_points}"
        elif pred.radius > MAX_RADIUS:
            reason = f"landing too uncertain yet (±{pred.radius:.1f} m)"
            pred = None
        return FlightInfo(shot_index=self._shot_index, velocity=vel,
                          peak_speed=self._peak_speed_value(), prediction=pred,
                          withheld_reason=reason, in_flight=True, confirmed=self._confirmed_now,
                          confirmed_path=self._confirmed_path)

    def _peak_speed_value(self) -> float | None:
        values = [v for v in (self._peak_speed, self._launch_speed) if v is not None]
        return max(values) if values else None

    # ---- without a court pose -----------------------------------------------------------------
    def _update_no_model(self, t: float, point: tuple | None) -> FlightInfo:
        """Local quadratic fit of the last few points: velocity only (gravity's direction unknown)."""
        p = self.params
        recent = self._recent
        if recent and t - recent[-1][0] > p.max_gap:
            recent.clear()
            self._velocity_no_model = None
        accepted = False
        if point is not None and all(math.isfinite(c) for c in point):
            z = np.asarray(point, dtype=float)
            if len(recent) >= 3:
                pos, _ = self._poly_fit(recent[-8:], t)
                accepted = float(np.linalg.norm(z - pos)) <= p.outlier_distance
                if not accepted:
                    self._misses_no_model += 1
                    if self._misses_no_model >= CONFIRM_POINTS:   # the track has really moved on
                        recent.clear()
                        accepted = True
            else:
                accepted = True
            if accepted:
                self._misses_no_model = 0
                if not recent:
                    self._shot_index += 1
                recent.append((t, float(z[0]), float(z[1]), float(z[2])))
                del recent[:-64]
                if len(recent) >= 3:
                    _, vel = self._poly_fit(recent[-8:], t)
                    self._velocity_no_model = tuple(float(v) for v in vel)
        vel = self._velocity_no_model if (accepted or (recent and t - recent[-1][0] <= p.max_gap)) else None
        return FlightInfo(shot_index=self._shot_index, velocity=vel, peak_speed=None,
                          prediction=None, withheld_reason=NO_COURT_POSE, in_flight=bool(recent))

    @staticmethod
    def _poly_fit(points: list, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Position and velocity at t of a least-squares quadratic (linear if < 4 points)."""
        arr = np.asarray(points, dtype=float)
        tau = arr[:, 0] - t
        degree = 2 if len(arr) >= 4 else 1
        A = np.vander(tau, degree + 1, increasing=True)
        coef, *_ = np.linalg.lstsq(A, arr[:, 1:], rcond=None)
        return coef[0], coef[1]

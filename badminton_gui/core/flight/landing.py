"""Landing prediction and the per-frame readout (``FlightInfo``) of the flight being followed.

Why this module exists: what the robot is told each frame — the velocity (when it is sure enough),
the peak speed, and above all where and when the shuttle will land with its uncertainty (the drag
model integrated down to Z = 0, the filter covariance carried along by the state-transition
matrices and projected on the floor, the in/out call by ``court.is_in``), or why that prediction
is withheld — is computed here, as a mixin of
:class:`~badminton_gui.core.flight.trajectory.Trajectory`; without a court pose the readout comes
from a local polynomial fit instead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import court, physics
from ..types import FlightInfo, LandingPrediction
from .shot_filter import _I7, _chain, _Filter, _rk4, _step_size, _transitions, _velocity_is_sure
from .takeover import CONFIRM_POINTS

NO_COURT_POSE = "no court pose: calibrate the court pose to get landing predictions"
COAST_VELOCITY_S = 0.1     # s: no speed shown after this long without a point (a hidden hit, seen in
                            # the demo: a shuttle behind a player for 190 ms, hit meanwhile)
MAX_RADIUS = 2.0            # m: a landing this uncertain is withheld (a fresh, poorly fixed track)
MAX_FLIGHT_TIME = 6.0       # s: the landing search stops here


@dataclass(frozen=True, slots=True)
class _Landing:
    """A landing computed from a filter state (cached until the next accepted point)."""

    prediction: LandingPrediction
    path: np.ndarray           # (M, 3) predicted positions from now to the floor



class LandingReadout:
    """Mixin of :class:`~badminton_gui.core.flight.trajectory.Trajectory`: the landing prediction
    and the :class:`~badminton_gui.core.types.FlightInfo` returned for each frame."""

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
            if pred is not None and self._apart_reason(t):
                pred, reason = None, self._apart_reason(t)
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
        elif self._apart_reason(t):
            reason, pred = self._apart_reason(t), None
        return FlightInfo(shot_index=self._shot_index, velocity=vel,
                          peak_speed=self._peak_speed_value(), prediction=pred,
                          withheld_reason=reason, in_flight=True, confirmed=self._confirmed_now,
                          confirmed_path=self._confirmed_path)

    def _apart_reason(self, t: float) -> str:
        """Why this shot's landing is withheld at time t because it started apart from a flight
        lost in the air (``_started_apart_from_lost``), or "" when it is not."""
        apart = self._apart_shot
        if apart is None or apart[0] != self._shot_index or t >= apart[1]:
            return ""
        return (f"a track apart from the lost shuttle's path (another object?): landing withheld "
                f"until that shuttle is down ({apart[1] - t:.2f} s)")

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

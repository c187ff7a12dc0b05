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
  row (a racket, a shoe) cannot replace a good flight. A track whose path passes metres from the
  flight's (``HIT_REACH``: an LED board's moving dot both cameras pair) is another object: it
  neither replaces the flight before that ends nor guides the cameras' search. If the new track's velocity differs from
  the flight's by more than ``hit_acceleration`` × the time step, that is a hit: a new shot
  starts. Otherwise the flight was only re-synchronised (model mismatch) and keeps its shot
  number and its L.
* The points' noise: ``measurement_noise`` is a floor; the filter measures the real scatter from
  the innovations of established flights (robust median) and uses the larger of the two, so a
  rig noisier than declared does not get its good points rejected and its shots chopped up.
* A flight ends when the shuttle reaches the floor (a point, or the model's landing time, says
  so), or after ``max_gap`` seconds without a usable point; its last landing prediction stays
  available (``in_flight`` False) until the next shot starts.
  A shot that starts beyond reach of a flight lost in the air, before that flight is down by
  its model, may be another object the cameras took up once the shuttle was lost (an LED
  board's dot): its landing, and that of shots hit from it, is withheld until then, with the
  reason.
* The landing point is the drag model integrated (RK4, adaptive step) from the current state down
  to Z = 0; its uncertainty is the filter covariance carried along that path by the linearised
  dynamics (state-transition matrices) and projected onto the floor. The in/out call uses
  ``court.is_in``.

Without a court pose (points in the left-camera frame) gravity's direction is unknown, so there is
no drag model: velocity comes from a local quadratic fit of the last few points, and landing
predictions are withheld with a reason.

Where the parts live: this module keeps :class:`Trajectory` (the shots it owns, which points it
takes, when a flight ends); the drag model and the Kalman filter of one shot are in
``shot_filter.py``, the tentative track that takes over the flight (hit or re-synchronisation) in
``takeover.py``, and the landing prediction and per-frame ``FlightInfo`` in ``landing.py``.
"""

from __future__ import annotations

import math

import numpy as np

from .. import physics
from ..params import TrajectoryParams
from ..types import FlightInfo
from .landing import LandingReadout, _Landing
from .shot_filter import K_MAX, K_MIN, MIN_FLIGHT_SPEED, _Filter, _points_travel, _propagate
from .takeover import HIT_REACH, LANDING_GRACE_S, STARVED_MIN_SPEED, TAKEOVER_POINTS, ShotTakeover

LANDED_HEIGHT = 0.03        # m: a flight whose estimate is this low has landed (cork radius ≈ 1.3 cm)
REST_MAX_HEIGHT = 0.10      # m: a point this low next to the last landing is the shuttle lying there
REST_RADIUS = 0.6           # m: ... within this distance of the predicted landing (it may bounce)
NOISE_WINDOW = 120          # innovations kept for the measured-noise estimate (~1 s at 120 fps)
NOISE_MIN_SAMPLES = 30      # before that many, the parameter alone sets the noise
TENTATIVE_REPORT_POINTS = 4  # a tentative track this long, consistent and fast, gives the robot its
                            # position while the old flight still refuses its points
                            # (``tentative_position``); at 3 the demo court's short runs of wrong
                            # points were reported too (one 90 cm off: 3D RMS 0.90 → 1.08 cm)


class Trajectory(ShotTakeover, LandingReadout):
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
        self._elsewhere_cache: tuple = (None, False)   # (key, result) of _tentative_elsewhere
        # The last flight when it was lost in the air, and its predicted landing time.
        self._lost: tuple[_Filter, float] | None = None
        # A shot that started apart from a flight lost in the air: (its index, until when (s)
        # its landing is withheld — that flight's landing time).
        self._apart_shot: tuple[int, float] | None = None
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
                lost = self._flight
                self._end_flight(keep_landing=True)   # lost: the robot keeps the last prediction
                if self._landing is not None and self._landing.prediction.t > t:
                    # Still in the air by its model: a track that starts elsewhere before it is
                    # down did not come from it (``_promote``).
                    self._lost = (lost, self._landing.prediction.t)
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
        if self._tentative_elsewhere():
            return None     # not the followed shuttle hit: another object's track
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

    def _tentative_elsewhere(self) -> bool:
        """The tentative track cannot be the followed shuttle: an established flight is followed
        and the track's path does not pass within reach of its path (``_within_reach``). Asked
        several times a step (guide, report), computed once per change of either."""
        f, tent = self._flight, self._tentative
        if f is None or tent is None or len(f.points) < self.params.min_points or len(tent.points) < 3:
            return False
        key = (id(tent), tent.t, len(tent.points), id(f), f.t)
        if self._elsewhere_cache[0] != key:
            self._elsewhere_cache = (key, not self._within_reach(f, tent))
        return self._elsewhere_cache[1]

    def guide(self, t: float) -> tuple[np.ndarray, np.ndarray] | None:
        """Where the followed flight puts the shuttle at time t: (position (3,), its covariance
        (3, 3)), or None when there is no established flight to trust (fewer than ``min_points``
        points, lost for longer than ``max_gap``, or a new track is being confirmed: a hit)."""
        motion = self.guide_motion(t)
        return None if motion is None else (motion[0], motion[1])

    def guide_motion(self, t: float) -> tuple[np.ndarray, np.ndarray, float, float] | None:
        """``guide(t)``'s (position, covariance) with the guiding flight's speed (m/s) there and
        the time (s) of its last point (None: no guide)."""
        f = self._flight
        p = self.params
        tent = self._tentative
        if tent is not None and self._tentative_elsewhere():
            # Another object's track (an LED board's dot): the followed flight stays the guide,
            # or the cameras' search would hand the shuttle over to it.
            tent = None
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
        position, covariance, speed = f.x[:3].copy(), f.P[0:3, 0:3].copy(), f.speed
        f.x, f.P, f.t = saved
        return position, covariance, speed, float(f.t)

    def reach(self, motion: tuple[np.ndarray, np.ndarray, float, float], t: float,
              top_speed: float) -> float:
        """How far (m) from the guide's position (``guide_motion(t)``) the followed shuttle can
        be at ``t``: ``HIT_REACH`` (a hit's first points off by the racket's blob) plus
        ``outlier_sigma`` of the guide's spread, plus the way a shuttle hit since the flight's
        last point at ``top_speed`` (m/s) and the flight itself can have gone apart since."""
        _, covariance, speed, t_last = motion
        spread = self.params.outlier_sigma * math.sqrt(max(float(np.trace(covariance)) / 3.0, 0.0))
        return HIT_REACH + spread + (top_speed + speed) * max(t - t_last, 0.0)

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
    def point_elsewhere(self) -> bool:
        """The last update's point, refused by the flight being followed, extended a track whose
        path passes metres from the flight's (``HIT_REACH``): another object's, which neither
        replaces the flight nor guides the cameras' search."""
        return self._rejected_now and self._extended_tentative and self._tentative_elsewhere()

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

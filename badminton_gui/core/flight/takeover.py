"""Tentative tracks: when points the flight refused replace it, as a new shot or a re-synchronisation.

Why this module exists: the rules that let a run of rejected points take over from the flight
being followed (how many, how consistent, how fast, how high, whether the paths meet where a hit
could have happened, whether the change of velocity is a hit) are the part of shot segmentation
most often tuned against recordings; they live here as a mixin of
:class:`~badminton_gui.core.flight.trajectory.Trajectory`, whose state they read and write.
"""

from __future__ import annotations

import math

import numpy as np

from .shot_filter import MIN_FLIGHT_SPEED, _chi2_999, _Filter, _propagate, position_on_path

LANDING_GRACE_S = 0.03      # s: a flight past its predicted landing time by this much has landed

CONFIRM_POINTS = 4          # consecutive agreeing points that start a flight
TAKEOVER_POINTS = 6         # ... that replace a flight being followed (a hit, or a re-synchronisation):
                            # the demo pipeline makes runs of 4 wrong points (centroid on the skirt
                            # or a racket for a few frames) that had replaced a good flight 230 ms
                            # before landing and cost its prediction
MIN_START_HEIGHT = 0.15     # m: no flight starts lower (a shuttle rolling or picked up off the floor;
                            # with noisy points its 4-point "speed" easily exceeds MIN_FLIGHT_SPEED)
TENTATIVE_FLOOR = 0.01      # m: noise added to the points of a tentative track at ≥ STARVED_MIN_SPEED: right
                            # after a hit the shuttle turns over and its points scatter by 1–6 cm
                            # about the new path (rally_11-46-22 429–432) where the stereo noise
                            # model says ≈ 2 mm, and the tentative track restarted at each
MIN_SHOT_TIME = 0.1         # s: no two hits closer together (a flight younger is re-synchronised)
HIT_SLACK = 0.05            # m: at a hit the blob's centroid swaps sides of the cork (skirt lag ~2 cm)
HIT_REACH = 1.0             # m: a new track whose path passes farther from the followed flight's is
                            # not that shuttle hit (``_within_reach``): a hit's first points are
                            # off by the racket's blob, centimetres to decimetres, not metres
STARVED_MIN_SPEED = 5.0     # m/s: a track that takes over a starved flight (``starved_takeover``) is a
                            # shot; a hand carrying a caught shuttle moves slower (≤ 2.6 m/s: the
                            # tracker's caught rule needs the flight to refuse those points)


class ShotTakeover:
    """Mixin of :class:`~badminton_gui.core.flight.trajectory.Trajectory`: the tentative track and
    its takeover of the flight (a hit starts a new shot; otherwise the flight is re-synchronised)."""

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
        gap, gate = self._paths_gap(old, tent) if old is not None else (0.0, 0.0)
        if gap > gate:
            # It is not where the followed shuttle is or could have been hit (a racket, a shoe,
            # the skirt for a few frames): the same, until it has gone on as a flight for
            # ``starved_takeover`` more points while the followed flight took none — a flight
            # does not starve while its shuttle is seen, and a racket's or a shoe's track is no
            # drag-model path for that long. After a hit whose first points are off (the blob
            # merged with the racket: rally_11-46-04 549–555) the new shot otherwise waited
            # for the old flight to run out (``max_gap``), 27 frames without a 3D point.
            # A track that does not even pass within reach of the flight's path is another object
            # (``_within_reach``): it waits for the flight to end, however long it goes on.
            self._apart += 1
            limit = self.params.starved_takeover
            if (limit <= 0 or self._apart < limit or tent.speed < STARVED_MIN_SPEED
                    or gap > max(gate, HIT_REACH)):
                self._drop_oldest(tent)
                return
        self._apart = 0
        apart_from_lost = old is None and self._started_apart_from_lost(tent)
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
            self._next_shot(old is not None, apart_from_lost)
        self._lost = None
        self._after_flight_update()

    def _next_shot(self, hit: bool, apart_from_lost: bool) -> None:
        """Number the new shot; it inherits the doubt of the shot it was hit from (the same
        object's track re-synchronised as a "hit", as an LED board's dot, which obeys no drag
        model, is), or starts apart from a flight lost in the air (``_started_apart_from_lost``)."""
        apart = self._apart_shot if hit and self._apart_shot is not None \
            and self._apart_shot[0] == self._shot_index else None
        self._shot_index += 1
        self._peak_speed = None
        self._launch_speed = None
        if apart_from_lost:
            apart = (self._shot_index, self._lost[1] + LANDING_GRACE_S)
        self._apart_shot = None if apart is None else (self._shot_index, apart[1])

    def _started_apart_from_lost(self, tent: _Filter) -> bool:
        """Does the track start before the flight lost in the air is down by its model, and
        pass beyond reach of its path (``_within_reach``)? Then it is another object (an LED
        board's dot the cameras paired once the shuttle was lost), or the shuttle hit where it
        was hidden and its path too far back to tell: either way its landing is not one the
        model can stand behind until the lost flight would have landed."""
        if self._lost is None:
            return False
        lost, t_down = self._lost
        t_first = tent.points[0][0]
        if t_first >= t_down:
            return False
        gap, gate = self._paths_gap(lost, tent)
        # Unseen since its last point, the lost flight is known less well the longer ago that
        # was: its position's spread then (the filter's covariance carried over the gap) widens
        # the reach.
        saved = (lost.x, lost.P, lost.t)
        lost.predict(t_first, self.params.model_noise)
        spread = self.params.outlier_sigma * math.sqrt(max(float(np.trace(lost.P[0:3, 0:3])) / 3.0, 0.0))
        lost.x, lost.P, lost.t = saved
        return gap > max(gate, HIT_REACH + spread)

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
        gap, gate = self._paths_gap(old, tent)
        return gap <= gate

    def _within_reach(self, old: _Filter, tent: _Filter) -> bool:
        """Could the new track be the followed shuttle, hit where its first points were off?

        The paths come within ``HIT_REACH`` of each other (or meet, ``_continuous``) somewhere
        between the flight's last point and the track's first one. Farther apart, the track is
        another object (an LED board's moving dot, a second shuttle): the followed shuttle does
        not jump metres between two frames.
        """
        gap, gate = self._paths_gap(old, tent)
        return gap <= max(gate, HIT_REACH)

    def _paths_gap(self, old: _Filter, tent: _Filter) -> tuple[float, float]:
        """(closest approach (m) of the flight's path and the track's between the flight's last
        point and the track's first one, the gate (m) within which they meet)."""
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
        return best, gate

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

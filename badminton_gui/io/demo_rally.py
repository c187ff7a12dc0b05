"""The rally script of the demo court: shots, shuttle flights and player motion, with exact truth.

Why this file exists: the synthetic demo court (``demo_scene.py``) needs a shuttle that flies
like a real one (the quadratic-drag model of ``core/physics.py``) between two players
who are where the shuttle is when they hit it. This module decides the shots (serve, clear,
drop, drive, smash), solves each launch velocity so that the shot lands in the opponent's court
(a shooting method on the planar drag equations), integrates the flight with
``physics.simulate`` and cuts it where the receiver hits it back. It also keys the players'
positions and swings to those contacts. Nothing here draws; everything is a pure function of
the seed and is generated lazily, rally by rally, as later times are asked for.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..core import court, physics

AERO_LENGTH = physics.DEFAULT_AERO_LENGTH   # 4.8 m
SHOT_KINDS = ("serve", "clear", "drop", "drive", "smash")
NEAR, FAR = 0, 1                      # player 0 defends Y < 0 (the robot's half), player 1 Y > 0
SERVE_DELAY = 0.15                    # s of empty court before the first serve
REST_ON_FLOOR = 0.4                   # s the shuttle lies where it landed after a rally
OFF_BETWEEN_RALLIES = 0.6             # s with no shuttle in play before the next serve
NET_CLEARANCE = court.NET_HEIGHT_POSTS + 0.05
SHOULDER_HEIGHT = 1.42
SHOULDER_HALF_WIDTH = 0.2
REACH = 1.25                          # shoulder to racket-head centre, arm straight (m)
ARM_LENGTH = 0.62                     # shoulder to hand (m); the rest of REACH is racket
CORK_RADIUS = 0.013                   # m; a landed shuttle's cork centre lies this high


@dataclass(frozen=True)
class Segment:
    """A time span of the shuttle's life: a flight, a rest on the floor, or no shuttle."""

    kind: str                 # "flight" / "rest" / "off"
    t0: float
    t1: float
    shot_index: int = -1
    shot_kind: str = ""
    hitter: int = -1
    times: np.ndarray | None = None      # absolute times of the dense samples (flight)
    pos: np.ndarray | None = None        # (N, 3)
    vel: np.ndarray | None = None        # (N, 3)
    rest_point: tuple[float, float, float] | None = None
    rest_dir: tuple[float, float, float] = (0.0, 1.0, 0.0)


@dataclass(frozen=True)
class Contact:
    """A racket contact, which the player's body and swing are keyed to."""

    t: float
    player: int
    point: tuple[float, float, float]
    overhead: bool


# ---- planar shooting method ------------------------------------------------------------------

def _planar_flight(h0: float, vr: float, vz: float, net_distance: float,
                   dt: float = 2e-3, t_max: float = 6.0) -> tuple[float, float]:
    """Range at the floor and height where the horizontal distance reaches the net.

    Drag acts along the velocity, so with no wind a flight stays in the vertical plane of its
    launch: two coordinates (r, z) suffice, and plain floats are fast enough to call this a
    few hundred times per rally. Same equations as ``physics.acceleration``.
    """
    r, z = 0.0, h0
    g, inv_l = physics.GRAVITY, 1.0 / AERO_LENGTH
    z_net = math.inf if net_distance <= 0 else math.nan
    t = 0.0

    hypot = math.hypot
    # The acceleration a(vr, vz) = (-s vr, -g - s vz), s = |v| / L, is written out four times
    # instead of called: this loop runs ~10^5 times per rally and the call was a third of it.
    while t < t_max:
        s = hypot(vr, vz) * inv_l
        a1r, a1z = -s * vr, -g - s * vz
        br, bz = vr + 0.5 * dt * a1r, vz + 0.5 * dt * a1z
        s = hypot(br, bz) * inv_l
        a2r, a2z = -s * br, -g - s * bz
        br, bz = vr + 0.5 * dt * a2r, vz + 0.5 * dt * a2z
        s = hypot(br, bz) * inv_l
        a3r, a3z = -s * br, -g - s * bz
        br, bz = vr + dt * a3r, vz + dt * a3z
        s = hypot(br, bz) * inv_l
        a4r, a4z = -s * br, -g - s * bz
        r_new = r + dt * (vr + dt / 6.0 * (a1r + a2r + a3r))
        z_new = z + dt * (vz + dt / 6.0 * (a1z + a2z + a3z))
        vr += dt / 6.0 * (a1r + 2 * a2r + 2 * a3r + a4r)
        vz += dt / 6.0 * (a1z + 2 * a2z + 2 * a3z + a4z)
        if math.isnan(z_net) and r_new >= net_distance:
            frac = (net_distance - r) / max(r_new - r, 1e-12)
            z_net = z + frac * (z_new - z)
        if z_new <= 0.0:
            frac = z / max(z - z_new, 1e-12)
            r_land = r + frac * (r_new - r)
            if math.isnan(z_net):
                z_net = -math.inf          # landed before the net
            return r_land, z_net
        r, z = r_new, z_new
        t += dt
    return r, (z_net if not math.isnan(z_net) else -math.inf)


def _solve_monotonic(fn, target: float, lo: float, hi: float, iters: int = 40,
                     tol: float = 0.01) -> float | None:
    """Root of fn(x) = target on [lo, hi] for increasing fn (Illinois regula falsi)."""
    f_lo, f_hi = fn(lo) - target, fn(hi) - target
    if f_lo > 0 or f_hi < 0:
        return None
    side = 0
    x = lo
    for _ in range(iters):
        x = (lo * f_hi - hi * f_lo) / (f_hi - f_lo) if f_hi != f_lo else 0.5 * (lo + hi)
        fx = fn(x) - target
        if abs(fx) < tol:
            return x
        if fx < 0:
            lo, f_lo = x, fx
            if side == -1:
                f_hi *= 0.5
            side = -1
        else:
            hi, f_hi = x, fx
            if side == 1:
                f_lo *= 0.5
            side = 1
    return x


def solve_launch(p0, target_xy, kind: str, rng: np.random.Generator) -> np.ndarray | None:
    """Launch velocity from ``p0`` that lands at ``target_xy`` and clears the net, or None.

    Lobbed shots fix the elevation and solve the speed; smashes fix a fast speed and solve the
    (downward) elevation. Preferred elevations are tried in order until one works.
    """
    p0 = np.asarray(p0, dtype=float)
    d = np.asarray(target_xy, dtype=float) - p0[:2]
    dist = float(np.hypot(*d))
    if dist < 0.5:
        return None
    u = d / dist
    # Horizontal distance at which the flight crosses the net plane Y = 0.
    net_distance = -p0[1] / u[1] if abs(u[1]) > 1e-9 and -p0[1] / u[1] > 0 else -1.0

    def velocity(speed: float, elev: float) -> np.ndarray:
        return np.array([speed * math.cos(elev) * u[0], speed * math.cos(elev) * u[1],
                         speed * math.sin(elev)])

    if kind == "smash":
        speed = float(rng.uniform(60.0, 95.0))

        def range_of_elev(e: float) -> float:
            return _planar_flight(p0[2], speed * math.cos(e), speed * math.sin(e), net_distance)[0]

        elev = _solve_monotonic(range_of_elev, dist, math.radians(-60), math.radians(12))
        if elev is None:
            return None
        _, z_net = _planar_flight(p0[2], speed * math.cos(elev), speed * math.sin(elev),
                                  net_distance)
        return velocity(speed, elev) if z_net >= NET_CLEARANCE else None

    preferred = {"serve": (45, 50, 40, 55, 35), "clear": (34, 40, 28, 46, 22),
                 "drop": (12, 22, 4, 32, 42), "drive": (6, 12, 2, 18, 26)}[kind]
    for elev_deg in preferred:
        elev = math.radians(elev_deg + rng.uniform(-2.0, 2.0))

        def range_of_speed(s: float, elev=elev) -> float:
            return _planar_flight(p0[2], s * math.cos(elev), s * math.sin(elev), net_distance)[0]

        speed = _solve_monotonic(range_of_speed, dist, 1.0, 120.0)
        if speed is None:
            continue
        _, z_net = _planar_flight(p0[2], speed * math.cos(elev), speed * math.sin(elev),
                                  net_distance)
        if z_net >= NET_CLEARANCE:
            return velocity(speed, elev)
    return None


# ---- the rally script ------------------------------------------------------------------------

def _side_sign(player: int) -> float:
    return -1.0 if player == NEAR else 1.0


def _target_for(kind: str, receiver: int, rng: np.random.Generator,
                server_x: float = 0.0) -> np.ndarray:
    """A landing point in the receiver's half, typical of the shot kind."""
    s = _side_sign(receiver)
    if kind == "serve":      # high singles serve, diagonally into the back of the service court
        x = -math.copysign(rng.uniform(0.6, 2.2), server_x if server_x != 0 else 1.0)
        y = rng.uniform(5.7, 6.5)
    elif kind == "clear":
        x, y = rng.uniform(-2.3, 2.3), rng.uniform(5.3, 6.4)
    elif kind == "drop":
        x, y = rng.uniform(-2.2, 2.2), rng.uniform(2.0, 3.0)
    elif kind == "drive":
        x, y = rng.uniform(-2.4, 2.4), rng.uniform(3.6, 5.2)
    else:                    # smash: deeper targets clear the net from the back court
        x, y = rng.uniform(-2.3, 2.3), rng.uniform(3.0, 6.2)
    return np.array([x, s * y])


def _next_kind(incoming: str, rng: np.random.Generator) -> tuple[str, float]:
    """What the receiver plays back, and the contact height that shot is struck at."""
    if incoming in ("serve", "clear"):
        kind = str(rng.choice(["clear", "drop", "smash"], p=[0.35, 0.25, 0.4]))
        return kind, float(rng.uniform(2.6, 2.9) if kind == "smash" else rng.uniform(2.3, 2.6))
    if incoming == "drop":
        kind = str(rng.choice(["clear", "drop"], p=[0.7, 0.3]))
        return kind, float(rng.uniform(0.5, 0.9))
    kind = str(rng.choice(["drive", "clear", "drop"], p=[0.5, 0.3, 0.2]))
    return kind, float(rng.uniform(0.8, 1.3))


class RallyScript:
    """Shots and player keys generated lazily from a seed; random access by time."""

    def __init__(self, seed: int = 0, shots: tuple[int, int] = (3, 10)) -> None:
        # ``shots``: a rally has lo ≤ n < hi shots; shorter rallies land more often per second
        # of footage (the landing benchmark of the randomised scenes, ``demo_style.py``).
        self._rng = np.random.default_rng(seed)
        self._shots = (int(shots[0]), int(shots[1]))
        self.segments: list[Segment] = []
        self._starts: list[float] = []
        self.contacts: list[Contact] = []
        self._contact_times: list[list[float]] = [[], []]
        self._contacts_by_player: list[list[Contact]] = [[], []]
        self._t_generated = 0.0
        self._shot_count = 0
        self._rally_count = 0
        self._rally = None
        self._add(Segment("off", 0.0, SERVE_DELAY))

    # -- generation --
    def _add(self, seg: Segment) -> None:
        self.segments.append(seg)
        self._starts.append(seg.t0)
        self._t_generated = seg.t1

    def _add_contact(self, c: Contact) -> None:
        self.contacts.append(c)
        self._contact_times[c.player].append(c.t)
        self._contacts_by_player[c.player].append(c)

    def ensure(self, t: float) -> None:
        """Generate shots until the script covers time ``t`` (plus look-ahead for players).

        One shot at a time (a few tens of ms), so a live consumer never stalls for a whole
        rally's worth of physics.
        """
        while self._t_generated < t + 3.0:
            if self._rally is None:
                self._rally = self._generate_rally()
            try:
                next(self._rally)
            except StopIteration:
                self._rally = None

    def _generate_rally(self):
        """Generator: adds one shot's segments per step until the rally ends."""
        rng = self._rng
        server = self._rally_count % 2
        self._rally_count += 1
        n_shots = int(rng.integers(*self._shots))
        s = _side_sign(server)
        server_x = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.3, 0.9))
        p0 = np.array([server_x, s * rng.uniform(2.4, 3.2), 1.0])
        kind, hitter, t = "serve", server, self._t_generated
        for i in range(n_shots):
            receiver = 1 - hitter
            v0 = None
            for _attempt in range(6):
                target = _target_for(kind, receiver, rng, server_x)
                v0 = solve_launch(p0, target, kind, rng)
                if v0 is not None:
                    break
            if v0 is None:               # fall back to a safe clear
                kind = "clear"
                for _attempt in range(10):
                    v0 = solve_launch(p0, _target_for("clear", receiver, rng), "clear", rng)
                    if v0 is not None:
                        break
            if v0 is None:
                self._add(Segment("off", t, t + OFF_BETWEEN_RALLIES))
                return
            ts, ps, vs = physics.simulate(p0, v0, 6.0, dt=1e-3, aero_length=AERO_LENGTH,
                                          floor_z=0.0)
            last = i == n_shots - 1
            next_kind, h_contact = _next_kind(kind, rng)
            cut = len(ts) - 1
            if not last:
                rs = _side_sign(receiver)
                ok = (ps[:, 1] * rs > 0.9) & (ps[:, 2] <= h_contact) & (vs[:, 2] < 0)
                hits = np.flatnonzero(ok)
                if len(hits) and abs(ps[hits[0], 1]) < court.HALF_LENGTH + 0.3:
                    cut = int(hits[0])
                else:
                    last = True          # the receiver cannot reach it: the rally ends
            self._add_contact(Contact(t, hitter, tuple(float(c) for c in p0),
                                      overhead=p0[2] > 1.8))
            seg = Segment("flight", t, t + float(ts[cut]), self._shot_count, kind, hitter,
                          t + ts[: cut + 1], ps[: cut + 1].copy(), vs[: cut + 1].copy())
            self._add(seg)
            self._shot_count += 1
            t = seg.t1
            if last:
                land = ps[cut]
                vh = vs[cut].copy()
                vh[2] = 0.0
                n = np.linalg.norm(vh)
                rest_dir = tuple(float(c) for c in (vh / n if n > 1e-6 else np.array([0, 1.0, 0])))
                self._add(Segment("rest", t, t + REST_ON_FLOOR, seg.shot_index, kind, hitter,
                                  rest_point=(float(land[0]), float(land[1]), CORK_RADIUS),
                                  rest_dir=rest_dir))
                self._add(Segment("off", t + REST_ON_FLOOR, t + REST_ON_FLOOR + OFF_BETWEEN_RALLIES))
                return
            p0 = ps[cut].copy()
            hitter, kind = receiver, next_kind
            yield

    # -- queries --
    def segment_at(self, t: float) -> Segment:
        self.ensure(t)
        i = bisect.bisect_right(self._starts, t) - 1
        return self.segments[max(i, 0)]

    def state(self, t: float) -> tuple[np.ndarray | None, np.ndarray | None, Segment]:
        """Cork centre and velocity at time ``t`` (None, None when no shuttle is in play)."""
        seg = self.segment_at(t)
        if seg.kind == "off":
            return None, None, seg
        if seg.kind == "rest":
            return np.array(seg.rest_point), np.zeros(3), seg
        return (*_hermite(seg.times, seg.pos, seg.vel, t), seg)

    def contacts_of(self, player: int, t: float) -> tuple[Contact | None, Contact | None]:
        """The player's last contact at or before ``t`` and the next one after it."""
        self.ensure(t)
        times = self._contact_times[player]
        i = bisect.bisect_right(times, t)
        prev = self._contacts_by_player[player][i - 1] if i > 0 else None
        nxt = self._contacts_by_player[player][i] if i < len(times) else None
        return prev, nxt


def _hermite(times: np.ndarray, pos: np.ndarray, vel: np.ndarray, t: float
             ) -> tuple[np.ndarray, np.ndarray]:
    """Cubic Hermite interpolation of the 1 ms RK4 samples (error ≪ 1 µm)."""
    if len(times) < 2:
        return pos[0].copy(), vel[0].copy()
    i = min(max(int(np.searchsorted(times, t)) - 1, 0), len(times) - 2)
    # Called ~10 times a frame pair on (3,) rows: numpy's per-call overhead on such tiny arrays
    # was most of the cost, so the basis is evaluated on Python floats, component by component.
    # Every product and sum is the one numpy's element-wise operators did, in the same order,
    # so the result is bit-identical (no dot products or fused operations involved).
    t0, t1 = float(times[i]), float(times[i + 1])
    h = t1 - t0
    s = min(max((t - t0) / h, 0.0), 1.0) if h > 0 else 0.0
    s2, s3 = s * s, s * s * s
    a0, a1 = 2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s          # basis of p0, m0
    a2, a3 = -2 * s3 + 3 * s2, s3 - s2                     # basis of p1, m1
    p0, p1 = pos[i].tolist(), pos[i + 1].tolist()
    v0, v1 = vel[i].tolist(), vel[i + 1].tolist()
    m0 = [c * h for c in v0]
    m1 = [c * h for c in v1]
    p = [a0 * p0[k] + a1 * m0[k] + a2 * p1[k] + a3 * m1[k] for k in range(3)]
    if h > 0:
        b0, b1 = 6 * s2 - 6 * s, 3 * s2 - 4 * s + 1
        b2, b3 = -6 * s2 + 6 * s, 3 * s2 - 2 * s
        dp = [(b0 * p0[k] + b1 * m0[k] + b2 * p1[k] + b3 * m1[k]) / h for k in range(3)]
    else:
        dp = v0
    return np.array(p), np.array(dp)


# ---- players -----------------------------------------------------------------------------------

@dataclass(frozen=True)
class Capsule:
    """A body part: a segment with a radius at each end (a sphere when a == b)."""

    a: tuple[float, float, float]
    b: tuple[float, float, float]
    ra: float
    rb: float
    part: str                 # colour key: "shirt", "shorts", "skin", "hair", "racket"
    occludes: bool = True     # thin racket parts do not hide the shuttle


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    n = np.linalg.norm(v)
    return v / n if n > 1e-12 else v


def _frame_of(player: int) -> tuple[np.ndarray, np.ndarray]:
    """(forward, right) unit vectors of a player facing the net."""
    if player == NEAR:
        return np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0])
    return np.array([0.0, -1.0, 0.0]), np.array([-1.0, 0.0, 0.0])


def _base_position(player: int) -> np.ndarray:
    return np.array([0.0, _side_sign(player) * 3.4])


def _jump_height(c: Contact) -> float:
    """How high the player leaves the floor to reach a contact above the standing reach."""
    return max(0.0, c.point[2] - SHOULDER_HEIGHT - 0.97 * REACH)


def _body_for_contact(player: int, c: Contact) -> np.ndarray:
    """Where the player's feet are so that the straight arm + racket reaches the contact."""
    _, right = _frame_of(player)
    dz = c.point[2] - SHOULDER_HEIGHT - _jump_height(c)
    d_h = math.sqrt(max(REACH ** 2 - dz ** 2, 0.0))
    body = np.asarray(c.point[:2]) - (SHOULDER_HALF_WIDTH + d_h) * right[:2]
    return body


def _smoothstep(u: float) -> float:
    u = min(max(u, 0.0), 1.0)
    return u * u * (3 - 2 * u)


def _lin(v, *terms) -> tuple[float, float, float]:
    """``v + k1 * w1 + k2 * w2 + ...`` on 3-tuples, summed left to right like numpy would.

    The players are rebuilt every frame from ~20 such sums of 3-vectors; on Python floats they
    cost a fraction of numpy's per-call overhead, with the same products and sums in the same
    order (so the same bits). ``a - k * w`` is written ``(-k, w)``: negation is exact.
    """
    x, y, z = v
    for k, w in terms:
        x, y, z = x + k * w[0], y + k * w[1], z + k * w[2]
    return (x, y, z)


def _player_body_xy(script: RallyScript, player: int, t: float) -> tuple[float, float]:
    """``player_body`` on Python floats (same operations, same order: the same bits)."""
    prev, nxt = script.contacts_of(player, t)
    base = (0.0, _side_sign(player) * 3.4)
    p_prev = _body_xy_for_contact(player, prev) if prev else base
    if nxt is None or nxt.t - t > 2.5:
        if prev is None:
            return base
        a, b, k = p_prev, base, _smoothstep((t - prev.t) / 0.8)
    else:
        p_next = _body_xy_for_contact(player, nxt)
        t_prev = prev.t if prev else nxt.t - 2.5
        gap = max(nxt.t - t_prev, 1e-6)
        u = (t - t_prev) / gap
        if gap < 1.2:
            a, b, k = p_prev, p_next, _smoothstep(u)
        elif u < 0.4:                    # recover to the base, then go to the next contact
            a, b, k = p_prev, base, _smoothstep(u / 0.4)
        else:
            a, b, k = base, p_next, _smoothstep((u - 0.4) / 0.6)
    return (a[0] + (b[0] - a[0]) * k, a[1] + (b[1] - a[1]) * k)


def player_body(script: RallyScript, player: int, t: float) -> np.ndarray:
    """Floor position (x, y) of a player at time t, keyed to their contacts."""
    return np.array(_player_body_xy(script, player, t))


def _blend_dirs(a: np.ndarray, b: np.ndarray, u: float) -> np.ndarray:
    return _unit(a + (b - a) * _smoothstep(u))


def _tuple_unit(v) -> tuple[float, float, float]:
    return tuple(_unit(v).tolist())


# Directions that depend only on the player (and a contact): normalised once with numpy's
# norm, exactly as when they were computed every frame, and kept as float tuples.
_UP = (0.0, 0.0, 1.0)
_UP_NP = np.array(_UP)
_POSE_DIRS = []
for _p in (NEAR, FAR):
    _f, _r = _frame_of(_p)
    _POSE_DIRS.append({
        "fwd": tuple(_f.tolist()), "right": tuple(_r.tolist()),
        "off_arm": _tuple_unit(0.35 * _f - 0.25 * _r - 0.9 * _UP_NP),
        "rest": _tuple_unit(0.55 * _f + 0.35 * _r - 0.45 * _UP_NP),
        "windup_overhead": _tuple_unit(-0.7 * _f + 0.2 * _r + 0.7 * _UP_NP),
        "windup_side": _tuple_unit(-0.6 * _f + 0.7 * _r - 0.2 * _UP_NP),
        "follow": _tuple_unit(0.7 * _f - 0.3 * _r - 0.6 * _UP_NP),
    })
del _p, _f, _r


@lru_cache(maxsize=4096)
def _body_xy_for_contact(player: int, c: Contact) -> tuple[float, float]:
    """``_body_for_contact`` as floats, cached: it is asked for ~6 times per player and frame."""
    return tuple(_body_for_contact(player, c).tolist())


@lru_cache(maxsize=4096)
def _arm_at_contact(player: int, c: Contact) -> tuple[float, float, float]:
    """Unit shoulder → contact direction at the contact (the swing passes through it)."""
    _, right = _frame_of(player)
    return _tuple_unit(np.asarray(c.point) - (np.array([*_body_for_contact(player, c),
                                                        _jump_height(c)])
                                              + SHOULDER_HEIGHT * _UP_NP
                                              + SHOULDER_HALF_WIDTH * right))


def player_capsules(script: RallyScript, player: int, t: float) -> list[Capsule]:
    """The articulated player at time t: legs, shorts, torso, head, two arms, racket.

    Vectors are float 3-tuples combined with ``_lin`` (see there why); the few unit vectors
    that change every frame still go through numpy's norm, so every value is bit-identical to
    the all-numpy formulation this replaced.
    """
    dirs = _POSE_DIRS[player]
    fwd, right, up = dirs["fwd"], dirs["right"], _UP
    bx, by = _player_body_xy(script, player, t)
    ax, ay = _player_body_xy(script, player, t + 0.01)
    cx, cy = _player_body_xy(script, player, t - 0.01)
    vel_x, vel_y = (ax - cx) / 0.02, (ay - cy) / 0.02
    speed = float(np.hypot(vel_x, vel_y))
    prev, nxt = script.contacts_of(player, t)
    jump = 0.0
    for c in (prev, nxt):
        if c is not None and abs(t - c.t) < 0.25:
            jump = max(jump, _jump_height(c) * math.cos(math.pi * (t - c.t) / 0.5) ** 2)
    body = (bx, by, jump)
    if speed > 0.2:
        sx, sy = _unit(np.array([vel_x, vel_y])).tolist()
    else:
        sx, sy = fwd[0], fwd[1]
    stride_dir = (sx, sy, 0.0)
    stride = min(speed / 4.0, 1.0) * 0.28 * math.sin(2 * math.pi * 2.2 * t)
    caps: list[Capsule] = []
    for side in (-1.0, 1.0):
        hip = _lin(body, (0.11 * side, right), (0.9, up))
        foot = _lin(body, (0.15 * side, right), (side * stride, stride_dir), (0.05, up))
        caps.append(Capsule(hip, foot, 0.075, 0.055, "skin"))
    caps.append(Capsule(_lin(body, (0.78, up)), _lin(body, (0.98, up)), 0.17, 0.17, "shorts"))
    caps.append(Capsule(_lin(body, (1.0, up)), _lin(body, (1.38, up)), 0.17, 0.19, "shirt"))
    head = _lin(body, (1.64, up))
    caps.append(Capsule(head, head, 0.11, 0.11, "hair"))
    # Off arm hangs, slightly forward.
    s_off = _lin(body, (SHOULDER_HEIGHT, up), (-SHOULDER_HALF_WIDTH, right))
    hand_off = _lin(s_off, (0.58, dirs["off_arm"]))
    caps.append(Capsule(s_off, hand_off, 0.05, 0.04, "skin"))
    # Racket arm: a swing keyed to the nearest contact.
    shoulder = _lin(body, (SHOULDER_HEIGHT, up), (SHOULDER_HALF_WIDTH, right))
    rest = dirs["rest"]
    direction = rest
    for c in (nxt, prev):
        if c is None:
            continue
        u = t - c.t
        if not -0.35 <= u <= 0.3:
            continue
        at_contact = _arm_at_contact(player, c)
        windup = dirs["windup_overhead"] if c.overhead else dirs["windup_side"]
        follow = dirs["follow"]
        if u < -0.18:
            a, b, k = rest, windup, (u + 0.35) / 0.17
        elif u < 0:
            a, b, k = windup, at_contact, (u + 0.18) / 0.18
        elif u < 0.12:
            a, b, k = at_contact, follow, u / 0.12
        else:
            a, b, k = follow, rest, (u - 0.12) / 0.18
        direction = tuple(_blend_dirs(np.array(a), np.array(b), k).tolist())
        break
    hand = _lin(shoulder, (ARM_LENGTH, direction))
    racket_centre = _lin(shoulder, (REACH, direction))
    caps.append(Capsule(shoulder, hand, 0.05, 0.04, "skin"))
    caps.append(Capsule(hand, _lin(racket_centre, (-0.13, direction)), 0.012, 0.006,
                        "racket", occludes=False))
    caps.append(Capsule(racket_centre, racket_centre, 0.115, 0.115, "racket_head",
                        occludes=False))
    return caps

"""Shuttlecock flight physics: the quadratic-drag model.

Why this file exists: the demo court flies its shuttle with this model and the trajectory
module fits it to measured points; both must agree on one definition.

    a = g − |v| v / L,   g = (0, 0, −9.81) m/s² in the court frame (Z up),
    L = 2 m / (ρ S C_D) ≈ 4.6–5.0 m (aerodynamic length), terminal speed √(g L).
"""

from __future__ import annotations

import numpy as np

GRAVITY = 9.81
GRAVITY_VECTOR = np.array([0.0, 0.0, -GRAVITY])
DEFAULT_AERO_LENGTH = 4.8          # m
AERO_LENGTH_BOUNDS = (3.0, 8.0)    # physical bounds for fitting (worn to new feathers)


def acceleration(velocity: np.ndarray, aero_length: float = DEFAULT_AERO_LENGTH) -> np.ndarray:
    """Acceleration for one (3,) or many (N, 3) velocities."""
    v = np.asarray(velocity, dtype=float)
    speed = np.linalg.norm(v, axis=-1, keepdims=True)
    return GRAVITY_VECTOR - speed * v / aero_length


def step_rk4(p: np.ndarray, v: np.ndarray, dt: float, aero_length: float) -> tuple[np.ndarray, np.ndarray]:
    """One Runge–Kutta 4 step of the drag model (works on (3,) or (N, 3) arrays)."""
    k1v = acceleration(v, aero_length)
    k1p = v
    k2v = acceleration(v + 0.5 * dt * k1v, aero_length)
    k2p = v + 0.5 * dt * k1v
    k3v = acceleration(v + 0.5 * dt * k2v, aero_length)
    k3p = v + 0.5 * dt * k2v
    k4v = acceleration(v + dt * k3v, aero_length)
    k4p = v + dt * k3v
    p_next = p + dt / 6.0 * (k1p + 2 * k2p + 2 * k3p + k4p)
    v_next = v + dt / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v)
    return p_next, v_next


def simulate(p0, v0, duration: float, dt: float = 1e-3,
             aero_length: float = DEFAULT_AERO_LENGTH, floor_z: float | None = 0.0
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Integrate a flight; returns (t (N,), positions (N,3), velocities (N,3)).

    Stops after ``duration`` or, when ``floor_z`` is given, at the step that crosses it (the
    last sample is interpolated onto the floor).
    """
    p = np.asarray(p0, dtype=float).copy()
    v = np.asarray(v0, dtype=float).copy()
    n_max = int(np.ceil(duration / dt)) + 1
    ts = [0.0]
    ps = [p.copy()]
    vs = [v.copy()]
    for i in range(1, n_max):
        p_new, v_new = step_rk4(p, v, dt, aero_length)
        if floor_z is not None and p_new[2] < floor_z <= p[2]:
            frac = (p[2] - floor_z) / max(p[2] - p_new[2], 1e-12)
            ts.append((i - 1 + frac) * dt)
            ps.append(p + frac * (p_new - p))
            vs.append(v + frac * (v_new - v))
            break
        p, v = p_new, v_new
        ts.append(i * dt)
        ps.append(p.copy())
        vs.append(v.copy())
    return np.asarray(ts), np.asarray(ps), np.asarray(vs)


def landing(p0, v0, aero_length: float = DEFAULT_AERO_LENGTH, dt: float = 2e-3,
            max_time: float = 6.0, floor_z: float = 0.0) -> tuple[np.ndarray, float] | None:
    """(landing position (3,), time of flight) from a state, or None if it does not land."""
    t, p, _ = simulate(p0, v0, max_time, dt, aero_length, floor_z)
    if p[-1, 2] > floor_z + 1e-6:
        return None
    return p[-1], float(t[-1])


def terminal_speed(aero_length: float = DEFAULT_AERO_LENGTH) -> float:
    return float(np.sqrt(GRAVITY * aero_length))

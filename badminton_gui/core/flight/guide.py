"""The followed flight's guide for one step, asked for at most once.

Why this file exists: several stages of one step (the guided look, the flight's vouch for a
pair, the exits from view) want to know where the flight puts the shuttle now; predicting it is
an RK4 propagation, so a step asks the trajectory once, and only when a stage needs it.
"""

from __future__ import annotations

import numpy as np

from .trajectory import Trajectory

Guide = tuple[np.ndarray, np.ndarray]   # the flight's (position, covariance) at a time, court frame


class StepGuide:
    """The trajectory's ``guide(t)`` for one step's time, computed on first use."""

    __slots__ = ("_trajectory", "_t", "_asked", "_motion")

    def __init__(self, trajectory: Trajectory, t: float) -> None:
        self._trajectory = trajectory
        self._t = t
        self._asked = False
        self._motion: tuple[np.ndarray, np.ndarray, float, float] | None = None

    def get(self) -> Guide | None:
        """The guide at this step's time (None: no flight to trust)."""
        if not self._asked:
            self._motion, self._asked = self._trajectory.guide_motion(self._t), True
        return self.known

    def reach(self, top_speed: float) -> tuple[np.ndarray, float] | None:
        """(the guide's position, how far (m) from it the followed shuttle can be now, a shuttle
        hit since the flight's last point leaving at ``top_speed`` m/s: ``Trajectory.reach``),
        or None without a guide."""
        if self.get() is None:
            return None
        return self._motion[0], self._trajectory.reach(self._motion, self._t, top_speed)

    @property
    def known(self) -> Guide | None:
        """The guide if a stage has asked for it already, else None (asks nothing)."""
        return None if self._motion is None else (self._motion[0], self._motion[1])

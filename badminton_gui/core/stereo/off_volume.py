"""Where pairs were refused as off the play volume: a memory that refuses a lone report there.

Why this file exists: an LED board beside the court carries a moving dot that both cameras see
where it is and the candidate classifier scores like the shuttle. When both cameras keep the dot
the same step, its pair triangulates outside the play volume and ``stereo.play_volume`` rejects
it in both; but a camera often keeps the dot alone (the other camera's dot merged, held back by
its track, or not found that step), and then nothing tells it from a shuttle only that camera
sees. The places where pairs were refused are the board's surface, fixed in the hall: a camera's
report whose line of sight passes within ``stereo.off_volume_radius`` of one of them, with no
partner inside the play volume, is that object again (``stereo.off_volume_memory``). The
court adapts the rule by itself: no labels, only the pairs it has already refused.
"""

from __future__ import annotations

import numpy as np

# At most this many remembered places: a new one replaces the oldest (a board's surface, at the
# radius, needs a few hundred).
MAX_PLACES = 2000


class OffVolumeMemory:
    """The 3D points (court frame) of pairs refused as off the play volume, each with the time it
    was last refused; a point within half the radius of a remembered one refreshes it instead of
    adding one."""

    def __init__(self) -> None:
        self._points = np.zeros((0, 3))
        self._times = np.zeros(0)

    def __len__(self) -> int:
        return len(self._times)

    def remember(self, points: np.ndarray, t: float, radius: float) -> None:
        """Pairs refused at time ``t`` at ``points`` (N, 3, court frame)."""
        for p in np.asarray(points, float).reshape(-1, 3):
            if len(self._times):
                d = np.linalg.norm(self._points - p, axis=1)
                k = int(np.argmin(d))
                if d[k] <= 0.5 * radius:
                    self._times[k] = t
                    continue
            self._points = np.vstack([self._points, p])[-MAX_PLACES:]
            self._times = np.append(self._times, t)[-MAX_PLACES:]

    def forget_before(self, t: float) -> None:
        """Places last refused before ``t`` are forgotten."""
        keep = self._times >= t
        if not keep.all():
            self._points, self._times = self._points[keep], self._times[keep]

    def near_sight(self, centre: np.ndarray, direction: np.ndarray, radius: float) -> bool:
        """Does the line of sight from ``centre`` along the unit ``direction`` pass, in front of
        the camera, within ``radius`` (m) of a remembered place?"""
        if not len(self._times):
            return False
        offset = self._points - centre
        along = offset @ direction
        ahead = along > 0.0
        if not ahead.any():
            return False
        miss = offset[ahead] - along[ahead, None] * direction
        return bool((np.einsum("ij,ij->i", miss, miss) <= radius * radius).any())

"""The epipolar gate: how far off its epipolar line a partner may lie, learnt from the rig.

Why this file exists: a rig calibrated by clicking court points misses by tens of px (the NYCU
rig imported from its ``.cfg`` files by ≈ 30 px), a chessboard-calibrated one by a few; the gate
the pairing, the vouch and the flight's noise model use is the configured one widened to what the
rig really achieves, measured on long, confident tracks seen by both cameras.
"""

from __future__ import annotations

import bisect
import math
from collections import deque

import numpy as np

from ..params import TrackerParams

# Sure pairs before the learnt epipolar tolerance replaces ``stereo.cold_epipolar_error``.
EPIPOLAR_LEARNT_SAMPLES = 20
# px: the least epipolar error taken as typical of a good pair (see ``EpipolarGate.inflation``)
EPIPOLAR_TYPICAL_MIN = 0.5


class EpipolarGate:
    """The epipolar errors of sure pairs seen so far, and the gates derived from them."""

    def __init__(self, params: TrackerParams) -> None:
        self.params = params
        self._samples: deque[float] = deque(maxlen=600)
        # The same samples kept sorted (and how many are NaN, which np.median would return):
        # their median is read several times a pair (the gate, the noise inflation) and changes
        # with each new sample, and np.median of 600 values costs ≈ 0.05 ms a call.
        self._sorted: list[float] = []
        self._nans = 0
        # The same pairs' errors with the cameras' roles exchanged: small where the direct ones
        # are large when the left and right inputs were swapped (``swapped_error_px``).
        self._swapped: deque[float] = deque(maxlen=600)
        self._swapped_median: tuple[int, float | None] = (0, None)   # (samples added, its median)
        self._swapped_added = 0

    @property
    def learnt(self) -> bool:
        """Enough sure pairs seen for the learnt figures to replace the configured ones."""
        return len(self._samples) >= EPIPOLAR_LEARNT_SAMPLES

    def tolerance(self) -> float:
        """The epipolar gate in use: the configured one, widened to the rig's measured error."""
        sp = self.params.stereo
        tol = float(sp.max_epipolar_error)
        if sp.adaptive_epipolar:
            if self.learnt:
                learnt = sp.adaptive_factor * self.median()
                tol = max(tol, min(learnt, sp.max_learnt_tolerance))
            else:
                # Nothing learnt yet (a fresh start): the rig may be off by tens of px, and the
                # 6 px gate left rally_11-47-02's serve unpaired in both cameras, then withheld
                # as one-camera reports (coarse, 33 frames).
                tol = max(tol, float(sp.cold_epipolar_error))
        return tol

    def vouch_tolerance(self) -> float:
        """The vouch's epipolar gate: ``stereo.vouch_max_epipolar``, widened to
        ``vouch_rig_factor`` × the rig's measured median epipolar error of sure pairs."""
        sp = self.params.stereo
        tol = float(sp.vouch_max_epipolar)
        if sp.vouch_rig_factor > 0 and self.learnt:
            tol = max(tol, sp.vouch_rig_factor * self.median())
        return tol

    def rig_error_px(self) -> float | None:
        """The median epipolar error (px) of the sure pairs learnt so far, or None before
        EPIPOLAR_LEARNT_SAMPLES of them."""
        if not self.learnt:
            return None
        median = self.median()
        return None if math.isnan(median) else median

    def inflation(self, epi: float) -> float:
        """How much less to trust a pair whose epipolar error is large for this rig.

        Two detections of one point meet their epipolar lines to a fraction of a pixel on a good
        rig; a pair several times further off has one centroid pulled aside (by a court line, the
        net's tape, a player's blob): the pair's 3D point is then biased, so the flight filter gets
        it with its noise scaled by 1 + (error / typical)².
        """
        typical = (max(EPIPOLAR_TYPICAL_MIN, 1.5 * self.median())
                   if self.learnt else EPIPOLAR_TYPICAL_MIN)
        return 1.0 + (epi / typical) ** 2

    def swapped_error_px(self) -> float | None:
        """The median epipolar error (px) the same sure pairs would have with the left and right
        images exchanged, or None before EPIPOLAR_LEARNT_SAMPLES of them."""
        if len(self._swapped) < EPIPOLAR_LEARNT_SAMPLES:
            return None
        # Read with every display packet; it changes only with a new sample.
        if self._swapped_median[0] != self._swapped_added:
            values = np.asarray(self._swapped)
            values = values[~np.isnan(values)]
            self._swapped_median = (self._swapped_added, float(np.median(values)) if len(values) else None)
        return self._swapped_median[1]

    def add_sample(self, err: float, swapped: float | None = None) -> None:
        """One sure pair's epipolar error, and the error it has with the cameras exchanged (the
        oldest of 600 leaves)."""
        if swapped is not None:
            self._swapped.append(swapped)
            self._swapped_added += 1
        samples = self._samples
        if len(samples) == samples.maxlen:
            old = samples[0]
            if math.isnan(old):
                self._nans -= 1
            else:
                ordered = self._sorted
                del ordered[bisect.bisect_left(ordered, old)]
        samples.append(err)
        if math.isnan(err):
            self._nans += 1
        else:
            bisect.insort(self._sorted, err)

    def median(self) -> float:
        """``float(np.median(samples))`` bit for bit (non-empty), from the sorted copy: the
        middle value, or the two middle values' sum halved as numpy's mean does."""
        if self._nans:
            return float(np.median(self._samples))
        ordered = self._sorted
        n = len(ordered)
        if n % 2:
            return ordered[n // 2]
        return (ordered[n // 2 - 1] + ordered[n // 2]) / 2.0

    def samples(self) -> tuple[float, ...]:
        """The samples held, oldest first."""
        return tuple(self._samples)

"""The 3D measurement of a step's pair: its point at the cork, in the output frame, and how sure
it is.

Why this file exists: the hand-off between the stereo stage and the 3D flight filter. A pair's
triangulated blob point is moved forward to the cork (``stereo/cork.py``); its noise shape is
the rig's stereo noise at those pixels, inflated when the pair's epipolar error is large for this
rig (``EpipolarGate.inflation``); the cork correction's own uncertainty goes beside it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..params import TrackerParams
from ..rig import StereoRig
from ..step import Step
from .cork import CorkCorrection
from .epipolar import EpipolarGate
from .pairing import StereoPairing


@dataclass(frozen=True, slots=True)
class Measurement:
    """A step's measured 3D point (output frame; None: no pair), its noise shape (3 × 3), and the
    cork correction's variance (m² per axis)."""

    point: tuple[float, float, float] | None = None
    noise_shape: np.ndarray | None = None
    head_variance: float = 0.0


def measure(step: Step, rig: StereoRig, params: TrackerParams, gate: EpipolarGate,
            pairing: StereoPairing, cork: CorkCorrection) -> Measurement:
    """The step's pair measured (``step.point`` becomes the cork's point, left-camera frame);
    remembers the blob point and the pair for the next step's checks."""
    head_var = 0.0
    blob = step.point
    left, right = step.dets
    if blob is not None and params.stereo.head_offset > 0:
        step.point = cork.to_head(left, right, blob)
        head_var = cork.variance(step.t, blob, step.point - blob)
    cork.note_blob(step.t, blob)
    if step.point is None:
        return Measurement(head_variance=head_var)
    if step.epi is not None:
        pairing.note_pair(step.t, left, right, step.epi)
    measured = tuple(float(v) for v in rig.to_output(step.point)[0])
    noise_shape = rig.noise_shape([[left.x, left.y]], [list(pairing.right_xy(right))])[0]
    if step.epi is not None:
        noise_shape = noise_shape * gate.inflation(step.epi)
    return Measurement(measured, noise_shape, head_var)

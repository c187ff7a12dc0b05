"""What each per-camera stage did with one frame's blobs, as numbers (``CameraDetector.last_diagnostics``).

Why this file exists: every candidate already names the filter that rejected it
(``Candidate.rejected_by``), which the tuning view draws; a study or a log wants the same per
stage, counted, without re-deriving them from the candidates (the reasons ``whiteness`` and
``motion`` are each given by two stages).
"""

from __future__ import annotations

import dataclasses


@dataclasses.dataclass(frozen=True, slots=True)
class ShapeReport:
    """The candidates stage: filters 1 and 2 on the mask's contours."""

    contours: int            # the mask's external contours
    rejected_length: int     # filter 1, contour length (``Candidate.rejected_by`` "length")
    rejected_short_side: int  # filter 2, shortest side of the tilted rectangle ("short_side")
    not_measured: int        # passed both, beyond ``association.max_measured`` ("whiteness")
    split_parts: int         # parts split off long blobs, measured as blobs of their own


@dataclasses.dataclass(frozen=True, slots=True)
class ScoreReport:
    """The scoring stage: filter 3, the one-frame motion rule and the score."""

    measured: int            # blobs measured at full resolution (split parts included)
    rejected_whiteness: int  # filter 3: whiteness, saturation or contrast ("whiteness")
    rejected_still: int      # where a blob was last frame (``motion.min_displacement``: "motion")
    rejected_score: int      # quality below ``association.min_quality`` ("score")


@dataclasses.dataclass(frozen=True, slots=True)
class TrackletReport:
    """The tracklets stage: filter 4, motion over frames."""

    linked: int              # blobs handed to the association
    rejected_motion: int     # not on a confirmed, travelling tracklet ("motion")
    passed: int              # may be the detection (``rejected_by`` None)
    exit_hold: bool          # every candidate held back: the shuttle is out of the picture
    coasting: bool           # the followed track's prediction stands in for a missing blob
    lone_accepted: bool      # a sure blob passed although no tracklet travels


@dataclasses.dataclass(frozen=True, slots=True)
class DetectionDiagnostics:
    """One frame of one camera, stage by stage."""

    windowed: bool           # segmentation ran in a window around the followed shuttle
    shapes: ShapeReport
    scoring: ScoreReport
    tracklets: TrackletReport

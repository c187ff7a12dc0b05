"""Behaviour added for broadcast (TV) footage, each gated by a parameter that is off by default.

The default preset (the two-camera rig) must not change: every switch here defaults to off, and
the tests check both that the switch does what it says and that it is off by default.
"""

import numpy as np
import pytest

from badminton_gui.core.association import TrackletAssociator
from badminton_gui.core.params import TrackerParams

FPS = 30.0


def _two_tracks(candidate_weight: float) -> list[tuple[int, float, float]]:
    """Two tracklets flying side by side; this frame one blob looks like a shuttle, one not."""
    p = TrackerParams().with_value("association.candidate_weight", candidate_weight)
    assoc = TrackletAssociator(p.motion, p.association)
    out = []
    for i in range(8):
        pos = np.array([[100.0 + 30 * i, 300.0], [100.0 + 30 * i, 500.0]])
        scores = np.array([0.6, 0.6]) if i < 7 else np.array([0.95, 0.2])
        out = assoc.update(i / FPS, pos, scores)
    return out


def test_candidate_weight_is_off_by_default():
    assert TrackerParams().association.candidate_weight == 0.0


def test_candidate_weight_adds_this_frames_quality_to_the_merit():
    plain = _two_tracks(0.0)
    weighted = _two_tracks(2.0)
    assert plain[0][2] >= 0 and plain[1][2] >= 0
    # Off: only the running quality counts. On: the shuttle-like blob gains 2 × 0.95, the other
    # 2 × 0.2, so this frame's looks separate the two tracklets more.
    assert weighted[0][2] - plain[0][2] == pytest.approx(2.0 * 0.95)
    assert weighted[1][2] - plain[1][2] == pytest.approx(2.0 * 0.2)

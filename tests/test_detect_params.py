"""Detector settings that were module constants: each reaches the stage that reads it.

``association.max_measured`` is the only cap on the blobs measured at full resolution (a second,
fixed cap of 64 used to stop the slider there), and ``colour.edge_exit_frames`` sets how many of
a tracklet's blob areas the edge-exit rule remembers.
"""

from __future__ import annotations

import numpy as np

from badminton_gui.core.detect.tracklets import TrackletLooks
from badminton_gui.core.detector import CameraDetector
from badminton_gui.core.params import TrackerParams


def _not_measured(max_measured: int) -> int:
    """A dark frame, then one with 100 small bright dots: how many passed filters 1 and 2 but
    were not measured."""
    p = TrackerParams().with_value("classifier.enabled", False).with_value("association.max_measured", max_measured)
    det = CameraDetector(p)
    dark = np.full((480, 640, 3), 30, np.uint8)
    dots = dark.copy()
    for k in range(100):
        x, y = 40 + 60 * (k % 10), 30 + 45 * (k // 10)
        dots[y - 2:y + 3, x - 2:x + 3] = 235
    for i, frame in enumerate((dark, dark, dots)):
        det.process(frame, i / 120.0, keep_mask=False)
    shapes = det.last_diagnostics.shapes
    assert shapes.contours - shapes.rejected_length - shapes.rejected_short_side >= 90
    return shapes.not_measured


def test_more_than_64_blobs_are_measured_when_asked():
    assert _not_measured(64) > 0
    assert _not_measured(200) == 0
    assert _not_measured(16) > _not_measured(64)


def test_the_edge_exit_remembers_the_configured_number_of_areas():
    looks = TrackletLooks()
    for area in range(10):
        looks.note(3, 4.0, float(area), 1, 8)
    assert list(looks.areas(3)) == [float(a) for a in range(2, 10)]
    looks.note(3, 4.0, 10.0, 1, 3)
    assert list(looks.areas(3)) == [8.0, 9.0, 10.0]
    looks.note(4, 4.0, 1.0, 1, 0)           # the edge exit off: nothing remembered
    assert looks.areas(4) is None

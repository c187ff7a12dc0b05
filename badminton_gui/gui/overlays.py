"""Colours and names shared by every view that draws detections and rejected candidates.

Why this file exists: the feeds, the tuning dialog's preview and their legends must agree on
which colour means which filter; one table here keeps them in step with ``core.types``.
"""

from __future__ import annotations

from PySide6.QtGui import QColor

from ..core.types import (REJECT_LENGTH, REJECT_MOTION, REJECT_SCORE, REJECT_SHORT_SIDE,
                          REJECT_STEREO, REJECT_WHITENESS)

DETECTION_COLOUR = QColor(255, 0, 0)          # the paper's red circle
TRAIL_COLOUR = QColor(255, 60, 60)
WINDOW_COLOUR = QColor(80, 220, 255)          # the windowed-tracking box (core/window.py)
LABEL_COLOUR = QColor(60, 230, 90)            # the source's truth: a label or the demo's shuttle

# (colour, legend text) per rejecting filter.
REJECT_STYLE: dict[str, tuple[QColor, str]] = {
    REJECT_LENGTH: (QColor(255, 170, 0), "contour length"),
    REJECT_SHORT_SIDE: (QColor(255, 255, 0), "tilted-rect side"),
    REJECT_WHITENESS: (QColor(0, 200, 255), "not white"),
    REJECT_MOTION: (QColor(200, 80, 255), "motion gate"),
    REJECT_STEREO: (QColor(0, 255, 120), "withheld by stereo"),
    REJECT_SCORE: (QColor(190, 190, 190), "lower score"),
}
UNKNOWN_REJECT = (QColor(255, 255, 255), "other")


def reject_style(reason: str | None) -> tuple[QColor, str]:
    return REJECT_STYLE.get(reason or "", UNKNOWN_REJECT)

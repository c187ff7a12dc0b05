"""Colours and names shared by every view that draws detections and rejected candidates.

Why this file exists: the feeds, the tuning dialog's preview and their legends must agree on
which colour means which filter; one table here keeps them in step with ``core.types``. The
feeds' trace panel (which rules fired, what each detector stage rejected) is worded here too,
as plain text from a result, so it can be checked without painting.
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

# The label beside a rejected candidate's ring: a word short enough for a busy court.
REJECT_SHORT: dict[str, str] = {
    REJECT_LENGTH: "len",
    REJECT_SHORT_SIDE: "side",
    REJECT_WHITENESS: "white",
    REJECT_MOTION: "motion",
    REJECT_STEREO: "stereo",
    REJECT_SCORE: "score",
}


def reject_style(reason: str | None) -> tuple[QColor, str]:
    return REJECT_STYLE.get(reason or "", UNKNOWN_REJECT)


def reject_short(reason: str | None) -> str:
    """The candidate label's word for a reject code (the code itself when it has none)."""
    return REJECT_SHORT.get(reason or "", reason or "?")


def trace_lines(trace: tuple[str, ...], side: str, diagnostics) -> list[str]:
    """The trace panel of camera ``side`` ("left" / "right"): the shuttle's phase and the rules
    that fired on this step for this camera or for the pair, named as ``badminton-track track
    --trace`` names them, then what each of the camera's detector stages rejected
    (``DetectionDiagnostics``; None: the step was tracked untraced)."""
    if diagnostics is None:
        return ["no trace: tracked before the overlay was on"]
    phase = [name for name in trace if name.startswith("phase:")]
    rules = [name for name in trace if not name.startswith("phase:")
             and (":" not in name or name.endswith(":" + side))]
    if not trace:
        head = "one camera: no stereo rules"
    else:
        head = " · ".join(phase[-1:] + (rules or ["no rule fired"]))
    shapes, scoring, tracklets = diagnostics.shapes, diagnostics.scoring, diagnostics.tracklets
    shape_line = (f"shapes {shapes.contours}: len {shapes.rejected_length} · side "
                  f"{shapes.rejected_short_side} · unmeasured {shapes.not_measured}")
    if shapes.split_parts:
        shape_line += f" · split +{shapes.split_parts}"
    if diagnostics.windowed:
        shape_line += " · windowed"
    flags = [text for on, text in ((tracklets.coasting, "coasting"), (tracklets.exit_hold, "exit hold"),
                                   (tracklets.lone_accepted, "lone")) if on]
    return [head, shape_line,
            f"scoring {scoring.measured}: white {scoring.rejected_whiteness} · still "
            f"{scoring.rejected_still} · score {scoring.rejected_score}",
            f"tracklets {tracklets.linked}: motion {tracklets.rejected_motion} · passed "
            f"{tracklets.passed}" + "".join(" · " + f for f in flags)]

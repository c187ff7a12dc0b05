"""Tells the operator when the running tracker finds the stereo calibration off, and what to do.

Why this file exists: a rig whose relative pose is wrong still tracks — the epipolar gate widens
to what the rig achieves (``StereoTracker.epipolar_tolerance``) — so nothing looked wrong, while
the 3D points, speeds and landing calls sent to the robot were off and the stereo checks let
more clutter through. The NYCU rig imported from its ``.cfg`` files is ≈ 10° off: its pairs miss
each other's epipolar lines by ≈ 30 px, where *Calibration ▸ Refine from tracked shuttle…*
brings them to ≈ 1.5 px. The tracker measures this on the shuttle's own
sure pairs; this turns the figure into a readout and, once per source, an advice line with the
button that opens the refinement (the same check ROS camera_calibration shows as its epipolar
error).

Plain Python, no Qt: the window feeds it the worker's statistics and shows what it returns.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..core.rig import inputs_look_swapped, refine_threshold, swapped_sentence

# The readout's colour for a rig worth refining (the display's "behind" orange).
WARN_COLOUR = "#e8a33c"


def readout_text(epipolar_px: float | None, image_width: int, swapped_px: float | None = None) -> str:
    """The "Stereo rig" readout (rich text): the measured error, in orange with what to do when
    the rig is worth refining or the cameras look swapped; a dash before enough sure pairs have
    been seen."""
    if epipolar_px is None:
        return "—"
    if epipolar_px <= refine_threshold(image_width):
        return f"pairs off their epipolar lines {epipolar_px:.1f} px"
    if inputs_look_swapped(epipolar_px, swapped_px, image_width):
        return (f"<span style='color:{WARN_COLOUR}'>pairs off their epipolar lines {epipolar_px:.0f} px:"
                f"<br>cameras swapped? Source ▸ Swap</span>")
    return (f"<span style='color:{WARN_COLOUR}'>pairs off their epipolar lines {epipolar_px:.0f} px:"
            f"<br>Calibration ▸ Refine</span>")


@dataclass(frozen=True)
class RigAdvice:
    """An advice line for the banner; ``swap``: its remedy is to exchange the cameras (else to
    refine the rig)."""

    text: str
    swap: bool = False


@dataclass
class RigCheck:
    """Fed the worker's statistics with each display packet; returns an advice once per source
    when the rig's measured error is above the threshold."""

    advised: bool = False

    def reset(self) -> None:
        """A new source or a new rig: judge afresh."""
        self.advised = False

    def update(self, stats, image_width: int) -> RigAdvice | None:
        px = getattr(stats, "rig_epipolar_px", None)
        if self.advised or px is None or px <= refine_threshold(image_width):
            return None
        self.advised = True
        swapped_px = getattr(stats, "rig_swapped_px", None)
        if inputs_look_swapped(px, swapped_px, image_width):
            return RigAdvice(swapped_sentence(px, swapped_px) + " Exchange the two cameras.", swap=True)
        return RigAdvice(f"The two cameras' calibration is off: the shuttle seen by both misses its "
                         f"epipolar lines by {px:.0f} px (median; a good rig stays under "
                         f"{refine_threshold(image_width):.0f} px here), so the 3D points, speeds and "
                         f"landing calls are off too. Refine it from the play itself, no board needed.")

"""Badminton court geometry in the court frame: metres, origin at the court centre on the floor,
X across the court, Y along it (the net at Y = 0), Z up.

Why this file exists: the demo court draws these lines, the GUI plots them, the court-pose step
of calibration asks the operator to click their intersections, and the in/out call tests
against them. Metres; origin at the court centre on the floor; X across the court, Y along it
(the net at Y = 0), Z up.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

HALF_WIDTH_DOUBLES = 3.05
HALF_WIDTH_SINGLES = 2.59
HALF_LENGTH = 6.70
SHORT_SERVICE = 1.98            # distance of the short service line from the net
LONG_SERVICE_DOUBLES = 6.70 - 0.76
NET_HEIGHT_CENTRE = 1.524
NET_HEIGHT_POSTS = 1.55
NET_TOP_OF_MESH_DROP = 0.76     # height of the net mesh (top tape to bottom edge)
LINE_WIDTH = 0.04


@dataclass(frozen=True, slots=True)
class CourtLine:
    name: str
    start: tuple[float, float]
    end: tuple[float, float]


def court_lines() -> list[CourtLine]:
    """Every painted line of a doubles/singles court, as centre-line segments on the floor."""
    w, ws, h = HALF_WIDTH_DOUBLES, HALF_WIDTH_SINGLES, HALF_LENGTH
    lines = [
        CourtLine("doubles sideline left", (-w, -h), (-w, h)),
        CourtLine("doubles sideline right", (w, -h), (w, h)),
        CourtLine("singles sideline left", (-ws, -h), (-ws, h)),
        CourtLine("singles sideline right", (ws, -h), (ws, h)),
        CourtLine("back boundary near", (-w, -h), (w, -h)),
        CourtLine("back boundary far", (-w, h), (w, h)),
        CourtLine("doubles long service near", (-w, -LONG_SERVICE_DOUBLES), (w, -LONG_SERVICE_DOUBLES)),
        CourtLine("doubles long service far", (-w, LONG_SERVICE_DOUBLES), (w, LONG_SERVICE_DOUBLES)),
        CourtLine("short service near", (-w, -SHORT_SERVICE), (w, -SHORT_SERVICE)),
        CourtLine("short service far", (-w, SHORT_SERVICE), (w, SHORT_SERVICE)),
        CourtLine("centre line near", (0.0, -h), (0.0, -SHORT_SERVICE)),
        CourtLine("centre line far", (0.0, SHORT_SERVICE), (0.0, h)),
    ]
    return lines


def court_keypoints() -> dict[str, tuple[float, float, float]]:
    """Named line intersections on the floor, for the court-pose step of calibration."""
    w, ws, h = HALF_WIDTH_DOUBLES, HALF_WIDTH_SINGLES, HALF_LENGTH
    pts: dict[str, tuple[float, float, float]] = {}
    for ys, yname in ((-1, "near"), (1, "far")):
        pts[f"{yname} back corner left"] = (-w, ys * h, 0.0)
        pts[f"{yname} back corner right"] = (w, ys * h, 0.0)
        pts[f"{yname} back singles left"] = (-ws, ys * h, 0.0)
        pts[f"{yname} back singles right"] = (ws, ys * h, 0.0)
        pts[f"{yname} short service left"] = (-w, ys * SHORT_SERVICE, 0.0)
        pts[f"{yname} short service right"] = (w, ys * SHORT_SERVICE, 0.0)
        pts[f"{yname} short service centre"] = (0.0, ys * SHORT_SERVICE, 0.0)
        pts[f"{yname} back centre"] = (0.0, ys * h, 0.0)
        pts[f"{yname} long service left"] = (-w, ys * LONG_SERVICE_DOUBLES, 0.0)
        pts[f"{yname} long service right"] = (w, ys * LONG_SERVICE_DOUBLES, 0.0)
    pts["net foot left"] = (-w, 0.0, 0.0)
    pts["net foot right"] = (w, 0.0, 0.0)
    return pts


def net_posts() -> tuple[np.ndarray, np.ndarray]:
    """Bottom and top of the two posts, (2, 2, 3): [post][bottom, top]."""
    w = HALF_WIDTH_DOUBLES
    bottoms = np.array([[-w, 0.0, 0.0], [w, 0.0, 0.0]])
    tops = bottoms + np.array([0.0, 0.0, NET_HEIGHT_POSTS])
    return np.stack([bottoms, tops], axis=1)


def is_in(x: float, y: float, doubles: bool = True) -> bool:
    """In/out call for a landing point (lines are in)."""
    half_w = HALF_WIDTH_DOUBLES if doubles else HALF_WIDTH_SINGLES
    return abs(x) <= half_w + LINE_WIDTH / 2 and abs(y) <= HALF_LENGTH + LINE_WIDTH / 2

"""Draws the window icon, resources/icons/badminton-gui.png (256 px, transparent corners).

Why this file exists: the icon is made, not downloaded, so it can be redrawn (a different size,
colour) from this one script: a white shuttlecock in flight inside the red circle the feeds draw
around a detection, on a dark court-green tile. Drawn at 4x and shrunk, for smooth edges.

    .venv/bin/python scripts/make-icon.py [OUTPUT.png]
"""

from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np

SIZE = 256
SCALE = 4


def draw_icon(size: int = SIZE) -> np.ndarray:
    n = size * SCALE
    img = np.zeros((n, n, 4), np.uint8)
    s = n / 256.0                                    # the drawing is laid out on a 256 grid

    def p(x: float, y: float) -> tuple[int, int]:
        return int(round(x * s)), int(round(y * s))

    # The tile: a rounded square in court green.
    tile = np.zeros((n, n), np.uint8)
    r, m = int(44 * s), int(8 * s)
    cv2.rectangle(tile, (m + r, m), (n - m - r, n - m), 255, -1)
    cv2.rectangle(tile, (m, m + r), (n - m, n - m - r), 255, -1)
    for cx, cy in ((m + r, m + r), (n - m - r, m + r), (m + r, n - m - r), (n - m - r, n - m - r)):
        cv2.circle(tile, (cx, cy), r, 255, -1, cv2.LINE_AA)
    img[tile > 0] = (70, 96, 30, 255)                # BGRA: a dark green
    # A court line across the tile.
    cv2.line(img, p(20, 222), p(236, 222), (235, 235, 235, 255), int(5 * s), cv2.LINE_AA)
    img[..., 3] = np.where(tile > 0, img[..., 3], 0)

    # The shuttlecock, flying down to the left: the cork, then the skirt opening behind it.
    white, grey = (250, 250, 250, 255), (170, 170, 170, 255)
    cork = np.array([102, 146])
    axis = np.array([1.0, -0.62])
    axis /= np.linalg.norm(axis)
    normal = np.array([-axis[1], axis[0]])
    base_near = cork + axis * 18
    base_far = cork + axis * 78
    corners = [base_near + normal * 11, base_far + normal * 34,
               base_far - normal * 34, base_near - normal * 11]
    cv2.fillPoly(img, [np.array([p(*c) for c in corners], np.int32)], white, cv2.LINE_AA)
    for t in (-0.66, -0.33, 0.0, 0.33, 0.66):      # the feathers' shafts
        a = base_near + normal * 11 * t
        b = base_far + normal * 34 * t
        cv2.line(img, p(*a), p(*b), grey, int(2.5 * s), cv2.LINE_AA)
    band = base_near + axis * 18
    cv2.line(img, p(*(band + normal * 17)), p(*(band - normal * 17)), grey, int(3 * s), cv2.LINE_AA)
    cv2.circle(img, p(*cork), int(20 * s), (60, 160, 235, 255), -1, cv2.LINE_AA)   # the cork
    cv2.circle(img, p(*(cork - axis * 4 + normal * 4)), int(7 * s), (140, 210, 250, 255), -1, cv2.LINE_AA)

    # The detection circle, as drawn over the feeds.
    cv2.circle(img, p(*(cork + axis * 30)), int(76 * s), (40, 40, 230, 255), int(11 * s), cv2.LINE_AA)
    return cv2.resize(img, (size, size), interpolation=cv2.INTER_AREA)


def main(argv: list[str]) -> int:
    out = Path(argv[1]) if len(argv) > 1 else Path(__file__).resolve().parents[1] / "resources" / "icons" / "badminton-gui.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(out), draw_icon(), [cv2.IMWRITE_PNG_COMPRESSION, 9]):
        print(f"cannot write {out}", file=sys.stderr)
        return 1
    print(f"{out}: {out.stat().st_size} bytes")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

"""The guided look for the shuttle at its flight's projection (core/guided.py, no Qt).

It must find a small white moving spot, and refuse what is not a shuttle in flight: nothing
bright, a court line crossing the window, a white shirt, a glint that did not move.
"""

import math

import cv2
import numpy as np

from badminton_gui.core.guided import find_spot


def floor(seed=0):
    rng = np.random.default_rng(seed)
    img = np.full((120, 160, 3), (90, 60, 40), np.uint8)              # blue-ish court
    return np.clip(img + rng.normal(0, 2.5, img.shape), 0, 255).astype(np.uint8)


def with_shuttle(img, x, y, r=2.0):
    out = img.copy()
    cv2.circle(out, (int(round(x * 16)), int(round(y * 16))), int(r * 16), (235, 235, 235), -1,
               lineType=cv2.LINE_AA, shift=4)
    return out


def test_a_white_moving_spot_is_found_at_its_centroid():
    before = with_shuttle(floor(1), 70.0, 58.0)
    now = with_shuttle(floor(2), 80.3, 61.6)
    spot = find_spot(now, 78.0, 60.0, radius=8.0, min_contrast=25, max_area=60, previous_bgr=before)
    assert spot is not None
    x, y, contrast, area = spot
    assert math.hypot(x - 80.3, y - 61.6) < 0.3
    assert contrast > 100 and 5 <= area <= 30


def test_nothing_bright_far_or_static_is_no_spot():
    empty = floor(3)
    assert find_spot(empty, 80, 60, 8.0, 25, 60) is None
    now = with_shuttle(floor(4), 100.0, 60.0)
    assert find_spot(now, 80, 60, 8.0, 25, 60) is None                      # beyond the radius
    glint = with_shuttle(floor(5), 80.0, 60.0)
    assert find_spot(glint, 80, 60, 8.0, 25, 60, previous_bgr=glint.copy()) is None   # did not move
    assert find_spot(glint, 80, 60, 8.0, 25, 60) is not None                # no previous frame: no test


def test_a_line_crossing_the_window_or_a_white_shirt_is_no_spot():
    line = floor(6)
    cv2.line(line, (0, 60), (159, 60), (230, 230, 230), 2)
    assert find_spot(line, 80, 60, 8.0, 25, 60, previous_bgr=floor(7)) is None
    shirt = floor(8)
    cv2.rectangle(shirt, (74, 54), (86, 66), (240, 240, 240), -1)           # 169 px: not a shuttle
    assert find_spot(shirt, 80, 60, 8.0, 25, 60, previous_bgr=floor(9)) is None
    for colour in ((40, 40, 230), (150, 180, 235)):                         # a red frame, a hand
        spot = floor(10)
        cv2.circle(spot, (80, 60), 2, colour, -1)                           # bright, but not white
        assert find_spot(spot, 80, 60, 8.0, 25, 60, previous_bgr=floor(11)) is None

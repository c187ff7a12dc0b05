"""Drawing the tracking overlays on video frames with OpenCV: the red circle, its fading trail,
the caption, the readouts and the court plan.

Why this file exists: an exported clip (`badminton-track render`, the GUI's *Export video…*) must
look like the window — same colours, same circle, same half-second trail — but it is drawn
without Qt, so the command line on a headless machine and the desktop tool produce the same
pictures from the same code. The window's own feeds paint with QPainter (gui/feed_view.py,
gui/court_views.py); the constants below are theirs, and a GUI test keeps them equal.

A frame is drawn from a :class:`ShuttleStep` (one row of a `track` or `detect` CSV, or one
tracked frame pair) plus the recent history a :class:`OverlayHistory` keeps: the trails of both
cameras and the last second of the 3D flight. Sizes are in output pixels, scaled with the output
feed's width (:func:`ui_scale`) so that a 2048-pixel clip is as readable as a 1280-pixel one.
"""

from __future__ import annotations

import collections
import functools
import math
from dataclasses import dataclass

import cv2
import numpy as np

from . import court

# Colours (BGR) of gui/overlays.py and gui/court_views.py.
DETECTION_COLOUR = (0, 0, 255)          # the paper's red circle
TRAIL_COLOUR = (60, 60, 255)
FLIGHT_COLOUR = (0, 210, 255)
POSITION_COLOUR = (0, 0, 255)
PREDICTED_COLOUR = (255, 220, 80)
IN_COLOUR = (90, 220, 40)
OUT_COLOUR = (70, 70, 255)
PLAN_BACKGROUND = (26, 20, 18)
PLAN_LINES = (230, 230, 230)
NET_COLOUR = (200, 160, 160)
TEXT_COLOUR = (255, 255, 255)
LABEL_TEXT_COLOUR = (170, 170, 170)

CIRCLE_RADIUS = 11.0      # px at a 1280-px-wide feed: the window's fixed on-screen radius
CIRCLE_WIDTH = 3.0
TRAIL_SECONDS = 0.5       # the fading trail behind the red circle
TRAIL_LEVELS = 8          # opacity steps of the fading trail
TRAIL_WIDTH = 2.5
TRAIL_MAX_ALPHA = 220
TRAIL_JOIN = 0.12         # consecutive trail points farther apart than this share of the feed's
                          # larger side are not joined: a hop to another object shows as a hop
FLIGHT_SECONDS = 1.0      # the court plan shows the last second of 3D points
FLIGHT_GAP_SECONDS = 0.25   # ... joined where they are closer in time than this
PLAN_RANGE_Y = 7.6        # m: the plan's half extents, as the window's plan view
PLAN_RANGE_X = 3.6
REFERENCE_WIDTH = 1280.0  # output feed width at which the sizes above hold

_SHIFT = 4                # sub-pixel bits for cv2 drawing
_ONE = 1 << _SHIFT
_FONT = cv2.FONT_HERSHEY_SIMPLEX


@dataclass(frozen=True, slots=True)
class ShuttleStep:
    """What the overlays of one output frame show: one step of a track (a frame pair, or one
    camera's frame), full-resolution pixels and metres, None where there is no value."""

    index: int                                   # left (or the one camera's) frame
    index_right: int                             # right frame, -1 for one camera
    timestamp: float                             # s
    left: tuple[float, float] | None = None      # shuttle in the left picture
    right: tuple[float, float] | None = None
    point: tuple[float, float, float] | None = None   # 3D position
    distance: float | None = None                # m
    speed: float | None = None                   # m/s
    landing: tuple[float, float, float] | None = None   # predicted landing x, y (m) and time (s)


class OverlayHistory:
    """The trails of both cameras and the recent 3D flight, as the window's worker keeps them:
    a camera's detection joins its trail when that camera's frame is new in the step, and points
    older than the trail's length (or from the future, after a seek) are dropped."""

    def __init__(self) -> None:
        self._trails = (collections.deque(), collections.deque())
        self._flight: collections.deque = collections.deque()
        self._last_index = [None, None]

    def push(self, step: ShuttleStep) -> None:
        t = step.timestamp
        for cam, (index, xy) in enumerate(((step.index, step.left), (step.index_right, step.right))):
            trail = self._trails[cam]
            if xy is not None and index != self._last_index[cam]:
                trail.append((t, xy[0], xy[1]))
            self._last_index[cam] = index
            while trail and (trail[0][0] < t - TRAIL_SECONDS or trail[0][0] > t):
                trail.popleft()
        if step.point is not None:
            self._flight.append((t, *step.point))
        while self._flight and (self._flight[0][0] < t - FLIGHT_SECONDS or self._flight[0][0] > t):
            self._flight.popleft()

    def trail(self, camera: int) -> np.ndarray:
        """(N, 3) t, x, y of the camera's recent detections, oldest first."""
        return np.array(self._trails[camera], dtype=float).reshape(-1, 3)

    def flight(self) -> np.ndarray:
        """(N, 4) t, X, Y, Z of the recent 3D points, oldest first."""
        return np.array(self._flight, dtype=float).reshape(-1, 4)


def ui_scale(feed_width: int) -> float:
    """How much larger than at a 1280-px feed the overlays are drawn (never smaller: a small
    clip keeps the window's sizes, as a small window does)."""
    return max(1.0, feed_width / REFERENCE_WIDTH)


def landing_call(x: float, y: float, doubles: bool = True) -> str:
    """'in' or 'out' for a predicted landing point (lines are in)."""
    return "in" if court.is_in(x, y, doubles) else "out"


def _fixed(x: float, y: float) -> tuple[int, int]:
    return int(round(x * _ONE)), int(round(y * _ONE))


def draw_trail(image: np.ndarray, trail: np.ndarray, scale: float) -> None:
    """The fading trail, in place: ``trail`` (N, 3) t, x, y in full-resolution pixels, drawn at
    ``scale`` (output / full-resolution). The newest point is under the circle and not drawn.

    The fade is one alpha mask (each segment and dot drawn at its level's opacity, the newer over
    the older) blended once over the trail's bounding box, not one blend per level."""
    if len(trail) < 2:
        return
    h, w = image.shape[:2]
    ui = ui_scale(w)
    thickness = max(2, int(round(TRAIL_WIDTH * ui)))
    pts = trail[:, 1:3] * scale
    fade = np.clip(1.0 - (trail[-1, 0] - trail[:-1, 0]) / TRAIL_SECONDS, 0.0, 1.0)
    level = np.ceil(fade * TRAIL_LEVELS).astype(int)
    joined = np.abs(np.diff(pts, axis=0)).sum(axis=1) < TRAIL_JOIN * max(w, h)
    pad = thickness + 2
    x0 = int(max(math.floor(pts[:, 0].min()) - pad, 0))
    y0 = int(max(math.floor(pts[:, 1].min()) - pad, 0))
    x1 = int(min(math.ceil(pts[:, 0].max()) + pad + 1, w))
    y1 = int(min(math.ceil(pts[:, 1].max()) + pad + 1, h))
    if x1 <= x0 or y1 <= y0:
        return
    mask = np.zeros((y1 - y0, x1 - x0), np.uint8)
    local = pts - (x0, y0)
    for i in np.argsort(level, kind="stable"):
        if level[i] == 0:
            continue
        alpha = int(TRAIL_MAX_ALPHA * level[i] / TRAIL_LEVELS)
        a = _fixed(*local[i])
        if joined[i]:
            cv2.line(mask, a, _fixed(*local[i + 1]), alpha, thickness, cv2.LINE_AA, _SHIFT)
        cv2.circle(mask, a, int(round(thickness / 2 * _ONE)), alpha, -1, cv2.LINE_AA, _SHIFT)
    roi = image[y0:y1, x0:x1]
    weight = mask.astype(np.float32)[..., None] / 255.0
    roi[:] = (roi * (1.0 - weight) + np.asarray(TRAIL_COLOUR, np.float32) * weight + 0.5).astype(np.uint8)


def draw_detection(image: np.ndarray, x: float, y: float) -> None:
    """The red circle around the shuttle at output pixel (x, y), in place."""
    ui = ui_scale(image.shape[1])
    cv2.circle(image, _fixed(x, y), int(round(CIRCLE_RADIUS * ui * _ONE)), DETECTION_COLOUR,
               max(2, int(round(CIRCLE_WIDTH * ui))), cv2.LINE_AA, _SHIFT)


def draw_caption(image: np.ndarray, text: str) -> None:
    """A line of white text on a translucent black box at the top left, as the window's feeds
    caption themselves, in place."""
    ui = ui_scale(image.shape[1])
    font_scale = 0.55 * ui
    thickness = max(1, int(round(1.2 * ui)))
    (tw, th), base = cv2.getTextSize(text, _FONT, font_scale, thickness)
    margin, pad = int(6 * ui), int(6 * ui)
    x0, y0 = margin, margin
    x1 = min(x0 + tw + 2 * pad, image.shape[1])
    y1 = min(y0 + th + base + 2 * pad, image.shape[0])
    roi = image[y0:y1, x0:x1]
    roi[:] = (roi.astype(np.float32) * (1.0 - 150 / 255)).astype(np.uint8)
    cv2.putText(image, text, (x0 + pad, y0 + pad + th), _FONT, font_scale, TEXT_COLOUR, thickness, cv2.LINE_AA)


def draw_feed(image: np.ndarray, scale: float, shuttle: tuple[float, float] | None,
              trail: np.ndarray, caption: str) -> None:
    """One camera's output frame, in place: the trail, the red circle on ``shuttle`` and the
    caption (under the others). ``image`` is already at output size; ``shuttle`` and ``trail`` are in
    full-resolution pixels, ``scale`` = output / full resolution."""
    draw_caption(image, caption)     # first: a shuttle near the top left stays circled over it
    draw_trail(image, trail, scale)
    if shuttle is not None:
        draw_detection(image, shuttle[0] * scale, shuttle[1] * scale)


def feed_caption(camera_name: str, step: ShuttleStep, frame_index: int, shuttle_found: bool) -> str:
    """'Left | frame 123 | 1.025 s | shuttle found' (plain ASCII: OpenCV's fonts have no more)."""
    return (f"{camera_name} | frame {frame_index} | {step.timestamp:.3f} s | "
            + ("shuttle found" if shuttle_found else "no shuttle"))


# ---- the court plan and the readouts --------------------------------------------------------

def plan_size(height: int) -> tuple[int, int]:
    """(width, height) of a court plan ``height`` pixels tall: the court's aspect."""
    return int(round(height * PLAN_RANGE_Y / PLAN_RANGE_X)), height


def _plan_px(width: int, height: int, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Court X (across) and Y (along) → plan pixels: Y to the right, X up, as the window's plan."""
    col = (np.asarray(y, float) + PLAN_RANGE_Y) / (2 * PLAN_RANGE_Y) * width
    row = (PLAN_RANGE_X - np.asarray(x, float)) / (2 * PLAN_RANGE_X) * height
    return np.stack([col, row], axis=-1)


def _fixed_pts(px: np.ndarray) -> np.ndarray:
    return np.round(np.asarray(px) * _ONE).astype(np.int32)


@functools.lru_cache(maxsize=4)
def _empty_court(height: int) -> np.ndarray:
    """The plan's lines and net, drawn once per size (every frame of a clip has the same)."""
    width, height = plan_size(height)
    img = np.full((height, width, 3), PLAN_BACKGROUND, np.uint8)
    ui = max(1.0, height / 200.0)
    for line in court.court_lines():
        a, b = _plan_px(width, height, [line.start[0], line.end[0]], [line.start[1], line.end[1]])
        cv2.line(img, tuple(_fixed_pts(a)), tuple(_fixed_pts(b)), PLAN_LINES, 1, cv2.LINE_AA, _SHIFT)
    wn = court.HALF_WIDTH_DOUBLES + 0.2
    a, b = _plan_px(width, height, [-wn, wn], [0.0, 0.0])
    cv2.line(img, tuple(_fixed_pts(a)), tuple(_fixed_pts(b)), NET_COLOUR, max(2, int(round(3 * ui))),
             cv2.LINE_AA, _SHIFT)
    img.setflags(write=False)
    return img


def draw_plan(height: int, step: ShuttleStep, flight: np.ndarray, doubles: bool = True) -> np.ndarray:
    """The court seen from above (Y along the court to the right): the last second of the 3D
    flight, the shuttle now, the straight top view of its predicted path to the landing point,
    and the in/out call there. Court-frame metres in, a BGR image ``height`` pixels tall out."""
    img = _empty_court(height).copy()
    width, height = plan_size(height)
    ui = max(1.0, height / 200.0)
    if len(flight) >= 2:
        px = _plan_px(width, height, flight[:, 1], flight[:, 2])
        near = np.diff(flight[:, 0]) < FLIGHT_GAP_SECONDS
        for i in np.flatnonzero(near):
            cv2.line(img, tuple(_fixed_pts(px[i])), tuple(_fixed_pts(px[i + 1])), FLIGHT_COLOUR,
                     max(2, int(round(2 * ui))), cv2.LINE_AA, _SHIFT)
    if step.landing is not None:
        lx, ly, _ = step.landing
        colour = IN_COLOUR if landing_call(lx, ly, doubles) == "in" else OUT_COLOUR
        land = _plan_px(width, height, lx, ly)
        if step.point is not None:
            _dashed_line(img, _plan_px(width, height, step.point[0], step.point[1]), land,
                         PREDICTED_COLOUR, max(1, int(round(2 * ui))), dash=6 * ui)
        cv2.circle(img, tuple(_fixed_pts(land)), int(round(7 * ui * _ONE)), colour, max(1, int(round(2 * ui))),
                   cv2.LINE_AA, _SHIFT)
        cv2.circle(img, tuple(_fixed_pts(land)), int(round(2 * ui * _ONE)), colour, -1, cv2.LINE_AA, _SHIFT)
        text = landing_call(lx, ly, doubles).upper()
        fs, thick = 0.5 * ui, max(1, int(round(1.3 * ui)))
        (tw, th), _ = cv2.getTextSize(text, _FONT, fs, thick)
        org = (int(np.clip(land[0] - tw / 2, 0, width - tw)), int(np.clip(land[1] - 10 * ui, th, height)))
        # On a dark outline: the call often sits on a court line (a landing near the back line).
        cv2.putText(img, text, org, _FONT, fs, PLAN_BACKGROUND, thick + 2, cv2.LINE_AA)
        cv2.putText(img, text, org, _FONT, fs, colour, thick, cv2.LINE_AA)
    if step.point is not None:
        c = tuple(_fixed_pts(_plan_px(width, height, step.point[0], step.point[1])))
        r = int(round(5.5 * ui * _ONE))
        cv2.circle(img, c, r, POSITION_COLOUR, -1, cv2.LINE_AA, _SHIFT)
        cv2.circle(img, c, r, TEXT_COLOUR, 1, cv2.LINE_AA, _SHIFT)
    return img


def _dashed_line(img: np.ndarray, a: np.ndarray, b: np.ndarray, colour, thickness: int, dash: float) -> None:
    length = float(np.hypot(*(b - a)))
    if length < 1e-6:
        return
    n = max(1, int(length // (2 * dash)))
    for k in range(n + 1):
        s0, s1 = 2 * k * dash / length, min((2 * k + 1) * dash / length, 1.0)
        if s0 >= 1.0:
            break
        cv2.line(img, tuple(_fixed_pts(a + (b - a) * s0)), tuple(_fixed_pts(a + (b - a) * s1)), colour,
                 thickness, cv2.LINE_AA, _SHIFT)


def readout_lines(step: ShuttleStep, doubles: bool = True) -> list[tuple[str, str, tuple[int, int, int]]]:
    """(name, value, value colour) rows of the readouts, as the window words them (ASCII)."""
    dist = "-" if step.distance is None else f"{step.distance * 1000:,.0f} mm".replace(",", " ")
    speed = "-" if step.speed is None else f"{step.speed * 3.6:.0f} km/h  {step.speed:.1f} m/s"
    rows = [("Distance", dist, TEXT_COLOUR), ("Speed", speed, TEXT_COLOUR)]
    if step.landing is not None:
        lx, ly, lt = step.landing
        call = landing_call(lx, ly, doubles)
        rows.append(("Landing", f"x {lx:+.2f} m  y {ly:+.2f} m", TEXT_COLOUR))
        rows.append(("Call", f"{call.upper()}, lands in {max(0.0, lt - step.timestamp):.2f} s",
                     IN_COLOUR if call == "in" else OUT_COLOUR))
    else:
        rows.append(("Landing", "-", TEXT_COLOUR))
    return rows


def draw_readouts(width: int, height: int, step: ShuttleStep, doubles: bool = True) -> np.ndarray:
    """The numbers beside the plan: distance (mm), speed, landing point and call."""
    img = np.full((height, width, 3), PLAN_BACKGROUND, np.uint8)
    rows = readout_lines(step, doubles)
    line_h = height / 4.6
    fs = 0.5 * line_h / 22.0 * 1.25
    thick = max(1, int(round(fs * 1.6)))
    name_w = cv2.getTextSize("Distance  ", _FONT, fs * 0.8, 1)[0][0]
    x = int(round(line_h * 0.4))
    for k, (name, value, colour) in enumerate(rows):
        y = int(round(line_h * (k + 1)))
        cv2.putText(img, name, (x, y), _FONT, fs * 0.8, LABEL_TEXT_COLOUR, max(1, thick - 1), cv2.LINE_AA)
        cv2.putText(img, value, (x + name_w, y), _FONT, fs, colour, thick, cv2.LINE_AA)
    return img

"""Windowed tracking: while a camera follows a confirmed shuttle, look only where it can be.

Why this file exists: issue #7 asks for 240 pairs/s at 2048×1536 (8.3 ms of CPU a pair) and
the whole-frame chain spends most of its CPU on the whole frame — the grey image from the
9.4 MB frame, the background model, and the contours and blob measures of everything else that
moved. While the followed tracklet is confirmed and was hit in the last frame, the shuttle can
only be inside its motion gate around the predicted position; so there, and only there, the
grey image is made, the background model is compared and learns, the mask is made, its
contours found and its blobs measured (coarse-to-fine). Every ``window.full_every``
frames, and whenever the followed tracklet is not confirmed or was missed, the whole frame is
processed as before: a serve, the other camera's partner candidate, a new shuttle after the
followed one is lost are found at most ``full_every − 1`` frames late.

Consequences, by design:
- the running average outside the window learns only on whole frames: at the same learning
  rate, so ``full_every`` × slower in time there (a player's ghost outside the window lasts
  longer in the whole frames' masks), unless ``window.catch_up`` gives the pixels no window
  covered the weight of the k updates they missed on the next whole frame, 1 − (1 − α)^k, and
  1 − (1 − α/10)^k under the foreground (a ghost fades as on whole frames; caught up at α
  only for the still pixels, a player's ghost outlasted the whole frames' by ``full_every`` ×
  and swallowed a shuttle landing beside it); the still pixels only where the grey value
  stayed within ``binarize.diff_threshold`` of the last whole frame's (``before_whole``: where
  it changed, a player moved in between, and the frame caught up would stand for missed frames
  that showed something else); the flicker gain of a windowed frame is
  estimated on the window's part of the sparse grid (a finer grid when it holds too few points);
- on windowed frames the mask (and the GUI's mask preview) is empty outside the window, so
  ``is_merged`` sees nothing there; ``is_blind`` reads the running average, stale outside;
- tracklets outside the window find no candidate there and are missed as on a whole frame
  where their blob vanished: they end after ``association.max_misses`` windowed frames. (Setting
  them aside for the windowed frames instead, neither hit nor missed, was tried and lost 1.5 F1
  points: a static blob's tracklet — a shuttle lying on the floor — kept the pause allowance it
  would have used up, came back on the next whole frame with its long history and took the
  choice from the shuttle's tracklet after a hit; rally_11-46-22 right frames 427–456, left
  784–911.)
- ``window.stagger`` (on in coarse): the cameras' scheduled whole frames follow a fixed clock,
  the right camera's half a period after the left's, so a pair never waits for two scheduled
  whole frames (the slowest pairs); a whole frame forced by a missed shuttle does not move the
  clock, so the next scheduled one may come sooner than ``full_every`` frames after it;
- ``window.min_quality`` (0.5 in coarse): no window while the followed tracklet's running
  quality is below it. Before a serve the followed tracklet can be clutter (a racket, a hand)
  that the stereo reporting withholds anyway; windowing on it hid the serve outside the window
  for up to ``full_every`` frames at a time, so its tracklet was confirmed ≈ 10 frames late
  (rally_11-46-04 left 300–311). Coarse, tuned-on rallies online: F1 96.41 → 96.62 % (default
  96.93), windowed share in play 71.3 → 67.7 %;
- no window while the followed tracklet has not travelled ``association.flight_travel`` px (a
  held shuttle, clutter taken up after the shuttle was lost, a path just struck, whose travel
  the association restarts): windowing on clutter starved the tracklets outside the window,
  the lost shuttle's own among them, which ended after ``max_misses`` frames with the history
  that lets a shuttle pause (rally_11-49-21 left 1452–1465);
- ``window.near_large``: no window while the followed shuttle is predicted within this many px
  of a blob too large for a shuttle on the last whole frame (a player and his racket: the
  boxes of a window's frame are clipped by its edge). There it may be struck, and the followed
  tracklet often goes on with the racket or the hand that struck it while the shuttle leaves
  its window at once on a path of its own, found only on the next scheduled whole frame, 1–7
  frames late;
- after a whole frame on which a rival tracklet (not followed, not confirmed, running quality
  ≥ ``window.watch_quality``) was seen, the next frame is whole too, so a new serve gets its
  confirming frames in a row.

Only the brighter-than-average method at a model scale whose grey image a crop reproduces
exactly (1, 1/2, or the quarter scale's row-skipping path) can be windowed; anything else
always runs whole. A window covering the whole frame gives exactly the whole-frame result
(tests/test_window.py).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .association import Tracklet, TrackletAssociator
from .background import BackgroundModel
from .params import TrackerParams

# Window corners are multiples of this many full-resolution pixels, so a crop's model pixels
# are the whole frame's (the quarter scale reads rows 4k and 4k + 2 and pairs of half columns).
ALIGN = 8


def supported(params: TrackerParams, width: int, height: int, scale: float) -> bool:
    """True when frames of this size can be windowed with these parameters."""
    if params.background.method != "bright_diff":
        return False
    if width % ALIGN or height % ALIGN:
        return False
    return scale in (1.0, 0.5, 0.25)


def crop_grey(frame_bgr: np.ndarray, scale: float, window: tuple[int, int, int, int]) -> np.ndarray:
    """The model's grey image of a window (full-resolution corners, multiples of ``ALIGN``):
    the pixels ``detect.segmentation.ModelGrey`` makes there from the whole frame."""
    x0, y0, x1, y1 = window
    crop = frame_bgr[y0:y1, x0:x1]
    if scale >= 1.0:
        return cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY)
    w, h = x1 - x0, y1 - y0
    if scale == 0.25:
        small = cv2.resize(crop[::2], (w // 2, h // 4), interpolation=cv2.INTER_AREA)
        gray = cv2.cvtColor(small, cv2.COLOR_BGR2GRAY)
        return cv2.resize(gray, (w // 4, h // 4), interpolation=cv2.INTER_LINEAR)
    small = cv2.resize(crop, (w // 2, h // 2), interpolation=cv2.INTER_AREA)
    return cv2.cvtColor(small, cv2.COLOR_BGR2GRAY)


class WindowTracker:
    """Chooses each frame's window and runs the model's part of the chain inside it."""

    def __init__(self, params: TrackerParams) -> None:
        self.params = params
        self._since_full = 0          # frames since the last whole frame
        self._gray: np.ndarray | None = None
        self.last_window: tuple[int, int, int, int] | None = None
        self.frames = 0
        self.windowed = 0
        self._touched: np.ndarray | None = None   # model pixels some window covered (255)
        self._skipped = 0                          # windowed frames since the last whole one
        self._last_whole: np.ndarray | None = None  # the last whole frame's grey image (catch_up)
        # ``window.stagger``: this camera's scheduled whole frames fall on the frames whose
        # count plus ``phase`` × ``full_every`` is a multiple of ``full_every`` (the stereo
        # tracker gives the right camera phase 0.5, so the two cameras' whole frames alternate).
        self.phase = 0.0
        self._large: np.ndarray | None = None     # the last whole frame's blobs too large for a shuttle

    def set_params(self, params: TrackerParams) -> None:
        self.params = params

    def reset(self) -> None:
        self._since_full = 0
        self.last_window = None
        self._skipped = 0
        self._large = None

    def before_whole(self, background: BackgroundModel, gray: np.ndarray | None = None) -> None:
        """Call before a whole frame's ``background.apply`` (``gray``: that frame's grey image,
        model scale): with ``window.catch_up`` the pixels no window covered since the last whole
        frame catch up on the updates they missed; those learning at α only where their grey
        value stayed within ``binarize.diff_threshold`` of the last whole frame's.

        The catch-up takes this frame as what the missed frames showed. Where the scene moved in
        between (beside a player) it did not, and a still pixel given a third of this frame's
        value (1 − (1 − α)^k at k = 7) drifted: a dark player's edge reached on a whole frame
        left a ghost of that one frame once he moved on, a brighter one raised the average beside
        him until his blob broke into shuttle-sized pieces (tests/test_window.py). Such a pixel
        learns from this frame alone, as a whole frame teaches it. Under the foreground (α/10)
        the stand-in errs by little and a player's ghost must fade as on whole frames even while
        he moves about beside it (a landed shuttle there would merge with it).
        """
        catch_up = self.params.window.catch_up
        if self._skipped and self._touched is not None and catch_up:
            last, changed = self._last_whole, None
            if gray is not None and last is not None and last.shape == gray.shape:
                changed = cv2.compare(cv2.absdiff(gray, last),
                                      float(self.params.binarize.diff_threshold), cv2.CMP_GT)
            background.catch_up(cv2.bitwise_not(self._touched), self._skipped, changed)
        self._skipped = 0
        if self._touched is not None:
            self._touched.fill(0)
        if catch_up and gray is not None and self.params.window.enabled:
            if self._last_whole is None or self._last_whole.shape != gray.shape:
                self._last_whole = np.empty_like(gray)
            np.copyto(self._last_whole, gray)

    # ---- the choice --------------------------------------------------------------------
    def plan(self, associator: TrackletAssociator, t: float, width: int, height: int,
             scale: float, whole: bool = False, large: np.ndarray | None = None
             ) -> tuple[int, int, int, int] | None:
        """This frame's window (x0, y0, x1, y1 in full-resolution px), or None: the whole frame
        (always when ``whole``). ``large``: the full-resolution boxes (x, y, w, h) of the last
        frame's blobs too large for a shuttle, kept when that frame was whole
        (``window.near_large``).

        Call once per frame, before the frame is processed (after the last frame's ``commit``).
        """
        self.frames += 1
        if self.last_window is None:
            # Blobs clipped by a window's edge look smaller than they are: the players are
            # those of the last whole frame (a few frames old; they move little meanwhile).
            self._large = large
        window = None if whole else self._choose(associator, t, width, height, scale)
        self.note(window)
        return window

    def note(self, window: tuple[int, int, int, int] | None) -> None:
        """Record what the frame really was (the caller may fall back to the whole frame)."""
        if window is None:
            self._since_full = 0
        else:
            self._since_full += 1
        self.last_window = window

    def _choose(self, associator: TrackletAssociator, t: float, width: int, height: int,
                scale: float) -> tuple[int, int, int, int] | None:
        wp = self.params.window
        if not wp.enabled or wp.full_every <= 1 or not supported(self.params, width, height, scale):
            return None
        if wp.stagger:
            # A fixed clock (``self.frames`` counts this frame): windowed runs still never
            # exceed full_every − 1 frames, and the two cameras' scheduled whole frames never
            # fall on the same pair (both whole: the slowest pairs, README Speed).
            if (self.frames - 1 + round(self.phase * wp.full_every)) % wp.full_every == 0:
                return None
        elif self._since_full + 1 >= wp.full_every:
            return None
        followed = followed_tracklet(associator)
        if (followed is None or not followed.hit_now or not followed.velocity_known
                or associator.merit(followed) < 0 or followed.quality < wp.min_quality):
            return None
        if followed.travel < associator.params.flight_travel:
            # Not a flight yet (a held shuttle, clutter taken up after the shuttle was lost, a
            # path just struck): windowed, the tracklets outside would starve, the lost
            # shuttle's own among them, which ends after max_misses frames with its history.
            return None
        if self._since_full == 0 and self._rival_seen(associator, followed):
            return None
        if wp.near_large > 0 and self._large is not None and near_box(
                followed.predict(t), self._large, wp.near_large * associator.factor(followed)):
            # Where a player or a racket is, the shuttle may be struck: its new path leaves the
            # window at once while the followed tracklet goes on with the racket or the hand
            # that struck; a whole frame finds the struck shuttle on its first frame.
            return None
        return window_around(associator, followed, t, width, height, wp.margin, wp.max_fraction)

    def _rival_seen(self, associator: TrackletAssociator, followed: Tracklet) -> bool:
        """A tracklet other than the followed one, hit on the last (whole) frame, not confirmed
        yet, that looks like a shuttle: the next frame stays whole so it can be confirmed."""
        wp, ap = self.params.window, associator.params
        if wp.watch_quality >= 1.0:
            return False
        return any(tr is not followed and tr.hit_now and tr.hits < ap.min_hits
                   and tr.quality >= wp.watch_quality for tr in associator.tracklets)

    # ---- the processing ------------------------------------------------------------------
    def model_mask(self, frame_bgr: np.ndarray, scale: float, window: tuple[int, int, int, int],
                   background: BackgroundModel):
        """(grey, mask, contours) at the model scale, made inside the window only, or None when
        the background model cannot be windowed yet (then the frame is processed whole).

        ``grey`` and ``mask`` are whole-model-size images (their pixels outside the window are
        stale / 0); the contours are in whole-model coordinates.
        """
        h, w = frame_bgr.shape[:2]
        model_w, model_h = round(w * scale), round(h * scale)
        if not background.can_window((model_h, model_w)):
            return None
        x0, y0, x1, y1 = window
        gray_win = crop_grey(frame_bgr, scale, window)
        mx0, my0 = int(x0 * scale), int(y0 * scale)
        mask_win = background.apply_window(gray_win, mx0, my0)
        if self._gray is None or self._gray.shape != (model_h, model_w):
            self._gray = np.zeros((model_h, model_w), np.uint8)
        gh, gw = gray_win.shape
        self._gray[my0:my0 + gh, mx0:mx0 + gw] = gray_win
        mask = np.zeros((model_h, model_w), np.uint8)   # calloc: untouched pages stay free
        mask[my0:my0 + gh, mx0:mx0 + gw] = mask_win
        contours, _ = cv2.findContours(mask_win, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE,
                                       offset=(mx0, my0))
        if self.params.window.catch_up:
            if self._touched is None or self._touched.shape != (model_h, model_w):
                self._touched = np.zeros((model_h, model_w), np.uint8)
            self._touched[my0:my0 + gh, mx0:mx0 + gw] = 255
        self._skipped += 1
        self.windowed += 1
        return self._gray, mask, contours


def followed_tracklet(associator: TrackletAssociator) -> Tracklet | None:
    for tr in associator.tracklets:
        if tr.ident == associator.selected:
            return tr
    return None


def near_box(point: tuple[float, float], boxes: np.ndarray, radius: float) -> bool:
    """True when ``point`` lies within ``radius`` of one of ``boxes`` (x, y, w, h)."""
    if not len(boxes):
        return False
    x, y = point
    b = np.asarray(boxes, dtype=float)
    return bool(np.any((b[:, 0] - radius <= x) & (x <= b[:, 0] + b[:, 2] + radius)
                       & (b[:, 1] - radius <= y) & (y <= b[:, 1] + b[:, 3] + radius)))


def window_around(associator: TrackletAssociator, tr: Tracklet, t: float, width: int, height: int,
                  margin: float, max_fraction: float) -> tuple[int, int, int, int] | None:
    """The window around the tracklet's prediction: its motion gate plus ``margin`` on each
    side, at most ``max_fraction`` of the frame's area (shrunk around the prediction), corners
    on multiples of ``ALIGN`` and inside the frame. None when nothing of it is in the frame."""
    dt = max(t - tr.t, 1e-3)
    px, py = tr.predict(t)
    half = associator.gate(tr, dt) + margin
    limit = 0.5 * math.sqrt(max_fraction * width * height)
    half = min(half, limit)
    x0 = max(int(math.floor((px - half) / ALIGN)) * ALIGN, 0)
    y0 = max(int(math.floor((py - half) / ALIGN)) * ALIGN, 0)
    x1 = min(int(math.ceil((px + half) / ALIGN)) * ALIGN, width)
    y1 = min(int(math.ceil((py + half) / ALIGN)) * ALIGN, height)
    if x1 - x0 < 2 * ALIGN or y1 - y0 < 2 * ALIGN:
        return None
    return x0, y0, x1, y1

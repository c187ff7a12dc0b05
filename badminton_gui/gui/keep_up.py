"""Notices when tracking falls behind its source: names the faster preset, slows the court views.

Why this file exists: with the default preset a pair of 2048×1536 cameras at 119 fps is tracked
at roughly 80–90 pairs/s on a 2-core laptop, so a third of the pairs are dropped (live) or the
recording plays at 0.7× (file), and nothing told the operator that the ``coarse`` preset is made
for exactly those cameras (README Speed: about twice as fast, F1 within 0.2 points). The
preset stays the operator's choice (issue 5: presets are chosen by the user); this only says
so, once per source, when tracking has been behind for ``SUSTAINED_S`` seconds without a pause.

:class:`DisplayYield` acts at once instead: while a live or paced source is being dropped or
played slow, the court views (3D, plan, side) and the readouts refresh at 4 Hz instead of 15,
the feeds stay at 30 Hz. Those views are most of what the display costs the tracker — PySide6
keeps the GIL through Qt's painting, and the 3D view paints through software OpenGL here: the
display-side CPU a pair shown fell 5.2 → 3.7 ms, and with the worker's two-pair camera buffer
the pairs dropped at 2048×1536 / 119 fps fell 4.37 → 1.35 % (``scripts/gui-timing.py --nycu 400
--preset coarse --ab 6``; the two changes not measured apart).

Plain Python, no Qt: the window feeds it the worker's statistics and shows what it returns.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

from ..core.detector import model_scale
from ..core.params import TrackerParams

# Seconds that tracking must stay behind before the advice is given (a key frame, a seek or a
# burst of clutter slows a second or two without meaning anything).
SUSTAINED_S = 5.0
# Seconds after a (re)start not judged: the rate meters start cold and the first frames of a
# recording decode slowly.
WARM_UP_S = 2.0
# Behind: more than this share of a live source's pairs dropped over the period, or a paced file
# played slower than this fraction of real time.
MAX_DROPPED_SHARE = 0.05
MIN_PLAYBACK = 0.95
# Frames at least this wide have a faster preset made for them (the coarse preset's
# ``background.coarse_from_width``).
COARSE_FROM_WIDTH = 1600
FAST_PRESET = "coarse"


def has_faster_preset(params: TrackerParams, width: int) -> bool:
    """True when frames ``width`` px wide would be tracked faster by the coarse preset: wide
    frames with the background model above a quarter scale, or without windowed tracking.
    When the far shuttle's size picks the model's scale (``background.coarse_shuttle_px``),
    that scale is already as coarse as the shuttle allows: only windowing is left to advise."""
    if width < COARSE_FROM_WIDTH:
        return False
    bg = params.background
    sized = int(bg.coarse_from_width) == 0 and bg.coarse_shuttle_px > 0
    coarse = sized or model_scale(bg, width) <= 0.25 + 1e-9
    return not coarse or not params.window.enabled


@dataclass
class KeepUpWatch:
    """Fed the worker's statistics about 15 times a second; returns an advice sentence once."""

    sustained_s: float = SUSTAINED_S
    warm_up_s: float = WARM_UP_S
    _started: float | None = None
    _behind_since: float | None = None
    _rates: list[tuple[float, float, float]] | None = None   # (processing, delivered, playback)
    _window: list[tuple[float, int, int]] | None = None    # (time, results, dropped) samples, live
    advised: bool = False

    def reset(self) -> None:
        """A new source, a pause, new parameters: start watching afresh."""
        self._started = self._behind_since = None
        self._window = self._rates = None
        self.advised = False

    def update(self, now: float, stats, *, live: bool, paced: bool, paused: bool,
               params: TrackerParams, image_size: tuple[int, int]) -> str | None:
        """The advice, the first time tracking has been behind for ``sustained_s``; else None.

        ``stats`` is the worker's ``WorkerStats`` (frames, dropped, processing_fps,
        capture_fps_left, playback_speed). ``live``: a camera pair (newest frame wins, drops
        counted); ``paced``: a file or the demo played in real time.
        """
        if self.advised:
            return None
        # Only advice that can be acted on: how fast tracking goes is in the readouts already.
        if paused or not (live or paced) or not has_faster_preset(params, image_size[0]):
            self._started = self._behind_since = None
            self._window = None
            return None
        if self._started is None:
            self._started = now
        if now - self._started < self.warm_up_s:
            return None
        behind, delivered = self._behind(now, stats, live)
        if not behind:
            self._behind_since = None
            return None
        if self._behind_since is None:
            self._behind_since, self._rates = now, []
        self._rates.append((stats.processing_fps, delivered, stats.playback_speed))
        if now - self._behind_since < self.sustained_s:
            return None
        self.advised = True
        width, height = image_size
        # The figures of the whole period behind, not of the last tick.
        rate, delivered, playback = (sorted(column)[len(column) // 2] for column in zip(*self._rates))
        what = ("so pairs are being dropped" if live
                else f"so it plays at {playback:.2f}× real time")
        return (f"Tracking keeps up with {rate:.0f} of the {delivered:.0f} frame pairs a second "
                f"the source delivers at {width}×{height}, {what}. The {FAST_PRESET} preset is "
                f"made for cameras this size and tracks about twice as fast, within 0.2 F1 points.")

    def _behind(self, now: float, stats, live: bool) -> tuple[bool, float]:
        """(behind now, pairs/s the source delivers)."""
        delivered = stats.capture_fps_left or 0.0
        if not live:
            return stats.playback_speed < MIN_PLAYBACK, delivered or stats.processing_fps / max(
                stats.playback_speed, 1e-3)
        # Live: the share of pairs dropped over the last ``sustained_s`` seconds.
        window = self._window = (self._window or []) + [(now, stats.frames, stats.dropped)]
        while len(window) > 2 and now - window[1][0] >= self.sustained_s:
            window.pop(0)
        (_, frames0, dropped0) = window[0]
        done, dropped = stats.frames - frames0, stats.dropped - dropped0
        if done + dropped <= 0:
            return False, delivered
        return dropped / (done + dropped) > MAX_DROPPED_SHARE, delivered


# The court views' refresh while the tracker is behind (normal: main_window.SLOW_VIEW_INTERVAL_S).
YIELD_INTERVAL_S = 0.25
# Behind, for the display: more than this share of a live source's pairs dropped over the last
# second, or a paced source played slower than this (a drop or two a second is the cameras'
# jitter against the tracker's slowest pairs, not a trend).
YIELD_DROPPED_SHARE = 0.01
YIELD_MIN_PLAYBACK = 0.98
# How long the views stay slowed after the last sign of being behind: slowing them is what lets
# the tracker catch up, so an immediate return would only make the display pulse.
YIELD_HOLD_S = 10.0
# s: how long a paced source must play below YIELD_MIN_PLAYBACK before the display yields. The
# playback speed is measured over the last 60 frames (0.5 s at 120 fps), in which one 10 ms
# hiccup is 2 %: the demo's first frames (the 3D view's first paint, the classifier loading) had
# the court views slowed for the first 10 s of every start, with the readouts saying "tracker
# behind" while it played at 1.00×.
YIELD_PACED_PERSIST_S = 1.0


@dataclass
class DisplayYield:
    """The court views' refresh interval: ``normal_s``, or ``slowed_s`` while tracking is behind.

    Fed the worker's statistics with every display packet (about 30 times a second).
    """

    normal_s: float
    slowed_s: float = YIELD_INTERVAL_S
    hold_s: float = YIELD_HOLD_S
    _behind_at: float | None = None
    _samples: deque = field(default_factory=deque)     # (time, results, dropped), live only
    _slow_since: float | None = None                   # paced: playing slow since then

    def reset(self) -> None:
        """A new source or a pause: back to the normal rate."""
        self._behind_at = None
        self._samples.clear()
        self._slow_since = None

    @property
    def slowed(self) -> bool:
        return self._behind_at is not None

    @property
    def interval(self) -> float:
        return self.slowed_s if self.slowed else self.normal_s

    def update(self, now: float, stats, *, live: bool, paced: bool, paused: bool) -> float:
        """The interval to use from now on. ``stats`` as for :meth:`KeepUpWatch.update`."""
        if paused or not (live or paced):
            self.reset()           # a paused display or a flat-out file: nothing to yield to
            return self.normal_s
        behind = False
        if live:
            samples = self._samples
            samples.append((now, stats.frames, stats.dropped))
            while len(samples) > 2 and now - samples[1][0] >= 1.0:
                samples.popleft()
            t0, frames0, dropped0 = samples[0]
            done, dropped = stats.frames - frames0, stats.dropped - dropped0
            behind = (now - t0 >= 0.5 and done + dropped > 0
                      and dropped / (done + dropped) > YIELD_DROPPED_SHARE)
        else:
            self._samples.clear()
            if stats.playback_speed >= YIELD_MIN_PLAYBACK:
                self._slow_since = None
            elif self._slow_since is None:
                self._slow_since = now
            behind = self._slow_since is not None and now - self._slow_since >= YIELD_PACED_PERSIST_S
        if behind:
            self._behind_at = now
        elif self._behind_at is not None and now - self._behind_at >= self.hold_s:
            self._behind_at = None
        return self.interval

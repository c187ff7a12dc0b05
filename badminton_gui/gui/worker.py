"""The tracking worker: reads the source and runs the StereoTracker off the GUI thread.

Why this file exists: the GUI thread must never wait for a camera or for OpenCV. A
:class:`TrackingWorker` (a QObject moved to a QThread) owns the source and the
tracker. Everything the GUI sends it (parameters, pause, step, robot link) goes through
lock-protected setters the loop reads at the top of each iteration (stytra's
``retrieve_params``), so the blocking loop never needs the Qt event queue. Everything it hands
back goes into a one-slot :class:`LatestSlot`: newest result wins, never an unbounded queue; the
GUI polls that slot with a ~30 Hz timer, so the display rate is independent of the tracking rate.

Display packets are built on request (:meth:`TrackingWorker.request_display`), not for every
result: shrinking and converting two frames, copying the trails and the flight is work the
tracker's thread would otherwise do at the tracking rate (240 pairs/s is the goal) for a
display that shows 30. The GUI asks for the first result finished after a given time — shortly
before its next tick — so it gets a fresh packet and the worker builds about one per tick (fewer
when the GUI runs late, none with no GUI at all).

The feeds may show each pair with the file commands' look-ahead readout instead of the live one
(:meth:`TrackingWorker.set_lookahead`, Playback ▸ Look-ahead view): the worker keeps each pair's
images until core/track_lookahead.py's ``DelayedReadout`` has decided its result K pairs later, then
scores, trails and shows that result on that pair — a recording then shows the rows `detect` and
`track` write (a TV clip's classifier adapted to it first when the parameters ask, as `detect`
does, as a step of opening it). The robot link and the result taps still get every live result at once.

Two more hooks serve the refine dialog (gui/refine_dialog.py): *result taps*, cheap functions
the worker calls with every result at the tracking rate (the display packets are throttled to
~30 Hz, far too few for collecting the shuttle's stereo pairs; the session recorder of
io/track_log.py is the other tap), and :meth:`TrackingWorker.set_rig`, which makes the running
loop continue with a new rig.

Live cameras get a grabber thread with its own buffer of ``LIVE_BUFFER_PAIRS`` pairs that drops
the oldest when full (ROS camera_calibration's ``BufferQueue``), so a slow tracker drops old
camera frames (counted and shown) instead of falling behind, while one slow pair — the GUI
thread holding the GIL through a paint, a whole frame among windowed ones — no longer costs a
pair: the tracker takes it up one pair late and catches up. File and demo sources are read in
step with the tracker and paced to their fps ("as fast as possible"
switches that off).
"""

from __future__ import annotations

import collections
import dataclasses
import inspect
import logging
import threading
import time
from dataclasses import dataclass
from typing import Any, Callable

import cv2
import numpy as np
from PySide6.QtCore import QObject, Signal

from ..core.adaptation import adapt_to_recording
from ..core.detect.diagnostics import DetectionDiagnostics
from ..core.errors import TrackerInputError
from ..core.evaluation import Label, LiveScore, Outcomes
from ..core.params import ParamError, TrackerParams
from ..core.rig import StereoRig
from ..core.mono import MonoTracker
from ..core.track_lookahead import DelayedReadout
from ..core.tracker import StereoTracker
from ..core.types import TrackResult
from ..io.detect_file import adaptation_asked
from ..io.sources import FrameSource, SourceError

_log = logging.getLogger(__name__)

# Failures that are the user's situation, not a bug: shown as one sentence in the banner.
USER_ERRORS: tuple[type[BaseException], ...] = (SourceError, TrackerInputError, ParamError, OSError,
                                                  cv2.error)
try:  # a missing / malformed classifier model file is the user's situation too
    from ..core.classifier import ClassifierError
    USER_ERRORS += (ClassifierError,)
except ImportError:  # pragma: no cover - the classifier is optional
    pass

DISPLAY_MAX_WIDTH = 960        # frame width for the display until the GUI says how wide the feeds are
TRAIL_SECONDS = 0.5            # the fading trail behind the red circle
RESYNC_AFTER = 0.25            # s behind the source clock before real-time pacing gives up catching up
# Camera pairs the grabber keeps for the tracker. One (newest wins) dropped a pair whenever a
# single pair took longer than the camera period: 2048×1536 at 119 fps with the coarse preset
# and the window open dropped 3–4 % of the pairs although the tracker's mean time (≈ 5.5 ms)
# is well inside the 8.4 ms period. Two absorb such a spike for at most one period of extra
# latency (the readouts' latency includes the wait), and a tracker that is simply too slow
# still drops the same share (and gets the faster-preset advice, gui/keep_up.py).
LIVE_BUFFER_PAIRS = 2
# Classifiers adapted to recordings (TrackingWorker._adapt), by (file, size, modification time)
# and parameters, shared by the workers of one session: the most recent ADAPTED_KEPT.
_ADAPTED: dict = {}
ADAPTED_KEPT = 4


class LatestSlot:
    """A bounded hand-off of capacity one: ``put`` replaces what was not taken yet."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._value: Any = None
        self.overwritten = 0

    def put(self, value: Any) -> bool:
        """Store value; True when an untaken value was dropped to make room."""
        with self._lock:
            dropped = self._value is not None
            if dropped:
                self.overwritten += 1
            self._value = value
            return dropped

    def take(self) -> Any:
        with self._lock:
            value, self._value = self._value, None
            return value

    def clear(self) -> None:
        with self._lock:
            self._value = None


class DropOldestBuffer:
    """A bounded FIFO hand-off: ``put`` appends and, when full, drops the oldest (counted);
    ``take`` returns the oldest or None. Capacity 1 is :class:`LatestSlot`'s newest-wins."""

    def __init__(self, capacity: int) -> None:
        if capacity < 1:
            raise ValueError("a frame buffer holds at least one pair")
        self._lock = threading.Lock()
        self._items: collections.deque = collections.deque()
        self.capacity = capacity
        self.overwritten = 0

    def put(self, value: Any) -> bool:
        """Store value; True when the oldest value was dropped to make room."""
        with self._lock:
            self._items.append(value)
            if len(self._items) > self.capacity:
                self._items.popleft()
                self.overwritten += 1
                return True
            return False

    def take(self) -> Any:
        with self._lock:
            return self._items.popleft() if self._items else None

    def set_capacity(self, capacity: int) -> None:
        """Hold at most ``capacity`` values from now on (the oldest beyond it dropped, counted)."""
        if capacity < 1:
            raise ValueError("a frame buffer holds at least one pair")
        with self._lock:
            self.capacity = capacity
            while len(self._items) > capacity:
                self._items.popleft()
                self.overwritten += 1

    def __len__(self) -> int:
        with self._lock:
            return len(self._items)


class RateMeter:
    """Events per second over the last second, on whatever clock the caller passes."""

    def __init__(self, window: float = 1.0) -> None:
        self.window = window
        self._times: collections.deque[float] = collections.deque()

    def tick(self, t: float) -> None:
        self._times.append(t)
        while self._times and self._times[0] < t - self.window:
            self._times.popleft()

    def rate(self) -> float:
        if len(self._times) < 2:
            return 0.0
        span = self._times[-1] - self._times[0]
        return (len(self._times) - 1) / span if span > 0 else 0.0


@dataclass(frozen=True, slots=True)
class WorkerStats:
    """Figures the readouts show, measured by the worker."""

    frames: int = 0                  # results produced since the source opened
    processing_fps: float = 0.0      # results per second (wall clock)
    capture_fps_left: float = 0.0    # frames per second of each camera (source clock)
    capture_fps_right: float = 0.0
    dropped: int = 0                 # camera frames never processed (live) — newest frame wins
    latency_ms: float = 0.0          # frame available → result ready (what the robot waits)
    # The view's look-ahead: frames each shown result waited for its future (0: live), and the
    # wait of the result shown, frame available → decided.
    lookahead_frames: int = 0
    shown_latency_ms: float = 0.0
    processing_ms: float = 0.0       # tracker time for this pair
    playback_speed: float = 1.0      # source seconds per wall second (file/demo sources)
    live: bool = False               # a camera pair: newest frame wins, drops counted
    paced: bool = False              # a file or the demo played in real time
    rig_epipolar_px: float | None = None   # the rig's measured epipolar error (StereoTracker), px
    rig_swapped_px: float | None = None    # the same with the cameras exchanged (StereoTracker), px
    # The readout scored against the source's truth (io/truth.py) since the parameters last
    # changed: None without a truth; ``truth_name`` says which ("demo truth", "labels").
    score_left: Outcomes | None = None
    score_right: Outcomes | None = None
    truth_name: str = ""
    # The court adaptation's progress (``StereoTracker.adaptation``), one line; '' when off.
    adapt_text: str = ""
    adapt_detail: str = ""


@dataclass(frozen=True, slots=True)
class DisplayPacket:
    """One result with what the GUI needs to draw it (arrays only; never widgets)."""

    left: np.ndarray                 # BGRA display image sized for the feed (and mask-tinted)
    right: np.ndarray | None         # None: a one-camera source
    display_scale: float             # display pixel = full-resolution pixel × scale
    result: TrackResult
    trail_left: np.ndarray           # (N, 3) t, x, y of recent detections (full-res px)
    trail_right: np.ndarray
    flight: np.ndarray | None        # (N, 4) t, x, y, z of the current flight
    predicted: np.ndarray | None     # (M, 3) predicted path to the floor
    stats: WorkerStats
    label_left: Label | None = None  # this pair's truth per camera (visible, x, y), when known
    label_right: Label | None = None
    # Traced (``TrackingWorker.set_trace``, the rejected-candidates overlay): what each camera's
    # detector counted on this pair, stage by stage (``CameraDetector.last_diagnostics``; None
    # for a camera the source has not). None when the pair was tracked untraced; the rules that
    # fired are then not in ``result.trace`` either.
    diagnostics: tuple[DetectionDiagnostics | None, DetectionDiagnostics | None] | None = None


SourceOpener = Callable[..., tuple[FrameSource, StereoRig]]


def _adapt_readout(tracker) -> dict[str, str]:
    """The court adaptation's status-bar line and its tooltip (none for one camera)."""
    if not isinstance(tracker, StereoTracker):
        return {}
    progress = tracker.adaptation.progress
    return {"adapt_text": progress.text, "adapt_detail": progress.detail if progress.text else ""}


class OpeningContext:
    """What an opener may use while it opens a source on the worker thread.

    Opening can take seconds (a camera; the scan of a video pair's frame times): ``report``
    shows how a long step is going (the feeds and the status bar say it, at most ten times a
    second) and ``cancelled`` turns true when the user chose another source, stopped, or closed
    the window meanwhile, so the step can give up at once instead of holding the thread.
    """

    def __init__(self, abort: threading.Event, emit: Callable[[str], None]) -> None:
        self._abort = abort
        self._emit = emit
        self._last = -1.0

    @property
    def cancelled(self) -> bool:
        return self._abort.is_set()

    def report(self, text: str) -> None:
        now = time.perf_counter()
        if now - self._last >= 0.1:
            self._last = now
            self._emit(text)

    def for_step(self, what: str, index: int, count: int
                 ) -> tuple[Callable[[float], None], Callable[[], bool]]:
        """(progress, should_stop) for step ``index`` of ``count`` equal steps of one job:
        ``progress(fraction of this step)`` reports the whole job's percentage."""
        def progress(fraction: float) -> None:
            self.report(f"{what}: {100.0 * (index + fraction) / count:.0f} %")
        return progress, lambda: self._abort.is_set()


def _call_opener(opener: SourceOpener, context: OpeningContext) -> tuple[FrameSource, StereoRig]:
    """``opener(context)`` when it takes an argument, else ``opener()`` (stand-ins in tests)."""
    try:
        takes_context = bool(inspect.signature(opener).parameters)
    except (TypeError, ValueError):
        takes_context = False
    return opener(context) if takes_context else opener()


class _LiveReader(threading.Thread):
    """Reads a live source as fast as it delivers; the tracker takes the newest pair."""

    def __init__(self, source: FrameSource, buffer_pairs: int = LIVE_BUFFER_PAIRS) -> None:
        super().__init__(name="camera-grabber", daemon=True)
        self.source = source
        self.slot = DropOldestBuffer(buffer_pairs)
        self.error: BaseException | None = None
        self.ended = False
        self.stop_flag = threading.Event()
        self.arrived = threading.Event()
        self.left_rate = RateMeter()
        self.right_rate = RateMeter()

    def run(self) -> None:
        try:
            while not self.stop_flag.is_set():
                frame = self.source.read()
                if frame is None:
                    self.ended = True
                    break
                if frame.fresh_left:
                    self.left_rate.tick(frame.t_left)
                if frame.fresh_right:
                    self.right_rate.tick(frame.t_right)
                self.slot.put((frame, time.perf_counter()))
                self.arrived.set()
        except USER_ERRORS as exc:
            self.error = exc
        finally:
            self.arrived.set()


class TrackingWorker(QObject):
    """Source + tracker loop; move to a QThread and connect ``thread.started`` to ``run``."""

    opened = Signal(str, object)      # source name, StereoRig
    rig_applied = Signal(object)      # the StereoRig set_rig asked for is now tracked with
    error = Signal(str)               # one sentence for the banner; the worker has stopped
    opening = Signal(str)             # how a long step of opening the source is going
    busy = Signal(str)                # how a long step while playing is going ("" when done)
    warning = Signal(str)             # one sentence for the banner; the worker goes on
    ended = Signal(str)               # the source ran out (not an error)
    finished = Signal()

    def __init__(self, open_source: SourceOpener, params: TrackerParams, realtime: bool = True,
                 show_mask: bool = False, live_buffer_pairs: int | None = None,
                 lookahead_frames: int = 0, trace: bool = False) -> None:
        super().__init__()
        self._trace = trace
        self._lookahead_frames = max(0, int(lookahead_frames))
        self._lookahead_changed = False
        # The classifier adapted to the recording (``_adapt``) and the classifier settings it
        # was adapted from: kept through tuning that leaves those settings as they are.
        self._adapted: tuple[Any, Any] | None = None
        self.adaptation_text = ""
        # The last (recording, classifier settings, view frames) passed over (``_adapt``).
        self._adapt_tried: tuple | None = None
        self._live_buffer_pairs = live_buffer_pairs or LIVE_BUFFER_PAIRS
        self._reader: _LiveReader | None = None
        self._open_source = open_source
        self.output = LatestSlot()
        self._lock = threading.Lock()
        self._pending_params: TrackerParams | None = params
        self._params_in_use = params
        self._abort = threading.Event()
        self._paused = False
        self._steps = 0
        self._realtime = realtime
        self._show_mask = show_mask
        self._display_box = (DISPLAY_MAX_WIDTH, DISPLAY_MAX_WIDTH)
        # perf_counter time from which a finished result is wanted as a display packet; None:
        # none wanted (the last one was built and the GUI has not asked again). The first
        # result is always wanted.
        self._display_due: float | None = 0.0
        self.latest_stats: WorkerStats | None = None     # of the newest result, packet or not
        self.packets_built = 0
        self._link = None
        self._link_lock = threading.Lock()
        self.link_error = ""
        self._result_taps: dict[str, Callable[[TrackResult], None]] = {}
        self._pending_rig: StereoRig | None = None
        self._rig_in_use: StereoRig | None = None
        self._tracker: StereoTracker | None = None      # worker thread only

    # ---- called from the GUI thread (thread-safe) -----------------------------------------
    def set_params(self, params: TrackerParams) -> None:
        with self._lock:
            self._pending_params = params

    def set_live_buffer_pairs(self, pairs: int) -> None:
        """Camera pairs the grabber keeps (1: the newest only, the lowest latency), now and for
        the rest of this source."""
        with self._lock:
            self._live_buffer_pairs = pairs
            reader = self._reader
        if reader is not None:
            reader.slot.set_capacity(pairs)

    @property
    def params_in_use(self) -> TrackerParams:
        """The snapshot the tracker runs with now (tests read this)."""
        return self._params_in_use

    @property
    def rig_in_use(self) -> StereoRig | None:
        """The rig the tracker runs with now (None before the source opened)."""
        return self._rig_in_use

    def set_rig(self, rig: StereoRig) -> None:
        """Track with this rig from the next frame pair on (``rig_applied`` says when).

        The loop replaces its tracker by a new one built on the rig with the parameters in use:
        everything a tracker learns depends on the rig (the epipolar gate widened to the old
        rig's error, the 3D flight), and the background models relearn in a few frames.
        """
        with self._lock:
            self._pending_rig = rig

    def set_result_tap(self, tap: Callable[[TrackResult], None] | None, key: str = "refine") -> None:
        """A function the worker thread calls with every result, at the tracking rate (None: no
        more calls); one per ``key`` ("refine": the refine dialog's pair collector, "record":
        the session recorder). It must be cheap and thread-safe."""
        with self._lock:
            if tap is None:
                self._result_taps.pop(key, None)
            else:
                self._result_taps[key] = tap

    def set_paused(self, paused: bool) -> None:
        with self._lock:
            self._paused = paused
            self._steps = 0

    def step(self) -> None:
        """Process exactly one more frame pair while paused."""
        with self._lock:
            self._steps += 1

    def set_lookahead(self, frames: int) -> None:
        """Show each pair once ``frames`` later pairs re-decided it (core/lookahead.py: the file
        commands' readout); 0: as soon as it is tracked. The robot and the result taps get every
        result at once either way."""
        with self._lock:
            self._lookahead_frames = max(0, int(frames))
            self._lookahead_changed = True

    @property
    def lookahead_frames(self) -> int:
        return self._lookahead_frames

    def set_realtime(self, realtime: bool) -> None:
        with self._lock:
            self._realtime = realtime

    def set_show_mask(self, show: bool) -> None:
        with self._lock:
            self._show_mask = show

    def set_trace(self, trace: bool) -> None:
        """From the next pair on, each result names the rules that fired (``TrackResult.trace``)
        and its display packet carries the detectors' per-stage counts (``DisplayPacket.
        diagnostics``); off, neither is made, so the overlay that shows them costs nothing."""
        with self._lock:
            self._trace = bool(trace)

    def set_display_size(self, width: int, height: int) -> None:
        """Shrink frames to fit this box before handing them over (painting 1:1 is cheap)."""
        with self._lock:
            self._display_box = (max(64, int(width)), max(64, int(height)))

    def request_display(self, not_before: float = 0.0) -> None:
        """Ask for one display packet: the first result finished at or after ``not_before``
        (a ``time.perf_counter()`` time). Until asked again, results are not turned into packets."""
        with self._lock:
            self._display_due = not_before

    def set_link(self, link) -> None:
        """Robot link that receives every result at full rate (None to stop sending)."""
        with self._link_lock:
            self._link = link

    def abort(self) -> None:
        self._abort.set()

    # ---- the loop (worker thread) ----------------------------------------------------------
    def run(self) -> None:
        source = reader = tracker = None
        try:
            context = OpeningContext(self._abort, self.opening.emit)
            source, rig = _call_opener(self._open_source, context)
            if getattr(source, "cameras", 2) == 1:
                # One view (a TV clip): the per-camera detector alone, no rig, no 3D.
                tracker = self._tracker = MonoTracker(self._params_in_use)
                rig = None
                if self._adapt(source, tracker, context):
                    self.opening.emit(self.adaptation_text)
                if self._abort.is_set():
                    return
            else:
                rig.check_image_size(*source.image_size, what="the source's frames")
                tracker = self._tracker = StereoTracker(rig, self._params_in_use)
            self._rig_in_use = rig
            self.opened.emit(getattr(source, "name", "source"), rig)
            if source.fps is None:
                with self._lock:
                    reader = self._reader = _LiveReader(source, self._live_buffer_pairs)
                reader.start()
            self._loop(source, tracker, reader)
        except USER_ERRORS as exc:
            self.error.emit(_one_sentence(exc))
        except Exception as exc:  # noqa: BLE001 - a bug must not kill the window silently
            _log.exception("tracking worker failed")
            self.error.emit(f"internal error in the tracker ({type(exc).__name__}: {exc}); "
                            f"details are in the log")
        finally:
            if reader is not None:
                reader.stop_flag.set()
                reader.join(timeout=2.0)
            if self._tracker is not None:      # the loop's newest tracker (set_rig replaces it)
                self._tracker.close()
                self._tracker = None
            if source is not None:
                try:
                    source.close()
                except USER_ERRORS:
                    pass
            self.finished.emit()

    def _loop(self, source: FrameSource, tracker: StereoTracker, reader: _LiveReader | None) -> None:
        rate = RateMeter()
        src_left_rate, src_right_rate = RateMeter(), RateMeter()
        trails = (collections.deque(), collections.deque())
        pace_wall = pace_src = None      # wall-clock and source-clock anchors of real-time pacing
        speed_meter: collections.deque[tuple[float, float]] = collections.deque(maxlen=60)
        frames = 0
        skipped_text = ""       # the banner's sentence on the last pair the tracker refused
        unshown = None          # the newest result that was not made a packet (shown at the end)
        truth = getattr(source, "frame_truth", None)
        score = LiveScore(source.image_size[0]) if truth is not None else None
        mismatch = getattr(truth, "mismatch", None)
        if mismatch is not None:
            text = mismatch(getattr(source, "frame_count", 0) or 0)
            if text:
                self.warning.emit(text[:1].upper() + text[1:])
        readout = self._readout(tracker)
        # Counts the parameter changes: a held pair tracked with the settings before the last
        # change is shown but not scored (the score belongs to the settings on screen).
        generation = 0

        def show(decided: list, stepping: bool = False) -> None:
            """Score, trail and (when the GUI asked for one) publish each decided result."""
            nonlocal unshown
            for result, (frame, labels, t_available, live_stats, tracked_in, diagnostics) in decided:
                if score is not None and tracked_in == generation:
                    # A camera that brought no new image this step was scored on its last one.
                    if frame.fresh_left:
                        score.add(0, result.left.detection, labels[0])
                    if frame.fresh_right:
                        score.add(1, result.right.detection, labels[1])
                t_step = frame.timestamp
                for trail, cam, fresh in zip(trails, (result.left, result.right),
                                             (frame.fresh_left, frame.fresh_right)):
                    if cam.detection is not None and fresh:
                        trail.append((t_step, cam.detection.x, cam.detection.y))
                    while trail and (trail[0][0] < t_step - TRAIL_SECONDS or trail[0][0] > t_step):
                        trail.popleft()
                t_shown = time.perf_counter()
                stats = dataclasses.replace(
                    live_stats, lookahead_frames=readout.frames,
                    shown_latency_ms=(t_shown - t_available) * 1000.0,
                    score_left=None if score is None else score.outcomes(0),
                    score_right=None if score is None else score.outcomes(1))
                self.latest_stats = stats
                with self._lock:
                    due = self._display_due
                    wanted = stepping or (due is not None and t_shown >= due)
                    if wanted:
                        self._display_due = None
                unshown = (frame, result, stats, show_mask, display_box, labels, diagnostics)
                if wanted:
                    self._publish(unshown, trails, tracker)
                    unshown = None

        show_mask, display_box = self._show_mask, self._display_box
        while not self._abort.is_set():
            with self._lock:
                params, self._pending_params = self._pending_params, None
                paused, realtime, show_mask = self._paused, self._realtime, self._show_mask
                trace = self._trace
                display_box = self._display_box
                taps = tuple(self._result_taps.values())
                new_rig, self._pending_rig = self._pending_rig, None
                stepping = paused and self._steps > 0
                if stepping:
                    self._steps -= 1
                lookahead_changed, self._lookahead_changed = self._lookahead_changed, False
            # A new rig, another look-ahead or other look-ahead rules (a preset chosen) start a new
            # readout; the held pairs are decided first with what future there is. Tuning the
            # filters does not: the held pairs go on to be decided as usual, so dragging a slider
            # does not stall the view (a broadcast view holds 74 frames, 2.5 s at 30 fps).
            restart = (new_rig is not None or lookahead_changed
                       or (params is not None and params.lookahead != self._params_in_use.lookahead))
            if restart:
                show(readout.flush())
            if params is not None:
                try:
                    tracker.set_params(params)
                    self._params_in_use = params
                    self._keep_adapted(tracker, params)
                    generation += 1
                    if score is not None:
                        score.reset()       # the score belongs to the settings on screen
                except USER_ERRORS as exc:   # e.g. a classifier model that is not there
                    tracker.set_params(self._params_in_use)
                    self.warning.emit("Parameters not applied: " + _one_sentence(exc))
            if new_rig is not None:
                tracker = self._switch_rig(tracker, new_rig, source)
            if restart:
                readout = self._readout(tracker)
            elif params is not None:
                readout.set_params(self._params_in_use)
            if ((restart or params is not None) and isinstance(tracker, MonoTracker)
                    and self._adapted is None):
                # The view turned on (or another preset chosen) while a TV clip plays: its
                # classifier is adapted now as it would have been on opening, a step shown
                # over the feed; the pairs after it are scored anew.
                context = OpeningContext(self._abort, self.busy.emit)
                tried = self._adapt_tried
                if self._adapt(source, tracker, context, while_playing=True):
                    show(readout.flush())
                    readout = self._readout(tracker)
                    generation += 1
                    if score is not None:
                        score.reset()
                if self._abort.is_set():
                    return
                if self._adapt_tried is not tried:
                    # A pass was made (or found made), adapted or not ("no run long enough"):
                    # it is no slow playback — the speed is measured afresh, real-time pacing
                    # starts again from the next frame — and the window hears it is over.
                    speed_meter.clear()
                    pace_wall = None
                    self.busy.emit(self.adaptation_text)
            if isinstance(tracker, StereoTracker):
                tracker.trace = trace       # (one camera has no rules to trace)
            if paused and not stepping:
                # Paused: the display shows the pair the tracker stopped on (so a step shows the
                # next one), even if the throttle had not asked for it.
                self._publish(unshown, trails, tracker)
                unshown = None
                pace_wall = None
                time.sleep(0.01)
                continue

            # -- next frame pair
            if reader is not None:
                item = reader.slot.take()
                if item is None:
                    if reader.error is not None:
                        raise reader.error
                    if reader.ended:
                        show(readout.flush())
                        self._publish(unshown, trails, tracker)
                        self.ended.emit("the cameras stopped delivering frames")
                        return
                    reader.arrived.wait(0.05)
                    reader.arrived.clear()
                    continue
                frame, t_available = item
            else:
                frame = source.read()
                t_available = time.perf_counter()
                if frame is None:
                    show(readout.flush())
                    self._publish(unshown, trails, tracker)
                    what = "video" if getattr(source, "cameras", 2) == 1 else "videos"
                    self.ended.emit(f"end of the {what}: choose Source ▸ Restart to play again")
                    return
                # A step of free-running cameras may bring one camera's image only
                # (``StereoFrame.fresh_left``): each rate counts its own new images.
                if frame.fresh_left:
                    src_left_rate.tick(frame.t_left)
                if frame.right is not None and frame.fresh_right:   # (one-camera sources: none)
                    src_right_rate.tick(frame.t_right)
                if realtime and not stepping:
                    t_src = frame.timestamp
                    if pace_wall is None or t_src < pace_src:
                        pace_wall, pace_src = t_available, t_src
                    due = pace_wall + (t_src - pace_src)
                    lag = t_available - due
                    if lag > RESYNC_AFTER:          # too slow for real time: play slower
                        pace_wall, pace_src = t_available, t_src
                    elif due > t_available:
                        self._sleep_until(due)
                        t_available = time.perf_counter()

            try:
                result = tracker.process_frame(frame)
            except TrackerInputError as exc:
                # A pair the tracker cannot use (a camera's NaN time, a frame of another size) is
                # skipped with a sentence in the banner, said once until it changes; the run
                # goes on with the next pair.
                text = "Frame skipped: " + _one_sentence(exc)
                if text != skipped_text:
                    self.warning.emit(text)
                    skipped_text = text
                continue
            skipped_text = ""
            t_done = time.perf_counter()
            diagnostics = _diagnostics(tracker) if trace else None
            frames += 1
            # The robot and the taps get the live result at once, whatever the view waits for.
            for tap in taps:
                tap(result)
            rate.tick(t_done)
            speed_meter.append((t_done, frame.timestamp))
            with self._link_lock:
                if self._link is not None:
                    try:
                        self._link.send_result(result)
                    except USER_ERRORS as exc:
                        self.link_error = _one_sentence(exc)

            labels = truth.for_frame(frame) if truth is not None else (None, None)
            if reader is not None:
                cap_l, cap_r, dropped = reader.left_rate.rate(), reader.right_rate.rate(), reader.slot.overwritten
            else:
                cap_l, cap_r, dropped = src_left_rate.rate(), src_right_rate.rate(), 0
            playback = 1.0
            if len(speed_meter) >= 2 and speed_meter[-1][0] > speed_meter[0][0]:
                playback = ((speed_meter[-1][1] - speed_meter[0][1])
                            / (speed_meter[-1][0] - speed_meter[0][0]))
            live_stats = WorkerStats(frames=frames, processing_fps=rate.rate(), capture_fps_left=cap_l,
                                     capture_fps_right=cap_r, dropped=dropped,
                                     latency_ms=(t_done - t_available) * 1000.0,
                                     processing_ms=result.processing_ms, playback_speed=playback,
                                     live=reader is not None,
                                     paced=reader is None and realtime and not stepping,
                                     rig_epipolar_px=tracker.rig_epipolar_px,
                                     rig_swapped_px=tracker.rig_swapped_px,
                                     truth_name="" if truth is None else truth.name,
                                     **_adapt_readout(tracker))
            show(readout.push(result, (frame, labels, t_available, live_stats, generation, diagnostics)),
                 stepping)

    def _adapt(self, source: FrameSource, tracker: MonoTracker, context: OpeningContext,
               while_playing: bool = False) -> bool:
        """A recorded TV clip viewed with the look-ahead gets `detect`'s rows: when the preset
        adapts its classifier to each recording (``classifier.adapt_min_run``; no shipped
        preset does), a first pass over the file does so now (core/adaptation.py), shown as a step
        of opening the source that Stop gives up with the source, and turning the view live
        gives up alone. A live view keeps the shipped classifier. The same when the view is
        turned on, or another preset chosen, while the clip plays (``while_playing``: once per
        view and parameters, whatever the pass found). True: an adapted classifier is in use."""
        frames = getattr(source, "recording_frames", None)
        with self._lock:
            k = self._lookahead_frames
        if frames is None or k <= 0:
            return False
        params = self._params_in_use.with_value("lookahead.frames", k)
        if not adaptation_asked(params, None):
            return False
        # Source ▸ Restart (the clip played again) finds the pass it made already: the same
        # file, unchanged, with the same parameters.
        key = (getattr(source, "recording_key", None), params)
        # A pass that found no run long enough is not made again while only the filters are
        # tuned (seconds a slider step), as an adapted classifier is kept through them.
        tried = (key[0], params.classifier, k)
        if while_playing and tried == self._adapt_tried:
            return False
        cached = _ADAPTED.get(key) if key[0] is not None else None
        if cached is None:
            what = "adapting the classifier to the recording (turn the look-ahead view off to skip)"
            progress, cancelled = context.for_step(what, 0, 1)

            def stop() -> bool:
                # Stop (or another source) gives the source up; the view turned live (a long
                # recording to watch at once) gives up the pass only.
                return cancelled() or self._lookahead_frames == 0
            start = time.perf_counter()
            classifier, harvest = adapt_to_recording(
                params, lambda: frames(lambda done, total: progress(done / total if total else 0.0)),
                should_stop=stop)
            if stop():
                return False
            text = ("no run of detections long enough to adapt the classifier to" if classifier is None
                    else f"classifier adapted to the recording: {harvest.runs} runs, {harvest.frames} "
                         f"frames ({time.perf_counter() - start:.1f} s)")
            cached = (classifier, text)
            if key[0] is not None:
                _ADAPTED[key] = cached
                while len(_ADAPTED) > ADAPTED_KEPT:
                    _ADAPTED.pop(next(iter(_ADAPTED)))
        self._adapt_tried = tried
        classifier, self.adaptation_text = cached
        if classifier is None:
            return False
        tracker.detector.use_classifier(classifier)
        self._adapted = (classifier, params.classifier)
        return True

    def _keep_adapted(self, tracker, params: TrackerParams) -> None:
        """After new parameters: the adapted classifier again while the classifier settings it
        came from hold (a filter slider moved), the preset's once they changed."""
        if self._adapted is None:
            return
        classifier, settings = self._adapted
        if params.classifier == settings:
            tracker.detector.use_classifier(classifier)
        else:
            self._adapted = None
            self.adaptation_text = ""

    def _readout(self, tracker) -> DelayedReadout:
        """A look-ahead of the view's frames for this tracker and the parameters in use."""
        if isinstance(tracker, MonoTracker):
            return DelayedReadout(self._params_in_use, self._lookahead_frames)
        return DelayedReadout(self._params_in_use, self._lookahead_frames, tracker.rig,
                              tracker.epipolar_tolerance)

    def _switch_rig(self, tracker: StereoTracker, rig: StereoRig, source: FrameSource) -> StereoTracker:
        """A new tracker on ``rig`` in place of ``tracker``; the old one when the rig does not fit
        the source's frames (said in the banner)."""
        if isinstance(tracker, MonoTracker):
            self.warning.emit("Rig not applied: the source has one camera (no stereo rig to use)")
            return tracker
        try:
            rig.check_image_size(*source.image_size, what="the source's frames")
            new = StereoTracker(rig, self._params_in_use)
        except USER_ERRORS as exc:
            self.warning.emit("Rig not applied: " + _one_sentence(exc))
            return tracker
        tracker.close()
        self._tracker = new
        self._rig_in_use = rig
        self.rig_applied.emit(rig)
        return new

    def _publish(self, unshown, trails, tracker: StereoTracker) -> None:
        """Build the display packet of (frame, result, stats, show_mask, box, labels, diagnostics)
        and hand it over."""
        if unshown is not None:
            frame, result, stats, show_mask, display_box, labels, diagnostics = unshown
            self.output.put(self._packet(frame, result, trails, tracker, stats, show_mask, display_box,
                                         labels, diagnostics))
            self.packets_built += 1

    def _sleep_until(self, due: float) -> None:
        while not self._abort.is_set():
            left = due - time.perf_counter()
            if left <= 0:
                return
            time.sleep(min(left, 0.02))

    @staticmethod
    def _packet(frame, result: TrackResult, trails, tracker: StereoTracker, stats: WorkerStats,
                show_mask: bool, display_box: tuple[int, int],
                labels: tuple[Label | None, Label | None] = (None, None),
                diagnostics: tuple | None = None) -> DisplayPacket:
        h, w = frame.left.shape[:2]
        scale = min(1.0, display_box[0] / float(w), display_box[1] / float(h))
        images = []
        for img, cam in ((frame.left, result.left), (frame.right, result.right)):
            if img is None:          # a one-camera source: no right view
                images.append(None)
                continue
            if scale < 1.0:
                img = _shrink(img, int(round(w * scale)), int(round(h * scale)))
            if show_mask and cam.mask is not None:
                img = _tint_mask(img, cam.mask)
            # BGRA is the GUI's paint format (QImage RGB32): converting here, off the GUI
            # thread, costs ~0.1 ms and saves a conversion on every paint.
            images.append(_to_bgra(img))
        flight = predicted = None
        trajectory = tracker.trajectory
        if trajectory is not None:
            # The filtered path (what the robot was given), not the raw points' scatter.
            if hasattr(trajectory, "current_track"):
                flight = trajectory.current_track()
            elif hasattr(trajectory, "current_flight"):
                flight = trajectory.current_flight()
            if hasattr(trajectory, "predicted_path"):
                predicted = trajectory.predicted_path()
            flight, predicted = _as_of(flight, predicted, result.timestamp)
        return DisplayPacket(
            left=images[0], right=images[1], display_scale=scale, result=result,
            trail_left=np.array(trails[0], dtype=float).reshape(-1, 3),
            trail_right=np.array(trails[1], dtype=float).reshape(-1, 3),
            flight=None if flight is None else np.asarray(flight, dtype=float),
            predicted=None if predicted is None else np.asarray(predicted, dtype=float),
            stats=stats, label_left=labels[0], label_right=labels[1], diagnostics=diagnostics)


def _diagnostics(tracker) -> tuple[DetectionDiagnostics | None, DetectionDiagnostics | None]:
    """Each camera's per-stage counts of its last frame (a camera that brought no new image
    this step: of the frame it last brought, as its candidates are)."""
    if isinstance(tracker, MonoTracker):
        return tracker.detector.last_diagnostics, None
    return tracker.left.last_diagnostics, tracker.right.last_diagnostics


def _as_of(flight, predicted, t: float):
    """The flight as the pair shown at time ``t`` sees it: the tracker may be ahead of the view
    (the look-ahead view shows pairs K steps late), so the part of its path after ``t`` belongs
    to the dashed prediction, not to the solid flight that ends at the red dot."""
    if flight is None or not len(flight):
        return flight, predicted
    flight = np.asarray(flight, dtype=float)
    later = flight[:, 0] > t + 1e-9
    if not later.any():
        return flight, predicted
    ahead = flight[later, 1:4]
    if predicted is not None and len(predicted):
        ahead = np.vstack([ahead, np.asarray(predicted, dtype=float).reshape(-1, 3)])
    return flight[~later], ahead


def _shrink(img: np.ndarray, width: int, height: int) -> np.ndarray:
    """The frame shrunk to width × height, nearly as smooth as INTER_AREA and ~10× cheaper.

    INTER_AREA by a whole factor is OpenCV's fast path; by any other factor it is its slow
    general path: 1280×720 → 634×357 took 5.5-11 ms (on the tracker's thread, per packet, so
    most of what the window cost the tracking rate), by 2 then INTER_LINEAR to the last few
    pixels 1.1 ms (mean difference to INTER_AREA 2 grey levels; INTER_LINEAR alone aliases
    court lines on larger reductions).

    A frame four times the box or more (2048×1536 cameras in a feed of ~476×357) first reads
    only every other row, averaged 2×2 by the area fast path (the model grey image's trick in
    core/detector.py): 2048×1536 → 476×357 took 5.1 ms a frame, 10 ms a packet on the tracker's
    thread, and takes 1.3 ms (mean difference to INTER_AREA 0.36 grey levels, 0.37 before).
    """
    h, w = img.shape[:2]
    if w >= 4 * width and h >= 4 * height and w % 2 == 0 and h % 4 == 0:
        img = cv2.resize(img[::2], (w // 2, h // 4), interpolation=cv2.INTER_AREA)
        h, w = img.shape[:2]
    k = max(1, min(w // width, h // height))
    if k > 1:
        img = cv2.resize(img, (w // k, h // k), interpolation=cv2.INTER_AREA)
    if img.shape[1] != width or img.shape[0] != height:
        img = cv2.resize(img, (width, height), interpolation=cv2.INTER_LINEAR)
    return img


def _to_bgra(img: np.ndarray) -> np.ndarray:
    """A gray, BGR or BGRA frame as a contiguous BGRA array."""
    if img.ndim == 2 or img.shape[2] == 1:
        return cv2.cvtColor(img, cv2.COLOR_GRAY2BGRA)
    if img.shape[2] == 3:
        return cv2.cvtColor(img, cv2.COLOR_BGR2BGRA)
    return np.ascontiguousarray(img)


def _tint_mask(img: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """The display image with foreground pixels tinted magenta (the foreground-mask overlay)."""
    if img.ndim == 2:
        img = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)
    h, w = img.shape[:2]
    if mask.shape[:2] != (h, w):
        mask = cv2.resize(mask, (w, h), interpolation=cv2.INTER_NEAREST)
    out = img.copy()
    fg = mask > 0
    out[fg] = out[fg] // 2 + np.array([127, 0, 127], dtype=np.uint8)   # magenta: stands out on a green court
    return out


def _one_sentence(exc: BaseException) -> str:
    """The message of a user-facing error, as one line."""
    text = str(exc).strip() or type(exc).__name__
    if isinstance(exc, cv2.error):
        text = "OpenCV: " + text.splitlines()[-1]
    return " ".join(text.split())

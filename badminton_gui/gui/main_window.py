"""The main window: two feeds, the court views, the readouts, and the controls around them.

Why this file exists: it wires the pieces and nothing more. It never processes a frame: it
starts a :class:`~.worker.TrackingWorker` on a QThread for the chosen source, polls the worker's
one-slot output with a ~30 Hz timer, and hands the newest packet to the feeds on every tick and
to the court views, readouts and tuning preview at most 15 times a second (only those on screen,
only when what they draw changed): every millisecond of Python on this thread holds the GIL the
tracker's threads need (scripts/gui-timing.py measures the cost). Errors from the worker arrive
as one sentence and are shown in a banner; the window stays usable and another source can be
chosen.

Calibration ▸ Refine from tracked shuttle… (gui/refine_dialog.py) collects the shuttle's stereo
pairs through the worker's result tap, on the worker's thread; an applied refit reaches the
running tracker through ``TrackingWorker.set_rig``, and a saved one becomes the source's rig
file for the next start, as the calibration wizard's rig does.

Around that, what users of a desktop program expect: a Help menu (gui/help_menu.py), the whole
window (docks, toolbars, splitters) as it was left, and files dropped on the window opened
through the same dialogs and checks as the menus.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Callable

from PySide6.QtCore import QByteArray, QMimeData, QObject, QPoint, QStandardPaths, Qt, QThread, QTimer, Signal
from PySide6.QtGui import QAction, QFont, QFontMetrics, QKeySequence, QPainter, QPixmap
from PySide6.QtWidgets import (QApplication, QDockWidget, QFileDialog, QFrame, QGridLayout,
                               QHBoxLayout, QLabel, QMainWindow, QMessageBox, QPushButton, QSizePolicy,
                               QSplitter, QVBoxLayout, QWidget)

from ..core.evaluation import Outcomes
from ..core.params import TrackerParams
from ..core.rig import RigError, StereoRig
from ..io.sources import SourceError
from ..io.presets import load_preset
from ..io.track_file import FILE_LOOKAHEAD
from ..io.track_log import RecordingError, TrackRecorder
from . import settings as st
from .court_views import CourtGLView, CourtPlanView, SideView, gl_unavailable_reason
from .feed_view import FeedView
from .help_menu import AboutDialog, ShortcutsDialog, app_icon, log_link_html, open_log_folder
from .keep_up import FAST_PRESET, DisplayYield, KeepUpWatch
from .overlays import trace_lines
from .rig_check import RigCheck, readout_text as rig_readout_text
from .robot_panel import RobotLinkPanel
from .sources import CameraPairDialog, SingleVideoDialog, VideoPairDialog, open_spec
from .worker import LIVE_BUFFER_PAIRS, DisplayPacket, RateMeter, SourceOpener, TrackingWorker

DISPLAY_INTERVAL_MS = 33          # feeds: ≈30 Hz, whatever the tracking rate
ONE_CAMERA_TEXT = ("One camera's video: no second view.\n"
                   "The shuttle is followed in the picture only (no 3D, distance, speed or landing).")
# The worker is asked for a result finished at least this long before the next tick, so the
# packet is ready when the tick comes, even with some timer jitter.
DISPLAY_LEAD_S = 0.016
# A tick that found no packet (the result was late: a loaded machine) looks again this often until
# one comes or the next tick does, instead of leaving the feeds a whole tick behind.
LATE_POLL_MS = 4
# The court views (3D, plan, side), the readouts and the tuning preview: ≤15 Hz. Each of them
# costs the GUI thread (and, through the GIL, the tracker) more than a feed, and a flight drawn
# 15 times a second, or a number changing 15 times a second, looks no different to the operator.
SLOW_VIEW_INTERVAL_S = 1.0 / 15.0
# The layout of docks, toolbars and splitters the saved window state describes: raise it when
# they change, and a state saved by an older layout is ignored instead of misplacing things.
WINDOW_STATE_VERSION = 1
# What a dropped file is, by its extension (anything else is refused with a status message).
VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".m4v", ".mpg", ".mpeg", ".webm")
RIG_SUFFIXES = (".yaml", ".yml", ".xml")
PRESET_SUFFIXES = (".json",)


def rig_save_dir() -> Path:
    """Where the wizard saves rigs: the project's ``calibration/`` folder (README), or, when the
    package is installed somewhere read-only, a ``rigs`` folder in the user's application data."""
    from .calibration_wizard import DEFAULT_SAVE_DIR
    try:
        DEFAULT_SAVE_DIR.mkdir(parents=True, exist_ok=True)
        probe = DEFAULT_SAVE_DIR / ".write-test"
        probe.touch()
        probe.unlink()
        return DEFAULT_SAVE_DIR
    except OSError:
        return Path(QStandardPaths.writableLocation(
            QStandardPaths.StandardLocation.AppDataLocation) or Path.home()) / "rigs"

# Tracking threads that did not stop when asked (a camera that hangs, a long step that ends on
# its own later). Qt aborts the whole program when a running QThread is destroyed, which would
# happen with its parent window; so such a thread loses its parent and is held here until it ends.
_UNFINISHED: list[tuple[QObject, QThread]] = []


def _keep_until_finished(worker: QObject, thread: QThread) -> None:
    thread.setParent(None)
    entry = (worker, thread)
    _UNFINISHED.append(entry)

    def release() -> None:
        if entry in _UNFINISHED:
            _UNFINISHED.remove(entry)
            worker.deleteLater()
            thread.deleteLater()
    thread.finished.connect(release)
    if thread.isFinished():
        release()


def _on_screen(widget: QWidget) -> bool:
    """Whether any of the widget is visible (shown, not collapsed to nothing by a splitter)."""
    return widget.isVisible() and widget.width() > 0 and widget.height() > 0


class Banner(QFrame):
    """A one-sentence line across the top of the window, with a close button: an error (red), or
    advice (blue) that may offer one action, e.g. switching to the preset it names."""

    STYLES = {
        "error": "#banner { background: #a8322d; border-radius: 4px; }",
        "advice": "#banner { background: #2d5f9a; border-radius: 4px; }",
    }

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("banner")
        self.kind = "error"
        self.label = QLabel("", self)
        self.label.setWordWrap(True)
        self.label.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        # Under an error: where the log is, as a link that opens the folder.
        self.log_label = QLabel(log_link_html(), self)
        self.log_label.setTextInteractionFlags(Qt.TextInteractionFlag.TextBrowserInteraction)
        self.log_label.linkActivated.connect(lambda _url: open_log_folder())
        self.log_label.setObjectName("log")
        self.log_label.hide()
        self.action_button = QPushButton("", self)
        self.action_button.hide()
        self.action_button.clicked.connect(self._run_action)
        self._action: Callable[[], None] | None = None
        close = QPushButton("✕", self)
        close.setFlat(True)
        close.setFixedWidth(28)
        close.setStyleSheet("color: white;")
        close.clicked.connect(self.hide)
        lay = QHBoxLayout(self)
        lay.setContentsMargins(10, 4, 4, 4)
        text = QVBoxLayout()
        text.setSpacing(0)
        text.addWidget(self.label)
        text.addWidget(self.log_label)
        lay.addLayout(text, 1)
        lay.addWidget(self.action_button)
        lay.addWidget(close)
        self._set_kind("error")
        self.hide()

    def _set_kind(self, kind: str) -> None:
        self.kind = kind
        self.setStyleSheet(self.STYLES[kind] + "#banner QLabel { color: white; font-weight: bold; }"
                           "#banner QLabel#log { font-weight: normal; }")

    def show_message(self, text: str, kind: str = "error",
                     action: tuple[str, Callable[[], None]] | None = None) -> None:
        """Show ``text``; ``action`` (button label, callable) adds a button that runs it and
        closes the line."""
        self._set_kind(kind)
        self.label.setText(text)
        self.log_label.setText(log_link_html())     # the log folder may have been moved since
        self.log_label.setVisible(kind == "error")
        self._action = action[1] if action else None
        self.action_button.setText(action[0] if action else "")
        self.action_button.setVisible(action is not None)
        self.show()

    def _run_action(self) -> None:
        action, self._action = self._action, None
        self.hide()
        if action is not None:
            action()

    @property
    def text(self) -> str:
        return self.label.text() if self.isVisible() else ""


def distance_text(measured: float | None, predicted: float | None) -> str:
    """The distance readout: measured in mm; on a frame with no 3D point in the middle of a
    flight (one camera hidden), the flight's prediction, greyed and marked, rather than a dash."""
    if measured is not None:
        return f"{measured * 1000:,.0f} mm".replace(",", " ")
    if predicted is not None:
        return (f"<span style='color:#999'>≈ {predicted * 1000:,.0f} mm</span>".replace(",", " ")
                + "<span style='font-size:small; font-weight:normal; color:#999'> predicted</span>")
    return "—"


def latency_text(stats) -> str:
    """The robot's latency (frame available → result sent) and, with the look-ahead view, the
    feeds' (the pair shown also waited for the next frames)."""
    text = f"{stats.latency_ms:.1f} ms"
    if stats.lookahead_frames > 0:
        text += f" · view {stats.shown_latency_ms:.0f} ms"
    return text


def latency_tooltip(stats) -> str:
    text = "Frame available → result sent to the robot"
    if stats.lookahead_frames > 0:
        text += (f"; the feeds and these readouts show each pair once the next "
                 f"{stats.lookahead_frames} are tracked (Playback ▸ Look-ahead view), "
                 f"{stats.shown_latency_ms:.0f} ms after it was available")
    return text


def score_text(left: Outcomes | None, right: Outcomes | None, truth_name: str) -> str:
    """The live score: each camera's accuracy against the source's truth (TrackNet's protocol)
    since the parameters last changed, or why there is none."""
    if left is None or right is None:
        return "<span style='color:#888'>no labels for this source</span>"
    frames = max(left.total, right.total)
    if frames == 0:
        return f"{truth_name}: no labelled frame yet"

    # A camera without a single labelled frame (one camera's video) is left out.
    cameras = " · ".join(f"{side} {100.0 * o.accuracy:.1f} %"
                         for side, o in (("L", left), ("R", right)) if o.total)
    return (f"{cameras}<br><span style='font-size:small; color:#aaa'>"
            f"{truth_name} · {frames:,} frames</span>")


def score_tooltip(left: Outcomes | None, right: Outcomes | None, truth_name: str) -> str:
    if left is None or right is None:
        return ("Open a video pair with label files (Source ▸ Stereo video pair…), or the demo "
                "court, to score the tracking against the truth while you tune.")
    return (f"Accuracy of each camera's report against the {truth_name}, with the benchmarks' "
            f"protocol (TrackNet's five outcomes), over the frames since the parameters last "
            f"changed.\nLeft:  {left.summary()}\nRight: {right.summary()}")


class Readouts(QWidget):
    """The numbers: distance (mm), speed, shot peak speed, rates, drops, latency, landing."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.values: dict[str, QLabel] = {}
        grid = QGridLayout(self)
        grid.setContentsMargins(8, 4, 8, 4)
        grid.setVerticalSpacing(3)
        big = QFont(self.font())
        big.setPointSizeF(big.pointSizeF() * 1.6)
        big.setBold(True)
        rows = [("distance", "Distance"), ("speed", "Speed"), ("peak", "Shot peak speed"),
                ("landing", "Landing"), ("call", "Call"), (None, None),
                ("capture", "Capture fps L / R"), ("processing", "Processing"),
                ("display", "Display"), ("dropped", "Dropped frames"), ("latency", "Latency"),
                ("playback", "Playback"), ("rig", "Stereo rig"), ("score", "Against the truth")]
        for r, (key, text) in enumerate(rows):
            if key is None:
                line = QFrame(self)
                line.setFrameShape(QFrame.Shape.HLine)
                line.setStyleSheet("color: #555;")
                grid.addWidget(line, r, 0, 1, 2)
                continue
            name = QLabel(text, self)
            name.setStyleSheet("color: #aaa;")
            value = QLabel("—", self)
            value.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
            if key in ("distance", "speed", "call"):
                value.setFont(big)
            value.setTextFormat(Qt.TextFormat.RichText)
            grid.addWidget(name, r, 0, Qt.AlignmentFlag.AlignTop)
            grid.addWidget(value, r, 1)
            self.values[key] = value
        grid.setRowStretch(len(rows), 1)
        grid.setColumnStretch(1, 1)
        # Wide enough for the longest values, so no readout is ever clipped.
        fm_big, fm = QFontMetrics(big), self.fontMetrics()
        self.setMinimumWidth(fm.horizontalAdvance("Shot peak speed") + 24 +
                             max(fm_big.horizontalAdvance("888 km/h") + fm.horizontalAdvance(" 88.8 m/s"),
                                 fm_big.horizontalAdvance("≈ 88 888 mm") + fm.horizontalAdvance(" predicted"),
                                 fm.horizontalAdvance("±0.00 m, lands in 0.00 s"),
                                 fm.horizontalAdvance("888 fps (888.8 ms/pair)")))

    def clear(self) -> None:
        """Dashes everywhere: no number may outlive the source it came from."""
        for value in self.values.values():
            value.setText("—")

    def show_packet(self, packet: DisplayPacket, display_hz: float,
                    slowed_views_hz: float | None = None) -> None:
        r, s = packet.result, packet.stats
        v = self.values
        v["distance"].setText(distance_text(r.distance, r.predicted_distance))
        v["speed"].setText(f"{r.speed * 3.6:.0f} km/h <span style='font-size:small; font-weight:normal'>"
                           f"{r.speed:.1f} m/s</span>" if r.speed is not None else "—")
        peak = r.flight.peak_speed
        v["peak"].setText(f"{peak * 3.6:.0f} km/h  ({peak:.1f} m/s)" if peak is not None else "—")
        lp = r.flight.prediction
        if lp is not None:
            v["landing"].setText(f"x {lp.x:+.2f} m  y {lp.y:+.2f} m<br>"
                                 f"±{lp.radius:.2f} m, lands in {max(0.0, lp.t - r.timestamp):.2f} s")
            colour = "#3c3" if lp.call == "in" else "#e44" if lp.call == "out" else "#ccc"
            v["call"].setText(f"<span style='color:{colour}'>{(lp.call or 'unknown').upper()}</span>")
        else:
            reason = r.flight.withheld_reason
            v["landing"].setText(f"withheld:<br>{reason}" if reason else "—")
            v["call"].setText("—")
        v["capture"].setText(f"{s.capture_fps_left:.0f} / "
                             + ("—" if packet.right is None else f"{s.capture_fps_right:.0f}"))
        v["processing"].setText(f"{s.processing_fps:.0f} fps  ({s.processing_ms:.1f} ms/pair)")
        v["display"].setText(f"{display_hz:.0f} Hz" if slowed_views_hz is None else
                             f"{display_hz:.0f} Hz<br><span style='color:#e8a33c'>court views "
                             f"{slowed_views_hz:.0f} Hz, tracker behind</span>")
        v["dropped"].setText(str(s.dropped))
        v["latency"].setText(latency_text(s))
        v["latency"].setToolTip(latency_tooltip(s))
        v["playback"].setText(f"{s.playback_speed:.2f}× real time")
        v["rig"].setText(rig_readout_text(s.rig_epipolar_px, r.left.image_size[0], s.rig_swapped_px))
        v["score"].setText(score_text(s.score_left, s.score_right, s.truth_name))
        v["score"].setToolTip(score_tooltip(s.score_left, s.score_right, s.truth_name))


class MainWindow(QMainWindow):
    """The operator's window."""

    sourceOpened = Signal(str)

    def __init__(self, params: TrackerParams | None = None, spec: st.SourceSpec | None = None,
                 start: bool = True) -> None:
        super().__init__()
        self.setWindowTitle("Badminton shuttle tracker")
        self.settings = st.open_settings()
        self.params = params or st.load_params(self.settings) or TrackerParams()
        self.spec = spec or st.load_source_spec(self.settings)
        # The preset the parameters were set from (tuning's Reset goes back to it).
        self.preset = st.load_preset_in_use(self.settings)
        self.rig: StereoRig | None = None
        self._source_name = "the source"     # as the worker named it when it opened
        self.worker: TrackingWorker | None = None
        self.thread: QThread | None = None
        self.latest_packet: DisplayPacket | None = None
        self.results_seen = 0               # packets taken from the worker
        self.display_refreshes = 0          # timer ticks that repainted
        self.slow_view_updates: dict[str, int] = {}   # packets shown per slow view (tests read it)
        self._slow_shown: dict[str, DisplayPacket] = {}
        self._slow_shown_at = float("-inf")
        self._display_rate = RateMeter()
        self._tuning = None
        self._refine = None                 # the refine dialog, built when first opened
        self._opened_with: tuple[SourceOpener, str] | None = None   # the source being tracked
        self._restart_rig: StereoRig | None = None   # applied by reopening the stopped source
        self._paused = False
        self._pending_start: tuple[SourceOpener, str] | None = None
        self._retiring: list[tuple[TrackingWorker, QThread]] = []
        self._recorder: TrackRecorder | None = None   # Source ▸ Record track, while on
        self._process = None                # Tools ▸ Process a recording, built when first opened
        self._keep_up = KeepUpWatch()       # advice when tracking falls behind (gui/keep_up.py)
        self._rig_check = RigCheck()        # advice when the stereo calibration is off (gui/rig_check.py)
        # The court views slow down while tracking is behind its source (gui/keep_up.py).
        self._display_yield = DisplayYield(SLOW_VIEW_INTERVAL_S)
        self._build_ui()
        self._build_actions()
        self._build_help_menu()
        self._about: AboutDialog | None = None
        self._set_icon()
        self.setAcceptDrops(True)           # videos, rigs and presets dropped on the window
        self._timer = QTimer(self)
        self._timer.setTimerType(Qt.TimerType.PreciseTimer)
        self._timer.timeout.connect(self._refresh_display)
        self._timer.start(DISPLAY_INTERVAL_MS)
        self._late_timer = QTimer(self)
        self._late_timer.setSingleShot(True)
        self._late_timer.setTimerType(Qt.TimerType.PreciseTimer)
        self._late_timer.timeout.connect(self._late_poll)
        self._record_timer = QTimer(self)     # the recording's row count and health, 2 Hz
        self._record_timer.timeout.connect(self._update_recording)
        self._restore_window_state()
        if start:
            self.start_spec(self.spec)

    # ---- layout ----------------------------------------------------------------------------
    def _build_ui(self) -> None:
        self.banner = Banner(self)
        self.left_feed = FeedView("Left camera")
        self.right_feed = FeedView("Right camera")
        feeds = QSplitter(Qt.Orientation.Horizontal)
        feeds.addWidget(self.left_feed)
        feeds.addWidget(self.right_feed)
        self.feeds_splitter = feeds

        self.gl_reason = gl_unavailable_reason()
        self.gl_view: CourtGLView | None = None
        if not self.gl_reason:
            try:
                self.gl_view = CourtGLView()
            except Exception as exc:  # noqa: BLE001 - any GL failure means: use the 2D views
                self.gl_reason = f"3D view unavailable: {exc}"
        self.plan = CourtPlanView()
        self.side = SideView()
        # With the 3D view the two plots stack beside it; without it they share the row side
        # by side, so the court stays large in the 2D fallback.
        plots = QSplitter(Qt.Orientation.Vertical if self.gl_view is not None else Qt.Orientation.Horizontal)
        plots.addWidget(self.plan.widget)
        plots.addWidget(self.side.widget)
        self.plots_splitter = plots
        self.readouts = Readouts()
        self.readouts.setSizePolicy(QSizePolicy.Policy.Preferred, QSizePolicy.Policy.Preferred)

        bottom = QSplitter(Qt.Orientation.Horizontal)
        if self.gl_view is not None:
            bottom.addWidget(self.gl_view.widget)
        bottom.addWidget(plots)
        bottom.addWidget(self.readouts)
        if self.gl_view is not None:
            bottom.setSizes([500, 360, 280])
        else:
            bottom.setSizes([800, 280])
        self.bottom_splitter = bottom

        main = QSplitter(Qt.Orientation.Vertical)
        main.addWidget(feeds)
        main.addWidget(bottom)
        main.setSizes([380, 300])
        self.main_splitter = main

        central = QWidget(self)
        lay = QVBoxLayout(central)
        lay.setContentsMargins(4, 4, 4, 4)
        lay.setSpacing(4)
        lay.addWidget(self.banner)
        lay.addWidget(main, 1)
        self.setCentralWidget(central)

        self.link_panel = RobotLinkPanel(str(self.settings.value("robot/port", "")),
                                         int(self.settings.value("robot/baud", 115200)))
        self.link_panel.linkChanged.connect(self._set_link)
        self.link_dock = QDockWidget("Robot link", self)
        self.link_dock.setObjectName("robot-link")
        self.link_dock.setWidget(self.link_panel)
        self.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, self.link_dock)
        self.link_dock.hide()
        self.status_source = QLabel("")
        self.statusBar().addWidget(self.status_source, 1)
        self.status_record = QLabel("")
        self.statusBar().addPermanentWidget(self.status_record)
        self.status_state = QLabel("")
        self.statusBar().addPermanentWidget(self.status_state)
        self.status_adapt = QLabel("")     # the court adaptation's progress ('adapt' parameters)
        self.statusBar().addPermanentWidget(self.status_adapt)
        if self.gl_reason:
            note = QLabel("2D views only")
            note.setToolTip(self.gl_reason)
            self.statusBar().addPermanentWidget(note)

    def _build_actions(self) -> None:
        menu = self.menuBar()
        src = menu.addMenu("&Source")
        self._action(src, "&Demo court", lambda: self.start_spec(
            st.SourceSpec("demo", realtime=self.realtime_action.isChecked())), "Ctrl+D")
        self._action(src, "Two &cameras…", self.choose_cameras)
        self._action(src, "Stereo &video pair…", self.choose_videos, "Ctrl+O")
        self._action(src, "&One video (TV broadcast)…", self.choose_single_video)
        src.addSeparator()
        self._action(src, "&Restart source", lambda: self.start_spec(self.spec), "Ctrl+R")
        self.swap_action = self._action(src, "S&wap left and right", self.swap_cameras)
        self.swap_action.setToolTip("Open the two cameras (or videos) again, each as the other: for a "
                                    "rack cabled the other way round")
        src.aboutToShow.connect(lambda: self.swap_action.setEnabled(self.spec.swappable))
        self.stop_action = self._action(src, "S&top", self.stop_source, "Ctrl+.")
        self.stop_action.setToolTip("Stop tracking and release the cameras or files (also gives up "
                                    "opening a source that takes long)")
        self.record_action = self._action(src, "Re&cord track to CSV…", self.toggle_recording,
                                          "Ctrl+Shift+R", checkable=True)
        self.record_action.setIconText("Record")      # the toolbar's label
        self.record_action.setToolTip("Write every tracked frame pair (2D, 3D, distance, speed, landing: "
                                      "what the robot gets) to a CSV file, in the columns of "
                                      "'badminton-track track'; again to stop")
        src.addSeparator()
        self._action(src, "&Quit", self.close, QKeySequence.StandardKey.Quit)

        play = menu.addMenu("&Playback")
        self.pause_action = self._action(play, "&Pause", self.toggle_pause, "Space", checkable=True)
        self.step_action = self._action(play, "&Single step", self.step, "Right")
        self.realtime_action = self._action(play, "&Real-time playback", self._realtime_changed,
                                            checkable=True)
        self.realtime_action.setChecked(self.spec.realtime)
        self.realtime_action.setToolTip("Pace file and demo sources to their frame rate; "
                                        "off: as fast as possible")
        self.newest_only_action = self._action(play, "&Newest camera pair only (lowest latency)",
                                               self._live_buffer_changed, checkable=True)
        self.newest_only_action.setChecked(
            str(self.settings.value("live/newest_only", "false")) == "true")
        self.newest_only_action.setToolTip(
            "Live cameras: track only the newest pair, for the lowest latency to the robot; a single "
            "slow pair then costs a dropped pair. Off: the grabber keeps two pairs, so a slow pair is "
            "taken up late instead of lost (at most one camera period more latency)")

        # The feeds show each pair with the file commands' readout: re-decided once the next
        # FILE_LOOKAHEAD pairs are tracked (a flight's first frames, the shuttle leaving the
        # racket; on TV the held shuttle's lead-in). It costs the view that many frames of
        # delay (34 ms at 119 fps, 133 ms at 30 fps); the robot gets every result at once.
        self.lookahead_action = self._action(play, "&Look-ahead view", self._lookahead_changed,
                                             checkable=True)
        self.lookahead_action.setChecked(str(self.settings.value("view/lookahead", "true")) == "true")
        self.lookahead_action.setToolTip(
            f"Show each frame once the next {FILE_LOOKAHEAD} are tracked, re-decided as "
            f"'badminton-track detect' and 'track' decide a file's rows (a flight's first frames, "
            f"the shuttle just off the racket). The view is {FILE_LOOKAHEAD} frames late (with the "
            f"broadcast preset's lead-in to the served shuttle, 70 more; under parameters that adapt the "
            f"classifier to a TV recording, that pass runs first, as in 'detect': turning the view off "
            f"meanwhile skips it); "
            f"the robot link and recordings get every result at once. Off: each frame as soon as "
            f"it is tracked")

        view = menu.addMenu("&View")
        self.mask_action = self._action(view, "Foreground &mask", self._overlays_changed, "M", checkable=True)
        self.rejected_action = self._action(view, "&Rejected candidates", self._overlays_changed, "C",
                                            checkable=True)
        self.rejected_action.setToolTip("Ring each candidate a filter refused in its colour and label the "
                                        "nearest to the shuttle; a corner panel names the rules that "
                                        "fired on the frame (as 'badminton-track track --trace') and what "
                                        "each detector stage rejected")
        # The truth's cross (labels, the demo's shuttle): on by default, it costs nothing
        # where the source has no truth.
        self.labels_action = self._action(view, "&Truth (labels)", self._overlays_changed, "L",
                                          checkable=True)
        self.labels_action.setChecked(True)
        view.addAction(self.link_dock.toggleViewAction())

        tools = menu.addMenu("&Tools")
        self._action(tools, "&Tuning…", self.open_tuning, "Ctrl+T")
        self._action(tools, "&Process a recording…", self.open_process, "Ctrl+P")
        self.export_video_action = self._action(tools, "&Export video…", self.open_export_video)
        tools.aboutToShow.connect(lambda: self.export_video_action.setEnabled(self.spec.kind in ("video", "single")))

        calibration = menu.addMenu("&Calibration")
        self._action(calibration, "&Calibrate with a chessboard…", self.open_calibration, "Ctrl+K")
        self.refine_action = self._action(calibration, "&Refine from tracked shuttle…",
                                          self.open_refine)
        self.refine_action.setToolTip("Refit the cameras' relative pose to the shuttle both "
                                      "cameras follow, while tracking")

        bar = self.addToolBar("Controls")
        bar.setObjectName("controls")
        bar.setMovable(False)
        for a in (self.pause_action, self.step_action, self.realtime_action, self.record_action, None,
                  self.mask_action, self.rejected_action, None):
            if a is None:
                bar.addSeparator()
            else:
                bar.addAction(a)
        bar.addAction("Tuning…", self.open_tuning)
        bar.addAction(self.link_dock.toggleViewAction())

    def _action(self, menu, text: str, slot: Callable, shortcut=None, checkable: bool = False) -> QAction:
        action = QAction(text, self)
        if shortcut is not None:
            action.setShortcut(QKeySequence(shortcut))
        action.setCheckable(checkable)
        action.triggered.connect(lambda *_: slot())
        menu.addAction(action)
        return action

    # ---- sources and the worker ------------------------------------------------------------
    def start_spec(self, spec: st.SourceSpec) -> None:
        """Open a source described by a spec (remembered for the next start)."""
        self.spec = dataclasses.replace(spec, realtime=self.realtime_action.isChecked()
                                        if hasattr(self, "realtime_action") else spec.realtime)
        st.save_source_spec(self.settings, self.spec)
        self.start_opener(lambda context, spec=self.spec: open_spec(spec, context), self.spec.describe())

    def swap_cameras(self) -> None:
        """Open the current two-camera source again with the left and right exchanged."""
        if self.spec.swappable:
            self.start_spec(self.spec.swapped())

    def start_opener(self, opener: SourceOpener, description: str) -> None:
        """Track a new source (tests pass stand-in openers here).

        The old worker is told to stop and retires on its own; the new one starts when the
        old thread has finished (a camera must be released before it can be reopened), so
        switching sources never blocks the GUI thread on a slow frame.
        """
        self.banner.hide()
        self.readouts.clear()
        self.status_source.setText(f"Opening {description}…")
        for feed in (self.left_feed, self.right_feed):
            feed.set_message(f"Opening {description}…")
        self._pending_start = (opener, description)
        self._opened_with = (opener, description)
        if self.worker is not None:
            self._retire_worker()
        self._start_pending()

    def _start_pending(self) -> None:
        if self._retiring or self._pending_start is None or self.worker is not None:
            return
        opener, _ = self._pending_start
        self._pending_start = None
        self.latest_packet = None
        worker = TrackingWorker(opener, self.params, realtime=self.realtime_action.isChecked(),
                                show_mask=self.mask_action.isChecked(),
                                trace=self.rejected_action.isChecked(),
                                live_buffer_pairs=self._live_buffer_pairs(),
                                lookahead_frames=self._view_lookahead())
        thread = QThread(self)
        thread.setObjectName("tracking")
        worker.moveToThread(thread)
        thread.started.connect(worker.run)
        worker.finished.connect(thread.quit)
        worker.opened.connect(self._on_opened)
        worker.error.connect(self._on_error)
        worker.opening.connect(self._on_opening)
        worker.busy.connect(self._on_busy)
        worker.warning.connect(self.banner.show_message)
        worker.ended.connect(self._on_ended)
        worker.rig_applied.connect(self._on_rig_applied)
        worker.set_paused(self._paused)
        worker.set_link(self.link_panel.link)
        if self._refine is not None:
            self._refine.source_changed(keep_result=self._restart_rig is not None)
            worker.set_result_tap(self._refine.pairs.add)
        if self._recorder is not None:          # a recording goes on across sources
            worker.set_result_tap(self._recorder.add, key="record")
        self.worker, self.thread = worker, thread
        thread.start()

    def _retire_worker(self) -> None:
        """Raise the abort flag of the current worker and forget it; it finishes on its own."""
        worker, thread = self.worker, self.thread
        self.worker = self.thread = None
        worker.abort()
        worker.set_link(None)
        worker.set_result_tap(None)
        worker.set_result_tap(None, key="record")
        # Queued signals of the old worker may still arrive; drop them.
        for sig, slot in ((worker.opened, self._on_opened), (worker.error, self._on_error),
                          (worker.opening, self._on_opening), (worker.busy, self._on_busy),
                          (worker.warning, self.banner.show_message), (worker.ended, self._on_ended),
                          (worker.rig_applied, self._on_rig_applied)):
            try:
                sig.disconnect(slot)
            except (RuntimeError, TypeError):
                pass
        self._retiring.append((worker, thread))
        thread.finished.connect(self._reap_retired)
        if thread.isFinished():          # it had already stopped (source error, end of file)
            self._reap_retired()

    def _reap_retired(self) -> None:
        for worker, thread in list(self._retiring):
            if thread.isFinished():
                self._retiring.remove((worker, thread))
                worker.deleteLater()
                thread.deleteLater()
        self._start_pending()

    def open_process(self) -> None:
        """Tools ▸ Process a recording…: a video pair tracked, or one camera's video detected, into
        a CSV, off the GUI thread, with the parameters in use now or a preset
        (gui/process_dialog.py). Tracking here goes on meanwhile."""
        from .process_dialog import ProcessDialog
        if self._process is None:
            self._process = ProcessDialog(self.spec, self.params, self)
        else:
            self._process.params = self.params
        self._process.show()
        self._process.raise_()

    def open_export_video(self) -> None:
        """Tools ▸ Export video…: the recording as an MP4 with the tracking drawn on it, made off
        the GUI thread (gui/render_dialog.py)."""
        from .render_dialog import RenderDialog
        dialog = RenderDialog(self.spec, self.params, self)
        dialog.finished.connect(dialog.deleteLater)
        dialog.show()

    # ---- recording the session -----------------------------------------------------------
    def toggle_recording(self) -> None:
        if self.record_action.isChecked():
            self.start_recording()
        else:
            self.stop_recording()

    def start_recording(self, path: str | Path | None = None) -> bool:
        """Record every result from now on to ``path`` (asked for when None); False when the
        user cancelled or the file cannot be made (the banner says why)."""
        self.stop_recording()
        if path is None:
            folder = st.dialog_folder(self.settings, "tracks")
            name = f"track-{time.strftime('%Y%m%d-%H%M%S')}.csv"
            path, _ = QFileDialog.getSaveFileName(self, "Record the track to", str(Path(folder) / name),
                                                  "CSV (*.csv);;All files (*)")
            if not path:
                self.record_action.setChecked(False)
                return False
        try:
            recorder = TrackRecorder(path)
        except RecordingError as exc:
            self.record_action.setChecked(False)
            message = str(exc)
            self.banner.show_message(message[:1].upper() + message[1:])
            return False
        st.remember_dialog_folder(self.settings, "tracks", str(recorder.path))
        self._recorder = recorder
        self.record_action.setChecked(True)
        if self.worker is not None:
            self.worker.set_result_tap(recorder.add, key="record")
        self._record_timer.start(500)
        self._update_recording()
        return True

    def stop_recording(self) -> None:
        """End the recording (the file keeps every row); the status bar says where it went."""
        recorder, self._recorder = self._recorder, None
        self.record_action.setChecked(False)
        self._record_timer.stop()
        if recorder is None:
            return
        for worker in [self.worker] + [w for w, _ in self._retiring]:
            if worker is not None:
                worker.set_result_tap(None, key="record")
        recorder.close()
        self.status_record.setStyleSheet("")
        if recorder.error:
            self.banner.show_message(f"Recording stopped: {recorder.error}. {recorder.rows_saved} rows "
                                     f"were saved in {recorder.path}; tracking goes on.")
            self.status_record.setText(f"recording stopped ({recorder.rows_saved} rows saved)")
        else:
            self.status_record.setText(f"recorded {recorder.rows_saved} rows to {recorder.path.name}")
        self.status_record.setToolTip(str(recorder.path))

    def _update_recording(self) -> None:
        recorder = self._recorder
        if recorder is None:
            return
        if recorder.error:
            self.stop_recording()
            return
        self.status_record.setStyleSheet("color: #c0392b; font-weight: bold;")
        self.status_record.setText(f"● REC {recorder.path.name} — {recorder.rows} rows")
        self.status_record.setToolTip(str(recorder.path))

    def stop_source(self) -> None:
        """Source ▸ Stop: the worker is told to stop (an opening step gives up at once) and
        retires on its own; the GUI thread does not wait for it."""
        self._pending_start = None
        if self.worker is not None:
            self._retire_worker()
        text = "Stopped — choose a source in the Source menu"
        self.status_source.setText(text)
        for feed in (self.left_feed, self.right_feed):
            feed.set_message(text)

    def stop_worker(self) -> None:
        """Cooperative stop, waited for: abort flag, the loop returns, QThread.wait()."""
        self._pending_start = None
        if self.worker is not None:
            self._retire_worker()
        for worker, thread in list(self._retiring):
            thread.quit()
            if not thread.wait(5000):
                self.banner.show_message("The tracking thread did not stop within 5 s (a camera may hang).")
                self._retiring.remove((worker, thread))
                _keep_until_finished(worker, thread)
        self._reap_retired()

    def _on_opening(self, step: str) -> None:
        """A long step of opening the source (the frame-time scan), shown where the feeds will be."""
        if self.worker is None or self.sender() not in (None, self.worker):
            return     # queued before that worker was stopped or replaced
        description = self._opened_with[1] if self._opened_with is not None else "the source"
        text = f"Opening {description}… {step}"
        self.status_source.setText(text)
        for feed in (self.left_feed, self.right_feed):
            feed.set_message(text)

    def _on_busy(self, step: str) -> None:
        """A long step while the source plays (a TV clip's classifier adapted when the look-ahead
        view is turned on): how it goes over the feed, then what it did in the status line."""
        if self.worker is None or self.sender() not in (None, self.worker):
            return
        if step.startswith("adapting"):
            self.left_feed.set_message(step[:1].upper() + step[1:])   # the next frame clears it
            self.status_source.setText(f"{self._source_name} — {step}")
        else:
            # The step is over: the pause it made in the feeds is no sign of a tracker behind.
            self._keep_up.reset()
            self._display_yield.reset()
            if self.rig is None:
                self.status_source.setText(self._one_camera_status(self._source_name))

    def _one_camera_status(self, name: str) -> str:
        adapted = self.worker.adaptation_text if self.worker is not None else ""
        return (f"{name} — no second camera: the shuttle in the picture only, "
                f"no 3D, distance, speed or landing" + (f"; {adapted}" if adapted else ""))

    def _on_opened(self, name: str, rig: StereoRig | None) -> None:
        self.rig = rig
        self._source_name = name
        self._keep_up.reset()
        self._rig_check.reset()
        self._display_yield.reset()
        self.left_feed.title = "Camera" if rig is None else "Left camera"
        if rig is None:
            # One camera's video: its picture in the left feed, 2D only.
            self.setWindowTitle(f"Badminton shuttle tracker — {name}")
            self.status_source.setText(self._one_camera_status(name))
            self.right_feed.show_text(ONE_CAMERA_TEXT)
            if self.gl_view is not None:
                self.gl_view.set_rig(None)
            self.sourceOpened.emit(name)
            return
        if self._restart_rig is not None:
            restarted, self._restart_rig = self._restart_rig is rig, None
            if restarted:
                self._on_rig_applied(rig)
        self.setWindowTitle(f"Badminton shuttle tracker — {name}")
        self.status_source.setText(f"{name} — rig {rig.image_size[0]}×{rig.image_size[1]}"
                                   f"{', court pose' if rig.has_court_pose else ', no court pose'}")
        if self.gl_view is not None:
            self.gl_view.set_rig(rig)
        if self.params.association.exit_margin > 0:
            # The parameters are remembered across sources and restarts: after a TV clip the
            # broadcast preset would silently track two fixed cameras (the demo court: ≈ 95
            # against 99 %). Its rule for a shuttle leaving a TV picture marks it.
            self.banner.show_message(
                "Tracking with parameters made for a TV broadcast (the broadcast preset, or one "
                "derived from it): fixed cameras track better with the default preset.",
                kind="advice", action=("Use default", lambda: self.use_preset("default")))
        self.sourceOpened.emit(name)

    def _on_error(self, message: str) -> None:
        self._restart_rig = None          # a reopen with a refined rig failed: nothing applied
        self.banner.show_message(message[:1].upper() + message[1:])
        self.status_source.setText("Stopped — choose a source in the Source menu")
        if self.worker is not None:
            self.worker.output.clear()    # the stopped worker's last result must not redraw the numbers
        self.readouts.clear()
        self._slow_shown["readouts"] = self.latest_packet     # nor a packet the throttle held back
        for feed in (self.left_feed, self.right_feed):
            feed.set_message("No frames: " + message)

    def _on_ended(self, message: str) -> None:
        self.status_source.setText(message[:1].upper() + message[1:])

    def choose_cameras(self) -> None:
        dialog = CameraPairDialog(self.spec, self)
        if dialog.exec():
            self.start_spec(dialog.spec(self.realtime_action.isChecked()))

    def choose_videos(self, spec: st.SourceSpec | None = None) -> None:
        """Source ▸ Stereo video pair…; ``spec`` fills the dialog in (two videos dropped)."""
        dialog = VideoPairDialog(spec or self.spec, self)
        if dialog.exec():
            self.start_spec(dialog.spec(self.realtime_action.isChecked()))

    def choose_single_video(self, spec: st.SourceSpec | None = None) -> None:
        """Source ▸ One video…; ``spec`` fills the dialog in (one video dropped)."""
        dialog = SingleVideoDialog(spec or self.spec, self)
        if dialog.exec():
            if dialog.broadcast.isChecked():
                self.use_preset("broadcast")
            self.start_spec(dialog.spec(self.realtime_action.isChecked()))

    # ---- controls --------------------------------------------------------------------------
    def toggle_pause(self) -> None:
        self._paused = self.pause_action.isChecked()
        self.status_state.setText("<b>❚❚ Paused</b> — Space resumes, → steps one frame" if self._paused else "")
        if self.worker is not None:
            self.worker.set_paused(self._paused)

    def step(self) -> None:
        if not self._paused:
            self.pause_action.setChecked(True)
            self.toggle_pause()
        elif self.worker is not None:
            self.worker.step()

    def _realtime_changed(self) -> None:
        self.spec = dataclasses.replace(self.spec, realtime=self.realtime_action.isChecked())
        st.save_source_spec(self.settings, self.spec)
        if self.worker is not None:
            self.worker.set_realtime(self.realtime_action.isChecked())

    def _view_lookahead(self) -> int:
        return FILE_LOOKAHEAD if self.lookahead_action.isChecked() else 0

    def _lookahead_changed(self) -> None:
        self.settings.setValue("view/lookahead", "true" if self.lookahead_action.isChecked() else "false")
        if self.worker is not None:
            self.worker.set_lookahead(self._view_lookahead())

    def _live_buffer_pairs(self) -> int:
        return 1 if self.newest_only_action.isChecked() else LIVE_BUFFER_PAIRS

    def _live_buffer_changed(self) -> None:
        self.settings.setValue("live/newest_only",
                               "true" if self.newest_only_action.isChecked() else "false")
        if self.worker is not None:
            self.worker.set_live_buffer_pairs(self._live_buffer_pairs())

    def _overlays_changed(self) -> None:
        if self.worker is not None:
            self.worker.set_show_mask(self.mask_action.isChecked())
            self.worker.set_trace(self.rejected_action.isChecked())
        for feed in (self.left_feed, self.right_feed):
            feed.show_rejected = self.rejected_action.isChecked()
            feed.show_window = self.rejected_action.isChecked() or self.mask_action.isChecked()
            feed.show_labels = self.labels_action.isChecked()
            feed.update()
        if self.latest_packet is not None:
            self._show_trace(self.latest_packet)

    def set_params(self, params: TrackerParams) -> None:
        """A new parameter snapshot from the tuning dialog: to the worker, and remembered."""
        self.params = params
        self._keep_up.reset()
        if self.worker is not None:
            self.worker.set_params(params)
        if self._process is not None:       # its next job tracks with them too
            self._process.params = params
        st.save_params(self.settings, params)

    def _set_link(self, link) -> None:
        if self.worker is not None:
            self.worker.set_link(link)
        self.settings.setValue("robot/port", self.link_panel.port.currentText())
        self.settings.setValue("robot/baud", int(self.link_panel.baud.currentText()))

    def open_tuning(self) -> None:
        from .tuning_dialog import TuningDialog
        if self._tuning is None:
            self._tuning = TuningDialog(self.params, self, preset=self.preset)
            self._tuning.paramsChanged.connect(self.set_params)
            self._tuning.presetChosen.connect(self.remember_preset)
        self._tuning.show()
        self._tuning.raise_()

    def open_calibration(self) -> None:
        """Pause tracking (the wizard needs the cameras), run the wizard, load its rig."""
        try:
            from .calibration_wizard import CalibrationWizard
        except ImportError as exc:
            QMessageBox.information(self, "Calibrate", f"The calibration wizard is not available "
                                    f"in this installation ({exc}).")
            return
        spec = self.spec
        self.stop_worker()
        save_dir = rig_save_dir()
        saved: list[str] = []
        def calibration_source():
            if spec.kind == "single":
                raise SourceError("a stereo calibration needs two cameras: the source is one video "
                                  "(choose two cameras or use folders of chessboard images)")
            return (open_spec(dataclasses.replace(spec, calib=""))[0] if spec.kind == "demo"
                    else open_spec(spec)[0])

        wizard = CalibrationWizard(calibration_source, parent=self, save_dir=save_dir)
        wizard.rigSaved.connect(saved.append)
        wizard.exec()
        if saved:
            spec = dataclasses.replace(spec, calib=saved[-1])
        self.start_spec(spec)
        if saved:
            self.statusBar().showMessage(f"Tracking with the new rig {saved[-1]}", 15000)

    def open_refine(self) -> None:
        """Calibration ▸ Refine from tracked shuttle…: the dialog, collecting from now on."""
        from .refine_dialog import RefineCalibrationDialog
        if self._refine is None:
            self._refine = RefineCalibrationDialog(
                lambda: self.worker.rig_in_use if self.worker is not None else None,
                rig_save_dir, self)
            self._refine.applyRequested.connect(self.apply_rig)
            self._refine.rigSaved.connect(self._on_refined_rig_saved)
            if self.worker is not None:
                self.worker.set_result_tap(self._refine.pairs.add)
        self._refine.show()
        self._refine.raise_()
        self._refine.activateWindow()

    def apply_rig(self, rig: StereoRig) -> None:
        """Track with ``rig`` from the next frame pair on (``_on_rig_applied`` follows).

        A source that has stopped (the end of a video pair, typically, where a refit is made
        after the rally) is reopened with the rig instead.
        """
        if self.worker is not None and self.thread is not None and self.thread.isRunning():
            self.worker.set_rig(rig)
            return
        if self._opened_with is None:
            self.banner.show_message("No source to track with the refined rig: choose one in "
                                     "the Source menu.")
            return
        opener, description = self._opened_with
        self._restart_rig = rig
        self.start_opener(lambda: (opener()[0], rig), description)

    def _on_rig_applied(self, rig: StereoRig) -> None:
        self.rig = rig
        self._rig_check.reset()             # the tracker learns the new rig's error afresh
        if self.gl_view is not None:
            self.gl_view.set_rig(rig)
        saved = self._refine.saved_path_of(rig) if self._refine is not None else None
        if saved is not None:
            self._remember_rig_file(saved)
        self.statusBar().showMessage(
            f"Tracking with the refined rig {saved}" if saved is not None else
            "Tracking with the refined rig (not saved: it lasts until the source restarts)", 15000)
        if self._refine is not None:
            self._refine.rig_applied(rig)

    def _on_refined_rig_saved(self, path: str, rig: StereoRig) -> None:
        if self.worker is not None and self.worker.rig_in_use is rig:
            self._remember_rig_file(Path(path))
            self.statusBar().showMessage(f"Tracking with the refined rig {path}", 15000)

    def _remember_rig_file(self, path: Path) -> None:
        """The source's rig file from now on (a restart, the next session), as after the wizard."""
        self.spec = dataclasses.replace(self.spec, calib=str(path))
        st.save_source_spec(self.settings, self.spec)

    # ---- help menu, icon, window state --------------------------------------------------------
    def _build_help_menu(self) -> None:
        help_menu = self.menuBar().addMenu("&Help")
        self.shortcuts_action = self._action(help_menu, "&Keyboard shortcuts", self.show_shortcuts,
                                             QKeySequence.StandardKey.HelpContents)
        self.log_folder_action = self._action(help_menu, "Open &log folder", self.open_log_folder)
        help_menu.addSeparator()
        self.about_action = self._action(help_menu, "&About", self.show_about)
        self.help_menu = help_menu

    def show_about(self) -> AboutDialog:
        """Help ▸ About: version, licence, the rigs', settings' and logs' folders, versions."""
        if self._about is None:
            self._about = AboutDialog(self)
        self._about.show()
        self._about.raise_()
        return self._about

    def show_shortcuts(self) -> ShortcutsDialog:
        """Help ▸ Keyboard shortcuts: every shortcut of the menus, listed from the menus."""
        dialog = ShortcutsDialog(self.menuBar(), self)
        dialog.setAttribute(Qt.WidgetAttribute.WA_DeleteOnClose)
        dialog.show()
        return dialog

    def open_log_folder(self) -> None:
        """Help ▸ Open log folder (created if nothing was logged yet)."""
        from ..io.app_dirs import log_dir
        if not open_log_folder():
            self.statusBar().showMessage(f"No file manager could open the log folder {log_dir()}", 15000)

    def _set_icon(self) -> None:
        icon = app_icon()
        self.setWindowIcon(icon)
        QApplication.setWindowIcon(icon)     # the dialogs' and the task bar's too

    def _layout_key(self) -> str:
        # The 2D fallback's bottom row has one pane fewer than the 3D layout's: each keeps its own sizes.
        return "window/3d" if self.gl_view is not None else "window/2d"

    def _splitters(self) -> dict[str, QSplitter]:
        return {"main": self.main_splitter, "feeds": self.feeds_splitter,
                "bottom": self.bottom_splitter, "plots": self.plots_splitter}

    def _save_window_state(self) -> None:
        """Geometry, docks, toolbars and splitters, for the next window."""
        key = self._layout_key()
        self.settings.setValue("window/geometry", self.saveGeometry())
        self.settings.setValue("window/state_version", WINDOW_STATE_VERSION)
        self.settings.setValue(f"{key}/state", self.saveState(WINDOW_STATE_VERSION))
        for name, splitter in self._splitters().items():
            self.settings.setValue(f"{key}/splitter_{name}", splitter.saveState())

    def _restore_window_state(self) -> None:
        """The last window's geometry; its docks, toolbars and splitters only if it had this layout."""
        geometry = self.settings.value("window/geometry")
        if isinstance(geometry, QByteArray):
            self.restoreGeometry(geometry)
        else:
            self.resize(1280, 720)
        try:
            version = int(self.settings.value("window/state_version", 0) or 0)
        except (TypeError, ValueError):
            version = 0
        if version != WINDOW_STATE_VERSION:
            return
        key = self._layout_key()
        state = self.settings.value(f"{key}/state")
        if isinstance(state, QByteArray):
            self.restoreState(state, WINDOW_STATE_VERSION)
        for name, splitter in self._splitters().items():
            saved = self.settings.value(f"{key}/splitter_{name}")
            if isinstance(saved, QByteArray):
                splitter.restoreState(saved)

    # ---- files dropped on the window ---------------------------------------------------------
    @staticmethod
    def _dropped_paths(mime: QMimeData) -> list[str]:
        return [url.toLocalFile() for url in mime.urls() if url.isLocalFile()] if mime.hasUrls() else []

    def dragEnterEvent(self, event) -> None:  # noqa: N802 - Qt naming
        if self._dropped_paths(event.mimeData()):
            event.acceptProposedAction()
        else:
            event.ignore()

    def dragMoveEvent(self, event) -> None:  # noqa: N802 - Qt naming
        self.dragEnterEvent(event)

    def dropEvent(self, event) -> None:  # noqa: N802 - Qt naming
        paths = self._dropped_paths(event.mimeData())
        if not paths:
            event.ignore()
            return
        event.acceptProposedAction()
        # Opened after the drop has returned: a dialog run inside it would hold the file
        # manager's drag until it closed.
        QTimer.singleShot(0, lambda: self.open_dropped_files(paths))

    def open_dropped_files(self, paths: list[str]) -> None:
        """Open dropped files as the menus would: one video (the one-video dialog), two (the
        video pair dialog, with a rig dropped with them), a rig (for the source in use), a
        preset (applied). Anything else is refused in the status line."""
        files = [Path(p) for p in paths]
        videos = sorted(str(f) for f in files if f.suffix.lower() in VIDEO_SUFFIXES)
        rigs = [str(f) for f in files if f.suffix.lower() in RIG_SUFFIXES]
        presets = [str(f) for f in files if f.suffix.lower() in PRESET_SUFFIXES]
        unknown = [f.name for f in files
                   if f.suffix.lower() not in VIDEO_SUFFIXES + RIG_SUFFIXES + PRESET_SUFFIXES]
        refusal = None
        if unknown:
            refusal = (f"Cannot open {', '.join(unknown)}: drop one or two videos "
                       f"({', '.join(VIDEO_SUFFIXES)}), a rig (.yaml, .yml, .xml) or a preset (.json)")
        elif len(videos) > 2 or len(rigs) > 1 or len(presets) > 1:
            refusal = "Drop at most two videos, one rig and one preset at a time"
        elif len(videos) == 1 and rigs:
            refusal = "A rig is for two cameras: drop it with two videos, or alone for the source in use"
        if refusal is not None:
            self.statusBar().showMessage(refusal, 15000)
            return
        if presets:
            self.use_preset(presets[0])
        if len(videos) == 2:
            calib = rigs[0] if rigs else (self.spec.calib if self.spec.kind in ("video", "cameras") else "")
            self.choose_videos(st.SourceSpec("video", videos[0], videos[1], calib))
        elif len(videos) == 1:
            self.choose_single_video(st.SourceSpec("single", videos[0]))
        elif rigs:
            self.use_rig_file(rigs[0])

    def use_rig_file(self, path: str) -> None:
        """Track the source in use with the rig in ``path`` (a rig dropped on the window); a rig
        that does not load is refused with the message the source dialogs' path gives."""
        if self.spec.kind == "single":
            self.statusBar().showMessage("A rig is for two cameras: the source is one camera's video. "
                                         "Drop the rig with two videos.", 15000)
            return
        try:
            StereoRig.load(path)
        except (RigError, OSError) as exc:
            message = str(exc)
            self.banner.show_message(message[:1].upper() + message[1:])
            return
        self.start_spec(dataclasses.replace(self.spec, calib=path))
        self.statusBar().showMessage(f"{self.spec.describe()} with the rig {path}", 15000)

    # ---- display ---------------------------------------------------------------------------
    def _refresh_display(self) -> None:
        """Timer tick (≈30 Hz): the feeds get the newest packet, the slower views maybe too.

        Newest frame wins: the worker keeps one packet, built on request (see the worker's
        module docstring), and the feeds show it; nothing queues up behind a slow display.
        """
        self._late_timer.stop()
        if self.worker is None:
            return
        now = time.perf_counter()
        if not self._show_newest(now):
            self._late_timer.start(LATE_POLL_MS)
        if now - self._slow_shown_at >= self._display_yield.interval - 0.002:   # a tick may come a little early
            self._refresh_slow_views(now)

    def _late_poll(self) -> None:
        """The tick found no packet: show it as soon as it comes, up to the next tick."""
        if self.worker is None or self._show_newest(time.perf_counter()):
            return
        if self._timer.remainingTime() > 2 * LATE_POLL_MS:
            self._late_timer.start(LATE_POLL_MS)

    def _show_newest(self, now: float) -> bool:
        """Give the feeds the worker's packet, if there is one, and ask for the next."""
        packet = self.worker.output.take()
        if packet is None:
            return False
        # Ask for the last result that can finish before the next tick: a tracker slower than
        # the ticks (one result per period) is asked for its very next result, a fast one for
        # a result just before the tick, so the packet shown is fresh either way.
        remaining = self._timer.remainingTime()
        next_tick = now + (remaining if remaining >= 0 else DISPLAY_INTERVAL_MS) / 1000.0
        period = 1.0 / max(packet.stats.processing_fps, 1.0)
        self.worker.request_display(next_tick - DISPLAY_LEAD_S - period)
        # Frames arrive already shrunk to the feeds' size, so painting them is nearly a copy.
        ratio = self.devicePixelRatioF()
        self.worker.set_display_size(int(max(self.left_feed.width(), self.right_feed.width()) * ratio),
                                     int(max(self.left_feed.height(), self.right_feed.height()) * ratio))
        self.latest_packet = packet
        stats = packet.stats
        self._display_yield.update(now, stats, live=stats.live, paced=stats.paced, paused=self._paused)
        self.results_seen += 1
        self.display_refreshes += 1
        self._display_rate.tick(now)
        r = packet.result
        self.left_feed.set_frame(packet.left, packet.display_scale, r.left, packet.trail_left,
                                 packet.label_left)
        if packet.right is not None:
            self.right_feed.set_frame(packet.right, packet.display_scale, r.right, packet.trail_right,
                                      packet.label_right)
        self._show_trace(packet)
        return True

    def _show_trace(self, packet: DisplayPacket) -> None:
        """The feeds' trace panels for this packet while the rejected-candidates overlay is on
        (the worker traces only then: ``TrackingWorker.set_trace``)."""
        if not self.rejected_action.isChecked():
            self.left_feed.set_trace(())
            self.right_feed.set_trace(())
            return
        diagnostics = packet.diagnostics or (None, None)
        self.left_feed.set_trace(trace_lines(packet.result.trace, "left", diagnostics[0]))
        if packet.right is not None:
            self.right_feed.set_trace(trace_lines(packet.result.trace, "right", diagnostics[1]))

    def _slow_views(self) -> list[tuple[str, QWidget, Callable[[DisplayPacket], None]]]:
        views = []
        if self.gl_view is not None:
            views.append(("3D", self.gl_view.widget, self.gl_view.show_packet))
        views += [("plan", self.plan.widget, self.plan.show_packet),
                  ("side", self.side.widget, self.side.show_packet),
                  ("readouts", self.readouts,
                   lambda p: self.readouts.show_packet(p, self._display_rate.rate(),
                                                       self._slowed_views_hz()))]
        if self._tuning is not None:
            views.append(("tuning preview", self._tuning, self._tuning.show_preview))
        return views

    def _slowed_views_hz(self) -> float | None:
        """The court views' refresh rate while they yield to a tracker that is behind, else None."""
        return 1.0 / self._display_yield.interval if self._display_yield.slowed else None

    def packet_shown_in(self, view: str) -> DisplayPacket | None:
        """The packet a slow view ("3D", "plan", "side", "readouts", "tuning preview") shows."""
        return self._slow_shown.get(view)

    def _refresh_slow_views(self, now: float) -> None:
        """Show the newest packet in each slow view that is on screen and does not show it yet.

        A view that is hidden (window minimised, splitter collapsed, dialog closed) is skipped
        and catches up when it shows again; an unchanged packet (paused) is not redrawn.
        """
        packet = self.latest_packet
        if packet is None or self.isMinimized():
            return
        self._slow_shown_at = now
        for name, widget, show in self._slow_views():
            if self._slow_shown.get(name) is packet or not _on_screen(widget):
                continue
            self._slow_shown[name] = packet
            self.slow_view_updates[name] = self.slow_view_updates.get(name, 0) + 1
            show(packet)
        if self.worker is not None and self.worker.link_error:
            self.link_panel.status.setText(self.worker.link_error)
        if self.status_adapt.text() != packet.stats.adapt_text:
            self.status_adapt.setText(packet.stats.adapt_text)
            self.status_adapt.setToolTip(packet.stats.adapt_detail)
        self._check_keep_up(now, packet)

    def _check_keep_up(self, now: float, packet: DisplayPacket) -> None:
        """Advice lines: the faster preset when tracking has been behind the source for a while
        (gui/keep_up.py), a refit when the stereo calibration is off (gui/rig_check.py)."""
        stats = packet.stats
        advice = self._keep_up.update(now, stats, live=stats.live, paced=stats.paced,
                                      paused=self._paused, params=self.params,
                                      image_size=packet.result.left.image_size)
        if advice is not None and not self.banner.isVisible():   # an error is not covered up
            self.banner.show_message(advice, kind="advice",
                                     action=(f"Use {FAST_PRESET}", lambda: self.use_preset(FAST_PRESET)))
        if not self.banner.isVisible():
            rig_advice = self._rig_check.update(stats, packet.result.left.image_size[0])
            if rig_advice is not None:
                action = (("Swap cameras", self.swap_cameras) if rig_advice.swap and self.spec.swappable
                          else ("Refine…", self.open_refine))
                self.banner.show_message(rig_advice.text, kind="advice", action=action)

    def use_preset(self, name: str) -> None:
        """Track with a shipped preset, or a preset .json file (dropped on the window), from now
        on (as choosing it in the Tuning dialog does)."""
        try:
            params = load_preset(name)
        except (OSError, ValueError) as exc:
            self.banner.show_message(f"The {name} preset could not be loaded: {exc}")
            return
        if self._tuning is not None:
            self._tuning.apply_preset(name, params)      # shows it, and sends it here
        else:
            self.set_params(params)
            self.remember_preset(name)
        self.statusBar().showMessage(f"Tracking with the {Path(name).stem} preset", 8000)

    def remember_preset(self, name_or_path: str) -> None:
        """The parameters now come from this preset (a name, or a .json file): the tuning
        dialog's Reset goes back to it, in this session and the next."""
        self.preset = name_or_path
        st.save_preset_in_use(self.settings, name_or_path)
        if self._tuning is not None and self._tuning.preset != name_or_path:
            self._tuning.set_preset(name_or_path)

    @property
    def display_rate(self) -> float:
        return self._display_rate.rate()

    def grab_window(self) -> QPixmap:
        """The window as an image, with the GL view composited from its framebuffer."""
        pixmap = self.grab()
        if self.gl_view is not None and self.gl_view.widget.isVisible():
            image = self.gl_view.window.grabFramebuffer()
            if not image.isNull():
                painter = QPainter(pixmap)
                painter.drawImage(self.gl_view.widget.mapTo(self, QPoint(0, 0)), image)
                painter.end()
        return pixmap

    def closeEvent(self, event) -> None:  # noqa: N802 - Qt naming
        self._timer.stop()
        self._late_timer.stop()
        if self._refine is not None:
            self._refine.shutdown()
        if self._process is not None:
            self._process.close()           # cancels and waits for a running job
        self.stop_worker()
        self.stop_recording()
        if self.link_panel.link is not None:
            self.link_panel.disconnect_link()
        self._save_window_state()
        st.save_params(self.settings, self.params)
        self.settings.sync()
        super().closeEvent(event)

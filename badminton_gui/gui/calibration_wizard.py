"""The stereo calibration wizard: board → live capture → solve → result → court pose.

Why this file exists: calibrating is the first thing an operator does at a new court, and the
usual tools fail them in four ways: the window freezes during the solve, coverage feedback
counts views that were never captured, the result lands somewhere unknown, and failures give no
reason. Here the camera reading and board detection run in a QThread worker (never on the GUI
thread), the solve runs in another with progress and Cancel, the bars show only captured views,
every refusal is a sentence, and the rig is saved as ``calibration/rig_YYYYmmdd_HHMMSS.yaml``
with the full path shown and ``rigSaved(path)`` emitted so the main window can load it at once.

All the judgement (is this view good, is it new, how much is covered, which views are outliers,
the solve, the court pose) is ``core.calibrate.stereo`` and friends; these pages only render it.
Workers hand over numpy arrays and frozen results, never widgets;
the live view is a newest-wins mailbox polled at ~30 Hz.
"""

from __future__ import annotations

import html
import shutil
import threading
import time
from dataclasses import dataclass, replace
from datetime import datetime
from pathlib import Path
from typing import Callable

import cv2
import numpy as np
from PySide6.QtCore import QObject, QPointF, QRectF, QSize, Qt, QThread, QTimer, Signal
from PySide6.QtGui import (QColor, QFont, QIcon, QImage, QKeySequence, QPainter, QPen, QPixmap,
                           QShortcut)
from PySide6.QtWidgets import (QCheckBox, QComboBox, QDialog, QDoubleSpinBox, QFileDialog,
                               QFormLayout, QGridLayout, QGroupBox, QHBoxLayout, QLabel,
                               QListWidget, QListWidgetItem, QProgressBar, QPushButton,
                               QScrollArea, QSizePolicy, QSpinBox, QStackedWidget,
                               QVBoxLayout, QWidget)

from ..core.calibrate.board import (BoardError, BoardSpec, charuco_available, detect_board,
                                to_gray)
from ..core.calibrate.court_pose import CourtClicks, CourtPoseResult
from ..core.calibrate.coverage import COVERAGE_NAMES, Coverage
from ..core.calibrate.folders import pair_image_files, views_from_pairs
from ..core.calibrate.stereo import (EPIPOLAR_ACCEPTABLE_PX, EPIPOLAR_EXCELLENT_PX,
                                CalibrationCancelled, CalibrationError, CalibrationResult,
                                CaptureGate, CaptureVerdict,
                                RejectedView, SolveOptions, StereoView, pair_detections,
                                rectified_preview, solve_stereo)
from ..core.court import court_lines
from ..core.rig import RigError, StereoRig
from ..io.app_dirs import rig_dir
from ..io.sources import FrameSource, SourceError
from . import settings as st

# The checkout's calibration/ folder, or a per-user folder when the package is installed.
DEFAULT_SAVE_DIR = rig_dir()
DISPLAY_MAX_WIDTH = 640          # the worker shrinks frames to this before handing them over
SEARCH_MAX_SIDE = 800            # board search resolution in live use (refined at full res)
GRADE_COLOURS = {"excellent": "#1b8a2e", "acceptable": "#b07800", "poor": "#c0392b"}
PAGE_TITLES = ("Board", "Capture", "Calibrate", "Result", "Court pose")


def write_rig(rig: StereoRig, path: Path) -> str | None:
    """Save and read back; None on success, else a sentence saying why it failed (the wizard
    and the refine dialog save rigs through this)."""
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        if shutil.disk_usage(path.parent).free < 256 * 1024:
            return f"the disk holding {path.parent} is full"
        rig.save(path)
        StereoRig.load(path)          # a full disk can leave a truncated file: check
    except PermissionError:
        return f"no permission to write in {path.parent}"
    except OSError as exc:
        return f"{exc.strerror or exc} ({path})"
    except RigError as exc:
        return f"{exc} (is the disk full or the folder read-only?)"
    return None


# ---- data handed from workers to the GUI ----------------------------------------------------
@dataclass(frozen=True, slots=True)
class LiveFrame:
    """The newest processed frame pair, shrunk for display with the corners drawn."""

    serial: int
    left: np.ndarray
    right: np.ndarray
    verdict: CaptureVerdict | None
    coverage: tuple[Coverage, Coverage]
    frames_read: int
    full_left: np.ndarray            # full-resolution left frame (court-pose step)


@dataclass(frozen=True, slots=True)
class CapturedPair:
    capture_id: int
    view: StereoView
    thumbnail: np.ndarray            # small side-by-side BGR
    images: tuple | None             # full-resolution (left, right), kept for the last one
    image_size: tuple[int, int]


@dataclass(frozen=True, slots=True)
class SolveOutcome:
    result: CalibrationResult
    skipped: tuple[RejectedView, ...]
    preview: np.ndarray | None


def _shrink(image: np.ndarray) -> tuple[np.ndarray, float]:
    h, w = image.shape[:2]
    scale = min(1.0, DISPLAY_MAX_WIDTH / w)
    if scale == 1.0:
        return image.copy(), 1.0
    return cv2.resize(image, (round(w * scale), round(h * scale)),
                      interpolation=cv2.INTER_AREA), scale


def _short_id(view_id: str) -> str:
    """A folder view is named "left07.jpg|right07.jpg": the left name is enough on screen."""
    return view_id.split("|")[0]


def _draw_corners(image: np.ndarray, det, scale: float, good: bool) -> np.ndarray:
    if image.ndim == 2:
        image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
    if det is None:
        return image
    pts = det.corners * scale
    colour = (60, 200, 60) if good else (0, 140, 255)
    for x, y in pts:
        cv2.circle(image, (int(round(x)), int(round(y))), 3, colour, 1, cv2.LINE_AA)
    poly = pts.reshape(-1, 1, 2).astype(np.int32)
    cv2.polylines(image, [poly], False, colour, 1, cv2.LINE_AA)
    return image


# ---- workers --------------------------------------------------------------------------------
class CaptureWorker(QObject):
    """Reads frame pairs, detects the board, judges and captures views (its own thread)."""

    captured = Signal(object)        # CapturedPair
    refused = Signal(str)            # manual capture refused, with the reason
    failed = Signal(str)
    finished = Signal()

    def __init__(self, source_factory: Callable[[], FrameSource], spec: BoardSpec,
                 existing: list[tuple[int, tuple]], next_id: int, auto: bool) -> None:
        super().__init__()
        self._factory = source_factory
        self._spec = spec
        self._gate = CaptureGate(spec)
        self._ids: list[int] = []
        for capture_id, params in existing:
            self._gate.captured_params.append(params)
            self._ids.append(capture_id)
        self._next_id = next_id
        self._auto = auto
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._latest: LiveFrame | None = None
        self._capture_requested = False
        self._to_remove: list[int] = []

    # thread-safe commands from the GUI
    def stop(self) -> None:
        self._stop.set()

    def set_auto(self, on: bool) -> None:
        with self._lock:
            self._auto = bool(on)

    def request_capture(self) -> None:
        with self._lock:
            self._capture_requested = True

    def remove(self, capture_id: int) -> None:
        with self._lock:
            self._to_remove.append(capture_id)

    def latest(self) -> LiveFrame | None:
        with self._lock:
            return self._latest

    def run(self) -> None:
        source = None
        try:
            source = self._factory()
            self._loop(source)
        except SourceError as exc:
            self.failed.emit(str(exc))
        except (OSError, cv2.error, ValueError) as exc:
            self.failed.emit(f"the camera source failed: {exc}")
        finally:
            if source is not None:
                try:
                    source.close()
                except (OSError, SourceError, RuntimeError):
                    pass
            self.finished.emit()

    def _loop(self, source: FrameSource) -> None:
        serial = 0
        while not self._stop.is_set():
            with self._lock:
                auto = self._auto
                manual, self._capture_requested = self._capture_requested, False
                removals, self._to_remove = self._to_remove, []
            for capture_id in removals:
                if capture_id in self._ids:
                    index = self._ids.index(capture_id)
                    self._gate.remove(index)
                    del self._ids[index]
            frame = source.read()
            if frame is None:
                self.failed.emit("the source ended")
                return
            gray_l, gray_r = to_gray(frame.left), to_gray(frame.right)
            det_l = detect_board(gray_l, self._spec, SEARCH_MAX_SIDE)
            det_r = detect_board(gray_r, self._spec, SEARCH_MAX_SIDE)
            verdict = self._gate.evaluate(det_l, det_r, gray_l, gray_r)
            if (auto and verdict.auto_capture) or manual:
                if verdict.acceptable:
                    self._capture(frame, det_l, det_r)
                elif manual:
                    self.refused.emit(verdict.reasons[0] if verdict.reasons else "not capturable")
            small_l, scale = _shrink(frame.left)
            small_r, _ = _shrink(frame.right)
            live = LiveFrame(serial, _draw_corners(small_l, det_l, scale, verdict.acceptable),
                             _draw_corners(small_r, det_r, scale, verdict.acceptable), verdict,
                             self._gate.coverage(), serial + 1, frame.left)
            serial += 1
            with self._lock:
                self._latest = live

    def _capture(self, frame, det_l, det_r) -> None:
        try:
            view = pair_detections(f"#{self._next_id}", det_l, det_r, self._spec)
        except CalibrationError as exc:
            self.refused.emit(str(exc))
            return
        self._gate.add(det_l, det_r)
        self._ids.append(self._next_id)
        thumb_l = cv2.resize(frame.left, (120, round(120 * frame.left.shape[0]
                                                     / frame.left.shape[1])))
        thumb_r = cv2.resize(frame.right, thumb_l.shape[1::-1])
        h, w = frame.left.shape[:2]
        self.captured.emit(CapturedPair(self._next_id, view, np.hstack([thumb_l, thumb_r]),
                                        (frame.left, frame.right), (w, h)))
        self._next_id += 1

    def params_of(self) -> list[tuple[int, tuple]]:
        return list(zip(self._ids, self._gate.captured_params))


class SolveWorker(QObject):
    """Runs the board detection (folder mode) and the solve; never touches widgets."""

    progress = Signal(float, str)
    succeeded = Signal(object)       # SolveOutcome
    failed = Signal(str)
    cancelled = Signal()
    finished = Signal()

    def __init__(self, spec: BoardSpec, views: list[StereoView] | None = None,
                 image_size: tuple[int, int] | None = None, preview_pair: tuple | None = None,
                 folders: tuple[Path, Path] | None = None) -> None:
        super().__init__()
        self._spec = spec
        self._views = views
        self._size = image_size
        self._preview_pair = preview_pair
        self._folders = folders
        self._cancel = threading.Event()

    def cancel(self) -> None:
        self._cancel.set()

    def run(self) -> None:
        try:
            skipped: tuple = ()
            views, size, pair = self._views, self._size, self._preview_pair
            solve_from, solve_span = 0.0, 1.0
            if self._folders is not None:
                pairs = pair_image_files(*self._folders)
                found = views_from_pairs(
                    pairs, self._spec, cancel=self._cancel.is_set,
                    progress=lambda f, text: self.progress.emit(0.4 * f, text))
                views, size, skipped = list(found.views), found.image_size, found.skipped
                first = next(p for p in pairs if p[0].name in {v.view_id.split("|")[0]
                                                               for v in views})
                pair = (cv2.imread(str(first[0])), cv2.imread(str(first[1])))
                solve_from, solve_span = 0.4, 0.6
            result = solve_stereo(
                views, size, self._spec, SolveOptions(), cancel=self._cancel.is_set,
                progress=lambda f, text: self.progress.emit(solve_from + solve_span * f, text))
            preview = None
            if pair is not None and pair[0] is not None and pair[1] is not None:
                preview = rectified_preview(result, pair[0], pair[1])
            self.succeeded.emit(SolveOutcome(result, tuple(skipped), preview))
        except CalibrationCancelled:
            self.cancelled.emit()
        except CalibrationError as exc:
            self.failed.emit(str(exc))
        except cv2.error as exc:
            self.failed.emit(f"OpenCV failed: {str(exc).strip().splitlines()[-1]}")
        finally:
            self.finished.emit()


class FrameGrabber(QObject):
    """Takes one frame pair from a fresh source (court-pose step), in its own thread."""

    grabbed = Signal(object)
    failed = Signal(str)
    finished = Signal()

    def __init__(self, source_factory: Callable[[], FrameSource]) -> None:
        super().__init__()
        self._factory = source_factory

    def run(self) -> None:
        try:
            source = self._factory()
            try:
                frame = source.read()
            finally:
                source.close()
            if frame is None:
                self.failed.emit("the source gave no frame")
            else:
                self.grabbed.emit(frame.left)
        except (SourceError, OSError, cv2.error, ValueError) as exc:
            self.failed.emit(str(exc))
        finally:
            self.finished.emit()


def _start(owner: QObject, worker: QObject) -> QThread:
    thread = QThread(owner)
    worker.moveToThread(thread)
    thread.started.connect(worker.run)
    worker.finished.connect(thread.quit)
    thread.start()
    return thread


# ---- widgets --------------------------------------------------------------------------------
def _qimage(image: np.ndarray) -> QImage:
    image = np.ascontiguousarray(image)
    h, w = image.shape[:2]
    if image.ndim == 2:
        return QImage(image.data, w, h, image.strides[0], QImage.Format.Format_Grayscale8).copy()
    return QImage(image.data, w, h, image.strides[0], QImage.Format.Format_BGR888).copy()


class ImageView(QWidget):
    """A numpy image scaled to fit, with optional marked points; clicks in image pixels."""

    clicked = Signal(float, float)

    def __init__(self, placeholder: str = "", parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._qimage: QImage | None = None
        self._image_size = (1, 1)
        self._points: list[tuple[float, float, QColor, str]] = []
        self._placeholder = placeholder
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Expanding)
        self.setMinimumSize(200, 150)

    def sizeHint(self) -> QSize:
        return QSize(400, 300)

    def set_image(self, image: np.ndarray | None, full_size: tuple[int, int] | None = None) -> None:
        """``full_size``: the (w, h) that point and click coordinates refer to."""
        self._qimage = None if image is None else _qimage(image)
        if image is not None:
            self._image_size = full_size or (image.shape[1], image.shape[0])
        self.update()

    def set_placeholder(self, text: str) -> None:
        self._placeholder = text
        self.update()

    def set_points(self, points: list[tuple[float, float, QColor, str]]) -> None:
        self._points = points
        self.update()

    def image_rect(self) -> QRectF:
        if self._qimage is None:
            return QRectF(self.rect())
        iw, ih = self._qimage.width(), self._qimage.height()
        k = min(self.width() / iw, self.height() / ih)
        return QRectF((self.width() - iw * k) / 2, (self.height() - ih * k) / 2, iw * k, ih * k)

    def to_widget(self, x: float, y: float) -> QPointF:
        r = self.image_rect()
        return QPointF(r.left() + (x + 0.5) * r.width() / self._image_size[0],
                       r.top() + (y + 0.5) * r.height() / self._image_size[1])

    def to_image(self, px: float, py: float) -> tuple[float, float]:
        r = self.image_rect()
        return ((px - r.left()) * self._image_size[0] / r.width() - 0.5,
                (py - r.top()) * self._image_size[1] / r.height() - 0.5)

    def mousePressEvent(self, event) -> None:  # noqa: N802 - Qt naming
        if self._qimage is None or event.button() != Qt.MouseButton.LeftButton:
            return
        pos = event.position()
        if self.image_rect().contains(pos):
            self.clicked.emit(*self.to_image(pos.x(), pos.y()))

    def paintEvent(self, event) -> None:  # noqa: N802 - Qt naming
        p = QPainter(self)
        p.fillRect(self.rect(), QColor(28, 28, 32))
        if self._qimage is None:
            p.setPen(QColor(200, 200, 200))
            p.drawText(self.rect(), Qt.AlignmentFlag.AlignCenter | Qt.TextFlag.TextWordWrap,
                       self._placeholder)
        else:
            # Smooth scaling keeps thin lines (rectification guides, corners) visible.
            p.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform, True)
            p.drawImage(self.image_rect(), self._qimage)
            p.setRenderHint(QPainter.RenderHint.Antialiasing, True)
            for x, y, colour, label in self._points:
                c = self.to_widget(x, y)
                p.setPen(QPen(colour, 2))
                p.drawEllipse(c, 6, 6)
                p.drawLine(QPointF(c.x() - 10, c.y()), QPointF(c.x() + 10, c.y()))
                p.drawLine(QPointF(c.x(), c.y() - 10), QPointF(c.x(), c.y() + 10))
                if label:
                    p.drawText(QPointF(c.x() + 8, c.y() - 8), label)
        p.end()


class CourtDiagram(QWidget):
    """A small top view of the court; the keypoint to click next is highlighted."""

    def __init__(self, clicks: CourtClicks, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.clicks = clicks
        self.setMinimumSize(150, 280)

    def sizeHint(self) -> QSize:
        return QSize(170, 320)

    def _map(self, x: float, y: float) -> QPointF:
        # Room at the top for the far points' numbers, at the bottom for the caption.
        margin, top, label = 12, 20, 18
        k = min((self.width() - 2 * margin) / 6.1, (self.height() - top - margin - label) / 13.4)
        cx, cy = self.width() / 2, top + (self.height() - top - margin - label) / 2
        return QPointF(cx + x * k, cy - y * k)      # far side (+Y) at the top

    def paintEvent(self, event) -> None:  # noqa: N802 - Qt naming
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing, True)
        p.fillRect(self.rect(), QColor(34, 110, 70))
        p.setPen(QPen(QColor(240, 240, 240), 1.5))
        for line in court_lines():
            p.drawLine(self._map(*line.start), self._map(*line.end))
        p.setPen(QPen(QColor(250, 250, 250), 1, Qt.PenStyle.DashLine))
        p.drawLine(self._map(-3.3, 0), self._map(3.3, 0))        # the net
        current = self.clicks.current_name
        small = QFont(self.font())
        small.setPointSizeF(max(6.0, small.pointSizeF() * 0.8))
        small.setBold(True)
        p.setFont(small)
        for number, name in enumerate(self.clicks.order, 1):
            x, y, _ = self.clicks.keypoints[name]
            c = self._map(x, y)
            # The same number labels the click on the camera image, so the two can be matched.
            p.setPen(QColor(255, 255, 255))
            side = -1 if x < 0 else 1
            text_x = c.x() + (10 if side > 0 else -24) if x != 0 else c.x() + 6
            p.drawText(QRectF(text_x, c.y() - 16, 18, 14),
                       Qt.AlignmentFlag.AlignCenter, str(number))
            if name == current:
                p.setPen(QPen(QColor(255, 60, 60), 3))
                p.setBrush(QColor(255, 220, 0))
                p.drawEllipse(c, 7, 7)
            elif name in self.clicks.clicked:
                p.setPen(QPen(QColor(20, 20, 20), 1))
                p.setBrush(QColor(80, 220, 90))
                p.drawEllipse(c, 4, 4)
            else:
                p.setPen(QPen(QColor(20, 20, 20), 1))
                p.setBrush(QColor(200, 200, 200))
                p.drawEllipse(c, 3, 3)
        p.setPen(QColor(255, 255, 255))
        p.drawText(QRectF(0, self.height() - 16, self.width(), 16),
                   Qt.AlignmentFlag.AlignCenter, "near side (camera)")
        p.end()


def _bar(name: str) -> QProgressBar:
    bar = QProgressBar()
    bar.setRange(0, 100)
    bar.setFormat(f"{name} %p%")
    bar.setTextVisible(True)
    return bar


# ---- the wizard -----------------------------------------------------------------------------
class CalibrationWizard(QDialog):
    """Five pages: board, live capture, calibrate, result (save), court pose (save)."""

    rigSaved = Signal(str)  # noqa: N815 - Qt signal naming

    PAGE_BOARD, PAGE_CAPTURE, PAGE_SOLVE, PAGE_RESULT, PAGE_COURT = range(5)

    def __init__(self, source_factory: Callable[[], FrameSource], parent: QWidget | None = None,
                 save_dir: Path = DEFAULT_SAVE_DIR) -> None:
        super().__init__(parent)
        self.setWindowTitle("Stereo calibration")
        self.resize(1180, 700)
        self._factory = source_factory
        self.save_dir = Path(save_dir)
        self.spec = BoardSpec()
        self.captures: list[CapturedPair] = []
        self._params: list[tuple[int, tuple]] = []   # kept across worker restarts
        self._next_id = 1
        self._capture_worker: CaptureWorker | None = None
        self._capture_thread: QThread | None = None
        self._solve_worker: SolveWorker | None = None
        self._solve_thread: QThread | None = None
        self._grab_thread: QThread | None = None
        self._grabber: FrameGrabber | None = None
        self._last_serial = -1
        self._frames_shown = 0
        self._notice: tuple[str, float] | None = None
        self._latest_left: np.ndarray | None = None
        self._folders: tuple[Path, Path] | None = None
        self.outcome: SolveOutcome | None = None
        self.saved_path: Path | None = None
        self.court_result: CourtPoseResult | None = None
        self.clicks = CourtClicks()
        self._court_image: np.ndarray | None = None

        self.stack = QStackedWidget()
        self.stack.addWidget(self._build_board_page())
        self.stack.addWidget(self._build_capture_page())
        self.stack.addWidget(self._build_solve_page())
        self.stack.addWidget(self._build_result_page())
        self.stack.addWidget(self._build_court_page())

        self.step_label = QLabel()
        f = QFont(self.step_label.font())
        f.setPointSizeF(f.pointSizeF() * 1.25)
        f.setBold(True)
        self.step_label.setFont(f)
        self.back_button = QPushButton("< Back")
        self.next_button = QPushButton("Next >")
        self.close_button = QPushButton("Close")
        self.back_button.clicked.connect(self.go_back)
        self.next_button.clicked.connect(self.go_next)
        self.close_button.clicked.connect(self.close)
        nav = QHBoxLayout()
        nav.addStretch(1)
        for b in (self.back_button, self.next_button, self.close_button):
            nav.addWidget(b)
        layout = QVBoxLayout(self)
        layout.addWidget(self.step_label)
        layout.addWidget(self.stack, 1)
        layout.addLayout(nav)

        self._poll = QTimer(self)
        self._poll.setInterval(33)            # display at ≤ 30 Hz whatever the camera rate
        self._poll.timeout.connect(self._show_latest)
        self._set_page(self.PAGE_BOARD)

    # ---- navigation -------------------------------------------------------------------------
    def _set_page(self, index: int) -> None:
        if self.stack.currentIndex() == self.PAGE_CAPTURE and index != self.PAGE_CAPTURE:
            self._stop_capture()
        self.stack.setCurrentIndex(index)
        self.step_label.setText(f"Step {index + 1} of {len(PAGE_TITLES)}: {PAGE_TITLES[index]}"
                                f"   ·   " + "  →  ".join(PAGE_TITLES))
        if index == self.PAGE_CAPTURE:
            self._start_capture()
        if index == self.PAGE_COURT:
            self._enter_court_page()
        self._update_nav()

    def _update_nav(self) -> None:
        page = self.stack.currentIndex()
        solving = self._solve_thread is not None
        self.back_button.setEnabled(page > 0 and not solving)
        if page == self.PAGE_CAPTURE:
            self.next_button.setText("Calibrate >")
            self.next_button.setEnabled(len(self.captures) >= SolveOptions().min_views)
        elif page == self.PAGE_SOLVE:
            self.next_button.setText("Next >")
            self.next_button.setEnabled(self.outcome is not None and not solving)
        elif page == self.PAGE_COURT:
            self.next_button.setText("Next >")
            self.next_button.setEnabled(False)
        else:
            self.next_button.setText("Next >")
            self.next_button.setEnabled(True)

    def go_next(self) -> None:
        page = self.stack.currentIndex()
        if page == self.PAGE_BOARD:
            if not self._apply_board():
                return
            self._set_page(self.PAGE_CAPTURE)
        elif page == self.PAGE_CAPTURE:
            self._folders = None
            self._set_page(self.PAGE_SOLVE)
            self.start_solve()
        elif page in (self.PAGE_SOLVE, self.PAGE_RESULT):
            self._set_page(page + 1)

    def go_back(self) -> None:
        page = self.stack.currentIndex()
        if page == self.PAGE_RESULT:
            self._set_page(self.PAGE_CAPTURE)
        elif page > 0:
            self._set_page(page - 1)

    # ---- page (a): board --------------------------------------------------------------------
    def _build_board_page(self) -> QWidget:
        page = QWidget()
        form = QFormLayout()
        self.cols_spin = QSpinBox()
        self.cols_spin.setRange(3, 30)
        self.cols_spin.setValue(9)
        self.rows_spin = QSpinBox()
        self.rows_spin.setRange(2, 30)
        self.rows_spin.setValue(6)
        self.square_spin = QDoubleSpinBox()
        self.square_spin.setRange(1.0, 500.0)
        self.square_spin.setDecimals(2)
        self.square_spin.setSuffix(" mm")
        self.square_spin.setValue(25.0)
        self.kind_combo = QComboBox()
        self.kind_combo.addItem("Chessboard", "chessboard")
        self.kind_combo.addItem("ChArUco board", "charuco")
        if not charuco_available():
            self.kind_combo.model().item(1).setEnabled(False)
            self.kind_combo.setItemText(1, "ChArUco board (not in this OpenCV build)")
        form.addRow("Inner corners across:", self.cols_spin)
        form.addRow("Inner corners down:", self.rows_spin)
        form.addRow("Square size:", self.square_spin)
        form.addRow("Board type:", self.kind_combo)
        help_text = QLabel(
            "Count the <b>inner</b> corners, where four squares meet: a board of 10 × 7 "
            "squares has 9 × 6 inner corners. Measure one square on the printed board with a "
            "ruler; it sets the unit of every distance the tracker reports.<br><br>"
            "Then show the board to both cameras at many positions, distances and tilts. "
            "Hold it still: views are captured automatically when the board is still and the "
            "pose adds coverage.")
        help_text.setWordWrap(True)
        self.board_error = QLabel()
        self.board_error.setStyleSheet("color: #c0392b; font-weight: bold")
        self.board_error.setWordWrap(True)
        layout = QVBoxLayout(page)
        box = QGroupBox("Calibration board")
        box.setLayout(form)
        layout.addWidget(box)
        layout.addWidget(help_text)
        layout.addWidget(self.board_error)
        layout.addStretch(1)
        return page

    def _apply_board(self) -> bool:
        try:
            spec = BoardSpec(self.cols_spin.value(), self.rows_spin.value(),
                             self.square_spin.value() / 1000.0, kind=self.kind_combo.currentData())
        except BoardError as exc:
            self.board_error.setText(str(exc))
            return False
        self.board_error.setText("")
        if spec != self.spec and self.captures:
            self.clear_captures()
        self.spec = spec
        return True

    # ---- page (b): capture ------------------------------------------------------------------
    def _build_capture_page(self) -> QWidget:
        page = QWidget()
        self.left_view = ImageView("starting the cameras…")
        self.right_view = ImageView("starting the cameras…")
        feeds = QHBoxLayout()
        feeds.addWidget(self.left_view)
        feeds.addWidget(self.right_view)

        bars = QGridLayout()
        self.coverage_bars: dict[str, list[QProgressBar]] = {"left": [], "right": []}
        for col, cam in enumerate(("left", "right")):
            bars.addWidget(QLabel(f"<b>{cam.capitalize()} camera coverage</b> "
                                  f"(captured views only)"), 0, col)
            for row, name in enumerate(COVERAGE_NAMES):
                bar = _bar(name)
                self.coverage_bars[cam].append(bar)
                bars.addWidget(bar, row + 1, col)

        self.status_label = QLabel("")
        self.status_label.setWordWrap(True)
        self.status_label.setMinimumHeight(40)
        self.auto_check = QCheckBox("Capture automatically when the board is still and the "
                                    "view is new")
        self.auto_check.setChecked(True)
        self.auto_check.toggled.connect(self._auto_toggled)
        self.capture_button = QPushButton("Capture now")
        self.capture_button.clicked.connect(self.capture_now)
        self.folders_button = QPushButton("Calibrate from two image folders…")
        self.folders_button.clicked.connect(self._choose_folders)
        buttons = QHBoxLayout()
        buttons.addWidget(self.auto_check, 1)
        restart = QPushButton("Restart camera")
        restart.setToolTip("Close and reopen the cameras (after a camera error)")
        restart.clicked.connect(self.restart_capture)
        buttons.addWidget(restart)
        buttons.addWidget(self.capture_button)
        buttons.addWidget(self.folders_button)

        self.thumb_list = QListWidget()
        self.thumb_list.setViewMode(QListWidget.ViewMode.IconMode)
        self.thumb_list.setIconSize(QSize(240, 45))
        self.thumb_list.setFlow(QListWidget.Flow.LeftToRight)
        self.thumb_list.setWrapping(False)
        self.thumb_list.setFixedHeight(84)
        self.thumb_list.setSelectionMode(QListWidget.SelectionMode.ExtendedSelection)
        self.remove_button = QPushButton("Remove selected")
        self.remove_button.clicked.connect(self.remove_selected)
        delete = QShortcut(QKeySequence(QKeySequence.StandardKey.Delete), self.thumb_list)
        delete.activated.connect(self.remove_selected)
        self.count_label = QLabel("0 views captured")
        thumbs_head = QHBoxLayout()
        thumbs_head.addWidget(self.count_label, 1)
        thumbs_head.addWidget(self.remove_button)

        layout = QVBoxLayout(page)
        layout.addLayout(feeds, 1)
        layout.addLayout(bars)
        layout.addWidget(self.status_label)
        layout.addLayout(buttons)
        layout.addLayout(thumbs_head)
        layout.addWidget(self.thumb_list)
        return page

    def _start_capture(self) -> None:
        if self._capture_thread is not None and not self._capture_thread.isRunning():
            self._stop_capture()           # the previous worker ended (source failed)
        if self._capture_thread is not None:
            return
        self._last_serial = -1
        self._frames_shown = 0
        self.status_label.setText("starting the cameras…")
        for view in (self.left_view, self.right_view):     # no stale frame from a past run
            view.set_image(None)
            view.set_placeholder("starting the cameras…")
        worker = CaptureWorker(self._factory, self.spec, list(self._params), self._next_id,
                               self.auto_check.isChecked())
        worker.captured.connect(self._on_captured)
        worker.refused.connect(self._on_refused)
        worker.failed.connect(self._on_capture_failed)
        self._capture_worker = worker
        self._capture_thread = _start(self, worker)
        self._poll.start()

    def _stop_capture(self) -> None:
        self._poll.stop()
        if self._capture_thread is None:
            return
        self._capture_worker.stop()
        self._capture_thread.quit()
        self._capture_thread.wait()
        self._params = self._capture_worker.params_of()
        self._capture_thread = None
        self._capture_worker = None

    def restart_capture(self) -> None:
        self._stop_capture()
        self._start_capture()

    def _auto_toggled(self, on: bool) -> None:
        if self._capture_worker is not None:
            self._capture_worker.set_auto(on)

    def capture_now(self) -> None:
        if self._capture_worker is not None:
            self._capture_worker.request_capture()

    def _show_latest(self) -> None:
        if self._capture_worker is None:
            return
        live = self._capture_worker.latest()
        if live is None or live.serial == self._last_serial:
            return
        self._last_serial = live.serial
        self._frames_shown += 1
        size = (live.full_left.shape[1], live.full_left.shape[0])
        self.left_view.set_image(live.left, size)
        self.right_view.set_image(live.right, size)
        self._latest_left = live.full_left
        for cam, cov in zip(("left", "right"), live.coverage):
            for bar, value in zip(self.coverage_bars[cam], cov.as_tuple()):
                bar.setValue(round(100 * value))
        self.status_label.setText(self._status_text(live))

    def _status_text(self, live: LiveFrame) -> str:
        notice = ""
        if self._notice and time.monotonic() < self._notice[1]:
            notice = f"<span style='color:#c0392b'><b>{self._notice[0]}</b></span><br>"
        return notice + self._verdict_text(live)

    def _verdict_text(self, live: LiveFrame) -> str:
        v = live.verdict
        skipped = live.frames_read - self._frames_shown
        tail = f"<br><span style='color:#777'>frames read {live.frames_read}, not displayed " \
               f"{max(skipped, 0)} (display limited to 30 Hz)</span>"
        if v is None:
            return "…" + tail
        if not (v.found_left and v.found_right):
            missing = [n for n, f in (("left", v.found_left), ("right", v.found_right)) if not f]
            return (f"<span style='color:#c0392b'>board not found in the {' and '.join(missing)}"
                    f" image</span>: show the whole board to both cameras" + tail)
        if v.reasons:
            return f"<span style='color:#b07800'>{'<br>'.join(v.reasons[:3])}</span>" + tail
        if not v.is_new:
            return ("<span style='color:#b07800'>good view, but too similar to one already "
                    "captured: move, tilt or bring the board closer</span>" + tail)
        return "<span style='color:#1b8a2e'>good new view</span>" + tail

    def _on_captured(self, pair: CapturedPair) -> None:
        # Keep full-resolution images of the newest capture only (for the rectified preview).
        self.captures = [replace(c, images=None) for c in self.captures] + [pair]
        self._next_id = pair.capture_id + 1
        item = QListWidgetItem(QIcon(QPixmap.fromImage(_qimage(pair.thumbnail))),
                               f"#{pair.capture_id}")
        item.setData(Qt.ItemDataRole.UserRole, pair.capture_id)
        self.thumb_list.addItem(item)
        self.thumb_list.scrollToItem(item)
        self._update_count()

    def _update_count(self) -> None:
        n = len(self.captures)
        need = SolveOptions().min_views
        self.count_label.setText(f"{n} view{'s' if n != 1 else ''} captured"
                                 + (f" (at least {need} needed)" if n < need else ""))
        self._update_nav()

    def _on_refused(self, reason: str) -> None:
        # Shown for a few seconds on top of the live status, which is redrawn every frame.
        self._notice = (f"not captured: {reason}", time.monotonic() + 3.0)
        self.status_label.setText(f"<span style='color:#c0392b'>not captured: {reason}</span>")

    def _on_capture_failed(self, message: str) -> None:
        self.status_label.setText(f"<span style='color:#c0392b'>camera problem: {message}</span>")
        self.left_view.set_image(None)
        self.left_view.set_placeholder(message)

    def remove_selected(self) -> None:
        ids = {item.data(Qt.ItemDataRole.UserRole) for item in self.thumb_list.selectedItems()}
        self.remove_captures(ids)

    def remove_captures(self, ids: set[int]) -> None:
        for capture_id in ids:
            if self._capture_worker is not None:
                self._capture_worker.remove(capture_id)
        self._params = [p for p in self._params if p[0] not in ids]
        self.captures = [c for c in self.captures if c.capture_id not in ids]
        for row in reversed(range(self.thumb_list.count())):
            if self.thumb_list.item(row).data(Qt.ItemDataRole.UserRole) in ids:
                self.thumb_list.takeItem(row)
        self._update_count()

    def clear_captures(self) -> None:
        self.remove_captures({c.capture_id for c in self.captures})
        self._params = []

    def _choose_folders(self) -> None:
        settings = st.open_settings()
        left = QFileDialog.getExistingDirectory(self, "Folder of LEFT camera images",
                                                st.dialog_folder(settings, "images"))
        if not left:
            return
        # The right camera's folder is usually the left one's sibling.
        right = QFileDialog.getExistingDirectory(self, "Folder of RIGHT camera images", str(Path(left).parent))
        if not right:
            return
        st.remember_dialog_folder(settings, "images", str(Path(left).parent))
        self.calibrate_from_folders(Path(left), Path(right))

    def calibrate_from_folders(self, left_dir: Path, right_dir: Path) -> None:
        """Calibrate from still images paired by sorted file name (same rules as the CLI)."""
        self._folders = (Path(left_dir), Path(right_dir))
        self._set_page(self.PAGE_SOLVE)
        self.start_solve()

    # ---- page (c): solve --------------------------------------------------------------------
    def _build_solve_page(self) -> QWidget:
        page = QWidget()
        self.solve_label = QLabel("")
        self.solve_label.setWordWrap(True)
        self.solve_bar = QProgressBar()
        self.solve_bar.setRange(0, 1000)
        self.cancel_button = QPushButton("Cancel")
        self.cancel_button.clicked.connect(self.cancel_solve)
        self.retry_button = QPushButton("Calibrate again")
        self.retry_button.clicked.connect(self.start_solve)
        self.solve_error = QLabel("")
        self.solve_error.setWordWrap(True)
        self.solve_error.setStyleSheet("color: #c0392b; font-weight: bold")
        row = QHBoxLayout()
        row.addWidget(self.solve_bar, 1)
        row.addWidget(self.cancel_button)
        row.addWidget(self.retry_button)
        layout = QVBoxLayout(page)
        layout.addStretch(1)
        layout.addWidget(self.solve_label)
        layout.addLayout(row)
        layout.addWidget(self.solve_error)
        note = QLabel("The solve runs in the background: the window stays responsive and "
                      "Cancel stops it between stages.")
        note.setStyleSheet("color: #777")
        layout.addWidget(note)
        layout.addStretch(2)
        return page

    def start_solve(self) -> None:
        if self._solve_thread is not None:
            return
        self.outcome = None
        self.solve_error.setText("")
        self.solve_bar.setValue(0)
        self.retry_button.setEnabled(False)
        self.cancel_button.setEnabled(True)
        if self._folders is not None:
            self.solve_label.setText(f"Calibrating from {self._folders[0]} and "
                                     f"{self._folders[1]}…")
            worker = SolveWorker(self.spec, folders=self._folders)
        else:
            views = [c.view for c in self.captures]
            last = next((c for c in reversed(self.captures) if c.images is not None), None)
            size = self.captures[0].image_size if self.captures else (0, 0)
            self.solve_label.setText(f"Calibrating from {len(views)} captured views…")
            worker = SolveWorker(self.spec, views, size, last.images if last else None)
        worker.progress.connect(self._on_solve_progress)
        worker.succeeded.connect(self._on_solved)
        worker.failed.connect(self._on_solve_failed)
        worker.cancelled.connect(self._on_solve_cancelled)
        worker.finished.connect(self._on_solve_finished)
        self._solve_worker = worker
        self._solve_thread = _start(self, worker)
        self._update_nav()

    def cancel_solve(self) -> None:
        if self._solve_worker is not None:
            self._solve_worker.cancel()
            self.solve_label.setText("Cancelling after the current stage…")
            self.cancel_button.setEnabled(False)

    def _on_solve_progress(self, fraction: float, text: str) -> None:
        self.solve_bar.setValue(round(1000 * fraction))
        self.solve_label.setText(f"{text}…")

    def _on_solved(self, outcome: SolveOutcome) -> None:
        self.outcome = outcome
        self.solve_label.setText("Calibration finished.")
        self._show_result(outcome)

    def _on_solve_failed(self, message: str) -> None:
        self.solve_label.setText("Calibration failed.")
        self.solve_error.setText(message)

    def _on_solve_cancelled(self) -> None:
        self.solve_label.setText("Calibration cancelled: nothing was changed.")

    def _on_solve_finished(self) -> None:
        if self._solve_thread is not None:
            self._solve_thread.quit()
            self._solve_thread.wait()
        self._solve_thread = None
        self._solve_worker = None
        self.cancel_button.setEnabled(False)
        self.retry_button.setEnabled(True)
        self._update_nav()
        if self.outcome is not None and self.stack.currentIndex() == self.PAGE_SOLVE:
            self._set_page(self.PAGE_RESULT)

    # ---- page (d): result -------------------------------------------------------------------
    def _build_result_page(self) -> QWidget:
        page = QWidget()
        self.epipolar_label = QLabel()
        f = QFont(self.epipolar_label.font())
        f.setPointSizeF(f.pointSizeF() * 1.3)
        f.setBold(True)
        self.epipolar_label.setFont(f)
        self.figures_label = QLabel()
        self.figures_label.setWordWrap(True)
        self.figures_label.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.view_errors_label = QLabel()
        self.view_errors_label.setWordWrap(True)
        self.rejected_label = QLabel()
        self.rejected_label.setWordWrap(True)
        self.preview_view = ImageView("no rectified preview")
        self.save_button = QPushButton("Save rig")
        self.save_button.clicked.connect(self.save_rig)
        self.save_label = QLabel("")
        self.save_label.setWordWrap(True)
        self.save_label.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        # Figures on top, the rectified pair (twice as wide as high) across the full width
        # below them, where it is large enough to judge the lines.
        figures = QVBoxLayout()
        figures.addWidget(self.epipolar_label)
        figures.addWidget(self.figures_label)
        figures.addStretch(1)
        views_box = QWidget()
        views = QVBoxLayout(views_box)
        views.setContentsMargins(0, 0, 0, 0)
        views.addWidget(self.view_errors_label)
        views.addWidget(self.rejected_label)
        views.addStretch(1)
        scroll = QScrollArea()
        scroll.setWidget(views_box)
        scroll.setWidgetResizable(True)
        scroll.setFrameShape(QScrollArea.Shape.NoFrame)
        scroll.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        top = QHBoxLayout()
        top.addLayout(figures, 3)
        top.addWidget(scroll, 2)
        save_row = QHBoxLayout()
        save_row.addWidget(self.save_button)
        save_row.addWidget(self.save_label, 1)
        layout = QVBoxLayout(page)
        layout.addLayout(top)
        layout.addWidget(QLabel("<b>Rectified pair</b>: every feature should sit on the same "
                                "horizontal line in both images"))
        layout.addWidget(self.preview_view, 1)
        layout.addLayout(save_row)
        return page

    def _show_result(self, outcome: SolveOutcome) -> None:
        r = outcome.result
        colour = GRADE_COLOURS[r.epipolar_grade]
        self.epipolar_label.setText(
            f"Epipolar error <span style='color:{colour}'>{r.epipolar_px:.3f} px — "
            f"{r.epipolar_grade}</span>")
        self.epipolar_label.setToolTip(f"< {EPIPOLAR_ACCEPTABLE_PX} px acceptable, < "
                                       f"{EPIPOLAR_EXCELLENT_PX} px excellent")
        rows = [
            ("Scale", f"&lt; {EPIPOLAR_ACCEPTABLE_PX} px acceptable, &lt; "
                      f"{EPIPOLAR_EXCELLENT_PX} px excellent"),
            ("RMS reprojection", f"left {r.rms_left:.3f} px · right {r.rms_right:.3f} px · "
                                 f"stereo {r.rms_stereo:.3f} px"),
            ("Baseline", f"{r.baseline * 1000:.1f} mm ± {r.baseline_std * 1000:.1f}"),
        ]
        for name, m, s in (("Left", r.M1, r.std_left), ("Right", r.M2, r.std_right)):
            rows.append((f"{name} camera",
                         f"fx {m[0, 0]:.1f} ± {s['fx']:.1f} · fy {m[1, 1]:.1f} ± "
                         f"{s['fy']:.1f} · cx {m[0, 2]:.1f} ± {s['cx']:.1f} · "
                         f"cy {m[1, 2]:.1f} ± {s['cy']:.1f} px"))
        rows += [("Views used", f"{len(r.view_errors)}"),
                 ("Intrinsics", r.intrinsics_mode),
                 ("Rectification", r.rectification_note)]
        self.figures_label.setText(
            "<table cellspacing=4>" + "".join(f"<tr><td><b>{a}</b></td><td>{b}</td></tr>"
                                              for a, b in rows) + "</table>")
        rejected = list(outcome.skipped) + list(r.rejected)
        if rejected:
            self.rejected_label.setText(
                "<b>Rejected views</b><ul>" + "".join(
                    f"<li><b>{html.escape(_short_id(v.view_id))}</b>: "
                    f"{html.escape(v.reason)}</li>"
                    for v in rejected) + "</ul>")
        else:
            self.rejected_label.setText("<b>Rejected views</b>: none")
        if outcome.preview is not None:
            self.preview_view.set_image(outcome.preview)
        else:
            self.preview_view.set_image(None)
            self.preview_view.set_placeholder("no rectified preview: " + r.rectification_note)
        self.save_label.setText(f"not saved yet; will be saved in {self.save_dir.resolve()}")
        self.saved_path = None
        worst = sorted(r.view_errors, key=lambda v: -v.rms_px)
        self.view_errors_label.setText(
            "<b>Per-view error</b> (worst first, px): " + ", ".join(
                f"{html.escape(_short_id(v.view_id))}&nbsp;{v.rms_px:.2f}" for v in worst[:12])
            + (f", … ({len(worst) - 12} more)" if len(worst) > 12 else ""))
        self._annotate_thumbnails(r)

    def _annotate_thumbnails(self, r: CalibrationResult) -> None:
        errors = {v.view_id: v for v in r.view_errors}
        rejected = {v.view_id: v.reason for v in r.rejected}
        for row in range(self.thumb_list.count()):
            item = self.thumb_list.item(row)
            key = f"#{item.data(Qt.ItemDataRole.UserRole)}"
            if key in errors:
                item.setText(f"{key}  {errors[key].rms_px:.2f} px")
                item.setToolTip(f"left {errors[key].left_px:.3f} px, right "
                                f"{errors[key].right_px:.3f} px, epipolar "
                                f"{errors[key].epipolar_px:.3f} px")
                item.setForeground(QColor(0, 0, 0))
            elif key in rejected:
                item.setText(f"{key}  rejected")
                item.setToolTip(rejected[key])
                item.setForeground(QColor(192, 57, 43))

    def save_rig(self) -> Path | None:
        if self.outcome is None:
            return None
        path = self.save_dir / f"rig_{datetime.now():%Y%m%d_%H%M%S}.yaml"
        error = write_rig(self.outcome.result.to_rig(), path)
        if error is not None:
            self.save_label.setText(f"<span style='color:#c0392b'><b>Not saved</b>: "
                                    f"{error}</span>")
            return None
        self.saved_path = path.resolve()
        self.save_label.setText(f"<span style='color:#1b8a2e'><b>Saved</b></span> "
                                f"{self.saved_path}")
        self.rigSaved.emit(str(self.saved_path))
        return self.saved_path

    # ---- page (e): court pose ---------------------------------------------------------------
    def _build_court_page(self) -> QWidget:
        page = QWidget()
        self.court_view = ImageView("waiting for a frame of the court…")
        self.court_view.clicked.connect(self.court_click)
        self.court_diagram = CourtDiagram(self.clicks)
        self.court_prompt = QLabel()
        self.court_prompt.setWordWrap(True)
        f = QFont(self.court_prompt.font())
        f.setBold(True)
        self.court_prompt.setFont(f)
        self.court_status = QLabel("")
        self.court_status.setWordWrap(True)
        grab = QPushButton("Take a new frame")
        grab.clicked.connect(self.grab_court_frame)
        load = QPushButton("Load image…")
        load.clicked.connect(self._load_court_image)
        skip = QPushButton("Not visible: skip")
        skip.clicked.connect(self.court_skip)
        undo = QPushButton("Undo")
        undo.clicked.connect(self.court_undo)
        self.court_solve_button = QPushButton("Solve court pose and save")
        self.court_solve_button.clicked.connect(self.solve_and_save_court)
        self.court_diagram.setFixedHeight(280)
        # Wrapped labels in a fixed-width column: give them room explicitly (Qt's
        # height-for-width of rich-text labels under-reports here).
        self.court_prompt.setMinimumHeight(44)
        self.court_status.setMinimumHeight(120)
        self.court_status.setAlignment(Qt.AlignmentFlag.AlignTop | Qt.AlignmentFlag.AlignLeft)
        side_widget = QWidget()
        side_widget.setFixedWidth(320)
        side = QVBoxLayout(side_widget)
        side.setContentsMargins(0, 0, 0, 0)
        side.addWidget(self.court_diagram)
        side.addWidget(self.court_prompt)
        for b in (skip, undo, grab, load, self.court_solve_button):
            side.addWidget(b)
        side.addWidget(self.court_status)
        side.addStretch(1)
        layout = QHBoxLayout(page)
        layout.addWidget(self.court_view, 1)
        layout.addWidget(side_widget)
        return page

    def _enter_court_page(self) -> None:
        if self._court_image is None:
            if self._latest_left is not None:
                self.set_court_image(self._latest_left)
            else:
                self.grab_court_frame()
        self._update_court()

    def set_court_image(self, image: np.ndarray) -> None:
        self._court_image = image
        self.court_view.set_image(image)
        self._update_court()

    def grab_court_frame(self) -> None:
        if self._grab_thread is not None:
            return
        self.court_status.setText("taking a frame…")
        self._grabber = FrameGrabber(self._factory)
        self._grabber.grabbed.connect(self.set_court_image)
        self._grabber.failed.connect(self._on_grab_failed)
        self._grabber.finished.connect(self._on_grab_finished)
        self._grab_thread = _start(self, self._grabber)

    def _on_grab_failed(self, message: str) -> None:
        self.court_status.setText(f"<span style='color:#c0392b'>no frame: {message}</span>")

    def _on_grab_finished(self) -> None:
        if self._grab_thread is not None:
            self._grab_thread.quit()
            self._grab_thread.wait()
        self._grab_thread = None
        self._grabber = None

    def _load_court_image(self) -> None:
        settings = st.open_settings()
        name, _ = QFileDialog.getOpenFileName(self, "Left camera image of the court",
                                              st.dialog_folder(settings, "images"),
                                              "Images (*.png *.jpg *.jpeg *.bmp *.tif)")
        if name:
            st.remember_dialog_folder(settings, "images", name)
            image = cv2.imread(name)
            if image is None:
                self.court_status.setText(f"cannot read {name}")
            else:
                self.set_court_image(image)

    def court_click(self, x: float, y: float) -> None:
        self.clicks.click(x, y)
        self._update_court()

    def court_skip(self) -> None:
        self.clicks.skip()
        self._update_court()

    def court_undo(self) -> None:
        self.clicks.undo()
        self._update_court()

    def _update_court(self) -> None:
        name = self.clicks.current_name
        n = len(self.clicks.clicked)
        self.court_prompt.setText(
            (f"Click point {self.clicks.order.index(name) + 1}: {name}" if name
             else "All points done") +
            f"  ({n} clicked, at least 4 needed)")
        # Label each click with the keypoint's number on the court drawing (not the click
        # count), so a skipped point does not shift the numbers.
        number = {name: k for k, name in enumerate(self.clicks.order, 1)}
        self.court_view.set_points([(x, y, QColor(80, 230, 90), str(number[name]))
                                    for name, (x, y) in self.clicks.clicked.items()])
        self.court_diagram.update()
        self.court_solve_button.setEnabled(self.clicks.ready and self.outcome is not None)

    def solve_and_save_court(self) -> Path | None:
        if self.outcome is None or not self.clicks.ready:
            return None
        rig = self.outcome.result.to_rig()
        try:
            result = self.clicks.solve(rig)
        except CalibrationError as exc:
            self.court_status.setText(f"<span style='color:#c0392b'>{exc}</span>")
            return None
        self.court_result = result
        path = self.saved_path or (self.save_dir / f"rig_{datetime.now():%Y%m%d_%H%M%S}.yaml")
        error = write_rig(result.rig, Path(path))
        if error is not None:
            self.court_status.setText(f"<span style='color:#c0392b'><b>Not saved</b>: "
                                      f"{error}</span>")
            return None
        self.saved_path = Path(path).resolve()
        camera = result.rig.camera_centres()[0]
        self.court_status.setText(
            f"Court pose: reprojection RMS {result.rms_px:.2f} px over "
            f"{len(result.errors_px)} points (worst {result.errors_px.max():.2f} px); left camera "
            f"at X {camera[0]:.2f}, Y {camera[1]:.2f}, Z {camera[2]:.2f} m.<br>"
            f"<span style='color:#1b8a2e'><b>Saved</b></span> {self.saved_path}")
        self.rigSaved.emit(str(self.saved_path))
        return self.saved_path

    # ---- closing ----------------------------------------------------------------------------
    def shutdown(self) -> None:
        """Stop every worker cooperatively and wait for its thread."""
        self._stop_capture()
        if self._solve_worker is not None:
            self._solve_worker.cancel()
        for thread in (self._solve_thread, self._grab_thread):
            if thread is not None:
                thread.quit()
                thread.wait()

    def closeEvent(self, event) -> None:  # noqa: N802 - Qt naming
        self.shutdown()
        super().closeEvent(event)

    def done(self, result: int) -> None:
        self.shutdown()
        super().done(result)


def main() -> int:
    """Try the wizard without cameras: ``python -m badminton_gui.gui.calibration_wizard``."""
    import sys

    from PySide6.QtWidgets import QApplication

    from ..io.synthetic_chessboard import SyntheticChessboardSource

    app = QApplication.instance() or QApplication(sys.argv)
    wizard = CalibrationWizard(lambda: SyntheticChessboardSource(
        BoardSpec(9, 6, 0.025), realtime_fps=15.0))
    wizard.show()
    return app.exec()


if __name__ == "__main__":
    raise SystemExit(main())

"""Calibration ▸ Refine from tracked shuttle…: self-calibration of the rig while tracking.

Why this file exists: a rig assembled from two cameras calibrated separately (the NYCU ``.cfg``
pair is ≈ 9.5° off) is refitted from the shuttle's own pairs by ``core.calibrate.refine``; before this
dialog only ``badminton-track refine-calib`` could do it, on a recording. Here the operator keeps
tracking (cameras, a video pair or the demo court) and:

* every result of the tracking worker goes through its *result tap* into a
  :class:`SharedPairs` (a ``PairCollector`` behind a lock), on the worker's thread and at the
  tracking rate — the display packets come at ~30 Hz, too few, and the GUI thread never
  tracks anything;
* the dialog shows how many pairs there are and how much of each image they cover, against
  what the refit needs (``DEFAULT_MIN_PAIRS``, ``DEFAULT_MIN_SPREAD``);
* Refit runs ``refine_relative_pose`` on a copy of the pairs in a :class:`RefitJob` on its own
  QThread, with its stages in a progress bar and Cancel (the core checks the flag between
  stages and polishing iterations);
* the report (median and p90 epipolar error before → after, accepted or why not) is shown, and
  an accepted rig can be applied to the running tracker (the main window hands it to
  ``TrackingWorker.set_rig``) and saved as a rig YAML (``calibration_wizard.write_rig``: a
  failure is one sentence and the refined rig stays in the dialog).

All the judgement is the core's; this file renders it.
"""

from __future__ import annotations

import html
import logging
import math
import threading
from datetime import datetime
from pathlib import Path
from typing import Callable

import cv2
import numpy as np
from PySide6.QtCore import QObject, QPointF, QRectF, Qt, QThread, QTimer, Signal
from PySide6.QtGui import QColor, QImage, QPainter, QPen
from PySide6.QtWidgets import (QDialog, QFileDialog, QGridLayout, QGroupBox, QHBoxLayout, QLabel,
                               QProgressBar, QPushButton, QSizePolicy, QVBoxLayout, QWidget)

from ..core.rig import StereoRig
from ..core.calibrate.refine import (DEFAULT_MIN_PAIRS, DEFAULT_MIN_SPREAD, PairCollector,
                               RefineCancelled, RefineReport, image_spread,
                               refine_relative_pose)
from .calibration_wizard import write_rig
from .settings import dialog_folder, open_settings, remember_dialog_folder

_log = logging.getLogger(__name__)

REFRESH_INTERVAL_MS = 250          # the pair count and coverage: 4 times a second is plenty
GREEN, AMBER, RED, GREY = "#1b8a2e", "#b07800", "#c0392b", "#777"

Refit = Callable[..., tuple[StereoRig, RefineReport]]


class SharedPairs:
    """A :class:`PairCollector` fed by the tracking worker's thread and read by the GUI thread.

    ``add`` is the worker's result tap (≈ 5 µs a result); the GUI takes copies. The kept pairs
    are also written into a growing array as they come: ``PairCollector.points`` builds its
    arrays from lists of tuples, 13 ms for 20,000 pairs under the lock the worker waits on, where
    a copy of the array takes a fraction of a millisecond.
    """

    def __init__(self, make_collector: Callable[[], PairCollector] = PairCollector) -> None:
        self._make = make_collector
        self._lock = threading.Lock()
        self._collector = make_collector()
        self._rows = np.empty((256, 4))          # left x, y, right x, y of the kept pairs
        self._n = 0

    def add(self, result) -> None:
        with self._lock:
            if not self._collector.add(result):
                return
            if self._n == len(self._rows):
                self._rows = np.concatenate([self._rows, np.empty_like(self._rows)])
            # What PairCollector keeps of a kept result: both cameras' detection positions.
            left, right = result.left.detection, result.right.detection
            self._rows[self._n] = (left.x, left.y, right.x, right.y)
            self._n += 1

    def __len__(self) -> int:
        with self._lock:
            return self._n

    def points(self) -> tuple[np.ndarray, np.ndarray]:
        """Copies of the (N, 2) left and right pixel points collected so far."""
        with self._lock:
            rows = self._rows[:self._n].copy()
        return rows[:, :2], rows[:, 2:]

    def clear(self) -> None:
        with self._lock:
            self._collector = self._make()
            self._n = 0


class RefitJob(QObject):
    """Runs one refit on a QThread; never touches widgets."""

    progress = Signal(float, str)
    succeeded = Signal(object, object)      # StereoRig (refined or the input), RefineReport
    failed = Signal(str)
    cancelled = Signal()
    finished = Signal()

    def __init__(self, rig: StereoRig, left: np.ndarray, right: np.ndarray,
                 refit: Refit = refine_relative_pose) -> None:
        super().__init__()
        self._rig, self._left, self._right, self._refit = rig, left, right, refit
        self._cancel = threading.Event()

    def cancel(self) -> None:
        self._cancel.set()

    @property
    def cancel_requested(self) -> bool:
        return self._cancel.is_set()

    def run(self) -> None:
        try:
            rig, report = self._refit(self._rig, self._left, self._right,
                                      progress=self.progress.emit, cancel=self._cancel.is_set)
            if self._cancel.is_set():          # asked after the core's last check
                self.cancelled.emit()
            else:
                self.succeeded.emit(rig, report)
        except RefineCancelled:
            self.cancelled.emit()
        except cv2.error as exc:
            self.failed.emit(f"OpenCV failed: {str(exc).strip().splitlines()[-1]}")
        except Exception as exc:  # noqa: BLE001 - a bug must not leave the dialog waiting
            _log.exception("refit failed")
            self.failed.emit(f"internal error in the refit ({type(exc).__name__}: {exc})")
        finally:
            self.finished.emit()


class CoverageView(QWidget):
    """Where the pairs lie in each camera's image: two frames side by side, one dot a pair.

    The dots are set in a numpy image and drawn in one call (cached until the points or the
    size change): a QPainter call per dot cost 45 ms a paint for 3,000 pairs on the GUI thread.
    """

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setMinimumSize(360, 120)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Preferred)
        self._size: tuple[int, int] | None = None
        self._left = self._right = np.zeros((0, 2))
        self._images: dict[tuple, QImage] = {}

    def set_points(self, image_size: tuple[int, int] | None, left: np.ndarray,
                   right: np.ndarray) -> None:
        self._size, self._left, self._right = image_size, left, right
        self._images = {}
        self.update()

    def _dots(self, points: np.ndarray, width: int, height: int, scale: float) -> QImage:
        """The frame's inside with a 3×3 dot at each point, as a QImage (cached)."""
        key = (id(points), width, height)
        if key not in self._images:
            canvas = np.empty((height, width, 4), np.uint8)
            canvas[:] = (42, 38, 35, 255)                     # BGRA: the dark frame
            if len(points):
                xy = np.floor(points * scale).astype(int)
                for dx in (-1, 0, 1):
                    for dy in (-1, 0, 1):
                        x, y = xy[:, 0] + dx, xy[:, 1] + dy
                        inside = (x >= 0) & (x < width) & (y >= 0) & (y < height)
                        canvas[y[inside], x[inside]] = (0, 196, 255, 255)      # amber
            self._images[key] = QImage(canvas.data, width, height, canvas.strides[0],
                                       QImage.Format.Format_ARGB32).copy()
        return self._images[key]

    def paintEvent(self, event) -> None:  # noqa: N802 - Qt naming
        painter = QPainter(self)
        painter.setRenderHint(QPainter.RenderHint.Antialiasing)
        w_img, h_img = self._size or (16, 9)
        gap, label_h = 12, 16
        box_w = (self.width() - gap) / 2
        scale = min(box_w / w_img, (self.height() - label_h) / h_img)
        for k, (name, pts) in enumerate((("left camera", self._left), ("right camera", self._right))):
            x0 = k * (box_w + gap)
            frame = QRectF(x0, label_h, w_img * scale, h_img * scale)
            width, height = max(1, int(frame.width())), max(1, int(frame.height()))
            painter.drawImage(QPointF(frame.left(), frame.top()), self._dots(pts, width, height, scale))
            painter.setPen(QPen(QColor(120, 120, 120), 1))
            painter.drawRect(frame)
            painter.setPen(QColor(60, 60, 60) if self.palette().window().color().lightness() > 128
                           else QColor(220, 220, 220))
            painter.drawText(QRectF(x0, 0, frame.width(), label_h),
                             Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter,
                             f"{name}: {len(pts)} pairs" if len(pts) else f"{name}: no pairs yet")
        painter.end()


def _coloured(text: str, colour: str, bold: bool = False) -> str:
    body = f"<b>{text}</b>" if bold else text
    return f"<span style='color:{colour}'>{body}</span>"


def _px(value: float) -> str:
    return "—" if not math.isfinite(value) else f"{value:.1f} px"


class RefineCalibrationDialog(QDialog):
    """Collect the shuttle's stereo pairs while tracking, refit the rig, apply it, save it."""

    applyRequested = Signal(object)         # noqa: N815 - Qt naming; the refined StereoRig
    rigSaved = Signal(str, object)          # noqa: N815 - path, the StereoRig saved there

    def __init__(self, rig_in_use: Callable[[], StereoRig | None], save_dir: Callable[[], Path],
                 parent: QWidget | None = None, refit: Refit = refine_relative_pose) -> None:
        """``rig_in_use()``: the rig the running tracker uses (None: nothing is tracking);
        ``save_dir()``: the folder Save as… offers; ``refit``: the core's function (tests pass
        a slow stand-in to catch the dialog mid-refit)."""
        super().__init__(parent)
        self.setWindowTitle("Refine calibration from the tracked shuttle")
        self.setModal(False)
        self._rig_in_use = rig_in_use
        self._save_dir = save_dir
        self._refit = refit
        self.pairs = SharedPairs()
        self.report: RefineReport | None = None
        self.refined: StereoRig | None = None     # the accepted refit, until another replaces it
        self.base_rig: StereoRig | None = None    # the rig that refit started from
        self.saved_path: Path | None = None       # where ``refined`` was saved, if it was
        self.applied = False
        self._job: RefitJob | None = None
        self._thread: QThread | None = None
        self._shown_count = -1
        self._shown_size: tuple[int, int] | None = None
        self._build_ui()
        self._timer = QTimer(self)
        self._timer.timeout.connect(self.refresh_pairs)
        self._timer.start(REFRESH_INTERVAL_MS)
        self.refresh_pairs()

    # ---- layout ------------------------------------------------------------------------------
    def _build_ui(self) -> None:
        intro = QLabel(
            "Keep tracking while the shuttle flies: every frame in which both cameras follow the "
            "same shuttle gives a pair of points. The refit turns the cameras' relative pose until "
            "the pairs lie on each other's epipolar lines; the lenses, the baseline's length and "
            "the court pose are kept. Rallies that cross the whole view give the best fit.")
        intro.setWordWrap(True)
        intro.setStyleSheet(f"color: {GREY}")

        pairs_box = QGroupBox("Pairs collected")
        self.count_label = QLabel()
        self.count_label.setTextFormat(Qt.TextFormat.RichText)
        self.spread_label = QLabel()
        self.spread_label.setWordWrap(True)
        self.spread_label.setTextFormat(Qt.TextFormat.RichText)
        self.coverage = CoverageView()
        self.clear_button = QPushButton("Clear pairs")
        self.clear_button.setToolTip("Start collecting again (after moving a camera, say)")
        self.clear_button.clicked.connect(self.clear_pairs)
        top = QHBoxLayout()
        top.addWidget(self.count_label, 1)
        top.addWidget(self.clear_button)
        lay = QVBoxLayout(pairs_box)
        lay.addLayout(top)
        lay.addWidget(self.spread_label)
        lay.addWidget(self.coverage, 1)

        refit_box = QGroupBox("Refit")
        self.refit_button = QPushButton("Refit now")
        self.refit_button.setDefault(True)
        self.refit_button.clicked.connect(self.start_refit)
        self.progress = QProgressBar()
        self.progress.setRange(0, 1000)
        self.progress.setTextVisible(False)
        self.cancel_button = QPushButton("Cancel refit")
        self.cancel_button.clicked.connect(self.cancel_refit)
        self.cancel_button.setEnabled(False)
        self.stage_label = QLabel("")
        self.stage_label.setWordWrap(True)
        row = QHBoxLayout()
        row.addWidget(self.refit_button)
        row.addWidget(self.progress, 1)
        row.addWidget(self.cancel_button)
        self.result_grid = QGridLayout()
        self.result_values: dict[str, QLabel] = {}
        for r, (key, text) in enumerate((("median", "Epipolar error, median"),
                                         ("p90", "Epipolar error, 90th percentile"),
                                         ("held", "Last third, under a refit of the rest"),
                                         ("agree", "Pairs agreeing with the refit"),
                                         ("turn", "Change of the relative pose"))):
            name = QLabel(text)
            name.setStyleSheet(f"color: {GREY}")
            value = QLabel("—")
            value.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
            self.result_grid.addWidget(name, r, 0)
            self.result_grid.addWidget(value, r, 1)
            self.result_values[key] = value
        self.result_grid.setColumnStretch(1, 1)
        self.verdict_label = QLabel("")
        self.verdict_label.setWordWrap(True)
        self.verdict_label.setTextFormat(Qt.TextFormat.RichText)
        self.verdict_label.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        lay = QVBoxLayout(refit_box)
        lay.addLayout(row)
        lay.addWidget(self.stage_label)
        lay.addLayout(self.result_grid)
        lay.addWidget(self.verdict_label)

        self.apply_button = QPushButton("Apply to the tracker")
        self.apply_button.setToolTip("Track with the refined rig from the next frame on")
        self.apply_button.clicked.connect(self.apply)
        self.save_button = QPushButton("Save as…")
        self.save_button.setToolTip("Write the refined rig as a rig file (YAML)")
        self.save_button.clicked.connect(self.save_as)
        close = QPushButton("Close")
        close.clicked.connect(self.close)
        self.message_label = QLabel("")
        self.message_label.setWordWrap(True)
        self.message_label.setTextFormat(Qt.TextFormat.RichText)
        self.message_label.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        buttons = QHBoxLayout()
        buttons.addWidget(self.apply_button)
        buttons.addWidget(self.save_button)
        buttons.addStretch(1)
        buttons.addWidget(close)

        outer = QVBoxLayout(self)
        outer.addWidget(intro)
        outer.addWidget(pairs_box, 1)
        outer.addWidget(refit_box)
        outer.addWidget(self.message_label)
        outer.addLayout(buttons)
        self.resize(640, 640)
        self._update_buttons()

    # ---- pairs ---------------------------------------------------------------------------------
    def refresh_pairs(self, force: bool = False) -> None:
        """Show the count and the coverage of the pairs (timer; only when they changed)."""
        rig = self._rig_in_use()
        size = rig.image_size if rig is not None else None
        n = len(self.pairs)
        if not force and n == self._shown_count and size == self._shown_size:
            return
        self._shown_count, self._shown_size = n, size
        left, right = self.pairs.points()
        need = DEFAULT_MIN_PAIRS
        if n >= need:
            count = _coloured(f"{n} pairs", GREEN, bold=True) + f" (a refit needs {need})"
        else:
            count = (_coloured(f"{n} pairs", AMBER, bold=True)
                     + f" — {need - n} more needed before a refit can succeed")
        self.count_label.setText(count)
        if size is None:
            # (no rig: nothing is tracking, or one camera's video, which has no stereo pose)
            self.spread_label.setText(_coloured("No two cameras are tracking: choose the demo court, "
                                                "a stereo video pair or two cameras in the Source "
                                                "menu.", AMBER))
        elif n < 2:
            self.spread_label.setText("Coverage: no pairs yet. A pair needs the shuttle followed "
                                      "in both cameras for a few frames.")
        else:
            spreads = [image_spread(pts, size) for pts in (left, right)]
            enough = min(min(s) for s in spreads) >= DEFAULT_MIN_SPREAD
            text = (f"They span {spreads[0][0]:.0%} × {spreads[0][1]:.0%} of the left image and "
                    f"{spreads[1][0]:.0%} × {spreads[1][1]:.0%} of the right (width × height; "
                    f"the refit needs {DEFAULT_MIN_SPREAD:.0%} each way")
            self.spread_label.setText(text + (")." if enough else
                                              ") — " + _coloured("too narrow yet", AMBER, bold=True)))
        self.coverage.set_points(size, left, right)
        self._update_buttons()

    def clear_pairs(self) -> None:
        self.pairs.clear()
        self.message_label.setText("Pairs cleared: collecting again.")
        self.refresh_pairs(force=True)

    def source_changed(self, keep_result: bool = False) -> None:
        """A new source (or the same one reopened): its pairs start over and any refit is void,
        unless ``keep_result`` (the stopped source reopened to apply the refined rig)."""
        self.cancel_refit()
        self.pairs.clear()
        if keep_result:
            self.message_label.setText("Reopening the source with the refined rig…")
        else:
            self._clear_result()
            self.message_label.setText("New source: the pairs start over.")
        self.refresh_pairs(force=True)

    # ---- refit ---------------------------------------------------------------------------------
    @property
    def running(self) -> bool:
        return self._thread is not None

    def start_refit(self) -> None:
        """Refit the rig in use to a copy of the pairs, on a QThread."""
        rig = self._rig_in_use()
        if self.running or rig is None:
            return
        self._clear_result()
        left, right = self.pairs.points()
        self.base_rig = rig
        self.message_label.setText("")
        self.stage_label.setText(f"Refitting with {len(left)} pairs…")
        self.progress.setValue(0)
        job = RefitJob(rig, left, right, self._refit)
        job.progress.connect(self._on_progress)
        job.succeeded.connect(self._on_refitted)
        job.failed.connect(self._on_failed)
        job.cancelled.connect(self._on_cancelled)
        job.finished.connect(self._on_job_finished)
        thread = QThread(self)
        thread.setObjectName("rig-refit")
        job.moveToThread(thread)
        thread.started.connect(job.run)
        job.finished.connect(thread.quit)
        self._job, self._thread = job, thread
        self._update_buttons()
        thread.start()

    def cancel_refit(self) -> None:
        if self._job is not None and not self._job.cancel_requested:
            self._job.cancel()
            self.stage_label.setText("Cancelling…")
            self.cancel_button.setEnabled(False)

    def _on_progress(self, fraction: float, text: str) -> None:
        if self._job is not None and not self._job.cancel_requested:
            self.progress.setValue(round(1000 * fraction))
            self.stage_label.setText(text[:1].upper() + text[1:] + "…")

    def _on_refitted(self, rig: StereoRig, report: RefineReport) -> None:
        if self._job is None or self._job.cancel_requested:     # cancelled as it finished
            self._on_cancelled()
            return
        self.report = report
        v = self.result_values

        def change(before: float, after: float, bold: bool = True) -> str:
            if not math.isfinite(after):
                return f"{_px(before)} (no refit)"
            return f"{_px(before)} → <b>{_px(after)}</b>" if bold else f"{_px(before)} → {_px(after)}"
        v["median"].setText(change(report.before_median_px, report.after_median_px))
        v["p90"].setText(change(report.before_p90_px, report.after_p90_px))
        v["held"].setText(change(report.held_back_before_px, report.held_back_after_px, bold=False))
        v["agree"].setText(f"{report.inliers} of {report.pairs}" if report.inliers else "—")
        v["turn"].setText(f"rotation {report.rotation_change_deg:.2f}°, baseline direction "
                          f"{report.baseline_turn_deg:.2f}°"
                          if math.isfinite(report.rotation_change_deg) else "—")
        self.progress.setValue(1000)
        if report.accepted:
            self.refined = rig
            self.stage_label.setText("Refit finished.")
            self.verdict_label.setText(
                _coloured("Accepted", GREEN, bold=True) + ": with the refined rig the pairs lie "
                f"{_px(report.after_median_px)} from their epipolar lines (median) instead of "
                f"{_px(report.before_median_px)}. Apply tracks with it now; Save as… keeps it "
                "for the next start.")
        else:
            self.refined = None
            self.stage_label.setText("Refit finished.")
            self.verdict_label.setText(
                _coloured("Not refined", RED, bold=True) + ": " + html.escape(report.reason)
                + ". The tracker keeps its rig." + self._advice(report))
        self._update_buttons()

    @staticmethod
    def _advice(report: RefineReport) -> str:
        if report.pairs < DEFAULT_MIN_PAIRS:
            return " Keep tracking until more pairs are collected, then refit."
        if "cover too little" in report.reason or "last third" in report.reason:
            return " Keep tracking: shots across other parts of the view help."
        return ""

    def _on_failed(self, message: str) -> None:
        self.stage_label.setText("")
        self.verdict_label.setText(_coloured("Refit failed", RED, bold=True) + ": "
                                   + html.escape(message) + ". The tracker keeps its rig.")

    def _on_cancelled(self) -> None:
        self.progress.setValue(0)
        self.stage_label.setText("Refit cancelled: nothing was changed.")

    def _on_job_finished(self) -> None:
        if self._thread is not None:
            self._thread.quit()
            self._thread.wait()
            self._thread.deleteLater()
        if self._job is not None:
            self._job.deleteLater()
        self._job = self._thread = None
        self._update_buttons()

    def _clear_result(self) -> None:
        self.report = self.refined = self.base_rig = self.saved_path = None
        self.applied = False
        for value in self.result_values.values():
            value.setText("—")
        self.verdict_label.setText("")
        self.stage_label.setText("")
        self.progress.setValue(0)
        self._update_buttons()

    def _update_buttons(self) -> None:
        running = self.running
        tracking = self._rig_in_use() is not None
        self.refit_button.setEnabled(not running and tracking and len(self.pairs) > 0)
        self.refit_button.setToolTip(
            f"Refit the rig in use to the pairs collected so far ({DEFAULT_MIN_PAIRS} needed)")
        self.cancel_button.setEnabled(running and self._job is not None
                                      and not self._job.cancel_requested)
        self.clear_button.setEnabled(len(self.pairs) > 0)
        self.apply_button.setEnabled(self.refined is not None and not self.applied and tracking)
        self.save_button.setEnabled(self.refined is not None)

    # ---- apply and save ------------------------------------------------------------------------
    def apply(self) -> None:
        """Ask the main window to track with the refined rig (``rig_applied`` confirms)."""
        if self.refined is None:
            return
        self.apply_button.setEnabled(False)
        self.message_label.setText("Applying the refined rig…")
        self.applyRequested.emit(self.refined)

    def rig_applied(self, rig: StereoRig) -> None:
        """The tracker now runs with ``rig`` (called by the main window)."""
        if rig is not self.refined:
            return
        self.applied = True
        note = (f" It is saved as {html.escape(str(self.saved_path))}." if self.saved_path
                else " Save as… keeps it for the next start.")
        self.message_label.setText(_coloured("Applied", GREEN, bold=True)
                                   + ": the tracker now uses the refined rig." + note)
        self.refresh_pairs(force=True)
        self._update_buttons()

    def default_save_path(self) -> Path:
        return self._save_dir() / f"rig_refined_{datetime.now():%Y%m%d_%H%M%S}.yaml"

    def save_as(self) -> Path | None:
        """Ask where, then write the refined rig there."""
        if self.refined is None:
            return None
        settings = open_settings()
        default = self.default_save_path()
        folder = Path(dialog_folder(settings, "rigs", first_time=str(default.parent)))
        path, _ = QFileDialog.getSaveFileName(self, "Save the refined rig", str(folder / default.name),
                                              "Rig (*.yaml *.yml);;All files (*)")
        if not path:
            return None
        remember_dialog_folder(settings, "rigs", path)
        return self.save_to(Path(path))

    def save_to(self, path: Path) -> Path | None:
        """Write the refined rig; on failure say why in the dialog and keep everything."""
        if self.refined is None:
            return None
        if path.suffix.lower() not in (".yaml", ".yml", ".xml"):
            path = path.with_name(path.name + ".yaml")
        error = write_rig(self.refined, path)
        if error is not None:
            self.message_label.setText(
                _coloured("Not saved", RED, bold=True) + f": {html.escape(error)}. The refined "
                "rig is still here: Save as… somewhere else.")
            return None
        self.saved_path = path.resolve()
        self.message_label.setText(_coloured("Saved", GREEN, bold=True) + " "
                                   + html.escape(str(self.saved_path)))
        self.rigSaved.emit(str(self.saved_path), self.refined)
        return self.saved_path

    def saved_path_of(self, rig: StereoRig) -> Path | None:
        """Where ``rig`` was saved from this dialog, if it was."""
        return self.saved_path if rig is self.refined else None

    # ---- closing -------------------------------------------------------------------------------
    def shutdown(self) -> None:
        """Cancel a running refit and wait for its thread."""
        self._timer.stop()
        if self._job is not None:
            self._job.cancel()
        if self._thread is not None:
            self._thread.quit()
            self._thread.wait()
        self._on_job_finished()

    def showEvent(self, event) -> None:  # noqa: N802 - Qt naming
        self._timer.start(REFRESH_INTERVAL_MS)
        self.refresh_pairs(force=True)
        super().showEvent(event)

    def hideEvent(self, event) -> None:  # noqa: N802 - Qt naming
        # The pairs keep coming in (the worker's tap stays); only the display stops.
        self._timer.stop()
        super().hideEvent(event)

"""Turning a remembered :class:`SourceSpec` into an open source + rig, and the Source dialogs.

Why this file exists: the worker opens sources on its own thread (a camera can take seconds to
open), so the GUI hands it a plain function built here. The dialogs only collect paths and
device indices; listing cameras (which opens each device) runs on a background thread.
"""

from __future__ import annotations

import os
import threading

from PySide6.QtCore import QObject, Signal
from PySide6.QtWidgets import (QCheckBox, QComboBox, QDialog, QDialogButtonBox, QFileDialog,
                               QFormLayout, QHBoxLayout, QLabel, QLineEdit, QPushButton,
                               QVBoxLayout, QWidget)

from ..core.rig import RigError, StereoRig
from ..io.sources import FrameSource, SourceError
from .settings import SourceSpec, dialog_folder, open_settings, remember_dialog_folder
from .worker import OpeningContext


def open_spec(spec: SourceSpec, context: OpeningContext | None = None) -> tuple[FrameSource, StereoRig]:
    """Open what the spec names; raises SourceError / RigError / OSError with one sentence.

    ``context`` (the worker's, when it opens the source) hears how a long step is going (the
    scan of a video pair's frame times) and says when the user asked for something else: the
    step then ends with ``OpeningCancelled``."""
    if spec.kind == "demo":
        try:
            from ..io.demo_scene import DemoScene
        except ImportError as exc:
            raise SourceError(f"the demo court is not available in this installation ({exc})") from None
        from ..io.truth import DemoTruth
        scene = DemoScene()
        rig = StereoRig.load(spec.calib) if spec.calib else scene.rig
        scene.frame_truth = DemoTruth(scene)
        return scene, rig
    if spec.kind == "video":
        from ..io.labels import CsvFormatError, read_timestamps
        from ..io.video import VideoPair, frame_times
        if not spec.calib:
            raise RigError("a video pair needs its rig file (Source ▸ Stereo video pair…)")
        rig = StereoRig.load(spec.calib)
        lt = rt = None
        if spec.left_times or spec.right_times:
            if not (spec.left_times and spec.right_times):
                raise SourceError("give timestamp files for both videos or for neither")
            try:
                lt = read_timestamps(spec.left_times)[1]
                rt = read_timestamps(spec.right_times)[1]
            except CsvFormatError as exc:
                raise SourceError(str(exc)) from None
        elif spec.video_times:
            lt, rt = (frame_times(path, *(() if context is None else context.for_step(
                          f"reading the {side} video's frame times", k, 2)))
                      for k, (side, path) in enumerate((("left", spec.left), ("right", spec.right))))
        # Decoded on a reader thread a few pairs ahead (io/prefetch.py), as `track` does: FFmpeg
        # releases the GIL, so decoding overlaps tracking instead of taking turns with it.
        from ..io.prefetch import PrefetchingReader
        reader = PrefetchingReader(VideoPair(spec.left, spec.right, lt, rt))
        reader.frame_truth = _label_truth(spec)
        return reader, rig
    if spec.kind == "single":
        # One camera's video (a TV broadcast): tracked in 2D by the one-camera tracker, no rig.
        from ..io.labels import CsvFormatError, read_point_labels
        from ..io.prefetch import PrefetchingReader
        from ..io.truth import LabelTruth
        from ..io.video import SingleVideo
        truth = None
        if spec.left_labels:
            try:
                truth = LabelTruth(read_point_labels(spec.left_labels).as_dict(), {})
            except CsvFormatError as exc:
                raise SourceError(f"{exc} (clear the label file to play the video without a score)") from None
        reader = PrefetchingReader(SingleVideo(spec.left))
        reader.frame_truth = truth
        # For the classifier's adaptation pass (the worker's, with the look-ahead view): the
        # recording read again from its start, as `detect` reads it.
        from ..io.detect_file import recording_frames
        reader.recording_frames = lambda progress=None, path=spec.left: recording_frames(path, progress)
        stat = os.stat(spec.left)
        reader.recording_key = (os.path.abspath(spec.left), stat.st_size, stat.st_mtime_ns)
        return reader, None
    if spec.kind == "cameras":
        from ..io.cameras import CameraPair
        if not spec.calib:
            raise RigError("two cameras need their rig file: calibrate first (Calibration ▸ Calibrate with a chessboard…)")
        rig = StereoRig.load(spec.calib)
        return CameraPair(spec.left, spec.right), rig
    raise SourceError(f"unknown source kind {spec.kind!r}")


def _label_truth(spec: SourceSpec):
    """The pair's labels for the live score (io/truth.py), or None: the label files named in the
    spec, else the timestamp files when they carry labels too (the NYCU recordings' CSVs)."""
    from ..io.labels import CsvFormatError
    from ..io.truth import LabelTruth, has_label_columns
    if spec.left_labels or spec.right_labels:
        if not (spec.left_labels and spec.right_labels):
            raise SourceError("give label files for both videos or for neither")
        try:
            return LabelTruth.read(spec.left_labels, spec.right_labels)
        except CsvFormatError as exc:
            raise SourceError(f"{exc} (clear the label files to play the videos without a score)") from None
    if spec.left_times and spec.right_times and all(map(has_label_columns, (spec.left_times, spec.right_times))):
        return LabelTruth.read(spec.left_times, spec.right_times)
    return None


def _open_cancel_layout(dialog: QDialog, form: QFormLayout) -> None:
    """A source dialog's layout: its form above Open and Cancel."""
    buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Open | QDialogButtonBox.StandardButton.Cancel)
    buttons.accepted.connect(dialog.accept)
    buttons.rejected.connect(dialog.reject)
    lay = QVBoxLayout(dialog)
    lay.addLayout(form)
    lay.addWidget(buttons)


def _file_row(parent: QWidget, edit: QLineEdit, caption: str, filter_: str, kind: str) -> QWidget:
    """A path field with its Browse… button; the dialog opens at the field's file, else in the
    folder last used for this kind of file (settings.FILE_KINDS)."""
    row = QWidget(parent)
    lay = QHBoxLayout(row)
    lay.setContentsMargins(0, 0, 0, 0)
    lay.addWidget(edit, 1)
    button = QPushButton("Browse…", row)

    def browse() -> None:
        settings = open_settings()
        path, _ = QFileDialog.getOpenFileName(parent, caption, edit.text() or dialog_folder(settings, kind),
                                              filter_)
        if path:
            remember_dialog_folder(settings, kind, path)
            edit.setText(path)

    button.clicked.connect(browse)
    lay.addWidget(button)
    return row


class VideoPairDialog(QDialog):
    """Two video files, the rig file, optional timestamp and label CSVs."""

    def __init__(self, spec: SourceSpec, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("Stereo video pair")
        self.setMinimumWidth(560)
        prev = spec if spec.kind == "video" else SourceSpec()
        self.left = QLineEdit(prev.left)
        self.right = QLineEdit(prev.right)
        self.calib = QLineEdit(prev.calib or spec.calib)
        self.left_times = QLineEdit(prev.left_times)
        self.right_times = QLineEdit(prev.right_times)
        videos = "Videos (*.mp4 *.avi *.mov *.mkv);;All files (*)"
        form = QFormLayout()
        form.addRow("Left video", _file_row(self, self.left, "Left camera video", videos, "videos"))
        form.addRow("Right video", _file_row(self, self.right, "Right camera video", videos, "videos"))
        form.addRow("Rig file", _file_row(self, self.calib, "Rig file", "Rig (*.yaml *.yml *.xml);;All files (*)", "rigs"))
        csvs = "CSV (*.csv);;All files (*)"
        form.addRow("Left timestamps (optional)", _file_row(self, self.left_times, "Left timestamps", csvs, "labels"))
        form.addRow("Right timestamps (optional)", _file_row(self, self.right_times, "Right timestamps", csvs, "labels"))
        self.left_labels = QLineEdit(prev.left_labels)
        self.right_labels = QLineEdit(prev.right_labels)
        for side, edit in (("Left", self.left_labels), ("Right", self.right_labels)):
            edit.setToolTip("Frame,Visibility,X,Y per frame of this camera (TrackNet's format): the "
                            "readouts then score the tracking against them live. Timestamp files "
                            "that carry these columns are used as labels without being named here.")
            form.addRow(f"{side} labels (optional)", _file_row(self, edit, f"{side} labels", csvs, "labels"))
        self.video_times = QCheckBox("Without timestamp files, pair by the videos' own frame times")
        self.video_times.setToolTip("For recordings whose cameras dropped frames: frame i of one file was "
                                    "then not taken with frame i of the other. Costs one decoding pass "
                                    "when the pair opens.")
        self.video_times.setChecked(prev.video_times)
        form.addRow("", self.video_times)
        _open_cancel_layout(self, form)

    def spec(self, realtime: bool) -> SourceSpec:
        return SourceSpec("video", self.left.text().strip(), self.right.text().strip(),
                          self.calib.text().strip(), self.left_times.text().strip(),
                          self.right_times.text().strip(), realtime,
                          video_times=self.video_times.isChecked(),
                          left_labels=self.left_labels.text().strip(),
                          right_labels=self.right_labels.text().strip())


class SingleVideoDialog(QDialog):
    """One camera's video (a TV broadcast clip), optional labels, and whether to switch to the
    broadcast preset (the default preset is made for fixed high-speed cameras)."""

    def __init__(self, spec: SourceSpec, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("One video (TV broadcast)")
        self.setMinimumWidth(560)
        prev = spec if spec.kind == "single" else SourceSpec()
        self.video = QLineEdit(prev.left)
        self.labels = QLineEdit(prev.left_labels)
        self.labels.setToolTip("Frame,Visibility,X,Y per frame (TrackNet's format, as the broadcast "
                               "clips' *_ball.csv): the readouts then score the tracking live.")
        form = QFormLayout()
        form.addRow("Video", _file_row(self, self.video, "Video",
                                       "Videos (*.mp4 *.avi *.mov *.mkv);;All files (*)", "videos"))
        form.addRow("Labels (optional)", _file_row(self, self.labels, "Labels", "CSV (*.csv);;All files (*)",
                                                   "labels"))
        self.broadcast = QCheckBox("Track with the broadcast preset")
        self.broadcast.setToolTip("Bigger steps between frames at 30 fps, a panning picture, the "
                                  "shuttle leaving through the top edge: the preset made for TV clips")
        self.broadcast.setChecked(True)
        form.addRow("", self.broadcast)
        note = QLabel("One view gives the shuttle's path in the picture only: no distance, speed, "
                      "3D flight or landing call.")
        note.setWordWrap(True)
        note.setStyleSheet("color: #888;")
        form.addRow("", note)
        _open_cancel_layout(self, form)

    def spec(self, realtime: bool) -> SourceSpec:
        return SourceSpec("single", self.video.text().strip(), realtime=realtime,
                          left_labels=self.labels.text().strip())


class _CameraScan(QObject):
    done = Signal(list)

    def start(self) -> None:
        def work() -> None:
            from ..io.cameras import list_cameras
            found = list_cameras()
            try:
                self.done.emit(found)
            except RuntimeError:  # the dialog was closed before the scan finished
                pass
        threading.Thread(target=work, name="camera-scan", daemon=True).start()


class CameraPairDialog(QDialog):
    """Two device indices (or URLs) and the rig file; lists the devices that open."""

    def __init__(self, spec: SourceSpec, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("Two cameras")
        self.setMinimumWidth(520)
        prev = spec if spec.kind == "cameras" else SourceSpec("cameras", "0", "1")
        self.left = QComboBox(editable=True)
        self.right = QComboBox(editable=True)
        self.left.setEditText(prev.left or "0")
        self.right.setEditText(prev.right or "1")
        self.calib = QLineEdit(prev.calib or spec.calib)
        self.found = QLabel("Looking for cameras…")
        self.found.setWordWrap(True)
        form = QFormLayout()
        form.addRow("Left camera", self.left)
        form.addRow("Right camera", self.right)
        form.addRow("Rig file", _file_row(self, self.calib, "Rig file", "Rig (*.yaml *.yml *.xml);;All files (*)", "rigs"))
        form.addRow("", self.found)
        _open_cancel_layout(self, form)
        self._scan = _CameraScan(self)
        self._scan.done.connect(self._show_found)
        self._scan.start()

    def _show_found(self, indices: list) -> None:
        if not indices:
            self.found.setText("No camera opened on this machine (indices 0–7); a URL can still be typed.")
            return
        self.found.setText("Cameras that open: " + ", ".join(str(i) for i in indices))
        for combo, current in ((self.left, self.left.currentText()), (self.right, self.right.currentText())):
            combo.clear()
            combo.addItems([str(i) for i in indices])
            combo.setEditText(current)

    def spec(self, realtime: bool) -> SourceSpec:
        return SourceSpec("cameras", self.left.currentText().strip(), self.right.currentText().strip(),
                          self.calib.text().strip(), realtime=realtime)

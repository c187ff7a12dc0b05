"""*Tools ▸ Process a recording…*: track a recorded video pair, or detect in one camera's video,
into a CSV file, off the GUI thread.

Why this file exists: an operator who recorded a session wants its track — for the robot's log,
for `badminton-track eval` — without a terminal, and with the tuning the window uses now. At
2048×1536 the job takes minutes, so it runs in a QThread with a progress bar, the rate and the
time left, and Cancel; a cancelled job leaves the rows done so far in a valid CSV and says so.
It runs the loop `badminton-track track` runs (io/track_file.py), so the rows are the same, and
the same sources (gui/sources.py), so a pair opens here exactly as in *Source ▸ Stereo video
pair*. Bad input (a missing video, a rig for another resolution, a full disk) ends the job with
one sentence; the dialog stays open to fix it.

One camera's video (a TV clip, *One video…*) runs the loop of `badminton-track detect`
(io/detect_file.py): with the broadcast preset the look-ahead with the lead-in from the held
shuttle (and, when the parameters ask, a first pass adapting the classifier) — the file readout,
which the live view (frame by frame, the shipped classifier) cannot give: on the held-out TV clips
82 against 77 %.
"""

from __future__ import annotations

import logging
import threading
import time
from pathlib import Path

from PySide6.QtCore import QObject, Qt, QThread, Signal
from PySide6.QtWidgets import (QComboBox, QDialog, QFileDialog, QFormLayout, QHBoxLayout, QLabel,
                               QLineEdit, QPushButton, QSpinBox, QWidget)

from ..core.params import ParamError, TrackerParams
from ..io.detect_file import ADAPTING, DetectFileSummary, adaptation_asked, detect_to_csv
from ..io.labels import CsvFormatError, read_point_labels
from ..io.safe_write import clashing_input
from .job_dialog import JobDialogMixin
from ..io.presets import list_presets, load_preset
from ..io.sources import OpeningCancelled, SourceError
from ..io.track_file import FILE_LOOKAHEAD, TrackFileSummary, track_to_csv
from .settings import SourceSpec, dialog_folder, open_settings, remember_dialog_folder
from .sources import SingleVideoDialog, VideoPairDialog, open_spec
from .worker import USER_ERRORS, OpeningContext, _one_sentence

_log = logging.getLogger(__name__)

# Progress reaches the dialog at most this often (s): the job runs at up to hundreds of pairs a
# second and the bar needs no more.
PROGRESS_EVERY_S = 0.1


def default_output(spec: SourceSpec) -> str:
    """``<left video's name>_track.csv`` beside the left video, ``<name>_detect.csv`` beside one
    camera's video ('' without one)."""
    if not spec.left:
        return ""
    left = Path(spec.left)
    return str(left.with_name(left.stem + ("_detect.csv" if spec.kind == "single" else "_track.csv")))


class ProcessJob(QObject):
    """Opens the pair (decoded ahead on a reader thread, gui/sources.py) and tracks it into the
    CSV; lives on its own QThread."""

    progress = Signal(int, int, str)     # pairs done, pairs in all (0: unknown), what is happening
    done = Signal(object, str)           # TrackFileSummary or None, error sentence ('' if none)

    def __init__(self, spec: SourceSpec, params: TrackerParams, output: str) -> None:
        super().__init__()
        self.spec, self.params, self.output = spec, params, output
        self._cancel = threading.Event()

    def cancel(self) -> None:
        """Thread-safe: the job stops before its next pair (or its frame-time scan gives up)."""
        self._cancel.set()

    def run(self) -> None:
        summary, error = None, ""
        try:
            summary = self._detect() if self.spec.kind == "single" else self._track()
        except OpeningCancelled:
            error = "cancelled before tracking began: nothing was written"
        except USER_ERRORS as exc:
            error = _one_sentence(exc)
        except Exception as exc:  # noqa: BLE001 - a bug must not kill the dialog silently
            _log.exception("processing a recording failed")
            error = f"internal error ({type(exc).__name__}: {exc}); details are in the log"
        self.done.emit(summary, error)

    def _track(self) -> TrackFileSummary:
        """The pair tracked into the CSV (`badminton-track track`'s loop)."""
        context = OpeningContext(self._cancel, lambda text: self.progress.emit(0, 0, text))
        source, rig = open_spec(self.spec, context)
        try:
            rig.check_image_size(*source.image_size, what="the videos")
            # Steps, not left frames: free-running cameras add the right frames no left
            # frame paired with (``VideoPair.step_count``).
            total = max(int(getattr(source, "step_count", 0) or getattr(source, "frame_count", 0) or 0), 0)
            start, last = time.perf_counter(), 0.0

            def report(n: int) -> None:
                nonlocal last
                now = time.perf_counter()
                if now - last >= PROGRESS_EVERY_S or n == total:
                    last = now
                    self.progress.emit(n, total, _rate_text(n, total, now - start))

            return track_to_csv(source, rig, self.params, self.output, progress=report,
                                should_stop=self._cancel.is_set)
        finally:
            source.close()

    def _detect(self) -> DetectFileSummary:
        """One camera's video detected into the CSV (`badminton-track detect`'s loop)."""
        labels = None
        if self.spec.left_labels:
            try:
                labels = read_point_labels(self.spec.left_labels).as_dict()
            except CsvFormatError as exc:
                raise SourceError(f"{exc} (clear the label file to process the video without a score)") from None
        starts: dict[str, float] = {}
        last = 0.0

        def report(stage: str, n: int, total: int) -> None:
            nonlocal last
            now = time.perf_counter()
            start = starts.setdefault(stage, now)
            if now - last >= PROGRESS_EVERY_S or n == total:
                last = now
                # The bar runs over both passes when there are two.
                two = adaptation_asked(self.params, None)
                done = (n if stage == ADAPTING or not two else total + n) if total else 0
                self.progress.emit(done, 2 * total if two else total,
                                   _frame_rate_text(stage, n, total, now - start))

        return detect_to_csv(self.spec.left, self.params, self.output, labels=labels,
                             progress=report, should_stop=self._cancel.is_set)


def _rate_text(n: int, total: int, elapsed: float) -> str:
    rate = n / elapsed if elapsed > 0 else 0.0
    text = f"{n:,} pairs tracked · {rate:.0f} pairs/s"
    if total and rate > 0 and n < total:
        text += f" · about {max(total - n, 0) / rate:.0f} s left"
    return text


def _frame_rate_text(stage: str, n: int, total: int, elapsed: float) -> str:
    rate = n / elapsed if elapsed > 0 else 0.0
    what = "adapting the classifier to the recording" if stage == ADAPTING else "detecting"
    text = f"{what}: {n:,} frame{'s' if n != 1 else ''}"
    if rate > 0:
        text += f" · {rate:.0f} frames/s"
    if total and rate > 0 and n < total:
        text += f" · about {max(total - n, 0) / rate:.0f} s left in this pass"
    return text


def summary_text(summary: TrackFileSummary | DetectFileSummary) -> str:
    if isinstance(summary, DetectFileSummary):
        return _detect_summary_text(summary)
    share = 100.0 * summary.points_3d / summary.pairs if summary.pairs else 0.0
    head = (f"Cancelled after {summary.pairs:,} pairs: their rows are in" if summary.cancelled
            else f"Done: {summary.pairs:,} pairs, 3D point in {share:.1f} %, "
                 f"{summary.pairs_per_second:.0f} pairs/s →")
    note = f"\n{summary.rig_note}" if summary.rig_note and not summary.cancelled else ""
    score = summary.score_text
    if score:
        score = f"\n{score[:1].upper()}{score[1:]}."
    # What the output may lack (a file cut short, 3D withheld while caught): the same sentence
    # ``track`` ends with, so the operator is told in the dialog and not only in the log.
    warning = f"\n{summary.warning[:1].upper()}{summary.warning[1:]}." if summary.warning else ""
    return f"{head} {summary.output}{score}{note}{warning}"


def _detect_summary_text(summary: DetectFileSummary) -> str:
    if summary.cancelled:
        if not summary.frames:
            return "Cancelled while adapting the classifier to the recording: nothing was written."
        return f"Cancelled after {summary.frames:,} frames: their rows are in {summary.output}"
    lines = [f"Done: {summary.frames:,} frames, shuttle found in {summary.found_share:.1f} %, "
             f"{summary.frames_per_second:.0f} frames/s → {summary.output}"]
    lines += [text[:1].upper() + text[1:] + "." for text in (
        summary.adaptation_text, summary.lead_in_text, summary.score_text) if text]
    if summary.truncated:
        lines.append(f"The video ended after {summary.frames:,} of {summary.frame_count:,} frames (truncated?).")
    return "\n".join(lines)


# The parameter choice that means "what the window uses now".
WINDOW_PARAMS = "the window's now (Tools ▸ Tuning)"


class ProcessDialog(JobDialogMixin, QDialog):
    """The recording (a video pair as in *Source ▸ Stereo video pair*, or one camera's video as
    in *Source ▸ One video*), the output file, the parameters, the look-ahead, Start / Cancel, and
    the progress."""

    def __init__(self, spec: SourceSpec, params: TrackerParams, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("Process a recording")
        self.setMinimumWidth(620)
        self.spec = spec if spec.kind in ("video", "single") else SourceSpec("video", calib=spec.calib)
        self.params = params
        self.job: ProcessJob | None = None
        self.thread: QThread | None = None
        self.last_summary: TrackFileSummary | DetectFileSummary | None = None
        self.last_error = ""

        self.recording = QLabel()     # two lines of its own: a wrapped label clipped in the form
        choose = QPushButton("Video pair…")
        choose.setToolTip("Two cameras' videos and their rig: tracked in 3D (`badminton-track track`)")
        choose.clicked.connect(self.choose_recording)
        choose_one = QPushButton("One video…")
        choose_one.setToolTip("One camera's video (a TV broadcast): detected in the picture "
                              "(`badminton-track detect`)")
        choose_one.clicked.connect(self.choose_single_video)
        rec_row = QHBoxLayout()
        rec_row.addWidget(self.recording, 1)
        rec_row.addWidget(choose)
        rec_row.addWidget(choose_one)
        self.output = QLineEdit(default_output(self.spec))
        browse = QPushButton("Browse…")
        browse.clicked.connect(self._browse_output)
        out_row = QHBoxLayout()
        out_row.addWidget(self.output, 1)
        out_row.addWidget(browse)
        self.lookahead = QSpinBox()
        self.lookahead.setRange(0, 60)
        self.lookahead.setValue(FILE_LOOKAHEAD)
        self.lookahead.setSuffix(" frames")
        self.lookahead.setToolTip("Each frame's detection is re-decided once this many later frames are "
                                  "known (a file has its future); 0 gives the live readout the robot gets")
        self.preset = QComboBox()
        self.preset.addItem(WINDOW_PARAMS)
        for name, description in list_presets().items():
            self.preset.addItem(f"preset {name}", name)
            self.preset.setItemData(self.preset.count() - 1, description, Qt.ItemDataRole.ToolTipRole)
        self.preset.setToolTip("The parameters of the job: those of the window now, or a preset as shipped")
        self.preset.currentIndexChanged.connect(self._show_recording)
        form = QFormLayout()
        form.addRow("Recording", rec_row)
        form.addRow("Output CSV", out_row)
        form.addRow("Parameters", self.preset)
        form.addRow("Look-ahead", self.lookahead)

        self._lay_out_job_controls(form)
        self._show_recording()

    # ---- inputs ----------------------------------------------------------------------------
    def job_params(self) -> TrackerParams:
        """The parameters the job runs with (the choice above), with the look-ahead set here."""
        name = self.preset.currentData()
        params = self.params if name is None else load_preset(name)
        return params.with_value("lookahead.frames", self.lookahead.value())

    def _show_recording(self) -> None:
        s = self.spec
        if not s.left:
            self.recording.setText("<i>none chosen</i>")
            return
        if s.kind == "single":
            try:
                params = self.job_params()
            except ParamError as exc:     # a preset file gone bad: said when Start is pressed
                _log.warning("%s", exc)
                params = self.params
            how = ("classifier adapted to it first, then detected" if adaptation_asked(params, None)
                   else "detected")
            labels = f" · scored against {Path(s.left_labels).name}" if s.left_labels else ""
            self.recording.setText(f"{Path(s.left).name} (one camera)<br>{how}{labels}")
            self.recording.setToolTip(f"{s.left}\n{s.left_labels}".strip())
            return
        pairing = ("timestamp files" if s.left_times else "the videos' own frame times" if s.video_times
                   else "frame index")
        self.recording.setText(f"{Path(s.left).name} + {Path(s.right).name}<br>"
                               f"rig {Path(s.calib).name or '—'} · paired by {pairing}")
        self.recording.setToolTip(f"{s.left}\n{s.right}\n{s.calib}")

    def choose_recording(self) -> None:
        dialog = VideoPairDialog(self.spec, self)
        if dialog.exec():
            old_default = default_output(self.spec)
            self.spec = dialog.spec(self.spec.realtime)
            if not self.output.text().strip() or self.output.text().strip() == old_default:
                self.output.setText(default_output(self.spec))
            self._show_recording()

    def choose_single_video(self) -> None:
        dialog = SingleVideoDialog(self.spec, self)
        if dialog.exec():
            old_default = default_output(self.spec)
            self.spec = dialog.spec(self.spec.realtime)
            if dialog.broadcast.isChecked():
                self.preset.setCurrentIndex(max(self.preset.findData("broadcast"), 0))
            if not self.output.text().strip() or self.output.text().strip() == old_default:
                self.output.setText(default_output(self.spec))
            self._show_recording()

    def _browse_output(self) -> None:
        settings = open_settings()
        # The field's file (beside the recording) when there is one, else where tracks went last.
        path, _ = QFileDialog.getSaveFileName(self, "Write the track to",
                                              self.output.text() or dialog_folder(settings, "tracks"),
                                              "CSV (*.csv);;All files (*)")
        if path:
            remember_dialog_folder(settings, "tracks", path)
            self.output.setText(path)

    # ---- the job ---------------------------------------------------------------------------
    @property
    def running(self) -> bool:
        return self.thread is not None

    def start(self) -> None:
        if self.running:
            return
        output = self.output.text().strip()
        if not self.spec.left or (self.spec.kind == "video" and not self.spec.right):
            self._finish_message("Choose the recording first (Video pair… or One video…).")
            return
        if not output:
            self._finish_message("Give the output CSV file.")
            return
        clash = clashing_input(output, [self.spec.left, self.spec.right, self.spec.calib,
                                        self.spec.left_times, self.spec.right_times,
                                        self.spec.left_labels, self.spec.right_labels])
        if clash is not None:
            self._finish_message(f"The output {output} is also an input ({clash}): writing it would "
                                 f"destroy the input; choose another file.")
            return
        try:
            params = self.job_params()
        except ParamError as exc:
            self._finish_message(str(exc)[:1].upper() + str(exc)[1:])
            return
        self._start_job(ProcessJob(self.spec, params, output), "process-recording")

    def _on_done(self, summary: TrackFileSummary | None, error: str) -> None:
        self._end_job(summary, error, summary_text(summary) if summary is not None else "")

    def _finish_message(self, text: str) -> None:
        self.status.setText(text)
        # A summary of several lines needs room: grow rather than squeeze the form above it.
        self.resize(self.width(), max(self.height(), self.sizeHint().height()))
        self.start_button.setEnabled(True)
        self.cancel_button.setEnabled(False)

    def done(self, result: int) -> None:  # noqa: D401 - Qt's close path (Close, Esc, window ✕)
        """Closing the dialog cancels a running job and waits for it (a pair at most)."""
        if self.job is not None:
            self.job.cancel()
        if self.thread is not None:
            self.thread.quit()
            self.thread.wait(10000)
        super().done(result)

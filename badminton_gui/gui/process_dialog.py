"""*Tools ▸ Process a recording…*: track a recorded video pair into a CSV file, off the GUI thread.

Why this file exists: an operator who recorded a session wants its track — for the robot's log,
for `badminton-track eval` — without a terminal, and with the tuning the window uses now. At
2048×1536 the job takes minutes, so it runs in a QThread with a progress bar, the rate and the
time left, and Cancel; a cancelled job leaves the rows done so far in a valid CSV and says so.
It runs the loop `badminton-track track` runs (io/track_file.py), so the rows are the same, and
the same sources (gui/sources.py), so a pair opens here exactly as in *Source ▸ Stereo video
pair*. Bad input (a missing video, a rig for another resolution, a full disk) ends the job with
one sentence; the dialog stays open to fix it.
"""

from __future__ import annotations

import logging
import threading
import time
from pathlib import Path

from PySide6.QtCore import QObject, QThread, Signal
from PySide6.QtWidgets import (QDialog, QDialogButtonBox, QFileDialog, QFormLayout, QHBoxLayout,
                               QLabel, QLineEdit, QProgressBar, QPushButton, QSpinBox,
                               QVBoxLayout, QWidget)

from ..core.params import TrackerParams
from ..io.sources import OpeningCancelled
from ..io.track_file import FILE_LOOKAHEAD, TrackFileSummary, track_to_csv
from .settings import SourceSpec
from .sources import VideoPairDialog, open_spec
from .worker import USER_ERRORS, OpeningContext, _one_sentence

_log = logging.getLogger(__name__)

# Progress reaches the dialog at most this often (s): the job runs at up to hundreds of pairs a
# second and the bar needs no more.
PROGRESS_EVERY_S = 0.1


def default_output(spec: SourceSpec) -> str:
    """``<left video's name>_track.csv`` beside the left video ('' without one)."""
    if not spec.left:
        return ""
    left = Path(spec.left)
    return str(left.with_name(left.stem + "_track.csv"))


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

                summary = track_to_csv(source, rig, self.params, self.output, progress=report,
                                       should_stop=self._cancel.is_set)
            finally:
                source.close()
        except OpeningCancelled:
            error = "cancelled before tracking began: nothing was written"
        except USER_ERRORS as exc:
            error = _one_sentence(exc)
        except Exception as exc:  # noqa: BLE001 - a bug must not kill the dialog silently
            _log.exception("processing a recording failed")
            error = f"internal error ({type(exc).__name__}: {exc}); details are in the log"
        self.done.emit(summary, error)


def _rate_text(n: int, total: int, elapsed: float) -> str:
    rate = n / elapsed if elapsed > 0 else 0.0
    text = f"{n:,} pairs tracked · {rate:.0f} pairs/s"
    if total and rate > 0 and n < total:
        text += f" · about {max(total - n, 0) / rate:.0f} s left"
    return text


def summary_text(summary: TrackFileSummary) -> str:
    share = 100.0 * summary.points_3d / summary.pairs if summary.pairs else 0.0
    head = (f"Cancelled after {summary.pairs:,} pairs: their rows are in" if summary.cancelled
            else f"Done: {summary.pairs:,} pairs, 3D point in {share:.1f} %, "
                 f"{summary.pairs_per_second:.0f} pairs/s →")
    note = f"\n{summary.rig_note}" if summary.rig_note and not summary.cancelled else ""
    score = summary.score_text
    if score:
        score = f"\n{score[:1].upper()}{score[1:]}."
    return f"{head} {summary.output}{score}{note}"


class ProcessDialog(QDialog):
    """The recording (as in *Source ▸ Stereo video pair*), the output file, the look-ahead,
    Start / Cancel, and the progress."""

    def __init__(self, spec: SourceSpec, params: TrackerParams, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("Process a recording")
        self.setMinimumWidth(620)
        self.spec = spec if spec.kind == "video" else SourceSpec("video", calib=spec.calib)
        self.params = params
        self.job: ProcessJob | None = None
        self.thread: QThread | None = None
        self.last_summary: TrackFileSummary | None = None
        self.last_error = ""

        self.recording = QLabel()     # two lines of its own: a wrapped label clipped in the form
        choose = QPushButton("Choose…")
        choose.clicked.connect(self.choose_recording)
        rec_row = QHBoxLayout()
        rec_row.addWidget(self.recording, 1)
        rec_row.addWidget(choose)
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
        form = QFormLayout()
        form.addRow("Recording", rec_row)
        form.addRow("Output CSV", out_row)
        form.addRow("Look-ahead", self.lookahead)
        form.addRow("", QLabel("Tracked with the parameters the window uses now (Tools ▸ Tuning)."))

        self.bar = QProgressBar()
        self.bar.setRange(0, 1000)
        self.bar.setValue(0)
        self.status = QLabel("")
        self.status.setWordWrap(True)
        self.start_button = QPushButton("Start")
        self.start_button.setDefault(True)
        self.start_button.clicked.connect(self.start)
        self.cancel_button = QPushButton("Cancel")
        self.cancel_button.setEnabled(False)
        self.cancel_button.clicked.connect(self.cancel)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Close)
        buttons.rejected.connect(self.reject)
        buttons.addButton(self.start_button, QDialogButtonBox.ButtonRole.ActionRole)
        buttons.addButton(self.cancel_button, QDialogButtonBox.ButtonRole.ActionRole)
        lay = QVBoxLayout(self)
        lay.addLayout(form)
        lay.addWidget(self.bar)
        lay.addWidget(self.status)
        lay.addWidget(buttons)
        self._show_recording()

    # ---- inputs ----------------------------------------------------------------------------
    def _show_recording(self) -> None:
        s = self.spec
        if not s.left:
            self.recording.setText("<i>none chosen</i>")
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

    def _browse_output(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Write the track to", self.output.text(),
                                              "CSV (*.csv);;All files (*)")
        if path:
            self.output.setText(path)

    # ---- the job ---------------------------------------------------------------------------
    @property
    def running(self) -> bool:
        return self.thread is not None

    def start(self) -> None:
        if self.running:
            return
        output = self.output.text().strip()
        if not self.spec.left or not self.spec.right:
            self._finish_message("Choose the recording first (Choose…).")
            return
        if not output:
            self._finish_message("Give the output CSV file.")
            return
        params = self.params.with_value("lookahead.frames", self.lookahead.value())
        self.last_summary, self.last_error = None, ""
        self.job = ProcessJob(self.spec, params, output)
        self.thread = QThread(self)
        self.thread.setObjectName("process-recording")
        self.job.moveToThread(self.thread)
        self.thread.started.connect(self.job.run)
        self.job.progress.connect(self._on_progress)
        self.job.done.connect(self._on_done)
        self.bar.setValue(0)
        self.status.setText("Opening the recording…")
        self.start_button.setEnabled(False)
        self.cancel_button.setEnabled(True)
        self.thread.start()

    def cancel(self) -> None:
        if self.job is not None:
            self.job.cancel()
            self.status.setText("Cancelling…")

    def _on_progress(self, done: int, total: int, text: str) -> None:
        if total > 0:
            self.bar.setValue(int(1000 * min(done / total, 1.0)))
        self.status.setText(text)

    def _on_done(self, summary: TrackFileSummary | None, error: str) -> None:
        self.last_summary, self.last_error = summary, error
        if summary is not None and not summary.cancelled:
            self.bar.setValue(1000)
        self._finish_message(summary_text(summary) if summary is not None
                             else error[:1].upper() + error[1:])
        thread, self.thread, self.job = self.thread, None, None
        if thread is not None:
            # ``done`` is the job's last act: its thread ends as soon as its loop sees quit().
            thread.quit()
            if thread.wait(5000):
                thread.deleteLater()

    def _finish_message(self, text: str) -> None:
        self.status.setText(text)
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

"""*Tools ▸ Export video…*: the recording with the tracking drawn on it, as an MP4, off the GUI
thread.

Why this file exists: an operator shows a rally — to a player, in a report — as a clip with the
red circle, the trail, the readouts and the court plan, and checks a track by watching it. The
clip is the one `badminton-track render` writes (io/render_video.py, drawn without Qt by
core/overlay_draw.py); the track is a CSV written earlier by `track` / `detect` (or *Process a
recording…*), or is made now with the window's parameters by the same loops. Both passes run on
a QThread with a progress bar and Cancel; a cancelled or failed export leaves no file behind.
"""

from __future__ import annotations

import logging
import threading
import time
from pathlib import Path

from PySide6.QtCore import QObject, QThread, Signal
from PySide6.QtWidgets import (QButtonGroup, QComboBox, QDialog, QFileDialog, QFormLayout, QHBoxLayout,
                               QLabel, QLineEdit, QPushButton, QRadioButton, QVBoxLayout, QWidget)

from ..core.params import TrackerParams
from ..core.rig import StereoRig
from ..io.detect_file import ADAPTING
from ..io.render_video import (RENDERING, TRACKING, RenderSummary, check_output_path, detect_for_render,
                               read_render_csv, render_video, track_for_render)
from ..io.sources import OpeningCancelled
from ..io.video import VideoFile
from .job_dialog import JobDialogMixin
from .settings import SourceSpec
from .sources import SingleVideoDialog, VideoPairDialog, open_spec
from .worker import USER_ERRORS, OpeningContext, _one_sentence

_log = logging.getLogger(__name__)

PROGRESS_EVERY_S = 0.1          # the bar needs no more than ten updates a second
# (label, cameras) of the camera choice; one camera's video has only the first camera.
CAMERA_CHOICES = (("Both, side by side", (0, 1)), ("Left", (0,)), ("Right", (1,)))
SIZE_CHOICES = (("Full size", 1.0), ("Half size", 0.5), ("Quarter size", 0.25))
_STAGE_TEXT = {ADAPTING: "adapting the classifier to the recording", TRACKING: "tracking",
               RENDERING: "drawing the clip"}


def default_clip(spec: SourceSpec) -> str:
    """``<left video's name>_render.mp4`` beside the left video ('' without one)."""
    if not spec.left:
        return ""
    left = Path(spec.left)
    return str(left.with_name(left.stem + "_render.mp4"))


class RenderJob(QObject):
    """Reads or makes the track, then writes the clip; lives on its own QThread."""

    progress = Signal(int, int, str)     # per mille of the whole job, 1000, what is happening
    done = Signal(object, str)           # RenderSummary or None, error sentence ('' if none)

    def __init__(self, spec: SourceSpec, params: TrackerParams, output: str, cameras: tuple[int, ...],
                 scale: float, csv_path: str = "") -> None:
        super().__init__()
        self.spec, self.params, self.output = spec, params, output
        self.cameras, self.scale, self.csv_path = cameras, scale, csv_path
        self.thread_ident: int | None = None     # the thread ``run`` ran on (tests look)
        self._cancel = threading.Event()
        self._last_report = 0.0
        self._stage_start: dict[str, float] = {}

    def cancel(self) -> None:
        """Thread-safe: the job stops before its next frame."""
        self._cancel.set()

    def run(self) -> None:
        self.thread_ident = threading.get_ident()
        summary, error = None, ""
        try:
            summary = self._run()
        except OpeningCancelled:
            summary = self._cancelled()
        except USER_ERRORS + (ValueError,) as exc:
            error = _one_sentence(exc)
        except Exception as exc:  # noqa: BLE001 - a bug must not kill the dialog silently
            _log.exception("exporting a video failed")
            error = f"internal error ({type(exc).__name__}: {exc}); details are in the log"
        self.done.emit(summary, error)

    def _cancelled(self) -> RenderSummary:
        return RenderSummary(0, 0.0, Path(self.output), True, (0, 0), 0.0)

    def _run(self) -> RenderSummary:
        spec = self.spec
        one_camera = spec.kind == "single"
        videos = {0: spec.left} if one_camera else {0: spec.left, 1: spec.right}
        check_output_path(self.output, [spec.left, spec.right, spec.calib, self.csv_path,
                                        spec.left_times, spec.right_times])
        video = VideoFile(videos[self.cameras[0]])
        fps = video.fps
        video.close()
        passes = 1 if self.csv_path else 2
        if self.csv_path:
            track = read_render_csv(self.csv_path, fps)
            court_frame = (StereoRig.load(spec.calib).has_court_pose if spec.calib and not one_camera
                           else track.has_landing)
        elif one_camera:
            track = detect_for_render(spec.left, self.params, fps=fps, should_stop=self._cancel.is_set,
                                      progress=lambda stage, n, total: self._report(stage, n, total, 0, passes))
            court_frame = False
        else:
            context = OpeningContext(self._cancel, lambda text: self.progress.emit(0, 1000, text))
            source, rig = open_spec(spec, context)
            try:
                rig.check_image_size(*source.image_size, what="the videos")
                total = int(getattr(source, "step_count", 0) or getattr(source, "frame_count", 0) or 0)
                track = track_for_render(source, rig, self.params, total=total, should_stop=self._cancel.is_set,
                                         progress=lambda stage, n, t: self._report(stage, n, t, 0, passes))
            finally:
                source.close()
            court_frame = rig.has_court_pose
        if track is None:
            return self._cancelled()
        cameras = self.cameras
        if not track.stereo:                   # one camera's detections: on that camera's video
            if len(cameras) == 2:
                raise ValueError(f"{track.source} is one camera's detections: export one camera")
            videos, cameras = {0: videos[cameras[0]]}, (0,)
        return render_video(track, videos, self.output, cameras=cameras, scale=self.scale,
                            court_frame=court_frame, should_stop=self._cancel.is_set,
                            progress=lambda stage, n, t: self._report(stage, n, t, passes - 1, passes))

    def _report(self, stage: str, done: int, total: int, index: int, passes: int) -> None:
        """Progress of pass ``index`` of ``passes`` (the bar runs over all of them)."""
        now = time.perf_counter()
        start = self._stage_start.setdefault(stage, now)
        if now - self._last_report < PROGRESS_EVERY_S and done != total:
            return
        self._last_report = now
        fraction = min(done / total, 1.0) if total else 0.0
        rate = done / (now - start) if now > start else 0.0
        unit = "frames" if stage in (RENDERING, ADAPTING) or self.spec.kind == "single" else "pairs"
        text = f"{_STAGE_TEXT.get(stage, 'detecting')}: {done:,}" + (f" of {total:,}" if total else "") + f" {unit}"
        if rate > 0:
            text += f" · {rate:.0f} {unit}/s"
            if total and done < total:
                text += f" · about {(total - done) / rate:.0f} s left"
        if passes > 1:
            text = f"step {index + 1} of {passes}, {text}"
        self.progress.emit(int(1000 * (index + fraction) / passes), 1000, text)


def summary_text(summary: RenderSummary) -> str:
    if summary.cancelled:
        return "Cancelled: nothing was written."
    w, h = summary.size
    return (f"Done: {summary.frames:,} frames, {w}×{h} at {summary.fps:g} fps, "
            f"{summary.frames_per_second:.0f} frames/s → {summary.output}")


class RenderDialog(JobDialogMixin, QDialog):
    """The recording, the track (made now or a CSV), the camera(s), the size, the output clip,
    Start / Cancel and the progress."""

    exportFinished = Signal(object, str)     # as RenderJob.done, once the dialog has shown it

    def __init__(self, spec: SourceSpec, params: TrackerParams, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("Export video")
        self.setMinimumWidth(620)
        self.spec = spec if spec.kind in ("video", "single") else SourceSpec("video", calib=spec.calib)
        self.params = params
        self.job: RenderJob | None = None
        self.thread: QThread | None = None
        self.last_summary: RenderSummary | None = None
        self.last_error = ""

        self.recording = QLabel()
        choose = QPushButton("Video pair…")
        choose.clicked.connect(self.choose_recording)
        choose_one = QPushButton("One video…")
        choose_one.clicked.connect(self.choose_single_video)
        rec_row = QHBoxLayout()
        rec_row.addWidget(self.recording, 1)
        rec_row.addWidget(choose)
        rec_row.addWidget(choose_one)

        self.track_now = QRadioButton("Track now, with the window's parameters")
        self.from_csv = QRadioButton("From a CSV written by 'track' or 'detect':")
        self.track_now.setChecked(True)
        group = QButtonGroup(self)
        group.addButton(self.track_now)
        group.addButton(self.from_csv)
        self.csv = QLineEdit()
        self.csv.setPlaceholderText("track or detect CSV")
        self.csv.textEdited.connect(lambda _: self.from_csv.setChecked(True))
        browse_csv = QPushButton("Browse…")
        browse_csv.clicked.connect(self._browse_csv)
        csv_row = QHBoxLayout()
        csv_row.addWidget(self.from_csv)
        csv_row.addWidget(self.csv, 1)
        csv_row.addWidget(browse_csv)
        track_box = QVBoxLayout()
        track_box.addWidget(self.track_now)
        track_box.addLayout(csv_row)

        self.camera = QComboBox()
        self.size = QComboBox()
        for text, scale in SIZE_CHOICES:
            self.size.addItem(text, scale)
        self.size.setCurrentIndex(1)
        self.output = QLineEdit(default_clip(self.spec))
        browse = QPushButton("Browse…")
        browse.clicked.connect(self._browse_output)
        out_row = QHBoxLayout()
        out_row.addWidget(self.output, 1)
        out_row.addWidget(browse)

        form = QFormLayout()
        form.addRow("Recording", rec_row)
        form.addRow("Track", track_box)
        form.addRow("Camera", self.camera)
        form.addRow("Size", self.size)
        form.addRow("Output clip", out_row)

        self._lay_out_job_controls(form)
        self._show_recording()

    # ---- inputs ----------------------------------------------------------------------------
    def _show_recording(self) -> None:
        s = self.spec
        self.camera.clear()
        if s.kind == "single":
            self.camera.addItem("The video", (0,))
        else:
            for text, cameras in CAMERA_CHOICES:
                self.camera.addItem(text, cameras)
        if not s.left:
            self.recording.setText("<i>none chosen</i>")
        elif s.kind == "single":
            self.recording.setText(f"{Path(s.left).name} (one camera)")
        else:
            self.recording.setText(f"{Path(s.left).name} + {Path(s.right).name}<br>rig {Path(s.calib).name or '—'}")

    def _chose(self, dialog) -> None:
        if dialog.exec():
            old_default = default_clip(self.spec)
            self.spec = dialog.spec(self.spec.realtime)
            if not self.output.text().strip() or self.output.text().strip() == old_default:
                self.output.setText(default_clip(self.spec))
            self._show_recording()

    def choose_recording(self) -> None:
        self._chose(VideoPairDialog(self.spec, self))

    def choose_single_video(self) -> None:
        self._chose(SingleVideoDialog(self.spec, self))

    def _browse_csv(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self, "Track to draw", self.csv.text(), "CSV (*.csv);;All files (*)")
        if path:
            self.csv.setText(path)
            self.from_csv.setChecked(True)

    def _browse_output(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self, "Write the clip to", self.output.text(), "MP4 video (*.mp4)")
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
        csv_path = self.csv.text().strip() if self.from_csv.isChecked() else ""
        if not self.spec.left or (self.spec.kind == "video" and not self.spec.right):
            self._finish_message("Choose the recording first (Video pair… or One video…).")
            return
        if self.from_csv.isChecked() and not csv_path:
            self._finish_message("Give the CSV to draw, or choose to track now.")
            return
        if not output:
            self._finish_message("Give the output clip (.mp4).")
            return
        self._start_job(RenderJob(self.spec, self.params, output, self.camera.currentData(),
                                  self.size.currentData(), csv_path), "export-video")

    def _on_done(self, summary: RenderSummary | None, error: str) -> None:
        self._end_job(summary, error, summary_text(summary) if summary is not None else "")
        self.exportFinished.emit(summary, error)

    def _finish_message(self, text: str) -> None:
        self.status.setText(text)
        self.start_button.setEnabled(True)
        self.cancel_button.setEnabled(False)

    def done(self, result: int) -> None:  # noqa: D401 - Qt's close path (Close, Esc, window ✕)
        """Closing the dialog cancels a running export and waits for it (a frame at most)."""
        if self.job is not None:
            self.job.cancel()
        if self.thread is not None:
            self.thread.quit()
            self.thread.wait(10000)
        super().done(result)

"""What the dialogs that run one long job off the GUI thread share: start, progress, cancel, end.

Why this file exists: *Process a recording…* and *Export video…* each run a job object on its
own QThread with a progress bar and Cancel; the thread's lifecycle is easy to get wrong (a
QThread destroyed while running aborts the program), so it is written once here.
The dialog provides ``start()`` and ``_finish_message(text)`` and lays its form out with
``_lay_out_job_controls``; its job provides ``run``, ``cancel`` and the signals
``progress(done, total, text)`` and ``done(summary, error)``.
"""

from __future__ import annotations

from PySide6.QtCore import QThread
from PySide6.QtWidgets import QDialogButtonBox, QLabel, QLayout, QProgressBar, QPushButton, QVBoxLayout


class JobDialogMixin:
    """Mixed into a QDialog: ``self.job`` runs on ``self.thread`` until it emits ``done``."""

    job = None
    thread: QThread | None = None

    def _lay_out_job_controls(self, form: QLayout) -> None:
        """The dialog's layout: ``form`` above the progress bar, the status line and the buttons
        (Start, Cancel, Close)."""
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

    def _start_job(self, job, thread_name: str) -> None:
        self.last_summary, self.last_error = None, ""
        self.job = job
        self.thread = QThread(self)
        self.thread.setObjectName(thread_name)
        job.moveToThread(self.thread)
        self.thread.started.connect(job.run)
        job.progress.connect(self._on_progress)
        job.done.connect(self._on_done)
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

    def _end_job(self, summary, error: str, summary_text: str) -> None:
        """The job's ``done``: say how it ended, then let its thread finish and go."""
        self.last_summary, self.last_error = summary, error
        if summary is not None and not summary.cancelled:
            self.bar.setValue(1000)
        self._finish_message(summary_text if summary is not None else error[:1].upper() + error[1:])
        thread, self.thread, self.job = self.thread, None, None
        if thread is not None:
            # ``done`` is the job's last act: its thread ends as soon as its loop sees quit().
            thread.quit()
            if thread.wait(5000):
                thread.deleteLater()

"""Tools ▸ Process a recording (gui/process_dialog.py): the rows `track` writes, progress,
Cancel that keeps a valid CSV, and bad input said in one sentence (pytest-qt, under Xvfb)."""

from __future__ import annotations

import csv
import os

import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("PySide6")

pytestmark = [pytest.mark.gui,
              pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (run under Xvfb)")]

from badminton_gui.cli import main  # noqa: E402
from badminton_gui.core.params import TrackerParams  # noqa: E402
from badminton_gui.gui.process_dialog import ProcessDialog  # noqa: E402
from badminton_gui.gui.settings import SourceSpec  # noqa: E402

from .test_cli import adapting_tv_preset, make_rig_for  # noqa: E402
from .test_track_file import write_pair  # noqa: E402


@pytest.fixture
def recording(tmp_path):
    write_pair(tmp_path, 240)
    return SourceSpec("video", str(tmp_path / "l.avi"), str(tmp_path / "r.avi"), str(tmp_path / "rig.yaml"))


@pytest.fixture
def slow_tracking(monkeypatch):
    """Each pair takes ≥ 10 ms, so a job is surely still running when the test cancels it."""
    import time

    from badminton_gui.core.tracker import StereoTracker
    real = StereoTracker.process

    def slow(self, *args, **kwargs):
        time.sleep(0.01)
        return real(self, *args, **kwargs)
    monkeypatch.setattr(StereoTracker, "process", slow)


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.reader(fh))


def test_processing_gives_the_rows_of_track_with_progress(qtbot, recording, tmp_path):
    dialog = ProcessDialog(recording, TrackerParams())
    qtbot.addWidget(dialog)
    assert dialog.output.text().endswith("l_track.csv")            # beside the left video
    dialog.output.setText(str(tmp_path / "gui.csv"))
    seen = []
    dialog.start()
    dialog.job.progress.connect(lambda done, total, text: seen.append((done, total)))
    qtbot.waitUntil(lambda: not dialog.running, timeout=60_000)
    assert dialog.last_error == "" and dialog.last_summary.pairs == 240
    assert dialog.status.text().startswith("Done: 240 pairs, 3D point in ")
    assert dialog.bar.value() == 1000
    assert seen and seen[-1] == (240, 240)
    assert main(["track", "--left", recording.left, "--right", recording.right, "--calib", recording.calib,
                 "-o", str(tmp_path / "cli.csv"), "--quiet"]) == 0
    assert _rows(tmp_path / "gui.csv") == _rows(tmp_path / "cli.csv")


def test_cancel_keeps_the_rows_done_and_bad_input_is_one_sentence(qtbot, recording, tmp_path, slow_tracking):
    dialog = ProcessDialog(recording, TrackerParams())
    qtbot.addWidget(dialog)
    dialog.output.setText(str(tmp_path / "part.csv"))
    dialog.start()
    qtbot.waitUntil(lambda: "pairs tracked" in dialog.status.text(), timeout=60_000)
    dialog.cancel_button.click()
    qtbot.waitUntil(lambda: not dialog.running, timeout=60_000)
    summary = dialog.last_summary
    assert summary.cancelled and 0 < summary.pairs < 240
    assert dialog.status.text().startswith(f"Cancelled after {summary.pairs:,} pairs: their rows are in")
    rows = _rows(tmp_path / "part.csv")
    assert [int(r[0]) for r in rows[1:]] == list(range(summary.pairs))
    assert dialog.start_button.isEnabled() and not dialog.cancel_button.isEnabled()

    # A rig for another resolution: said, nothing else happens, the dialog stays usable.
    make_rig_for((640, 480)).save(tmp_path / "big.yaml")
    dialog.spec = SourceSpec("video", recording.left, recording.right, str(tmp_path / "big.yaml"))
    dialog.start()
    qtbot.waitUntil(lambda: not dialog.running, timeout=60_000)
    assert dialog.last_summary is None and "640" in dialog.last_error and "320" in dialog.last_error
    assert dialog.status.text() == dialog.last_error[:1].upper() + dialog.last_error[1:]
    # A missing video.
    dialog.spec = SourceSpec("video", str(tmp_path / "gone.avi"), recording.right, recording.calib)
    dialog.start()
    qtbot.waitUntil(lambda: not dialog.running, timeout=60_000)
    assert "video not found" in dialog.last_error


def test_closing_the_dialog_mid_job_cancels_it_cleanly(qtbot, recording, tmp_path, slow_tracking):
    dialog = ProcessDialog(recording, TrackerParams())
    qtbot.addWidget(dialog)
    dialog.output.setText(str(tmp_path / "closed.csv"))
    dialog.show()
    dialog.start()
    thread = dialog.thread
    qtbot.waitUntil(lambda: "pairs tracked" in dialog.status.text(), timeout=60_000)
    dialog.reject()                                       # Close / Esc / the window's ✕
    assert thread.isFinished()
    qtbot.waitUntil(lambda: not dialog.running, timeout=10_000)
    assert _rows(tmp_path / "closed.csv")[0][0] == "Frame"   # a valid CSV of what was done


def test_a_labelled_recording_ends_with_its_score(qtbot, tmp_path):
    """A pair opened with labels (here its label files) ends with each camera's accuracy against
    them, the file commands' figure (look-ahead 4); the rows are those of an unlabelled run."""
    from .test_cli import W, moving_dot_frames
    write_pair(tmp_path, 60)
    for name, offset in (("l.csv", 0.0), ("r.csv", -12.0)):
        _, truth = moving_dot_frames(60, offset=offset)
        (tmp_path / name).write_text("Frame,Visibility,X,Y\n" + "".join(     # (visible while in the picture)
            f"{i},{int(0 <= x < W)},{x},{y}\n" for i, (x, y) in enumerate(truth)), encoding="utf-8")
    spec = SourceSpec("video", str(tmp_path / "l.avi"), str(tmp_path / "r.avi"), str(tmp_path / "rig.yaml"),
                      left_labels=str(tmp_path / "l.csv"), right_labels=str(tmp_path / "r.csv"))
    dialog = ProcessDialog(spec, TrackerParams())
    qtbot.addWidget(dialog)
    dialog.output.setText(str(tmp_path / "gui.csv"))
    dialog.start()
    qtbot.waitUntil(lambda: not dialog.running, timeout=60_000)
    summary = dialog.last_summary
    assert summary.score_left.total == 60 and summary.score_right.total == 60
    assert summary.score_left.accuracy > 0.9
    assert "Against the labels: left " in dialog.status.text()
    assert main(["track", "--left", spec.left, "--right", spec.right, "--calib", spec.calib,
                 "-o", str(tmp_path / "cli.csv"), "--quiet"]) == 0
    assert _rows(tmp_path / "gui.csv") == _rows(tmp_path / "cli.csv")


# --- one camera's video (a TV clip): `detect`'s loop, io/detect_file.py ----------------------

@pytest.fixture
def one_video(tmp_path):
    from .test_cli import moving_dot_frames, write_labels, write_video
    frames, truth = moving_dot_frames()
    write_video(tmp_path / "dot.avi", frames)
    write_labels(tmp_path / "dot_ball.csv", truth)
    return SourceSpec("single", str(tmp_path / "dot.avi"), left_labels=str(tmp_path / "dot_ball.csv"))


def test_one_video_gives_the_rows_of_detect_with_its_score(qtbot, one_video, tmp_path):
    dialog = ProcessDialog(one_video, TrackerParams())
    qtbot.addWidget(dialog)
    assert dialog.output.text().endswith("dot_detect.csv")
    assert "dot.avi (one camera)" in dialog.recording.text() and "dot_ball.csv" in dialog.recording.text()
    # The broadcast preset as shipped: one pass, as trained (its classifier saw every venue).
    dialog.preset.setCurrentIndex(dialog.preset.findData("broadcast"))
    assert dialog.recording.text().endswith("<br>detected · scored against dot_ball.csv")
    # The window's parameters asking for the adaptation: two passes, the classifier adapted first.
    dialog.params = adapting_tv_preset()
    dialog.preset.setCurrentIndex(0)
    assert dialog.recording.text().endswith("classifier adapted to it first, then detected · scored against dot_ball.csv")
    dialog.output.setText(str(tmp_path / "gui.csv"))
    seen = []
    dialog.start()
    dialog.job.progress.connect(lambda done, total, text: seen.append((done, total, text)))
    qtbot.waitUntil(lambda: not dialog.running, timeout=120_000)
    summary = dialog.last_summary
    assert dialog.last_error == "" and summary.frames == 40 and summary.adapt_asked
    assert seen[-1][:2] == (80, 80) and seen[-1][2].startswith("detecting: 40 frames")   # both passes on the bar
    assert any(text.startswith("adapting the classifier to the recording: ") for _, _, text in seen)
    assert dialog.bar.value() == 1000
    text = dialog.status.text()
    assert text.startswith(f"Done: 40 frames, shuttle found in {summary.found_share:.1f} %")
    assert f"Against the labels: {100 * summary.score.accuracy:.2f} %" in text
    assert main(["detect", one_video.left, "--preset", "broadcast", "--adapt", "-o", str(tmp_path / "cli.csv"),
                 "--quiet"]) == 0
    assert _rows(tmp_path / "gui.csv") == _rows(tmp_path / "cli.csv")


def test_one_video_cancel_and_bad_input(qtbot, one_video, tmp_path, monkeypatch):
    import time

    from badminton_gui.core.detector import CameraDetector
    real = CameraDetector.process

    def slow(self, *args, **kwargs):
        time.sleep(0.02)
        return real(self, *args, **kwargs)
    monkeypatch.setattr(CameraDetector, "process", slow)
    dialog = ProcessDialog(one_video, TrackerParams())
    qtbot.addWidget(dialog)
    dialog.output.setText(str(tmp_path / "part.csv"))
    dialog.start()
    qtbot.waitUntil(lambda: dialog.status.text().startswith("detecting: "), timeout=60_000)
    dialog.cancel_button.click()
    qtbot.waitUntil(lambda: not dialog.running, timeout=60_000)
    summary = dialog.last_summary
    assert summary.cancelled and 0 < summary.frames < 40
    assert dialog.status.text().startswith(f"Cancelled after {summary.frames} frames: their rows are in")
    assert [int(r[0]) for r in _rows(tmp_path / "part.csv")[1:]] == list(range(summary.frames))
    # A missing video, a label file that is not one: one sentence each, the dialog usable.
    dialog.spec = SourceSpec("single", str(tmp_path / "gone.mp4"))
    dialog.start()
    qtbot.waitUntil(lambda: not dialog.running, timeout=60_000)
    assert dialog.last_summary is None and "video not found" in dialog.last_error
    (tmp_path / "bad.csv").write_text("Frame,Visibility,X,Y\n0,yes,1,2\n", encoding="utf-8")
    dialog.spec = SourceSpec("single", one_video.left, left_labels=str(tmp_path / "bad.csv"))
    dialog.start()
    qtbot.waitUntil(lambda: not dialog.running, timeout=60_000)
    assert "bad.csv" in dialog.last_error and "clear the label file" in dialog.last_error
    assert dialog.start_button.isEnabled() and not dialog.cancel_button.isEnabled()


def test_an_output_that_is_an_input_is_refused_before_anything_runs(qtbot, recording):
    """Processing into the recording's own video (or rig) would destroy it: refused in a sentence."""
    dialog = ProcessDialog(recording, TrackerParams())
    qtbot.addWidget(dialog)
    for target in (recording.left, recording.calib):
        before = open(target, "rb").read()
        dialog.output.setText(target)
        dialog.start()
        assert not dialog.running
        assert "is also an input" in dialog.status.text()
        assert open(target, "rb").read() == before

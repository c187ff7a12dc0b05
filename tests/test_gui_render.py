"""Tools ▸ Export video (gui/render_dialog.py): the clip `render` writes, made on a thread with
progress, Cancel that leaves no file, bad input in one sentence, and the drawing's constants
equal to the window's (pytest-qt, under Xvfb)."""

from __future__ import annotations

import os
import threading

import cv2
import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("PySide6")

pytestmark = [pytest.mark.gui,
              pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (run under Xvfb)")]

from badminton_gui.cli import main  # noqa: E402
from badminton_gui.core import overlay_draw as od  # noqa: E402
from badminton_gui.core.params import TrackerParams  # noqa: E402
from badminton_gui.gui.render_dialog import RenderDialog  # noqa: E402
from badminton_gui.gui.settings import SourceSpec  # noqa: E402

W, H, N = 640, 360, 48


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    assert main(["demo", "--frames", str(N), "--size", f"{W}x{H}", "--out", str(out)]) == 0
    assert main(["track", "--left", str(out / "left.mp4"), "--right", str(out / "right.mp4"),
                 "--calib", str(out / "rig.yaml"), "-o", str(out / "track.csv"), "--quiet"]) == 0
    return out


def spec_of(demo):
    return SourceSpec("video", str(demo / "left.mp4"), str(demo / "right.mp4"), str(demo / "rig.yaml"))


def leftovers(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


@pytest.fixture
def slow_drawing(monkeypatch):
    """Each frame of the clip takes ≥ 20 ms, so an export is surely running when it is cancelled."""
    import time

    import badminton_gui.io.render_video as rv
    real = rv.compose_frame

    def slow(*args, **kwargs):
        time.sleep(0.02)
        return real(*args, **kwargs)
    monkeypatch.setattr(rv, "compose_frame", slow)


def test_export_from_csv_on_a_thread_with_progress(qtbot, demo, tmp_path):
    dialog = RenderDialog(spec_of(demo), TrackerParams())
    qtbot.addWidget(dialog)
    assert dialog.output.text().endswith("left_render.mp4")          # beside the left video
    out = tmp_path / "gui.mp4"
    dialog.output.setText(str(out))
    dialog.from_csv.setChecked(True)
    dialog.csv.setText(str(demo / "track.csv"))
    dialog.camera.setCurrentIndex(0)                                  # both, side by side
    dialog.size.setCurrentIndex(1)                                    # half size
    seen = []
    with qtbot.waitSignal(dialog.exportFinished, timeout=120_000) as finished:
        dialog.start()
        job = dialog.job
        job.progress.connect(lambda done, total, text: seen.append((done, total, text)))
    summary, error = finished.args
    assert error == "" and not summary.cancelled and summary.frames == N
    assert job.thread_ident is not None and job.thread_ident != threading.get_ident()
    assert seen and seen[-1][:2] == (1000, 1000) and "drawing the clip" in seen[-1][2]
    assert dialog.bar.value() == 1000 and dialog.status.text().startswith(f"Done: {N} frames")
    cap = cv2.VideoCapture(str(out))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == N
    assert (int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT))) == (2 * W // 2, H // 2 + 120)
    cap.release()
    assert leftovers(tmp_path) == []


@pytest.mark.parametrize("track_now", [True, False], ids=["tracking-now", "from-csv"])
def test_cancel_leaves_no_file(qtbot, demo, tmp_path, slow_drawing, track_now):
    dialog = RenderDialog(spec_of(demo), TrackerParams())
    qtbot.addWidget(dialog)
    out = tmp_path / "gui.mp4"
    dialog.output.setText(str(out))
    if not track_now:
        dialog.from_csv.setChecked(True)
        dialog.csv.setText(str(demo / "track.csv"))
    dialog.start()
    stage = "tracking" if track_now else "drawing the clip"
    qtbot.waitUntil(lambda: stage in dialog.status.text(), timeout=120_000)
    with qtbot.waitSignal(dialog.exportFinished, timeout=60_000) as finished:
        dialog.cancel_button.click()
    summary, error = finished.args
    assert error == "" and summary.cancelled
    assert dialog.status.text() == "Cancelled: nothing was written."
    assert not out.exists() and leftovers(tmp_path) == []
    assert dialog.start_button.isEnabled() and not dialog.cancel_button.isEnabled()


def test_bad_input_is_one_sentence(qtbot, demo, tmp_path):
    dialog = RenderDialog(spec_of(demo), TrackerParams())
    qtbot.addWidget(dialog)
    dialog.output.setText(str(tmp_path / "gui.mp4"))
    dialog.from_csv.setChecked(True)
    dialog.csv.setText(str(demo / "left_labels.csv"))                # one camera's rows, both cameras asked
    with qtbot.waitSignal(dialog.exportFinished, timeout=60_000) as finished:
        dialog.start()
    summary, error = finished.args
    assert summary is None and "one camera's detections" in error and "\n" not in error
    assert not (tmp_path / "gui.mp4").exists()
    dialog.output.setText(str(demo / "left.mp4"))                    # the output would overwrite an input
    with qtbot.waitSignal(dialog.exportFinished, timeout=60_000) as finished:
        dialog.start()
    assert "one of the inputs" in finished.args[1]


def test_export_action_follows_the_source(qtbot, main_window, demo):
    from PySide6.QtWidgets import QMenu
    window = main_window(spec=SourceSpec("demo"))
    menu = next(m for m in window.findChildren(QMenu) if window.export_video_action in m.actions())
    menu.aboutToShow.emit()
    assert not window.export_video_action.isEnabled()               # no recording to export
    window.spec = spec_of(demo)
    menu.aboutToShow.emit()
    assert window.export_video_action.isEnabled()
    window.export_video_action.trigger()
    dialog = next(d for d in window.findChildren(RenderDialog) if d.isVisible())
    assert dialog.spec == window.spec
    dialog.close()


def test_drawing_uses_the_windows_colours_and_sizes():
    """core/overlay_draw.py repeats the window's constants (it cannot import Qt): they must agree."""
    from badminton_gui.gui import court_views, feed_view, overlays, worker

    def bgr(colour):
        return colour.blue(), colour.green(), colour.red()

    assert od.DETECTION_COLOUR == bgr(overlays.DETECTION_COLOUR)
    assert od.TRAIL_COLOUR == bgr(overlays.TRAIL_COLOUR)
    assert od.CIRCLE_RADIUS == feed_view.CIRCLE_RADIUS
    assert od.TRAIL_LEVELS == feed_view.TRAIL_LEVELS
    assert od.TRAIL_SECONDS == worker.TRAIL_SECONDS
    for ours, theirs in ((od.FLIGHT_COLOUR, court_views.FLIGHT_COLOUR),
                         (od.POSITION_COLOUR, court_views.POSITION_COLOUR),
                         (od.PREDICTED_COLOUR, court_views.PREDICTED_COLOUR),
                         (od.IN_COLOUR, court_views.IN_COLOUR), (od.OUT_COLOUR, court_views.OUT_COLOUR)):
        assert ours == tuple(reversed(theirs))

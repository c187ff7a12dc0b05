"""The main window's conveniences (pytest-qt, under Xvfb): Help ▸ About / Open log folder /
Keyboard shortcuts, the window icon, the whole window state restored, files dropped on the
window, undo and reset in the tuning dialog, and file dialogs that remember their folders.

Why this file exists: each of these is a promise to the operator that no tracking test would
notice breaking.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("PySide6")

pytestmark = [pytest.mark.gui,
              pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (run under Xvfb)")]

from PySide6.QtCore import QMimeData, QPoint, QPointF, Qt, QUrl  # noqa: E402
from PySide6.QtGui import QDragEnterEvent, QDropEvent, QKeySequence  # noqa: E402
from PySide6.QtWidgets import QApplication, QFileDialog, QPushButton  # noqa: E402

import badminton_gui  # noqa: E402
from badminton_gui.core.params import TrackerParams  # noqa: E402
from badminton_gui.gui import help_menu  # noqa: E402
from badminton_gui.gui import settings as st  # noqa: E402
from badminton_gui.gui.sources import SingleVideoDialog, VideoPairDialog  # noqa: E402
from badminton_gui.io import app_dirs  # noqa: E402
from badminton_gui.io.demo_scene import make_rig  # noqa: E402
from badminton_gui.io.presets import load_preset  # noqa: E402

WAIT_MS = 40_000


@pytest.fixture(autouse=True)
def isolated_state_dir(tmp_path, monkeypatch):
    """Logs (and a wheel's rigs) in the test's folder, never the user's."""
    monkeypatch.setenv(app_dirs.STATE_DIR_ENV, str(tmp_path / "state"))
    return tmp_path / "state"


@pytest.fixture
def opened_urls(monkeypatch):
    """What the program asked the desktop to open, instead of opening it."""
    urls: list[QUrl] = []
    monkeypatch.setattr(help_menu.QDesktopServices, "openUrl", lambda url: urls.append(url) or True)
    return urls


# ---- Help menu, icon --------------------------------------------------------------------------
def test_about_shows_the_version_licence_and_the_three_folders(main_window, isolated_gui_settings):
    window = main_window()
    window.about_action.trigger()
    about = window._about
    assert about is not None and about.isVisible()
    assert f"Version {badminton_gui.__version__}" in about.title.text()
    assert "MIT" in about.title.text()
    expected = {"Rigs": app_dirs.rig_dir(), "Settings": isolated_gui_settings, "Logs": app_dirs.log_dir()}
    for name, path in expected.items():
        assert str(path) in about.folder_labels[name].text(), name
    import cv2
    import numpy
    import PySide6
    text = about.versions_label.text()
    for version in (PySide6.__version__, cv2.__version__, numpy.__version__):
        assert version in text
    assert str(app_dirs.log_dir()) in about.report_text()
    for name, path in expected.items():
        about.copy_buttons[name].click()
        assert QApplication.clipboard().text() == str(path)


def test_about_folder_link_opens_that_folder(main_window, opened_urls):
    window = main_window()
    about = window.show_about()
    about.folder_labels["Logs"].linkActivated.emit("ignored")
    assert [Path(u.toLocalFile()) for u in opened_urls] == [app_dirs.log_dir()]


def test_open_log_folder_creates_and_opens_the_log_folder(main_window, opened_urls):
    window = main_window()
    assert not app_dirs.log_dir().exists()
    window.log_folder_action.trigger()
    assert len(opened_urls) == 1 and opened_urls[0].isLocalFile()
    assert Path(opened_urls[0].toLocalFile()) == app_dirs.log_dir()
    assert app_dirs.log_dir().is_dir()


def test_error_banner_says_where_the_log_is(main_window, opened_urls):
    window = main_window()
    window.banner.show_message("Video not found: x.mp4")
    assert window.banner.text == "Video not found: x.mp4"       # the message itself unchanged
    assert window.banner.log_label.isVisibleTo(window)
    assert str(app_dirs.log_dir()) in window.banner.log_label.text()
    window.banner.log_label.linkActivated.emit("ignored")
    assert Path(opened_urls[0].toLocalFile()) == app_dirs.log_dir()
    window.banner.show_message("Tracking is behind", kind="advice")
    assert not window.banner.log_label.isVisibleTo(window)     # advice is no error


def test_keyboard_shortcuts_are_read_from_the_menus(main_window):
    window = main_window()
    rows = help_menu.shortcut_rows(window.menuBar())
    assert ("Playback", "Pause", "Space") in rows
    assert ("Tools", "Tuning…", "Ctrl+T") in rows
    assert any(keys == "Ctrl+Z" for where, _, keys in rows if where == "Tuning dialog")
    dialog = window.show_shortcuts()
    assert dialog.table.rowCount() == len(rows)


def test_the_window_and_the_application_have_the_icon(main_window):
    window = main_window()
    assert help_menu.icon_path().is_file()
    assert not window.windowIcon().isNull()
    assert not QApplication.windowIcon().isNull()
    assert window.windowIcon().pixmap(64, 64).width() == 64


# ---- window state -----------------------------------------------------------------------------
def test_docks_and_splitters_come_back_in_the_next_window(main_window, qtbot):
    first = main_window()
    assert not first.link_dock.isVisibleTo(first)                # hidden the first time
    first.link_dock.show()
    total = sum(first.main_splitter.sizes())
    first.main_splitter.setSizes([total - 150, 150])
    first.feeds_splitter.setSizes([700, sum(first.feeds_splitter.sizes()) - 700])
    main_sizes, feed_sizes = first.main_splitter.sizes(), first.feeds_splitter.sizes()
    first.close()

    second = main_window()
    qtbot.waitUntil(lambda: second.link_dock.isVisibleTo(second), timeout=5000)
    assert all(abs(a - b) <= 2 for a, b in zip(second.main_splitter.sizes(), main_sizes))
    assert all(abs(a - b) <= 2 for a, b in zip(second.feeds_splitter.sizes(), feed_sizes))


def test_a_state_saved_by_another_layout_version_is_ignored(main_window, qtbot):
    first = main_window()
    first.link_dock.show()
    first.close()
    settings = st.open_settings()
    settings.setValue("window/state_version", 0)                 # as an older layout saved it
    settings.sync()
    second = main_window()
    qtbot.wait(50)
    assert not second.link_dock.isVisibleTo(second)


# ---- drag and drop ----------------------------------------------------------------------------
def _drop(window, paths) -> None:
    mime = QMimeData()
    mime.setUrls([QUrl.fromLocalFile(str(p)) for p in paths])
    event = QDropEvent(QPointF(200, 200), Qt.DropAction.CopyAction, mime,
                       Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier)
    window.dropEvent(event)
    assert event.isAccepted()


def test_files_dragged_over_any_view_are_taken_by_the_window(main_window):
    window = main_window()
    for target in (window.left_feed, window.plan.widget, window.readouts):
        files = QMimeData()
        files.setUrls([QUrl.fromLocalFile("/data/rig.yaml")])
        event = QDragEnterEvent(QPoint(10, 10), Qt.DropAction.CopyAction, files,
                                Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier)
        QApplication.sendEvent(target, event)
        assert event.isAccepted(), type(target).__name__
    text = QMimeData()
    text.setText("not a file")
    event = QDragEnterEvent(QPoint(10, 10), Qt.DropAction.CopyAction, text,
                            Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier)
    QApplication.sendEvent(window.left_feed, event)
    assert not event.isAccepted()


def test_dropping_an_unknown_file_says_so_in_the_status_line(main_window, qtbot, tmp_path):
    window = main_window()
    notes = tmp_path / "notes.txt"
    notes.write_text("x")
    spec, params = window.spec, window.params
    _drop(window, [notes])
    qtbot.waitUntil(lambda: "notes.txt" in window.statusBar().currentMessage(), timeout=5000)
    assert window.statusBar().currentMessage().startswith("Cannot open notes.txt")
    assert window.spec == spec and window.params == params and window.worker is None


def test_dropping_a_preset_applies_it_and_tuning_resets_to_it(main_window, qtbot, tmp_path):
    window = main_window()
    params = TrackerParams().with_value("binarize.threshold", 97)
    path = tmp_path / "club.json"
    params.save(path)
    _drop(window, [path])
    qtbot.waitUntil(lambda: window.params == params, timeout=5000)
    assert window.preset == str(path)
    assert "club" in window.statusBar().currentMessage()
    window.open_tuning()
    assert "'club'" in window._tuning.reset_button.text()


def test_dropping_a_rig_tracks_the_source_with_it(main_window, qtbot, tmp_path):
    window = main_window()
    rig = tmp_path / "court_rig.yaml"
    make_rig("binocular").save(rig)
    _drop(window, [rig])
    qtbot.waitUntil(lambda: window.spec.calib == str(rig), timeout=5000)
    assert window.worker is not None                              # the source restarted with it
    assert st.load_source_spec(st.open_settings()).calib == str(rig)
    assert "court_rig.yaml" in window.statusBar().currentMessage()


def test_dropping_a_broken_rig_keeps_the_source_and_says_why(main_window, qtbot, tmp_path):
    window = main_window()
    rig = tmp_path / "broken.yaml"
    rig.write_text("%YAML:1.0\n---\nnot_a_rig: 1\n")
    spec = window.spec
    window.open_dropped_files([str(rig)])
    assert window.banner.text != "" and window.banner.kind == "error"
    assert window.spec == spec and window.worker is None


def test_dropping_two_videos_opens_the_pair_dialog_filled_in(main_window, qtbot, tmp_path, monkeypatch):
    window = main_window()
    left, right, rig = tmp_path / "cam_left.mp4", tmp_path / "cam_right.mp4", tmp_path / "rig.yaml"
    seen = []
    monkeypatch.setattr(VideoPairDialog, "exec",
                        lambda self: seen.append((self.left.text(), self.right.text(), self.calib.text())) or 0)
    window.open_dropped_files([str(right), str(rig), str(left)])
    assert seen == [(str(left), str(right), str(rig))]
    assert window.worker is None                                   # cancelled: nothing opened


def test_dropping_one_video_opens_the_one_video_dialog(main_window, tmp_path, monkeypatch):
    window = main_window()
    clip = tmp_path / "final.mp4"
    seen = []
    monkeypatch.setattr(SingleVideoDialog, "exec", lambda self: seen.append(self.video.text()) or 0)
    window.open_dropped_files([str(clip)])
    assert seen == [str(clip)]


# ---- tuning: undo, redo, reset --------------------------------------------------------------
def test_tuning_undo_and_redo_walk_the_parameter_snapshots(main_window):
    window = main_window(params=TrackerParams())
    window.open_tuning()
    tuning = window._tuning
    assert QKeySequence("Ctrl+Z") in tuning.undo_action.shortcuts()
    assert QKeySequence("Ctrl+Shift+Z") in tuning.redo_action.shortcuts()
    original = tuning.params
    assert not tuning.undo_action.isEnabled()
    tuning.editors["binarize.threshold"].spin.setValue(120)
    after_first = tuning.params
    tuning.editors["background.history"].spin.setValue(321)
    assert tuning.params.background.history == 321

    tuning.undo_action.trigger()
    assert tuning.params == after_first and window.params == after_first
    assert tuning.editors["background.history"].spin.value() == original.background.history
    tuning.undo_action.trigger()
    assert tuning.params == original and window.params == original
    assert not tuning.undo_action.isEnabled()
    tuning.redo_action.trigger()
    assert tuning.params == after_first and window.params == after_first
    assert tuning.editors["binarize.threshold"].spin.value() == 120
    # A new change forgets what was undone.
    tuning.editors["binarize.threshold"].spin.setValue(130)
    assert not tuning.redo_action.isEnabled()


def test_ctrl_z_in_the_tuning_dialog_undoes(main_window, qtbot):
    window = main_window(params=TrackerParams())
    window.open_tuning()
    tuning = window._tuning
    tuning.activateWindow()
    qtbot.waitUntil(tuning.isActiveWindow, timeout=5000)
    tuning.editors["binarize.threshold"].spin.setValue(120)
    tuning.group_list.setFocus()
    qtbot.keyClick(tuning.group_list, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert tuning.params == TrackerParams()
    qtbot.keyClick(tuning.group_list, Qt.Key.Key_Z,
                   Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier)
    assert tuning.params.binarize.threshold == 120


def test_a_slider_drag_is_one_undo_step(main_window):
    window = main_window(params=TrackerParams())
    window.open_tuning()
    tuning = window._tuning
    original = tuning.params
    slider = tuning.editors["binarize.threshold"].slider
    slider.setSliderDown(True)
    for step in range(1, 6):
        slider.setValue(slider.value() - step)
    slider.setSliderDown(False)
    assert tuning.params != original
    tuning.undo()
    assert tuning.params == original


def test_reset_goes_to_the_preset_in_use_not_the_built_in_values(main_window):
    window = main_window(params=TrackerParams())
    window.use_preset("coarse")
    coarse = load_preset("coarse")
    assert coarse != TrackerParams()
    assert window.params == coarse
    window.open_tuning()
    tuning = window._tuning
    assert tuning.reset_button.text() == "Reset to preset 'coarse'"
    tuning.editors["binarize.threshold"].spin.setValue(coarse.binarize.threshold - 11)
    edited = tuning.params
    tuning.reset_button.click()
    assert tuning.params == coarse and window.params == coarse
    tuning.undo()                                                 # a reset can be undone too
    assert tuning.params == edited
    tuning.defaults_action.trigger()                              # the built-in values stay in reach
    assert tuning.params == TrackerParams()
    window.close()
    assert st.load_preset_in_use(st.open_settings()) == "coarse"  # and the next session knows


def test_the_next_session_resets_to_the_preset_chosen_in_this_one(main_window):
    first = main_window(params=TrackerParams())
    first.open_tuning()
    first._tuning.preset_combo.setCurrentText("coarse")
    first._tuning._preset_chosen(first._tuning.preset_combo.findText("coarse"))
    first.close()
    second = main_window(params=TrackerParams())
    second.open_tuning()
    second._tuning.reset_to_preset()
    assert second.params == load_preset("coarse")


# ---- file dialogs remember their folders ----------------------------------------------------
def test_the_rig_browser_opens_in_the_rig_folder_then_the_last_one(qtbot, tmp_path, monkeypatch):
    asked: list[str] = []
    chosen = tmp_path / "rigs" / "club.yaml"
    chosen.parent.mkdir()
    monkeypatch.setattr(QFileDialog, "getOpenFileName",
                        staticmethod(lambda parent, caption, folder, filter_: (asked.append(folder) or str(chosen), "")))
    for _ in range(2):
        dialog = VideoPairDialog(st.SourceSpec())
        qtbot.addWidget(dialog)
        dialog.calib.parentWidget().findChild(QPushButton).click()
        assert dialog.calib.text() == str(chosen)
    assert asked == [str(app_dirs.rig_dir()), str(chosen.parent)]
    # Videos keep their own folder: not the rigs' one.
    dialog = VideoPairDialog(st.SourceSpec())
    qtbot.addWidget(dialog)
    dialog.left.parentWidget().findChild(QPushButton).click()
    assert asked[-1] == str(Path.home())


def test_preset_dialogs_open_in_the_last_preset_folder(main_window, tmp_path, monkeypatch):
    window = main_window(params=TrackerParams())
    window.open_tuning()
    folder = tmp_path / "presets"
    folder.mkdir()
    preset = folder / "evening.json"
    TrackerParams().with_value("binarize.threshold", 140).save(preset)
    asked: list[str] = []
    monkeypatch.setattr(QFileDialog, "getOpenFileName",
                        staticmethod(lambda parent, caption, where, filter_: (asked.append(where) or str(preset), "")))
    monkeypatch.setattr(QFileDialog, "getSaveFileName",
                        staticmethod(lambda parent, caption, where, filter_: (asked.append(where) or "", "")))
    window._tuning._load_file()
    assert window.params.binarize.threshold == 140
    window._tuning._save_file()
    assert asked == [str(Path.home()), str(folder / "preset.json")]


def test_the_recording_dialog_opens_in_the_last_recording_folder(main_window, tmp_path, monkeypatch):
    window = main_window()
    asked: list[str] = []
    monkeypatch.setattr(QFileDialog, "getSaveFileName",
                        staticmethod(lambda parent, caption, where, filter_: (asked.append(where) or "", "")))
    assert not window.start_recording()                            # cancelled
    assert Path(asked[-1]).parent == Path.home()
    folder = tmp_path / "tracks"
    folder.mkdir()
    assert window.start_recording(folder / "rally.csv")
    window.stop_recording()
    assert not window.start_recording()
    assert Path(asked[-1]).parent == folder


def test_the_process_dialog_output_opens_where_tracks_went_last(qtbot, tmp_path, monkeypatch):
    from badminton_gui.gui.process_dialog import ProcessDialog
    folder = tmp_path / "tracks"
    folder.mkdir()
    asked: list[str] = []
    monkeypatch.setattr(QFileDialog, "getSaveFileName",
                        staticmethod(lambda parent, caption, where, filter_:
                                     (asked.append(where) or str(folder / "rally.csv"), "")))
    for _ in range(2):
        dialog = ProcessDialog(st.SourceSpec(), TrackerParams())      # no recording chosen yet
        qtbot.addWidget(dialog)
        dialog._browse_output()
        assert dialog.output.text() == str(folder / "rally.csv")
    assert asked == [str(Path.home()), str(folder)]


def test_the_refined_rig_is_saved_where_rigs_went_last(qtbot, tmp_path, monkeypatch):
    from badminton_gui.gui.refine_dialog import RefineCalibrationDialog
    first_folder, chosen = tmp_path / "calibration", tmp_path / "club-rigs" / "refined.yaml"
    chosen.parent.mkdir()
    dialog = RefineCalibrationDialog(lambda: None, lambda: first_folder)
    qtbot.addWidget(dialog)
    dialog.refined = make_rig("binocular")
    asked: list[str] = []
    monkeypatch.setattr(QFileDialog, "getSaveFileName",
                        staticmethod(lambda parent, caption, where, filter_: (asked.append(where) or str(chosen), "")))
    assert dialog.save_as() == chosen.resolve()
    assert dialog.save_as() == chosen.resolve()
    assert [Path(a).parent for a in asked] == [first_folder, chosen.parent]
    assert all(Path(a).name.startswith("rig_refined_") for a in asked)


def test_a_preset_named_from_outside_the_dialog_becomes_its_reset(main_window):
    """As `badminton-gui --preset coarse` would say it: the window is told which preset its
    parameters came from, and the open dialog's Reset follows."""
    window = main_window(params=load_preset("coarse"))
    window.open_tuning()
    window.remember_preset("coarse")
    tuning = window._tuning
    assert tuning.reset_button.text() == "Reset to preset 'coarse'"
    tuning.editors["binarize.threshold"].spin.setValue(load_preset("coarse").binarize.threshold - 5)
    tuning.reset_to_preset()
    assert window.params == load_preset("coarse")

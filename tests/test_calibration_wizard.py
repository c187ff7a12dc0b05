"""The calibration wizard driven end to end on the synthetic chessboard source (pytest-qt).

Why this file exists: the wizard's promises (live capture in a worker thread, honest coverage,
a background solve, a findable saved rig announced by ``rigSaved``, the court-pose step) are
checked here on the real widgets. Run under Xvfb (DEVELOPERS.md). Set WIZARD_SCREENSHOT_DIR to
keep a picture of every page.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import cv2
import numpy as np
import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("PySide6")

from badminton_gui.core.calibrate.board import BoardSpec  # noqa: E402
from badminton_gui.core.court import court_lines  # noqa: E402
from badminton_gui.core.rig import StereoRig  # noqa: E402
from badminton_gui.gui.calibration_wizard import CalibrationWizard, SolveWorker  # noqa: E402
from badminton_gui.io.synthetic_chessboard import (SyntheticChessboardSource,  # noqa: E402
                                                   default_synthetic_rig)

pytestmark = pytest.mark.gui

BOARD = BoardSpec(9, 6, 0.03)


def _source():
    return SyntheticChessboardSource(BOARD, n_poses=12, hold_frames=4, move_frames=3, seed=21)


def _shot(widget, name: str) -> None:
    folder = os.environ.get("WIZARD_SCREENSHOT_DIR")
    if folder:
        widget.grab().save(str(Path(folder) / f"wizard_{name}.png"))


def _court_camera():
    """Left camera 5 m behind the near baseline, 4.5 m up, looking at the court; its image."""
    centre = np.array([0.0, -11.7, 4.5])
    target = np.array([0.0, -1.0, 0.0])
    forward = (target - centre) / np.linalg.norm(target - centre)
    right = np.cross(forward, [0, 0, 1.0])
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    r_cam = np.stack([right, down, forward])
    truth = default_synthetic_rig().with_court_pose(r_cam.T, centre)
    image = np.full((480, 640, 3), (60, 120, 70), np.uint8)
    for line in court_lines():
        ends = np.array([[*line.start, 0.0], [*line.end, 0.0]])
        seg = np.linspace(ends[0], ends[1], 40)
        px = truth.project(0, seg).astype(np.int32)
        cv2.polylines(image, [px.reshape(-1, 1, 2)], False, (235, 235, 235), 2, cv2.LINE_AA)
    return truth, image


def test_wizard_capture_calibrate_save_and_court(qtbot, tmp_path):
    save_dir = tmp_path / "calibration"
    wizard = CalibrationWizard(_source, save_dir=save_dir)
    qtbot.addWidget(wizard)
    wizard.show()
    qtbot.waitExposed(wizard)

    # (a) board
    wizard.cols_spin.setValue(9)
    wizard.rows_spin.setValue(6)
    wizard.square_spin.setValue(30.0)
    _shot(wizard, "board")
    wizard.go_next()
    assert wizard.stack.currentIndex() == wizard.PAGE_CAPTURE
    assert wizard.spec == BOARD

    # (b) live capture: the worker auto-captures still, new views; bars only count captures
    qtbot.waitUntil(lambda: wizard.left_view._qimage is not None, timeout=30000)
    assert wizard.next_button.isEnabled() is False          # fewer than 5 views
    qtbot.waitUntil(lambda: len(wizard.captures) >= 9, timeout=120000)
    qtbot.waitUntil(lambda: wizard.coverage_bars["left"][0].value() > 0, timeout=10000)
    assert wizard.thumb_list.count() == len(wizard.captures)
    ids = [c.capture_id for c in wizard.captures]
    assert len(set(ids)) == len(ids)
    _shot(wizard, "capture")
    wizard.remove_captures({ids[0]})
    assert wizard.thumb_list.count() == len(wizard.captures) == len(ids) - 1
    assert ids[0] not in [c.capture_id for c in wizard.captures]

    # (c) solve in the background
    wizard.auto_check.setChecked(False)
    wizard.go_next()
    assert wizard.stack.currentIndex() == wizard.PAGE_SOLVE
    assert wizard._capture_thread is None                    # the camera worker stopped
    _shot(wizard, "calibrate")
    qtbot.waitUntil(lambda: wizard.stack.currentIndex() == wizard.PAGE_RESULT, timeout=60000)

    # (d) result
    result = wizard.outcome.result
    truth = _source().rig
    assert abs(result.M1[0, 0] / truth.M1[0, 0] - 1) < 0.01
    assert abs(result.baseline / truth.baseline - 1) < 0.01
    assert "px" in wizard.epipolar_label.text() and result.epipolar_grade in \
        wizard.epipolar_label.text()
    assert "Baseline" in wizard.figures_label.text()
    assert wizard.preview_view._qimage is not None            # rectified preview shown
    assert "px" in wizard.thumb_list.item(0).text()           # per-view error on thumbnails
    _shot(wizard, "result")
    with qtbot.waitSignal(wizard.rigSaved, timeout=10000) as saved:
        wizard.save_button.click()
    path = Path(saved.args[0])
    assert path.parent == save_dir.resolve()
    assert re.fullmatch(r"rig_\d{8}_\d{6}\.yaml", path.name)
    assert str(path) in wizard.save_label.text()
    rig = StereoRig.load(path)
    np.testing.assert_allclose(rig.M1, result.M1)

    # (e) court pose from clicks on the left image
    wizard.go_next()
    assert wizard.stack.currentIndex() == wizard.PAGE_COURT
    court_truth, court_image = _court_camera()
    wizard.set_court_image(court_image)
    first = wizard.clicks.current_name
    assert first in wizard.court_prompt.text()
    keypoints = wizard.clicks.keypoints
    for _ in range(6):
        name = wizard.clicks.current_name
        x, y = court_truth.project(0, np.array([keypoints[name]]))[0]
        assert 0 <= x < 640 and 0 <= y < 480, name
        wizard.court_click(x, y)
    assert wizard.court_solve_button.isEnabled()
    _shot(wizard, "court")
    with qtbot.waitSignal(wizard.rigSaved, timeout=10000) as saved_court:
        wizard.court_solve_button.click()
    assert Path(saved_court.args[0]) == path                  # the same rig file, updated
    with_court = StereoRig.load(path)
    assert with_court.has_court_pose
    centre = with_court.camera_centres()[0]
    assert np.linalg.norm(centre - np.array([0.0, -11.7, 4.5])) < 0.3
    _shot(wizard, "court_solved")
    wizard.close()


def test_wizard_from_folders_and_save_failure(qtbot, tmp_path):
    src = SyntheticChessboardSource(BOARD, n_poses=8, seed=31)
    left, right = tmp_path / "left", tmp_path / "right"
    left.mkdir(), right.mkdir()
    for k, pose in enumerate(src.poses):
        a, b = src.render_pair(pose)
        cv2.imwrite(str(left / f"{k:02d}.png"), a)
        cv2.imwrite(str(right / f"{k:02d}.png"), b)
    not_a_dir = tmp_path / "occupied"
    not_a_dir.write_text("a file where the folder should be")
    wizard = CalibrationWizard(_source, save_dir=not_a_dir)
    qtbot.addWidget(wizard)
    wizard.square_spin.setValue(30.0)
    assert wizard._apply_board()
    wizard.calibrate_from_folders(left, right)
    qtbot.waitUntil(lambda: wizard.stack.currentIndex() == wizard.PAGE_RESULT, timeout=60000)
    assert abs(wizard.outcome.result.baseline / src.rig.baseline - 1) < 0.01
    with qtbot.assertNotEmitted(wizard.rigSaved):
        assert wizard.save_rig() is None
    assert "Not saved" in wizard.save_label.text()
    wizard.close()


def test_wizard_reports_folder_errors(qtbot, tmp_path):
    (tmp_path / "L").mkdir()
    (tmp_path / "R").mkdir()
    wizard = CalibrationWizard(_source, save_dir=tmp_path)
    qtbot.addWidget(wizard)
    wizard.calibrate_from_folders(tmp_path / "L", tmp_path / "R")
    qtbot.waitUntil(lambda: wizard._solve_thread is None, timeout=30000)
    assert "no images" in wizard.solve_error.text()
    assert wizard.stack.currentIndex() == wizard.PAGE_SOLVE
    wizard.close()


def test_solve_worker_cancel_is_cooperative(qtbot):
    src = SyntheticChessboardSource(BOARD, n_poses=2, seed=3)
    worker = SolveWorker(BOARD, views=[], image_size=src.image_size)
    worker.cancel()
    with qtbot.waitSignal(worker.cancelled, timeout=5000):
        worker.run()


def test_wizard_board_page_refuses_square_board(qtbot):
    wizard = CalibrationWizard(_source)
    qtbot.addWidget(wizard)
    wizard.cols_spin.setValue(7)
    wizard.rows_spin.setValue(7)
    wizard.go_next()
    assert wizard.stack.currentIndex() == wizard.PAGE_BOARD
    assert "square" in wizard.board_error.text()


def test_wizard_reports_a_failing_camera_and_restarts(qtbot):
    from badminton_gui.io.sources import SourceError
    attempts = []

    def flaky():
        attempts.append(1)
        if len(attempts) == 1:
            raise SourceError("camera 1 is not connected")
        return _source()

    wizard = CalibrationWizard(flaky)
    qtbot.addWidget(wizard)
    wizard.square_spin.setValue(30.0)
    wizard.go_next()
    qtbot.waitUntil(lambda: "not connected" in wizard.status_label.text(), timeout=10000)
    qtbot.waitUntil(lambda: not wizard._capture_thread.isRunning(), timeout=10000)
    wizard.restart_capture()
    qtbot.waitUntil(lambda: wizard.left_view._qimage is not None, timeout=30000)
    assert len(attempts) == 2
    wizard.close()


def test_detection_and_solve_never_run_on_the_gui_thread(qtbot, tmp_path, monkeypatch):
    """The two complaints about other tools: a frozen window during capture and solve."""
    import threading

    import badminton_gui.gui.calibration_wizard as wiz_module
    threads = {"detect": set(), "solve": set()}
    real_detect, real_solve = wiz_module.detect_board, wiz_module.solve_stereo

    def detect(*args, **kwargs):
        threads["detect"].add(threading.get_ident())
        return real_detect(*args, **kwargs)

    def solve(*args, **kwargs):
        threads["solve"].add(threading.get_ident())
        return real_solve(*args, **kwargs)

    monkeypatch.setattr(wiz_module, "detect_board", detect)
    monkeypatch.setattr(wiz_module, "solve_stereo", solve)
    wizard = CalibrationWizard(_source, save_dir=tmp_path)
    qtbot.addWidget(wizard)
    wizard.square_spin.setValue(30.0)
    wizard.go_next()
    qtbot.waitUntil(lambda: len(wizard.captures) >= 5, timeout=120000)
    wizard.go_next()
    qtbot.waitUntil(lambda: wizard.outcome is not None, timeout=60000)
    gui_thread = threading.get_ident()
    assert threads["detect"] and gui_thread not in threads["detect"]
    assert threads["solve"] and gui_thread not in threads["solve"]
    wizard.close()


def test_court_click_labels_match_the_drawing_after_a_skip(qtbot):
    """The numbers on the clicked image are the keypoints' numbers on the court drawing, so a
    skipped point does not shift them."""
    wizard = CalibrationWizard(_source)
    qtbot.addWidget(wizard)
    _, image = _court_camera()
    wizard.set_court_image(image)
    wizard.court_click(10, 10)
    wizard.court_skip()
    assert "point 3:" in wizard.court_prompt.text()
    wizard.court_click(20, 20)
    assert [label for *_, label in wizard.court_view._points] == ["1", "3"]
    wizard.close()

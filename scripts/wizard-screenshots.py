"""Drive the calibration wizard on the synthetic chessboard source and save a picture of each page.

Why this file exists: the docs and reviews need to see what the operator sees at every step
(live capture, the solve with its progress and Cancel, the result, the saved path, the court
pose), produced the same way every time, without cameras. Run under a display, e.g.

    QT_QPA_PLATFORM=xcb xvfb-run -a -s "-screen 0 1280x720x24" \\
        .venv/bin/python scripts/wizard-screenshots.py OUT_DIR

The rig files it saves go to a temporary folder, never into calibration/.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np
from PySide6.QtCore import QEventLoop, QTimer
from PySide6.QtWidgets import QApplication

from badminton_gui.core.calibrate.board import BoardSpec
from badminton_gui.core.court import court_lines
from badminton_gui.gui.calibration_wizard import CalibrationWizard
from badminton_gui.io.synthetic_chessboard import (SyntheticChessboardSource,
                                                   default_synthetic_rig)

BOARD = BoardSpec(9, 6, 0.03)


def source():
    return SyntheticChessboardSource(BOARD, n_poses=14, hold_frames=5, move_frames=3, seed=21)


def court_view():
    """The synthetic left camera 5 m behind the near baseline, 4.5 m up; its court image."""
    centre = np.array([0.0, -11.7, 4.5])
    forward = np.array([0.0, -1.0, 0.0]) - centre
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0, 0, 1.0])
    right /= np.linalg.norm(right)
    rig = default_synthetic_rig().with_court_pose(
        np.stack([right, np.cross(forward, right), forward]).T, centre)
    image = np.full((480, 640, 3), (60, 120, 70), np.uint8)
    for line in court_lines():
        seg = np.linspace([*line.start, 0.0], [*line.end, 0.0], 40)
        px = rig.project(0, seg).astype(np.int32)
        cv2.polylines(image, [px.reshape(-1, 1, 2)], False, (235, 235, 235), 2, cv2.LINE_AA)
    return rig, image


def wait_until(condition, timeout_s: float = 120.0) -> None:
    loop = QEventLoop()
    timer = QTimer()
    timer.timeout.connect(lambda: condition() and loop.quit())
    timer.start(20)
    QTimer.singleShot(round(timeout_s * 1000), loop.quit)
    loop.exec()
    timer.stop()
    if not condition():
        raise SystemExit(f"timed out waiting for {condition.__doc__ or 'the wizard'}")


def main(out: Path) -> int:
    out.mkdir(parents=True, exist_ok=True)
    app = QApplication.instance() or QApplication(sys.argv)
    wizard = CalibrationWizard(source, save_dir=Path(tempfile.mkdtemp()) / "calibration")
    wizard.show()
    shots = []

    def shot(name: str) -> None:
        app.processEvents()
        path = out / f"wizard_{len(shots) + 1:02d}_{name}.png"
        wizard.grab().save(str(path))
        shots.append(path)

    wizard.square_spin.setValue(30.0)
    shot("board")
    wizard.go_next()

    def live_good():
        """a live view the gate accepts, with some views captured"""
        live = wizard._capture_worker.latest() if wizard._capture_worker else None
        return (len(wizard.captures) >= 4 and live is not None and live.verdict is not None
                and live.verdict.acceptable and wizard.left_view._qimage is not None)
    wait_until(live_good)
    shot("capture_live")
    wait_until(lambda: len(wizard.captures) >= 12)
    wizard.auto_check.setChecked(False)
    shot("capture_many")

    # Start the solve, grab the page mid-way, cancel, then calibrate again to the end.
    wizard.go_next()
    wait_until(lambda: wizard.solve_bar.value() > 0)
    shot("calibrate_progress")
    wizard.cancel_button.click()
    wait_until(lambda: wizard._solve_thread is None)
    shot("calibrate_cancelled")
    wizard.retry_button.click()
    wait_until(lambda: wizard.stack.currentIndex() == wizard.PAGE_RESULT)
    shot("result")

    # Back to the capture page: the thumbnails now carry their per-view errors.
    wizard.go_back()
    wait_until(lambda: "px" in wizard.thumb_list.item(0).text()
               and wizard.left_view._qimage is not None)
    shot("capture_with_errors")
    wizard.go_next()
    wait_until(lambda: wizard.stack.currentIndex() == wizard.PAGE_RESULT)
    wizard.save_button.click()
    shot("result_saved")

    wizard.go_next()
    rig, image = court_view()
    wizard.set_court_image(image)
    shot("court_start")
    for k in range(6):
        name = wizard.clicks.current_name
        if k == 5:
            wizard.court_skip()                  # a point the camera cannot see
            name = wizard.clicks.current_name
        x, y = rig.project(0, np.array([wizard.clicks.keypoints[name]]))[0]
        wizard.court_click(x, y)
    shot("court_clicked")
    wizard.court_solve_button.click()
    shot("court_solved")
    wizard.close()
    for path in shots:
        print(path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("wizard-screenshots")))

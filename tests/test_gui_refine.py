"""Calibration ▸ Refine from tracked shuttle… (gui/refine_dialog.py), driven as an operator would.

Why this file exists: it checks the dialog's promises on the demo court tracked with a rig whose
relative rotation is turned by 3°: pairs are collected from the running worker, the refit runs off
the GUI thread and is accepted with the error brought down, Apply makes the worker track with the
refined rig, Save as… writes a rig file ``StereoRig.load`` reads back (and a failing save says why
and loses nothing); a refit with too few pairs is refused in words; Cancel stops a refit.
"""

from __future__ import annotations

import os
import threading
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("PySide6")

pytestmark = [pytest.mark.gui,
              pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (run under Xvfb)")]

from PySide6.QtCore import Qt  # noqa: E402
from PySide6.QtWidgets import QFileDialog  # noqa: E402

from badminton_gui.core.rig import StereoRig  # noqa: E402
from badminton_gui.core.calibrate.refine import RefineCancelled, refine_relative_pose  # noqa: E402
from badminton_gui.gui.refine_dialog import RefineCalibrationDialog  # noqa: E402
from badminton_gui.gui.settings import load_source_spec, open_settings  # noqa: E402
from badminton_gui.io.demo_scene import DemoScene, make_rig  # noqa: E402
# How the core's tests turn a rig and make pairs of points both cameras see.
from tests.test_rig_refine import angle_between, rotated, visible_pairs  # noqa: E402

WAIT_MS = 60_000
SIZE = (640, 360)          # a small demo court: tracked fast enough under Xvfb on a loaded machine


TRUTH = make_rig("binocular", SIZE)
WRONG = rotated(TRUTH, (1.0, 0.3, 0.2), 3.0)


def _wrong_rig_demo():
    return DemoScene(seed=0, size=SIZE), WRONG


def _result(left, right):
    """A stand-in for a TrackResult: what PairCollector reads of it (x, y, tracklet, predicted)."""
    def det(d):
        return SimpleNamespace(x=d[0], y=d[1], tracklet=d[2], predicted=False)
    return SimpleNamespace(left=SimpleNamespace(detection=det(left)),
                           right=SimpleNamespace(detection=det(right)))


def _standalone_dialog(qtbot, n_pairs: int, refit=refine_relative_pose, save_dir=None):
    """A dialog on the true demo rig, fed ``n_pairs`` pairs of one long tracklet per camera."""
    dialog = RefineCalibrationDialog(lambda: TRUTH, lambda: save_dir or Path("."), refit=refit)
    qtbot.addWidget(dialog)
    for i in range(n_pairs + 4):      # a tracklet's first 4 frames make no pair
        dialog.pairs.add(_result((10.0 + i, 20.0 + i, 1), (30.0 + i, 40.0 + 0.5 * i, 2)))
    dialog.show()
    dialog.refresh_pairs(force=True)
    return dialog


def test_refine_on_the_demo_court_collects_refits_applies_and_saves(main_window, qtbot, tmp_path,
                                                                    monkeypatch):
    window = main_window()
    window.realtime_action.setChecked(False)
    window.start_opener(_wrong_rig_demo, "demo with a rig turned by 3°")
    qtbot.waitUntil(lambda: window.worker is not None and window.worker.rig_in_use is WRONG,
                    timeout=WAIT_MS)
    window.refine_action.trigger()                       # Calibration ▸ Refine from tracked shuttle…
    dialog = window._refine
    assert dialog.isVisible()
    # Pairs come from the worker's thread; the dialog shows their count and spread.
    qtbot.waitUntil(lambda: len(dialog.pairs) >= 250, timeout=WAIT_MS)
    dialog.refresh_pairs(force=True)
    assert dialog.refit_button.isEnabled()
    assert "pairs" in dialog.count_label.text() and "needed" not in dialog.count_label.text()
    assert "of the left image" in dialog.spread_label.text()
    assert not dialog.apply_button.isEnabled() and not dialog.save_button.isEnabled()

    qtbot.mouseClick(dialog.refit_button, Qt.MouseButton.LeftButton)
    assert dialog.running and not dialog.refit_button.isEnabled()
    qtbot.waitUntil(lambda: not dialog.running, timeout=WAIT_MS)
    report = dialog.report
    assert report is not None and report.accepted, dialog.verdict_label.text()
    assert report.before_median_px > 5.0 and report.after_median_px < 1.0
    assert "Accepted" in dialog.verdict_label.text()
    assert f"{report.after_median_px:.1f} px" in dialog.result_values["median"].text()
    refined = dialog.refined
    # Points of the whole court, never tracked: the refined rig pairs them as the true one does.
    # (On this short, wide-angle baseline the rotation and the baseline's direction trade a
    # little against each other, so the rotation alone need not come back exactly.)
    fresh = visible_pairs(TRUTH, 300, seed=5)
    assert np.median(refined.pair_errors(*fresh)) < 1.0 < 5.0 < np.median(WRONG.pair_errors(*fresh))
    assert angle_between(refined.R, TRUTH.R) < angle_between(WRONG.R, TRUTH.R) - 1.0

    # Apply: the running worker tracks with the refined rig (the same object), the window knows.
    qtbot.mouseClick(dialog.apply_button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: window.worker.rig_in_use is refined, timeout=WAIT_MS)
    qtbot.waitUntil(lambda: dialog.applied, timeout=WAIT_MS)
    assert window.rig is refined and "Applied" in dialog.message_label.text()
    assert not dialog.apply_button.isEnabled()
    # Tracking goes on with it: new frames arrive after the switch.
    frames = window.worker.latest_stats.frames
    qtbot.waitUntil(lambda: window.worker.latest_stats.frames > frames + 30, timeout=WAIT_MS)

    # Save as…: the file dialog is answered with a path; the rig file reads back as the refit,
    # and it becomes the source's rig file (as the wizard's does).
    target = tmp_path / "rigs" / "refined"
    monkeypatch.setattr(QFileDialog, "getSaveFileName",
                        staticmethod(lambda *args, **kwargs: (str(target), "")))
    qtbot.mouseClick(dialog.save_button, Qt.MouseButton.LeftButton)
    saved = target.with_name("refined.yaml")
    assert dialog.saved_path == saved.resolve() and "Saved" in dialog.message_label.text()
    loaded = StereoRig.load(saved)
    assert np.allclose(loaded.R, refined.R, atol=1e-9) and np.allclose(loaded.T, refined.T, atol=1e-9)
    assert load_source_spec(open_settings()).calib == str(saved.resolve())

    # A second refit starts from the rig in use, the applied one, which already fits the pairs.
    qtbot.mouseClick(dialog.refit_button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: not dialog.running, timeout=WAIT_MS)
    assert dialog.base_rig is refined and dialog.report.before_median_px < 1.0


def test_a_new_source_starts_the_pairs_over(main_window, qtbot):
    window = main_window()
    window.realtime_action.setChecked(False)
    window.start_opener(_wrong_rig_demo, "demo")
    window.open_refine()
    dialog = window._refine
    qtbot.waitUntil(lambda: len(dialog.pairs) >= 5, timeout=WAIT_MS)
    old_worker = window.worker
    window.start_opener(_wrong_rig_demo, "demo again")
    qtbot.waitUntil(lambda: window.worker is not None and window.worker is not old_worker,
                    timeout=WAIT_MS)
    assert len(dialog.pairs) < 5 and "start over" in dialog.message_label.text()
    qtbot.waitUntil(lambda: len(dialog.pairs) >= 5, timeout=WAIT_MS)   # collecting from the new one
    # A rig for other frames is refused in a sentence; the tracker keeps its rig and goes on.
    window.apply_rig(make_rig("binocular", (1280, 720)))
    qtbot.waitUntil(lambda: "Rig not applied" in window.banner.text, timeout=WAIT_MS)
    assert window.worker.rig_in_use is WRONG and window.thread.isRunning()


def test_apply_after_the_source_ended_reopens_it_with_the_refined_rig(main_window, qtbot):
    """A recorded rally is refitted after it has played out: Apply reopens it on the new rig."""
    window = main_window()
    window.realtime_action.setChecked(False)
    window.start_opener(lambda: (DemoScene(seed=0, size=SIZE, n_frames=700), WRONG), "short demo")
    window.open_refine()
    dialog = window._refine
    qtbot.waitUntil(lambda: window.thread is not None and window.thread.isFinished(), timeout=WAIT_MS)
    assert "end of the videos" in window.status_source.text().lower()
    dialog.refresh_pairs(force=True)
    assert len(dialog.pairs) >= 150 and dialog.refit_button.isEnabled()
    dialog.start_refit()
    qtbot.waitUntil(lambda: not dialog.running, timeout=WAIT_MS)
    assert dialog.report.accepted, dialog.verdict_label.text()
    refined = dialog.refined
    dialog.apply_button.click()
    qtbot.waitUntil(lambda: dialog.applied, timeout=WAIT_MS)
    assert window.worker.rig_in_use is refined and window.thread.isRunning()
    assert window.rig is refined and "Applied" in dialog.message_label.text()


def test_too_few_pairs_are_refused_in_words(qtbot):
    dialog = _standalone_dialog(qtbot, 50)
    assert len(dialog.pairs) == 50
    assert "50 more needed" in dialog.count_label.text()
    qtbot.mouseClick(dialog.refit_button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: not dialog.running, timeout=WAIT_MS)
    text = dialog.verdict_label.text()
    assert "Not refined" in text and "only 50 pairs, 100 needed" in text
    assert "keeps its rig" in text and "Keep tracking" in text
    assert dialog.refined is None
    assert not dialog.apply_button.isEnabled() and not dialog.save_button.isEnabled()


def test_cancel_stops_a_running_refit(qtbot):
    """A stand-in refit that works until the core's cancel hook says stop: Cancel must reach it,
    the dialog must return to idle saying nothing changed, and show no result."""
    started, stopped = threading.Event(), threading.Event()

    def slow_refit(rig, left, right, progress=None, cancel=None):
        progress(0.05, "fitting the cameras' relative pose")
        started.set()
        for _ in range(3000):
            if cancel():
                stopped.set()
                raise RefineCancelled("refit cancelled")
            threading.Event().wait(0.01)
        raise AssertionError("the cancel request never arrived")

    dialog = _standalone_dialog(qtbot, 120, refit=slow_refit)
    qtbot.mouseClick(dialog.refit_button, Qt.MouseButton.LeftButton)
    assert started.wait(10)
    qtbot.waitUntil(lambda: "Fitting" in dialog.stage_label.text(), timeout=WAIT_MS)
    assert dialog.running and dialog.cancel_button.isEnabled() and dialog.progress.value() == 50
    qtbot.mouseClick(dialog.cancel_button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: not dialog.running, timeout=WAIT_MS)
    assert stopped.is_set()
    assert "cancelled" in dialog.stage_label.text() and dialog.report is None
    assert dialog.refit_button.isEnabled() and not dialog.cancel_button.isEnabled()
    assert not dialog.apply_button.isEnabled() and not dialog.save_button.isEnabled()


def test_a_failed_save_says_why_and_loses_nothing(qtbot, tmp_path):
    truth = make_rig("binocular", SIZE)
    dialog = RefineCalibrationDialog(lambda: truth, lambda: tmp_path)
    qtbot.addWidget(dialog)
    dialog.refined = rotated(truth, (0, 1, 0), 0.5)        # as an accepted refit leaves it
    dialog._update_buttons()
    assert dialog.save_button.isEnabled()
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("a file where the folder should be")
    assert dialog.save_to(blocker / "rig.yaml") is None
    text = dialog.message_label.text()
    assert "Not saved" in text and "not-a-folder" in text and "still here" in text
    assert dialog.refined is not None and dialog.save_button.isEnabled()
    good = dialog.save_to(tmp_path / "ok.yaml")
    assert good is not None and np.allclose(StereoRig.load(good).R, dialog.refined.R)
    assert dialog.default_save_path().parent == tmp_path


def test_shared_pairs_hold_what_the_pair_collector_keeps():
    """SharedPairs stores the kept pairs itself (for cheap copies): they must be the collector's."""
    from badminton_gui.core.calibrate.refine import PairCollector
    from badminton_gui.gui.refine_dialog import SharedPairs
    from tests.test_rig_refine import result

    rng = np.random.default_rng(2)
    shared, plain = SharedPairs(), PairCollector()
    for i in range(2000):
        left = (float(rng.uniform(0, 640)), float(rng.uniform(0, 360)), i // 40, bool(rng.random() < 0.05))
        right = (float(rng.uniform(0, 640)), float(rng.uniform(0, 360)), i // 55, False)
        one = result(left, right if rng.random() > 0.02 else None)
        shared.add(one)
        plain.add(one)
    assert len(shared) == len(plain) > 300
    for got, want in zip(shared.points(), plain.points()):
        assert np.array_equal(got, want)
    shared.clear()
    assert len(shared) == 0 and shared.points()[0].shape == (0, 2)

"""The stereo calibration check (gui/rig_check.py, ``StereoTracker.rig_epipolar_px``): the
tracker measures how far the shuttle's sure pairs miss their epipolar lines, the readout shows
it, and a rig worth refining gets one advice line per source whose button opens the refinement."""

from __future__ import annotations

import os
from pathlib import Path
from types import SimpleNamespace

import pytest

from badminton_gui.core.params import TrackerParams
from badminton_gui.core.rig import REFINE_FROM_PX, inputs_look_swapped, refine_threshold
from badminton_gui.core.stereo.epipolar import EPIPOLAR_LEARNT_SAMPLES
from badminton_gui.core.tracker import StereoTracker
from badminton_gui.gui.rig_check import RigCheck, readout_text
from badminton_gui.io.demo_scene import DemoScene, make_rig


def test_the_tracker_reports_the_rigs_error_once_it_has_enough_sure_pairs():
    tracker = StereoTracker(make_rig("binocular", (1280, 720)), TrackerParams(), parallel=False)
    for k in range(EPIPOLAR_LEARNT_SAMPLES - 1):
        tracker.gate.add_sample(float(k))
    assert tracker.rig_epipolar_px is None
    tracker.gate.add_sample(100.0)
    assert tracker.rig_epipolar_px == 9.5            # the median of 0 … 18 and 100
    tracker.reset()
    assert tracker.rig_epipolar_px is None
    tracker.close()


def test_the_readout_and_the_advice_scale_with_the_image_and_come_once():
    assert refine_threshold(1280) == REFINE_FROM_PX and refine_threshold(2560) == 2 * REFINE_FROM_PX
    assert readout_text(None, 1280) == "—"
    assert "Refine" not in readout_text(1.4, 1280) and "1.4 px" in readout_text(1.4, 1280)
    assert "Refine" in readout_text(31.0, 2048) and "31 px" in readout_text(31.0, 2048)
    assert "Refine" not in readout_text(9.0, 2048)       # 9 px at 2048 px is 5.6 px at 1280

    check = RigCheck()
    assert check.update(SimpleNamespace(rig_epipolar_px=None), 2048) is None
    assert check.update(SimpleNamespace(rig_epipolar_px=1.5), 2048) is None
    advice = check.update(SimpleNamespace(rig_epipolar_px=31.0), 2048)
    assert advice is not None and "31 px" in advice.text and not advice.swap
    assert check.update(SimpleNamespace(rig_epipolar_px=31.0), 2048) is None    # once
    check.reset()
    assert check.update(SimpleNamespace(rig_epipolar_px=31.0), 2048) is not None


@pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs Xvfb (QT_QPA_PLATFORM=xcb)")
def test_the_banner_advises_a_refit_and_its_button_opens_the_refinement(main_window):
    from badminton_gui.gui.worker import WorkerStats

    window = main_window(params=TrackerParams())
    packet = SimpleNamespace(stats=WorkerStats(rig_epipolar_px=31.0),
                             result=SimpleNamespace(left=SimpleNamespace(image_size=(2048, 1536))))
    window._check_keep_up(0.0, packet)
    assert window.banner.isVisible() and window.banner.kind == "advice"
    assert "calibration is off" in window.banner.text
    assert window.banner.action_button.text() == "Refine…"
    window.banner.action_button.click()
    assert window._refine is not None and window._refine.isVisible()
    window._refine.close()
    window._check_keep_up(0.1, packet)
    assert not window.banner.isVisible()                 # once per source


@pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs Xvfb (QT_QPA_PLATFORM=xcb)")
def test_swapped_cameras_get_a_button_that_opens_them_the_other_way_round(main_window, monkeypatch):
    from badminton_gui.gui.settings import SourceSpec
    from badminton_gui.gui.worker import WorkerStats

    window = main_window(params=TrackerParams())
    window.spec = SourceSpec("video", "l.mp4", "r.mp4", "rig.yaml")
    opened = []
    monkeypatch.setattr(window, "start_spec", opened.append)
    packet = SimpleNamespace(stats=WorkerStats(rig_epipolar_px=20.6, rig_swapped_px=0.06),
                             result=SimpleNamespace(left=SimpleNamespace(image_size=(1280, 720))))
    window._check_keep_up(0.0, packet)
    assert window.banner.isVisible() and "look swapped" in window.banner.text
    assert window.banner.action_button.text() == "Swap cameras"
    window.banner.action_button.click()
    assert [(s.left, s.right) for s in opened] == [("r.mp4", "l.mp4")]


DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
RALLY = DATA / "nycu-stereo" / "rally_11-46-04"


@pytest.mark.skipif(not (RALLY / "CameraReader_1.mp4").is_file(),
                    reason="real data (../shared/data) not available")
def test_the_nycu_rig_imported_from_its_cfg_files_is_found_off():
    """The rig imported from the recordings' .cfg files is ≈ 10° off in its relative pose: its
    sure pairs miss by tens of px, well above the threshold (the refit takes them to ≈ 1.5 px)."""
    from badminton_gui.io.labels import read_timestamps
    from badminton_gui.io.nycu import rig_from_nycu
    from badminton_gui.io.presets import load_preset
    from badminton_gui.io.video import VideoPair

    rig = rig_from_nycu(RALLY / "CameraReader_1.cfg", RALLY / "CameraReader_2.cfg")
    src = VideoPair(RALLY / "CameraReader_1.mp4", RALLY / "CameraReader_2.mp4",
                    read_timestamps(RALLY / "CameraReader_1.csv")[1],
                    read_timestamps(RALLY / "CameraReader_2.csv")[1])
    tracker = StereoTracker(rig, load_preset("coarse"))
    try:
        for _ in range(500):
            f = src.read()
            if f is None:
                break
            tracker.process(f.left, f.right, f.t_left, f.index, f.index_right, keep_masks=False)
            if tracker.rig_epipolar_px is not None:
                break
    finally:
        tracker.close()
        src.close()
    assert tracker.rig_epipolar_px is not None
    assert tracker.rig_epipolar_px > 2 * refine_threshold(2048)
    # Off, but not swapped: exchanged, its pairs miss by about ten times more.
    assert not inputs_look_swapped(tracker.rig_epipolar_px, tracker.rig_swapped_px, 2048)


def _tracked(left: int, right: int, frames: int = 200) -> StereoTracker:
    """The demo court (640×360) tracked with camera ``left`` as the left input and ``right`` as
    the right one."""
    scene = DemoScene(seed=0, size=(640, 360), n_frames=frames)
    tracker = StereoTracker(scene.rig, TrackerParams(), parallel=False)
    while (f := scene.read()) is not None:
        images = (f.left, f.right)
        tracker.process(images[left], images[right], f.t_left, keep_masks=False)
    tracker.close()
    return tracker


def test_cameras_given_the_other_way_round_are_named_as_swapped_not_as_an_off_rig():
    as_given, exchanged = _tracked(0, 1), _tracked(1, 0)
    width = 640
    # A rig that fits as given never measures the other way round (it costs a pair's time).
    assert as_given.rig_epipolar_px < 1.0 and as_given.rig_swapped_px is None
    assert not inputs_look_swapped(as_given.rig_epipolar_px, as_given.rig_swapped_px, width)
    assert exchanged.rig_epipolar_px > refine_threshold(width) and exchanged.rig_swapped_px < 1.0
    assert inputs_look_swapped(exchanged.rig_epipolar_px, exchanged.rig_swapped_px, width)
    # A rig that is off is off both ways round: that stays advice to refine.
    assert not inputs_look_swapped(31.0, 25.0, 2048)

    advice = RigCheck().update(SimpleNamespace(rig_epipolar_px=exchanged.rig_epipolar_px,
                                               rig_swapped_px=exchanged.rig_swapped_px), width)
    assert advice.swap and "look swapped" in advice.text
    assert "swapped?" in readout_text(exchanged.rig_epipolar_px, width, exchanged.rig_swapped_px)
    from badminton_gui.io.track_file import TrackFileSummary
    summary = TrackFileSummary(200, 100, 2.0, Path("t.csv"), False, exchanged.rig_epipolar_px, width,
                               rig_swapped_px=exchanged.rig_swapped_px)
    assert "look swapped" in summary.rig_note and "refine-calib" not in summary.rig_note


def test_swapping_a_source_exchanges_everything_that_belongs_to_a_camera():
    from badminton_gui.gui.settings import SourceSpec
    spec = SourceSpec("video", "l.mp4", "r.mp4", "rig.yaml", "lt.csv", "rt.csv", left_labels="ll.csv",
                      right_labels="rl.csv")
    back = spec.swapped()
    assert (back.left, back.right, back.left_times, back.right_times, back.left_labels, back.right_labels) == (
        "r.mp4", "l.mp4", "rt.csv", "lt.csv", "rl.csv", "ll.csv")
    assert back.calib == "rig.yaml" and back.swapped() == spec
    assert spec.swappable and not SourceSpec("demo").swappable and not SourceSpec("single", "a.mp4").swappable


def test_a_file_tracked_with_an_off_rig_says_so_and_one_that_held_does_not(tmp_path):
    """``track`` and *Process a recording* end with the same note (TrackFileSummary.rig_note)."""
    from badminton_gui.gui.process_dialog import summary_text
    from badminton_gui.io.track_file import TrackFileSummary

    off = TrackFileSummary(900, 500, 9.0, tmp_path / "t.csv", False, 31.0, 2048)
    held = TrackFileSummary(900, 500, 9.0, tmp_path / "t.csv", False, 1.5, 2048)
    unknown = TrackFileSummary(900, 500, 9.0, tmp_path / "t.csv", False)
    assert "31 px" in off.rig_note and "refine-calib" in off.rig_note
    assert held.rig_note == "" and unknown.rig_note == ""
    assert off.rig_note in summary_text(off) and "\n" not in summary_text(held)


def test_the_process_dialog_ends_with_tracks_closing_warning(tmp_path):
    """What the CSV lacks (3D withheld while caught, a video cut short) is said in the dialog's
    summary too, as ``track`` says it at the end; nothing is added when nothing is wrong."""
    from badminton_gui.gui.process_dialog import summary_text
    from badminton_gui.io.track_file import TrackFileSummary

    clean = TrackFileSummary(900, 500, 9.0, tmp_path / "t.csv", False)
    short = TrackFileSummary(900, 500, 9.0, tmp_path / "t.csv", False,
                             withheld=(("caught: out of play", 12),),
                             source_notes=("the right video ended 40 frames before the left",))
    assert clean.warning == "" and "\n" not in summary_text(clean)
    text = summary_text(short)
    assert "3D withheld in 12 rows (12 caught: out of play" in text
    assert "The right video ended 40 frames before the left" in text

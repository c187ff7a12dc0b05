"""One camera's video (a TV clip) tracked live: the one-camera tracker and the GUI source.

Why this file exists: the broadcast preset is for `detect`, `track` and the GUI (issue 5); the
GUI's worker drives a tracker with the stereo tracker's interface, so the one-camera tracker
must give what `detect` gives, frame by frame, with an empty right camera and no 3D.
"""

from __future__ import annotations

import pytest

from badminton_gui.core.detector import CameraDetector
from badminton_gui.core.mono import NO_3D, MonoTracker
from badminton_gui.core.params import TrackerParams
from badminton_gui.io.video import SingleVideo

from .test_cli import moving_dot_frames, write_video


def test_the_one_camera_tracker_reports_what_the_detector_reports(tmp_path):
    frames, centres = moving_dot_frames(20)
    params = TrackerParams()
    mono, detector = MonoTracker(params), CameraDetector(params)
    found = 0
    for i, frame in enumerate(frames):
        result = mono.process(frame, None, i / 30.0, index=i)
        alone = detector.process(frame, i / 30.0)
        assert (result.left.detection is None) == (alone.detection is None)
        if alone.detection is not None:
            found += 1
            assert (result.left.detection.x, result.left.detection.y) == (alone.detection.x, alone.detection.y)
        assert result.right.detection is None and result.point is None and result.distance is None
        assert result.flight.withheld_reason == NO_3D
        assert result.right.image_size == result.left.image_size
    assert found >= 10


def test_a_single_video_source_reads_frames_without_a_second_view(tmp_path):
    frames, _ = moving_dot_frames(5)
    write_video(tmp_path / "tv.avi", frames, fps=30.0)
    source = SingleVideo(tmp_path / "tv.avi")
    try:
        assert source.cameras == 1 and source.fps == pytest.approx(30.0)
        pairs = [source.read() for _ in range(5)]
        assert source.read() is None
    finally:
        source.close()
    assert [p.index for p in pairs] == list(range(5))
    assert all(p.right is None for p in pairs)
    assert pairs[3].t_left == pytest.approx(0.1)

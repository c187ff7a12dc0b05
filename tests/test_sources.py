"""Frame sources: video pairs and live cameras share one protocol and fail with clear sentences."""

import dataclasses

import numpy as np
import pytest

from badminton_gui.io.cameras import CameraPair
from badminton_gui.io.sources import FrameSource, SourceError
from badminton_gui.io.video import VideoPair

from .test_cli import H, W, moving_dot_frames, write_video


@pytest.fixture()
def two_videos(tmp_path):
    frames, _ = moving_dot_frames(12)
    write_video(tmp_path / "a.avi", frames)
    write_video(tmp_path / "b.avi", frames[::-1])
    return tmp_path / "a.avi", tmp_path / "b.avi"


def test_video_pair_reads_by_index(two_videos):
    src = VideoPair(*two_videos)
    assert isinstance(src, FrameSource)
    assert src.image_size == (W, H)
    seen = []
    while (f := src.read()) is not None:
        seen.append((f.index, f.index_right, f.t_left))
        assert f.left.shape == (H, W, 3)
    src.close()
    assert [s[0] for s in seen] == list(range(12))
    assert seen[3][2] == pytest.approx(3 / 30.0)


def test_video_pair_loops_when_asked(two_videos):
    src = VideoPair(*two_videos, loop=True)
    indices = [src.read().index for _ in range(30)]
    src.close()
    assert indices[:14] == list(range(12)) + [0, 1]


def test_video_pair_rejects_mismatched_sizes(tmp_path, two_videos):
    import cv2
    small = tmp_path / "small.avi"
    w = cv2.VideoWriter(str(small), cv2.VideoWriter_fourcc(*"MJPG"), 30, (160, 120))
    for _ in range(3):
        w.write(np.zeros((120, 160, 3), np.uint8))
    w.release()
    with pytest.raises(SourceError, match="differ in size"):
        VideoPair(two_videos[0], small)


def test_camera_that_cannot_open_says_so(tmp_path):
    with pytest.raises(SourceError, match="left camera .* cannot be opened"):
        CameraPair(str(tmp_path / "no-such-device"), 0)


def test_camera_that_stops_delivering_says_so(two_videos):
    """A capture that runs dry (here a file opened as a 'camera') is a camera unplugged."""
    cams = CameraPair(str(two_videos[0]), str(two_videos[1]))
    frames = []
    with pytest.raises(SourceError, match="stopped delivering frames"):
        for _ in range(100):
            frames.append(cams.read())
    cams.close()
    assert len(frames) == 12
    times = [f.t_left for f in frames]
    assert all(b >= a for a, b in zip(times, times[1:]))
    assert all(abs(f.t_right - f.t_left) < 0.5 for f in frames)


def test_the_gui_opens_a_video_pair_by_its_own_frame_times(tmp_path):
    """The video-pair dialog's 'pair by the videos' own frame times' reaches the source: a right
    file recorded at half the rate pairs left frame 2k with right frame k."""
    pytest.importorskip("PySide6")
    from badminton_gui.gui.settings import SourceSpec
    from badminton_gui.gui.sources import open_spec

    from .test_cli import make_rig_for
    frames, _ = moving_dot_frames(12)
    write_video(tmp_path / "l.avi", frames, fps=30.0)
    write_video(tmp_path / "r.avi", frames[::2], fps=15.0)
    make_rig_for().save(tmp_path / "rig.yaml")
    spec = SourceSpec("video", str(tmp_path / "l.avi"), str(tmp_path / "r.avi"),
                      str(tmp_path / "rig.yaml"), video_times=True)
    source, rig = open_spec(spec)
    try:
        pairs = [source.read() for _ in range(7)]
    finally:
        source.close()
    assert [round(p.t_right * 15) for p in pairs[0::2]] == [0, 1, 2, 3]
    assert [p.t_left for p in pairs] == pytest.approx([i / 30 for i in range(7)], abs=1e-3)


def test_the_frame_time_scan_reports_progress_and_can_be_given_up(tmp_path):
    """``frame_times`` reports rising fractions up to the file's end, and stops with
    OpeningCancelled as soon as it is asked to; ``open_spec`` passes the worker's context on."""
    from badminton_gui.io.sources import OpeningCancelled
    from badminton_gui.io.video import frame_times

    frames, _ = moving_dot_frames(100)
    write_video(tmp_path / "l.avi", frames, fps=30.0)
    fractions = []
    times = frame_times(tmp_path / "l.avi", progress=fractions.append)
    assert len(times) == 100
    assert len(fractions) == 3 and fractions == sorted(fractions) and fractions[-1] == pytest.approx(0.96)
    asked = []

    def stop_on_second_ask():
        asked.append(True)
        return len(asked) >= 2

    with pytest.raises(OpeningCancelled, match="l.avi"):
        frame_times(tmp_path / "l.avi", should_stop=stop_on_second_ask)
    assert len(asked) == 2

    pytest.importorskip("PySide6")
    import threading

    from badminton_gui.gui.settings import SourceSpec
    from badminton_gui.gui.sources import open_spec
    from badminton_gui.gui.worker import OpeningContext

    from .test_cli import make_rig_for
    write_video(tmp_path / "r.avi", frames, fps=30.0)
    make_rig_for().save(tmp_path / "rig.yaml")
    spec = SourceSpec("video", str(tmp_path / "l.avi"), str(tmp_path / "r.avi"),
                      str(tmp_path / "rig.yaml"), video_times=True)
    abort, reports = threading.Event(), []
    source, _ = open_spec(spec, OpeningContext(abort, reports.append))
    source.close()
    assert reports and reports[0].startswith("reading the left video's frame times: ")
    abort.set()
    with pytest.raises(OpeningCancelled):
        open_spec(spec, OpeningContext(abort, reports.append))


def test_a_video_seek_lands_on_the_frame_a_sequential_decode_gives(tmp_path):
    """VideoFile.seek(i) then read() is decoded frame i, forward and back; on the real
    launcher-stereo video (irregular timestamps, where OpenCV's index seek to 100 / 200 / 300
    lands on decoded frame 105 / 212 / 317) too, when the data is there."""
    import hashlib
    from pathlib import Path

    from badminton_gui.io.video import VideoFile

    frames, _ = moving_dot_frames(40)
    write_video(tmp_path / "v.avi", frames, fps=30.0)
    cases = [(tmp_path / "v.avi", (30, 35, 3, 0, 20))]
    real = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "launcher-stereo" / \
        "2024-09-19_10-26-01_1.mp4"
    if real.exists():
        cases.append((real, (300, 100, 5, 0, 212)))
    for path, indices in cases:
        video = VideoFile(path)
        decoded = [hashlib.md5(video.read().tobytes()).hexdigest() for _ in range(max(indices) + 1)]
        video.close()
        video = VideoFile(path)
        for i in indices:
            video.seek(i)
            frame = video.read()
            assert hashlib.md5(frame.tobytes()).hexdigest() == decoded[i], (path.name, i)
            assert video.next_index == i + 1
        video.close()


def test_a_labelled_video_pair_carries_its_truth_and_bad_labels_are_named(tmp_path):
    """Label files (or timestamp files that carry labels, as the NYCU recordings') reach the
    opened source as its truth for the live score; a broken or half-given pair is one sentence."""
    pytest.importorskip("PySide6")
    from badminton_gui.gui.settings import SourceSpec
    from badminton_gui.gui.sources import open_spec

    from .test_cli import make_rig_for
    frames, centres = moving_dot_frames(6)
    write_video(tmp_path / "l.avi", frames)
    write_video(tmp_path / "r.avi", frames)
    make_rig_for().save(tmp_path / "rig.yaml")
    labels = tmp_path / "labels.csv"
    labels.write_text("Frame,Visibility,X,Y,Timestamp\n" + "".join(
        f"{i},1,{x},{y},{i / 30}\n" for i, (x, y) in enumerate(centres)), encoding="utf-8")
    base = SourceSpec("video", str(tmp_path / "l.avi"), str(tmp_path / "r.avi"), str(tmp_path / "rig.yaml"))
    for spec in (dataclasses.replace(base, left_labels=str(labels), right_labels=str(labels)),
                 dataclasses.replace(base, left_times=str(labels), right_times=str(labels))):
        source, _ = open_spec(spec)
        try:
            frame = source.read()
            assert source.frame_truth.for_frame(frame)[0] == (True, *map(float, centres[0]))
        finally:
            source.close()
    source, _ = open_spec(base)                  # no labels: no truth
    source.close()
    assert source.frame_truth is None
    with pytest.raises(SourceError, match="both videos"):
        open_spec(dataclasses.replace(base, left_labels=str(labels)))
    broken = tmp_path / "broken.csv"
    broken.write_text("Frame,Visible\n0,1\n", encoding="utf-8")
    with pytest.raises(SourceError, match="broken.csv.*without a score"):
        open_spec(dataclasses.replace(base, left_labels=str(broken), right_labels=str(broken)))

"""How benchmarks/accuracy.py scores a clip whose labels were drawn on the frames seeks returned.

Why this file exists: launcher-stereo's labels were numbered through seeks (benchmarks/clips.py,
LABELLED_BY_SEEK), so label row i describes the image a seek to i shows, not decoded frame i.
The scoring must compare each label row with the prediction for that image, and leave out rows
whose seek shows nothing; the seek map itself must be the identity on a regular video.
"""

from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
sys.path.insert(0, str(BENCHMARKS))

import accuracy  # noqa: E402
import clips  # noqa: E402
from badminton_gui.io.labels import write_point_labels  # noqa: E402
from badminton_gui.io.video import frame_times  # noqa: E402


def test_label_rows_are_scored_against_the_image_their_seek_shows(tmp_path, monkeypatch):
    # Decoded frames 0..7; a seek to i shows frame i for i < 3, then i + 2, and nothing past 5.
    seek = np.array([0, 1, 2, 5, 6, 7, -1, -1])
    monkeypatch.setattr(accuracy, "seek_frame_map", lambda video: seek)
    labels = tmp_path / "labels.csv"
    # Label rows 0..5 follow a shuttle at x = 100 + 10 * (decoded frame the row was drawn on).
    rows = range(6)
    write_point_labels(labels, rows, [True] * 6, [(100 + 10 * seek[i], 50) for i in rows])
    pred = {j: (True, 100.0 + 10 * j, 50.0) for j in range(8)}
    through_seek = accuracy.score(pred, labels, 512, None, seek_video=Path("video.mp4"))
    assert (through_seek.tp, through_seek.fp1, through_seek.fn) == (6, 0, 0)
    # Scored frame by frame, rows 3..5 meet the prediction of another image: 20 px away.
    plain = accuracy.score(pred, labels, 512, None)
    assert (plain.tp, plain.fp1) == (3, 3)


def test_a_label_row_whose_seek_shows_nothing_is_left_out(tmp_path, monkeypatch):
    monkeypatch.setattr(accuracy, "seek_frame_map", lambda video: np.array([0, 1, -1]))
    labels = tmp_path / "labels.csv"
    write_point_labels(labels, [0, 1, 2], [True, True, True], [(10, 10), (20, 10), (30, 10)])
    out = accuracy.score({0: (True, 10.0, 10.0), 1: (True, 20.0, 10.0)}, labels, 512, None,
                         seek_video=Path("video.mp4"))
    assert (out.tp, out.fn, out.tp + out.tn + out.fp1 + out.fp2 + out.fn) == (2, 0, 2)


def test_seeks_and_decoding_agree_on_a_regular_video(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    video = tmp_path / "regular.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 30.0, (64, 48))
    if not writer.isOpened():
        pytest.skip("no MJPG writer in this OpenCV build")
    for i in range(20):
        frame = np.zeros((48, 64, 3), np.uint8)
        frame[:, i * 3:i * 3 + 3] = 255
        writer.write(frame)
    writer.release()
    times = frame_times(video)
    assert len(times) == 20 and np.allclose(np.diff(times), 1 / 30, atol=1e-3)
    assert np.array_equal(clips.seek_frame_map(video), np.arange(20))
    cached = list((tmp_path / "cache" / "badminton-gui" / "seek-maps").glob("*.npy"))
    assert len(cached) == 1                                     # cached for the next run, privately
    assert cached[0].parent.stat().st_mode & 0o077 == 0
    assert np.array_equal(clips.seek_frame_map(video), np.arange(20))



def test_benchmark_caches_are_private(tmp_path, monkeypatch):
    """A cache another local user could plant (a symlink to their folder, a folder open to
    others) is refused or closed before anything is read from it."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    folder = clips.cache_dir("probe")
    assert folder == tmp_path / "badminton-gui" / "probe" and folder.stat().st_mode & 0o777 == 0o700
    folder.chmod(0o777)
    assert clips.cache_dir("probe").stat().st_mode & 0o777 == 0o700
    elsewhere = tmp_path / "planted"
    elsewhere.mkdir()
    (tmp_path / "badminton-gui" / "linked").symlink_to(elsewhere)
    with pytest.raises(RuntimeError, match="symlink"):
        clips.cache_dir("linked")


def test_the_in_play_row_leaves_the_held_serve_out(tmp_path):
    # A shuttle held still for 1 s (30 frames at 30 fps, no Timestamp column), then flying: a
    # chain that never reports the held shuttle misses 30 labelled frames by the protocol; in
    # play, those of them at rest are left out (clips.rest_frames, the video's frame rate).
    video = tmp_path / "clip.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 30.0, (64, 48))
    if not writer.isOpened():
        pytest.skip("no MJPG writer in this OpenCV build")
    for _ in range(60):
        writer.write(np.zeros((48, 64, 3), np.uint8))
    writer.release()
    labels = tmp_path / "labels.csv"
    xs = [100.0] * 30 + [100.0 + 15 * k for k in range(1, 31)]
    write_point_labels(labels, range(60), [True] * 60, [(x, 50.0) for x in xs])
    pred = {f: (f >= 30, xs[f], 50.0) for f in range(60)}
    row = accuracy.scored("c", "-", "detect", True, "broadcast", pred, labels, 1280, None, video,
                          False, 30.0, "frames/s")
    assert (row.outcomes.tp, row.outcomes.fn) == (30, 30)
    assert row.rest >= 25 and (row.in_play.tp, row.in_play.fn) == (30, 30 - row.rest)

"""The session recorder (io/track_log.py): the rows of `track`, and a failing disk ends the
recording with a reason while what was written stays."""

from __future__ import annotations

import csv
import errno
import os

import pytest

from badminton_gui.core.params import TrackerParams
from badminton_gui.core.tracker import StereoTracker
from badminton_gui.io.demo_scene import DemoScene
from badminton_gui.io.labels import TRACK_COLUMNS, track_row
from badminton_gui.io.track_log import RecordingError, TrackRecorder


def _results(n):
    scene = DemoScene(seed=0)
    tracker = StereoTracker(scene.rig, TrackerParams())
    try:
        out = []
        for _ in range(n):
            f = scene.read()
            out.append(tracker.process(f.left, f.right, f.t_left, f.index, f.index_right, keep_masks=False))
        return out
    finally:
        tracker.close()
        scene.close()


def test_the_recording_holds_the_rows_track_writes(tmp_path):
    results = _results(40)
    rec = TrackRecorder(tmp_path / "deep" / "session.csv")      # folders are made
    for r in results:
        rec.add(r)
    assert rec.rows == 40
    rec.close()
    rec.close()                                                 # twice is harmless
    rec.add(results[0])                                         # after close: ignored
    assert rec.rows == rec.rows_saved == 40 and rec.error == ""
    with (tmp_path / "deep" / "session.csv").open(newline="") as fh:
        rows = list(csv.reader(fh))
    assert tuple(rows[0]) == TRACK_COLUMNS
    assert rows[1:] == [track_row(r) for r in results]
    assert sum(row[9] == "1" for row in rows[1:]) > 10          # the demo shuttle was triangulated


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs Linux's /dev/full")
def test_a_full_disk_is_said_at_once_when_recording_starts():
    """/dev/full fails every write with ENOSPC, as a full disk does."""
    with pytest.raises(RecordingError, match="^cannot record: the disk is full writing /dev/full$"):
        TrackRecorder("/dev/full")


class _DiskFillsUp:
    """A file whose disk fills up after ``room`` characters (ENOSPC on the write that overflows)."""

    def __init__(self, real, room):
        self.real, self.room = real, room

    def write(self, text):
        if len(text) > self.room:
            raise OSError(errno.ENOSPC, "No space left on device")
        self.room -= len(text)
        return self.real.write(text)

    def flush(self):
        self.real.flush()

    def close(self):
        self.real.close()

    def __getattr__(self, name):
        return getattr(self.real, name)


def test_a_disk_filling_up_while_recording_ends_the_recording_not_the_tracker(tmp_path, monkeypatch):
    """``add`` runs on the tracking thread: it never raises; the recorder says the disk is full,
    writes nothing more, and the rows flushed before stay in the file."""
    import badminton_gui.io.track_log as track_log
    results = _results(30)
    monkeypatch.setattr(track_log, "FLUSH_EVERY_S", 0.0)        # every row reaches the disk
    path = tmp_path / "session.csv"
    rec = TrackRecorder(path)
    rec._fh._fh = _DiskFillsUp(rec._fh._fh, room=1500)        # the recorder's raw file
    for r in results:
        rec.add(r)                                              # must not raise
    assert rec.error == f"the disk is full writing {path}"
    assert rec.closed and 0 < rec.rows_saved < 30
    kept = path.read_text().splitlines()
    assert len(kept) == 1 + rec.rows_saved                      # the header and the saved rows
    rec.close()
    assert rec.error                                            # closing does not hide what happened


def test_a_file_that_cannot_be_made_is_refused_with_one_sentence(tmp_path):
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    with pytest.raises(RecordingError, match="cannot record: "):
        TrackRecorder(blocker / "session.csv")                  # its "folder" is a file

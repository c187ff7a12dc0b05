"""io/track_file.py: the loop `track` and the GUI's Process-a-recording run — the same rows for
the same recording, cancellation that leaves a valid CSV, and a full disk said in one sentence."""

from __future__ import annotations

import csv
import os

import pytest

from badminton_gui.cli import main
from badminton_gui.core.params import TrackerParams
from badminton_gui.io.labels import TRACK_COLUMNS
from badminton_gui.io.track_file import TrackFileError, track_to_csv
from badminton_gui.io.video import VideoPair

from .test_cli import make_rig_for, moving_dot_frames, write_video


def write_pair(folder, n):
    """l.avi, r.avi (the dot seen by two cameras, ``n`` frames) and their rig.yaml in ``folder``."""
    frames_l, _ = moving_dot_frames(n)
    frames_r, _ = moving_dot_frames(n, offset=-12.0)
    write_video(folder / "l.avi", frames_l)
    write_video(folder / "r.avi", frames_r)
    make_rig_for().save(folder / "rig.yaml")
    return folder


@pytest.fixture
def pair(tmp_path):
    return write_pair(tmp_path, 60)


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.reader(fh))


def test_the_same_rows_as_the_track_command(pair):
    assert main(["track", "--left", str(pair / "l.avi"), "--right", str(pair / "r.avi"),
                 "--calib", str(pair / "rig.yaml"), "-o", str(pair / "cli.csv"), "--quiet"]) == 0
    done = []
    source = VideoPair(pair / "l.avi", pair / "r.avi")
    summary = track_to_csv(source, make_rig_for(), TrackerParams(), pair / "gui.csv", progress=done.append)
    source.close()
    assert _rows(pair / "gui.csv") == _rows(pair / "cli.csv")
    assert summary.pairs == 60 and done == list(range(1, 61)) and not summary.cancelled
    assert summary.points_3d == sum(r[9] == "1" for r in _rows(pair / "gui.csv")[1:]) > 0


def test_cancelling_keeps_a_valid_csv_of_the_pairs_done(pair):
    done = []
    source = VideoPair(pair / "l.avi", pair / "r.avi")
    summary = track_to_csv(source, make_rig_for(), TrackerParams(), pair / "part.csv",
                           progress=done.append, should_stop=lambda: len(done) >= 25)
    source.close()
    assert summary.cancelled and summary.pairs == 25
    rows = _rows(pair / "part.csv")
    assert tuple(rows[0]) == TRACK_COLUMNS
    assert [int(r[0]) for r in rows[1:]] == list(range(25))   # the look-ahead's pending rows too


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs Linux's /dev/full")
def test_a_full_disk_is_one_sentence(pair):
    source = VideoPair(pair / "l.avi", pair / "r.avi")
    with pytest.raises(TrackFileError, match="^cannot write the track: the disk is full writing /dev/full$"):
        track_to_csv(source, make_rig_for(), TrackerParams(), "/dev/full")
    source.close()



class _Counting:
    """A classifier that counts its calls (and scores as the one it wraps)."""

    def __init__(self, inner) -> None:
        self.inner, self.calls = inner, 0
        self.name, self.feature_names = inner.name, inner.feature_names

    def probability(self, features):
        self.calls += 1
        return self.inner.probability(features)


def test_classifiers_given_replace_the_presets_per_camera(pair):
    """``classifiers=(left, right)``: each camera scores its blobs with its own (an adapted or a
    leave-one-rally-out classifier) instead of the preset's file."""
    import dataclasses

    from badminton_gui.core.classifier import load_classifier
    shipped = load_classifier(TrackerParams().classifier.model)

    def run(name, classifiers):
        source = VideoPair(pair / "l.avi", pair / "r.avi")
        track_to_csv(source, make_rig_for(), TrackerParams(), pair / name, classifiers=classifiers)
        source.close()
        return _rows(pair / name)
    left, right = _Counting(shipped), _Counting(shipped)
    assert run("given.csv", (left, right)) == run("preset.csv", None)
    assert left.calls >= 40 and right.calls >= 40       # a call a frame with blobs (60 frames), each camera
    # The output bias pushed down by 1000: every blob is clutter, and nothing is reported.
    blind = dataclasses.replace(shipped, biases=(shipped.biases[0], shipped.biases[1] - 1e3))
    rows = run("blind.csv", (blind, blind))
    head = rows[0]
    assert not any(r[head.index("VisL")] == "1" or r[head.index("VisR")] == "1" for r in rows[1:])

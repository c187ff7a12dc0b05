"""io/detect_file.py: the loop `detect` and the GUI's Process-a-recording (one video) run — its
score equal to `eval` of the file it wrote, progress per pass, cancellation in either pass, a
full disk and an unreadable video said in one sentence."""

from __future__ import annotations

import csv
import os

import pytest

from badminton_gui.cli import main
from badminton_gui.core.params import TrackerParams
from badminton_gui.io.detect_file import ADAPTING, DETECTING, DetectFileError, detect_to_csv
from badminton_gui.io.labels import read_point_labels
from badminton_gui.io.sources import SourceError

from .test_cli import N, moving_dot_frames, write_labels, write_video


@pytest.fixture
def dot(tmp_path):
    frames, truth = moving_dot_frames()
    write_video(tmp_path / "dot.avi", frames)
    write_labels(tmp_path / "dot_ball.csv", truth)
    return tmp_path


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.reader(fh))


def _params(lookahead=4, adapt_min_run=0):
    return (TrackerParams().with_value("lookahead.frames", lookahead)
            .with_value("classifier.adapt_min_run", adapt_min_run))


def test_the_rows_of_detect_scored_as_eval_scores_them(dot, capsys):
    labels = read_point_labels(dot / "dot_ball.csv").as_dict()
    seen = []
    summary = detect_to_csv(dot / "dot.avi", _params(), dot / "io.csv", labels=labels,
                            progress=lambda stage, n, total: seen.append((stage, n, total)))
    assert summary.frames == N and not summary.cancelled and not summary.adapt_asked
    assert seen == [(DETECTING, n, N) for n in range(1, N + 1)]
    rows = _rows(dot / "io.csv")
    assert rows[0] == ["Frame", "Visibility", "X", "Y"] and len(rows) == N + 1
    assert summary.found == sum(r[1] == "1" for r in rows[1:]) > N // 2
    # The CLI writes the same rows.
    assert main(["detect", str(dot / "dot.avi"), "-o", str(dot / "cli.csv"), "--quiet"]) == 0
    assert _rows(dot / "cli.csv") == rows
    # The in-loop score is `eval`'s of the written file.
    capsys.readouterr()
    assert main(["eval", str(dot / "io.csv"), str(dot / "dot_ball.csv"), "--width", "320"]) == 0
    printed = capsys.readouterr().out
    s = summary.score
    assert s.total == N and f"TP {s.tp}  TN {s.tn}  FP1 {s.fp1}  FP2 {s.fp2}  FN {s.fn}" in printed
    assert summary.score_text == f"against the labels: {100 * s.accuracy:.2f} % (F1 {100 * s.f1:.2f})"


def test_adapting_first_is_a_pass_of_its_own_and_the_cli_says_so(dot, capsys):
    stages = []
    summary = detect_to_csv(dot / "dot.avi", _params(adapt_min_run=20), dot / "a.csv",
                            progress=lambda stage, n, total: stages.append(stage))
    assert stages == [ADAPTING] * N + [DETECTING] * N
    assert summary.adapt_asked and summary.adapted and summary.adapted_runs == 1
    assert summary.adapted_frames >= 20 and summary.adaptation_text.startswith("adapted to the recording: 1 runs")
    # Never for the live readout (look-ahead 0) unless asked; a run too short keeps the classifier.
    assert not detect_to_csv(dot / "dot.avi", _params(0, 20), dot / "b.csv").adapt_asked
    short = detect_to_csv(dot / "dot.avi", _params(adapt_min_run=N + 1), dot / "c.csv")
    assert short.adapt_asked and not short.adapted and "no run of detections long enough" in short.adaptation_text
    capsys.readouterr()
    assert main(["detect", str(dot / "dot.avi"), "-o", str(dot / "d.csv"), "--adapt"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0].startswith("adapted to the recording: 1 runs")
    assert f"{N} frames, shuttle found in " in out


def test_cancelling_keeps_a_valid_csv_and_cancelling_the_adaptation_writes_nothing(dot):
    done = []
    summary = detect_to_csv(dot / "dot.avi", _params(), dot / "part.csv",
                            progress=lambda stage, n, total: done.append(n), should_stop=lambda: len(done) >= 15)
    assert summary.cancelled and summary.frames == 15
    rows = _rows(dot / "part.csv")
    assert [int(r[0]) for r in rows[1:]] == list(range(15))      # the look-ahead's pending rows too
    done.clear()
    summary = detect_to_csv(dot / "dot.avi", _params(adapt_min_run=20), dot / "none.csv",
                            progress=lambda stage, n, total: done.append(stage), should_stop=lambda: len(done) >= 10)
    assert summary.cancelled and summary.frames == 0 and set(done) == {ADAPTING}
    assert not (dot / "none.csv").exists()


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs Linux's /dev/full")
def test_a_full_disk_and_an_unreadable_video_are_one_sentence(dot):
    with pytest.raises(DetectFileError, match="^cannot write the detections: the disk is full writing /dev/full$"):
        detect_to_csv(dot / "dot.avi", _params(), "/dev/full")
    (dot / "junk.mp4").write_bytes(b"not a video at all")
    with pytest.raises(SourceError, match="junk.mp4"):
        detect_to_csv(dot / "junk.mp4", _params(adapt_min_run=20), dot / "j.csv")
    assert not (dot / "j.csv").exists()

"""The label oracle of benchmarks/broadcast_census.py: a ceiling must be the ceiling.

Why this file exists: ``broadcast_census.py --oracle`` scores every candidate from the labels to
say what a perfect classifier would leave (the thirty-second round's finding: on the TV clips the
ceiling sits below the 90 % goal, so the next rounds go to the candidates and the data, not the
classifier). An
oracle that scored the wrong rows, or that stayed installed in the detector module after its
census, would report a ceiling that is not there — and would silently change every later run in
the same process.
"""

from __future__ import annotations

import csv
import sys
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
sys.path.insert(0, str(BENCHMARKS))

import broadcast_census  # noqa: E402
from badminton_gui.core import detector as detector_module  # noqa: E402


def _record(oracle, *positions):
    """What the detector's calls of ``measure_blobs`` hand the oracle: one array pair a call."""
    for xs, ys in positions:
        oracle._xs.append(np.asarray(xs, float))
        oracle._ys.append(np.asarray(ys, float))


def test_only_candidates_at_a_visible_label_score_as_the_shuttle():
    oracle = broadcast_census.LabelOracle(tol=10.0)
    oracle.label = (True, 100.0, 100.0)
    # The frame's blobs, then the parts split off merged blobs: scored in one call, in that order;
    # 8 px from the label is within the tolerance, 15 px is not.
    _record(oracle, ([100.0, 300.0], [105.0, 300.0]), ([92.0, 85.0], [100.0, 100.0]))
    scores = oracle._scores(np.zeros(4), np.zeros(4), np.zeros((4, 1)))
    assert scores.tolist() == [oracle.SHUTTLE, oracle.OTHER, oracle.SHUTTLE, oracle.OTHER]
    oracle.label = (False, 100.0, 100.0)
    _record(oracle, ([100.0], [100.0]))
    assert oracle._scores(np.zeros(1), np.zeros(1), np.zeros((1, 1))).tolist() == [oracle.OTHER]


def test_a_count_that_does_not_match_the_scored_rows_is_an_error():
    oracle = broadcast_census.LabelOracle(tol=10.0)
    _record(oracle, ([1.0, 2.0], [1.0, 2.0]))
    with pytest.raises(AssertionError):
        oracle._scores(np.zeros(3), np.zeros(3), np.zeros((3, 1)))


@dataclass(frozen=True)
class _Clip:
    name: str
    video: Path
    labels: Path


def _dot_clip(tmp_path: Path, label_shift: float) -> _Clip:
    """A white dot crossing a green court at 30 fps, and labels ``label_shift`` px beside it."""
    video, labels = tmp_path / "dot.avi", tmp_path / f"dot_{label_shift:g}.csv"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 30.0, (1280, 720))
    rows = []
    for i in range(45):
        frame = np.zeros((720, 1280, 3), np.uint8)
        frame[:] = (60, 140, 60)
        x, y = 200 + 20 * i, 300 + 4 * i
        cv2.circle(frame, (x, y), 4, (255, 255, 255), -1)
        writer.write(frame)
        rows.append((i, 1, x + label_shift, y))
    writer.release()
    with labels.open("w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["Frame", "Visibility", "X", "Y"])
        out.writerows(rows)
    return _Clip("dot", video, labels)


def test_the_oracle_decides_what_the_chain_reports_and_leaves_the_detector_as_it_was(tmp_path):
    original = detector_module.measure_blobs
    right = broadcast_census.census(_dot_clip(tmp_path, 0.0), "broadcast", 4, None, oracle=True)
    assert detector_module.measure_blobs is original
    # Labels beside the dot: the oracle calls every candidate clutter, so the dot is never
    # followed — the chain's reports come from the oracle's scores, not from the classifier.
    wrong = broadcast_census.census(_dot_clip(tmp_path, 60.0), "broadcast", 4, None, oracle=True)
    assert detector_module.measure_blobs is original
    assert right["TP"] >= 35, right
    assert wrong["FN"] >= 35 and wrong["FP1"] <= 5, wrong


def test_skipped_frames_leave_the_counts_and_are_counted_apart(tmp_path):
    clip = _dot_clip(tmp_path, 0.0)
    whole = broadcast_census.census(clip, "broadcast", 4, None, oracle=True)
    part = broadcast_census.census(clip, "broadcast", 4, None, oracle=True, skip_frames=frozenset(range(10)))
    outcomes = ("TP", "TN", "FP1", "FP2", "FN")
    assert sum(whole[k] for k in outcomes) == 45 and sum(part[k] for k in outcomes) == 35
    assert part["skipped"] == 10
    # The frames counted are the same frames, scored alike.
    assert part["TP"] >= whole["TP"] - 10


def test_the_disputed_frames_are_the_held_serves_of_the_tuned_on_tv_clips():
    import clips
    assert set(clips.DISPUTED_FRAMES) == {"bwf_00001", "bwf_00025"}
    assert not any(name in clips.HELD_OUT for name in clips.DISPUTED_FRAMES)

"""Where a source's truth comes from (io/truth.py): label files per camera, the demo court.

Why this file exists: the GUI's live score is only as right as the truth it looks up for each
frame pair; a right camera paired by time (not by index) must be looked up by its own index.
"""

from __future__ import annotations

import pytest

from badminton_gui.core.types import StereoFrame
from badminton_gui.io.truth import DemoTruth, LabelTruth, has_label_columns

from .conftest_data import NYCU_DIR, requires_data


def _write(path, rows, header="Frame,Visibility,X,Y,Timestamp"):
    path.write_text(header + "\n" + "\n".join(rows) + "\n", encoding="utf-8")
    return path


def test_each_camera_is_looked_up_by_its_own_frame_index(tmp_path):
    left = _write(tmp_path / "l.csv", ["0,1,10,20,0.0", "1,1,11,21,0.01", "2,0,,,0.02"])
    right = _write(tmp_path / "r.csv", ["0,0,,,0.0", "1,1,31,41,0.02"])
    truth = LabelTruth.read(left, right)
    frame = StereoFrame(left=None, right=None, t_left=0.02, t_right=0.02, index=2, index_right=1)
    left_label, right_label = truth.for_frame(frame)
    assert left_label[0] is False                          # labelled: no shuttle in this frame
    assert right_label == (True, 31.0, 41.0)               # the right camera's own frame 1
    same = StereoFrame(left=None, right=None, t_left=0.0, t_right=0.0, index=1)   # index_right -1
    assert truth.for_frame(same) == ((True, 11.0, 21.0), (True, 31.0, 41.0))
    beyond = StereoFrame(left=None, right=None, t_left=1.0, t_right=1.0, index=9, index_right=9)
    assert truth.for_frame(beyond) == (None, None)       # outside the files: not scored


def test_timestamp_files_that_carry_labels_are_recognised(tmp_path):
    assert has_label_columns(_write(tmp_path / "nycu.csv", ["0,1,5,6,0.0,0,0.0"],
                                    header="Frame,Visibility,X,Y,Z,Event,Timestamp"))
    assert not has_label_columns(_write(tmp_path / "times.csv", ["0,0.0"], header="Frame,Timestamp"))
    assert not has_label_columns(tmp_path / "missing.csv")


def test_the_demo_truth_is_the_scene_projection_where_visible():
    from badminton_gui.io.demo_scene import DemoScene
    scene = DemoScene(seed=0)
    truth = DemoTruth(scene)
    seen = 0
    for index in range(0, 400, 7):
        exact = scene.truth(index)
        left, right = truth.for_frame(StereoFrame(None, None, 0.0, 0.0, index))
        for label, visible, uv in ((left, exact.visible_left, exact.uv_left),
                                   (right, exact.visible_right, exact.uv_right)):
            assert label[0] == bool(visible and uv is not None)
            if label[0]:
                assert label[1:] == pytest.approx(uv)
                seen += 1
    assert seen > 20


RALLY = NYCU_DIR / "rally_11-46-04"


@requires_data
def test_the_live_score_is_the_benchmarks_figure_on_a_real_rally(tmp_path):
    """The GUI's live score (LiveScore fed by the worker with each result and its labels) counts
    what the benchmarks count from `track --lookahead 0`'s CSV: the same outcomes per camera on
    the serve and first rally shots of a NYCU rally (labels from its timestamp CSVs)."""
    import csv

    from badminton_gui.core.evaluation import LiveScore, evaluate, tolerance_px
    from badminton_gui.core.tracker import StereoTracker
    from badminton_gui.io.labels import read_point_labels, read_timestamps
    from badminton_gui.io.nycu import rig_from_nycu
    from badminton_gui.io.presets import load_preset
    from badminton_gui.io.track_file import track_to_csv
    from badminton_gui.io.video import VideoPair

    rig = rig_from_nycu(RALLY / "CameraReader_1.cfg", RALLY / "CameraReader_2.cfg")
    params = load_preset(None).with_value("lookahead.frames", 0)
    times = [read_timestamps(RALLY / f"CameraReader_{k}.csv")[1] for k in (1, 2)]
    labels = [RALLY / f"CameraReader_{k}.csv" for k in (1, 2)]
    first, count = 280, 220              # the serve (labelled from frame 301) and what follows

    def pairs():
        source = VideoPair(RALLY / "CameraReader_1.mp4", RALLY / "CameraReader_2.mp4", *times)
        for _ in range(first):
            source.read()
        return source

    source = pairs()
    try:
        track_to_csv(source, rig, params, tmp_path / "track.csv", max_frames=count)
    finally:
        source.close()
    with (tmp_path / "track.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    from_csv = []
    for side, frame_col, key in (("L", "Frame", 0), ("R", "FrameR", 1)):
        pred = {int(r[frame_col]): (r[f"Vis{side}"] == "1", float(r[f"X{side}"] or 0), float(r[f"Y{side}"] or 0))
                for r in rows}
        truth = {f: v for f, v in read_point_labels(labels[key]).as_dict().items() if f in pred}
        from_csv.append(evaluate(pred, truth, tolerance_px(2048)))

    truth = LabelTruth.read(*labels)
    score = LiveScore(2048)
    tracker = StereoTracker(rig, params)
    source = pairs()
    try:
        for _ in range(count):
            frame = source.read()
            result = tracker.process(frame.left, frame.right, frame.t_left, frame.index, frame.index_right)
            left, right = truth.for_frame(frame)
            score.add(0, result.left.detection, left)
            score.add(1, result.right.detection, right)
    finally:
        source.close()
        tracker.close()
    assert score.outcomes(0) == from_csv[0] and score.outcomes(1) == from_csv[1]
    assert from_csv[0].tp > 100 and from_csv[1].tp > 100


def test_labels_of_another_recording_are_said_to_be_so(tmp_path):
    labels = _write(tmp_path / "l.csv", [f"{i},1,10,20,{i / 30}" for i in range(100)])
    truth = LabelTruth.read(labels, labels)
    assert truth.mismatch(100) == "" and truth.mismatch(104) == ""
    assert "another recording" in truth.mismatch(759)
    assert truth.mismatch(0) == ""          # a source that does not know its length

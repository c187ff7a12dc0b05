"""Where a source's truth comes from (io/truth.py): label files per camera, the demo court.

Why this file exists: the GUI's live score is only as right as the truth it looks up for each
frame pair; a right camera paired by time (not by index) must be looked up by its own index.
"""

from __future__ import annotations

import pytest

from badminton_gui.core.types import StereoFrame
from badminton_gui.io.truth import DemoTruth, LabelTruth, has_label_columns


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
    assert has_label_columns(_write(tmp_path / "nycu.csv", ["0,1,5,6,0.0"],
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

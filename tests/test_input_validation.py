"""Hostile but fair input, case by case: each is refused at the boundary with a sentence that
names the file and the key, or — where the output may be wrong rather than impossible — the run
goes on and says so at the end, with the affected rows marked and their 3D withheld.

Why this file exists: every case here once passed silently (exit 0, 0 % 3D or 3D points metres
off) or crashed in the middle of a run. tests/test_fuzz_inputs.py checks the same readers with
random input; this file pins the cases a user met, with the messages they should read.
"""

from __future__ import annotations

import csv

import numpy as np
import pytest

from badminton_gui.cli import main
from badminton_gui.core.rig import RigError, StereoRig
from badminton_gui.io.labels import CsvFormatError, read_point_labels, read_timestamps
from badminton_gui.io.nycu import rig_from_nycu
from badminton_gui.io.sources import SourceError
from badminton_gui.io.track_file import track_to_csv
from badminton_gui.io.video import VideoPair
from badminton_gui.core.params import TrackerParams

from .test_cli import make_rig_for, moving_dot_frames, write_video
from .test_fuzz_inputs import _nycu_pair


# ---- rig files ---------------------------------------------------------------------------------

def _rig_text(tmp_path) -> str:
    path = tmp_path / "good.yaml"
    make_rig_for().save(path)
    return path.read_text()


def _replace_matrix(text: str, key: str, rows: int, cols: int, data: str) -> str:
    start = text.index(f"{key}:")
    end = text.index("]", start) + 1
    return text[:start] + (f"{key}: !!opencv-matrix\n   rows: {rows}\n   cols: {cols}\n   dt: d\n"
                           f"   data: [ {data} ]") + text[end:]


RIG_CASES = {
    "M1 NaN": (("M1", 3, 3, ".nan, 0., 160., 0., 300., 120., 0., 0., 1."), "M1 holds a value that is not finite"),
    "T inf": (("T", 3, 1, ".inf, 0., 0."), "T holds a value that is not finite"),
    "T zero": (("T", 3, 1, "0., 0., 0."), "T is zero"),
    "R not a rotation": (("R", 3, 3, "1.5, 0., 0., 0., 1.5, 0., 0., 0., 1.5"), "R is not a rotation matrix"),
    "M1 zeros": (("M1", 3, 3, "0., 0., 0., 0., 0., 0., 0., 0., 0."), "M1 has focal lengths fx = 0, fy = 0"),
    "D1 of 3": (("D1", 1, 3, "0., 0., 0."), "D1 has 3 coefficients; OpenCV takes 4, 5, 8, 12 or 14"),
    "M1 2x2": (("M1", 2, 2, "1., 0., 0., 1."), "M1 must be 3×3 (9 numbers) but has 2×2 (4)"),
    # FileNode.mat() trusts cols: this one wrote outside its buffer and killed the process later.
    "D1 cols -2.5": (("D1", 1, "-2.5", "0., 0., 0., 0., 0."), "key 'D1' is not a matrix"),
}


@pytest.mark.parametrize("case", sorted(RIG_CASES))
def test_a_rig_that_cannot_be_right_is_refused_naming_file_and_key(tmp_path, case):
    (key, rows, cols, data), expected = RIG_CASES[case]
    path = tmp_path / "rig.yaml"
    path.write_text(_replace_matrix(_rig_text(tmp_path), key, rows, cols, data))
    with pytest.raises(RigError) as info:
        StereoRig.load(path)
    assert str(info.value).startswith(f"rig file {path}: ") and expected in str(info.value)


def test_non_numeric_rig_values_are_named(tmp_path):
    text = _rig_text(tmp_path)
    path = tmp_path / "rig.yaml"
    assert "image_width: 320" in text
    path.write_text(text.replace("image_width: 320", 'image_width: "abc"'))
    with pytest.raises(RigError, match="image_width is not a number"):
        StereoRig.load(path)
    path.write_text(text.replace(text[text.index("M1:"):text.index("D1:")], 'M1: "a string"\n'))
    with pytest.raises(RigError, match="key 'M1' is not a matrix"):
        StereoRig.load(path)


def test_the_api_refuses_the_same_rigs_with_the_one_input_error():
    from badminton_gui import TrackerInputError
    k = np.array([[300.0, 0, 80], [0, 300.0, 60], [0, 0, 1]])
    with pytest.raises(TrackerInputError, match="R is not a rotation"):
        StereoRig(k, np.zeros(5), k, np.zeros(5), 2 * np.eye(3), [-0.3, 0, 0], (160, 120))
    with pytest.raises(TrackerInputError, match="M2 holds a value that is not finite"):
        StereoRig(k, np.zeros(5), np.full((3, 3), np.nan), np.zeros(5), np.eye(3), [-0.3, 0, 0], (160, 120))
    rig = StereoRig(k, np.zeros(4), k, np.zeros(14), np.eye(3), [-0.3, 0, 0], (160, 120))
    assert rig.baseline == 0.3


# ---- NYCU .cfg import --------------------------------------------------------------------------

def _cfgs(tmp_path, left_text=None, encoding="utf-8"):
    left, right = _nycu_pair()
    (tmp_path / "l.cfg").write_bytes((left_text if left_text is not None else left).encode(encoding))
    (tmp_path / "r.cfg").write_text(right)
    return tmp_path / "l.cfg", tmp_path / "r.cfg"


@pytest.mark.parametrize("key, value, expected", [
    ("ks", "[[NaN, 0.0, 80.0], [0.0, 300.0, 60.0], [0.0, 0.0, 1.0]]", "ks in [Other] holds a value that is not finite"),
    ("ks", "[[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]", "ks in [Other] has focal lengths 0 and 0"),
    ("ks", "{1, 2, 3}", "ks in [Other] is not a list of numbers"),
    ("dist", "[[-0.2, 0.04, 0.0]]", "dist in [Other] has 3 coefficients"),
])
def test_the_nycu_importer_refuses_what_cannot_become_a_rig(tmp_path, key, value, expected):
    left, _ = _nycu_pair()
    lines = [f"{key} = {value}" if line.startswith(f"{key} = ") else line for line in left.splitlines()]
    cfg_left, cfg_right = _cfgs(tmp_path, "\n".join(lines) + "\n")
    with pytest.raises(RigError) as info:
        rig_from_nycu(cfg_left, cfg_right)
    assert str(info.value).startswith(f"{cfg_left}: ") and expected in str(info.value)


@pytest.mark.parametrize("variant", ["bom", "latin-1", "percent"])
def test_the_nycu_importer_reads_bom_latin1_and_percent_signs(tmp_path, variant):
    left, _ = _nycu_pair()
    expected = rig_from_nycu(*_cfgs(tmp_path))
    text = {"bom": "\ufeff" + left,
            "latin-1": left.replace("[Other]\n", "[Other]\nowner = José\n"),
            "percent": left.replace("[Other]\n", "[Other]\nnote = 100%(x)s sure\n")}[variant]
    rig = rig_from_nycu(*_cfgs(tmp_path, text, "latin-1" if variant == "latin-1" else "utf-8"))
    assert np.allclose(rig.M1, expected.M1) and np.allclose(rig.T, expected.T)


# ---- timestamp and label files -----------------------------------------------------------------

def _write(path, text):
    path.write_text(text)
    return path


def test_timestamp_files_that_time_nothing_are_refused(tmp_path):
    nan = _write(tmp_path / "nan.csv", "Frame,Timestamp\n0,0.0\n1,nan\n2,0.02\n")
    with pytest.raises(CsvFormatError, match=r"nan.csv line 3: Timestamp is 'nan', not a finite number"):
        read_timestamps(nan)
    equal = _write(tmp_path / "equal.csv", "Frame,Timestamp\n0,5.0\n1,5.0\n2,5.0\n")
    with pytest.raises(CsvFormatError, match="all 3 timestamps are 5.0 s"):
        read_timestamps(equal)
    back = _write(tmp_path / "back.csv", "Frame,Timestamp\n0,0.0\n1,0.02\n2,0.01\n")
    with pytest.raises(CsvFormatError, match=r"line 4: timestamps go backwards \(0.02 then 0.01 s\)"):
        read_timestamps(back)
    stalled = _write(tmp_path / "stalled.csv", "Frame,Timestamp\n0,0.0\n1,0.01\n2,0.01\n3,0.03\n")
    assert read_timestamps(stalled)[1].tolist() == [0.0, 0.01, 0.01, 0.03]   # marked later, by VideoPair


@pytest.mark.parametrize("rows, expected", [
    ("0,1,5,6\n1,1,7,8\n1,0,0,0\n3,1,2,2\n3,1,2,2\n", r"gives 2 frame number\(s\) more than once \(1, 3\)"),
    ("0,1,5,6\n12345678901234567890,1,7,8\n", r"line 3: Frame is '12345678901234567890', not a frame number"),
    ("0,1,5,6\n-3,1,7,8\n", "line 3: Frame is '-3', not a frame number"),
    ("0,1,5,6\n1.5,1,7,8\n", "line 3: Frame is '1.5', not a whole number"),
    ("0,1,5,6\n1,1,7\n", "line 3 has 3 fields, the header 4: a torn row"),
])
def test_label_files_with_duplicates_absurd_numbers_or_torn_rows_are_refused(tmp_path, rows, expected):
    with pytest.raises(CsvFormatError, match=expected):
        read_point_labels(_write(tmp_path / "labels.csv", "Frame,Visibility,X,Y\n" + rows))


def test_a_last_row_without_a_line_break_is_read_with_a_warning(tmp_path, caplog):
    """It may be complete (a tool that omits the last line break) or cut off in a number: read,
    and said, so a torn value is never taken silently."""
    labels = read_point_labels(_write(tmp_path / "labels.csv", "Frame,Visibility,X,Y\n0,1,5,6\n1,1,80.39,4"))
    assert labels.frames.tolist() == [0, 1]
    assert "line 3, the last, does not end with a line break" in caplog.text


# ---- the video pair and the track file ---------------------------------------------------------

N_FRAMES = 30


@pytest.fixture
def dot_pair(tmp_path):
    frames_l, _ = moving_dot_frames(N_FRAMES)
    frames_r, _ = moving_dot_frames(N_FRAMES, offset=-12.0)
    write_video(tmp_path / "l.avi", frames_l)
    write_video(tmp_path / "r.avi", frames_r)
    write_video(tmp_path / "r_short.avi", frames_r[:20])
    make_rig_for().save(tmp_path / "rig.yaml")
    return tmp_path


def test_clocks_in_different_units_or_that_never_overlap_are_refused(dot_pair):
    t = np.arange(N_FRAMES) / 30.0
    with pytest.raises(SourceError, match="1000× apart, as if one file were in milliseconds"):
        VideoPair(dot_pair / "l.avi", dot_pair / "r.avi", t, t * 1000.0)
    with pytest.raises(SourceError, match="they never overlap"):
        VideoPair(dot_pair / "l.avi", dot_pair / "r.avi", t, t + 100.0)


def test_a_stalled_clock_and_a_frame_beyond_the_other_recording_are_doubted(dot_pair):
    t = np.arange(N_FRAMES) / 30.0
    frozen = t.copy()
    frozen[10:15] = frozen[10]
    pair = VideoPair(dot_pair / "l.avi", dot_pair / "r.avi", t, frozen)
    try:
        assert [pair.doubt(i, i) for i in (9, 10, 14, 15)] == ["", "clock_stalled", "clock_stalled", ""]
        assert "the right clock stalled: 5 of its frames share a timestamp" in pair.notes[0]
    finally:
        pair.close()
    short = VideoPair(dot_pair / "l.avi", dot_pair / "r.avi", t, t[:20])
    try:
        # Frame 20 is a frame interval after the right recording ends (paired as usual), 22 beyond it.
        assert short.doubt(22, 19) == "no_partner_frame" and short.doubt(20, 19) == ""
    finally:
        short.close()


def test_timestamps_shorter_than_the_video_are_noted(dot_pair):
    t = np.arange(20) / 30.0
    pair = VideoPair(dot_pair / "l.avi", dot_pair / "r.avi", t, t)
    try:
        assert pair.notes == [f"the {side} timestamps time 20 of the {N_FRAMES} frames of {name}: the 10 "
                              f"after are not tracked" for side, name in (("left", "l.avi"), ("right", "r.avi"))]
    finally:
        pair.close()


def _track(dot_pair, right="r.avi", times=None):
    pair = VideoPair(dot_pair / "l.avi", dot_pair / right, *(times or (None, None)))
    out = dot_pair / "track.csv"
    try:
        summary = track_to_csv(pair, make_rig_for(), TrackerParams(), out)
    finally:
        pair.close()
    with out.open(newline="") as fh:
        return summary, list(csv.DictReader(fh))


def test_a_frozen_clock_withholds_3d_in_the_rows_it_times_and_says_so(dot_pair):
    t = np.arange(N_FRAMES) / 30.0
    _, plain_rows = _track(dot_pair, times=(t, t))
    stalled = t.copy()
    stalled[10:20] = stalled[10]
    summary, rows = _track(dot_pair, times=(t, stalled))
    marked = [r for r in rows if r["withheld_reason"]]
    assert marked and {r["withheld_reason"] for r in marked} == {"clock_stalled"}
    assert all(r["Vis3D"] == "0" and r["X"] == r["Speed"] == "" for r in marked)
    assert all(10 <= int(r["FrameR"]) < 20 for r in marked)
    assert sum(r["Vis3D"] == "1" for r in plain_rows) > sum(r["Vis3D"] == "1" for r in rows)
    assert summary.points_3d == sum(r["Vis3D"] == "1" for r in rows)
    assert f"3D withheld in {len(marked)} rows ({len(marked)} clock_stalled" in summary.warning
    assert list(rows[0])[-1] == "withheld_reason"


def test_a_video_that_ends_early_is_said_once_at_the_end(dot_pair, capsys):
    summary, rows = _track(dot_pair, right="r_short.avi")
    assert len(rows) == 20
    assert summary.warning == f"r_short.avi ended after 20 frames; 10 frames of l.avi after it were not tracked"
    code = main(["track", "--left", str(dot_pair / "l.avi"), "--right", str(dot_pair / "r_short.avi"),
                 "--calib", str(dot_pair / "rig.yaml"), "-o", str(dot_pair / "cli.csv"), "--video-times"])
    assert code == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("badminton-track: warning: 3D withheld in ")
    assert "no_partner_frame" in err[-1]


def test_a_truncated_video_is_said_with_its_announced_length(dot_pair):
    data = (dot_pair / "l.avi").read_bytes()
    (dot_pair / "cut.avi").write_bytes(data[: len(data) // 2])
    pair = VideoPair(dot_pair / "cut.avi", dot_pair / "r.avi")
    try:
        while pair.read() is not None:
            pass
        assert pair.read() is None                  # asked again past the end: said once
        assert len(pair.notes) == 1
        assert f"of the {N_FRAMES} its header announces (a truncated file?)" in pair.notes[0]
    finally:
        pair.close()


# ---- command-line numbers ----------------------------------------------------------------------

@pytest.mark.parametrize("argv, expected", [
    (["demo", "--frames", "2", "--out", "x", "--size", "0x0"], "each side must be 64 to 4096 px"),
    (["demo", "--frames", "2", "--out", "x", "--size", "garbage"], "is not WIDTHxHEIGHT"),
    (["demo", "--frames", "2", "--out", "x", "--size", "8192x8192"], "each side must be 64 to 4096 px"),
    (["demo", "--frames", "2", "--out", "x", "--fps", "inf"], "the frame rate must be 1 to 1000 fps"),
    (["demo", "--frames", "2", "--out", "x", "--fps", "1e12"], "the frame rate must be 1 to 1000 fps"),
    (["demo", "--frames", "2", "--out", "x", "--seed=-1"], "the seed must be 0 to 4294967295"),
    (["eval", "p.csv", "l.csv", "--tolerance=-4"], "the tolerance must be a finite number of pixels above 0"),
    (["eval", "p.csv", "l.csv", "--tolerance", "nan"], "the tolerance must be a finite number of pixels above 0"),
    (["eval", "p.csv", "l.csv", "--width", "0"], "the image width must be 1 to 100000 px"),
])
def test_numbers_out_of_range_are_usage_errors(argv, expected, capsys):
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert expected in err and "Traceback" not in err


def test_eval_notes_the_labelled_frames_without_prediction(tmp_path, capsys):
    labels = _write(tmp_path / "labels.csv", "Frame,Visibility,X,Y\n" + "".join(
        f"{i},1,{10 + i},{20 + i}\n" for i in range(8)))
    pred = _write(tmp_path / "pred.csv", "Frame,Visibility,X,Y\n0,1,10,20\n1,1,11,21\n")
    assert main(["eval", str(pred), str(labels), "--width", "640"]) == 0
    assert (f"warning: 6 of the 8 labelled frames have no prediction in {pred}; they are scored as not "
            f"detected") in capsys.readouterr().err


class _FramesWithAStalledPair:
    """Pairs of the dot video whose fifth pair repeats the fourth's time (no ``doubt`` to say so)."""

    def __init__(self, n: int) -> None:
        from badminton_gui.core.types import StereoFrame
        frames_l, _ = moving_dot_frames(n)
        frames_r, _ = moving_dot_frames(n, offset=-12.0)
        times = [i / 30.0 for i in range(n)]
        times[4] = times[3]
        self.frames = [StereoFrame(l, r, t, t, i, i) for i, (l, r, t) in enumerate(zip(frames_l, frames_r, times))]

    def read(self):
        return self.frames.pop(0) if self.frames else None


def test_a_pair_the_tracker_refuses_keeps_its_row_empty_and_marked(tmp_path):
    out = tmp_path / "track.csv"
    summary = track_to_csv(_FramesWithAStalledPair(12), make_rig_for(), TrackerParams(), out)
    with out.open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["Frame"] for r in rows] == [str(i) for i in range(12)]
    assert [r["withheld_reason"] for r in rows if r["withheld_reason"]] == ["input_refused"]
    refused = rows[4]
    assert refused["withheld_reason"] == "input_refused" and refused["VisL"] == refused["VisR"] == "0"
    assert summary.pairs == 12 and "3D withheld in 1 row (1 input_refused" in summary.warning


@pytest.mark.parametrize("command", ["track", "render", "refine-calib"])
@pytest.mark.parametrize("value", ["-5", "0", "1.5", "many"])
def test_max_frames_is_refused_when_parsed(command, value, capsys):
    """--max-frames -5 once ran and then said "the videos hold no frames"."""
    from badminton_gui.cli import main
    with pytest.raises(SystemExit) as stop:
        main([command, "--max-frames", value])
    assert stop.value.code == 2
    assert "argument --max-frames:" in capsys.readouterr().err


def test_one_video_given_as_both_cameras_is_refused_not_triangulated(dot_pair, capsys):
    # A toed-in rig triangulates an identical pair to plausible points metres off: every pair is
    # refused, its row marked, and the sentence says what happened.
    summary, rows = _track(dot_pair, right="l.avi")
    assert len(rows) == N_FRAMES and summary.points_3d == 0
    assert {r["withheld_reason"] for r in rows} == {"input_refused"}
    assert f"{N_FRAMES} pairs refused: the left and right images are identical" in summary.warning
    code = main(["track", "--left", str(dot_pair / "l.avi"), "--right", str(dot_pair / "l.avi"),
                 "--calib", str(dot_pair / "rig.yaml"), "-o", str(dot_pair / "cli.csv")])
    assert code == 0
    assert "the same camera or video given twice?" in capsys.readouterr().err


def test_identical_images_are_refused_but_uniform_ones_are_not():
    from badminton_gui.core.errors import TrackerInputError
    from badminton_gui.core.tracker import StereoTracker
    frames, _ = moving_dot_frames(2)
    rig = make_rig_for()
    tracker = StereoTracker(rig, parallel=False)
    try:
        with pytest.raises(TrackerInputError, match="identical"):
            tracker.process(frames[0], frames[0].copy(), 0.0)
        black = np.zeros_like(frames[0])
        assert tracker.process(black, black.copy(), 0.0).timestamp == 0.0   # cameras starting up
        other = frames[1].copy()
        other[-1, -1, 0] ^= 1                                   # one pixel apart: two pictures
        assert tracker.process(frames[1], other, 1 / 30).timestamp == 1 / 30
    finally:
        tracker.close()

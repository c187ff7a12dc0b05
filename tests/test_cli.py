"""The command line end to end on small videos made here, and its answers to bad input."""

import csv

import cv2
import numpy as np
import pytest

from badminton_gui.cli import main
from badminton_gui.core.rig import StereoRig

W, H, N = 320, 240, 40


def adapting_tv_preset():
    """The broadcast preset with the classifier adapted to each recording (``classifier.adapt_min_run``
    25, its value until the shipped TV classifier was trained on every venue): the adaptation is
    no longer the preset's, but the CLI and the GUI still offer it, so their tests ask for it."""
    from badminton_gui.io.presets import load_preset
    return load_preset("broadcast").with_value("classifier.adapt_min_run", 25)


def moving_dot_frames(n=N, offset=0.0):
    """A white 'shuttle' crossing a dark textured floor; returns frames and the true centres."""
    rng = np.random.default_rng(0)
    floor = rng.integers(20, 60, size=(H, W, 3), dtype=np.uint8)
    frames, truth = [], []
    for i in range(n):
        img = floor.copy()
        x, y = 30 + 6 * i + offset, 60 + 2.5 * i
        cv2.circle(img, (int(round(x * 16)), int(round(y * 16))), 3 * 16, (245, 245, 245), -1,
                   cv2.LINE_AA, shift=4)
        frames.append(img)
        truth.append((x, y))
    return frames, truth


def write_video(path, frames, fps=30.0):
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), fps, (W, H))
    assert writer.isOpened()
    for f in frames:
        writer.write(f)
    writer.release()


def write_labels(path, truth, first_visible=0):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["Frame", "Visibility", "X", "Y"])
        for i, (x, y) in enumerate(truth):
            w.writerow([i, int(i >= first_visible), x if i >= first_visible else 0, y if i >= first_visible else 0])


@pytest.fixture()
def dot_video(tmp_path):
    frames, truth = moving_dot_frames()
    path = tmp_path / "dot.avi"
    write_video(path, frames)
    labels = tmp_path / "dot_ball.csv"
    write_labels(labels, truth)
    return path, labels, truth


def test_detect_then_eval(dot_video, tmp_path, capsys):
    video, labels, truth = dot_video
    out = tmp_path / "pred.csv"
    assert main(["detect", str(video), "-o", str(out), "--quiet"]) == 0
    rows = list(csv.DictReader(out.open()))
    assert [r for r in rows][0].keys() == {"Frame", "Visibility", "X", "Y"}
    assert len(rows) == N
    hits = [r for r in rows if r["Visibility"] == "1"]
    assert len(hits) >= N - 5  # the background model needs a frame or two to learn
    for r in hits:
        x, y = truth[int(r["Frame"])]
        assert abs(float(r["X"]) - x) < 2.0 and abs(float(r["Y"]) - y) < 2.0
    assert main(["eval", str(out), str(labels), "--width", str(W)]) == 0
    text = capsys.readouterr().out
    assert "accuracy" in text and "F1" in text


def make_rig_for(size=(W, H)) -> StereoRig:
    k = np.array([[300.0, 0, size[0] / 2], [0, 300.0, size[1] / 2], [0, 0, 1]])
    return StereoRig(k, np.zeros(5), k, np.zeros(5), np.eye(3), [-0.3, 0, 0], size)


def test_track_writes_one_row_per_left_frame(tmp_path):
    frames_l, _ = moving_dot_frames()
    frames_r, _ = moving_dot_frames(offset=-10.0)   # disparity 10 px: same row, so epipolar-consistent
    write_video(tmp_path / "l.avi", frames_l)
    write_video(tmp_path / "r.avi", frames_r)
    make_rig_for().save(tmp_path / "rig.yaml")
    out = tmp_path / "track.csv"
    assert main(["track", "--left", str(tmp_path / "l.avi"), "--right", str(tmp_path / "r.avi"),
                 "--calib", str(tmp_path / "rig.yaml"), "-o", str(out), "--quiet"]) == 0
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == N
    assert list(rows[0].keys())[:15] == ["Frame", "FrameR", "Timestamp", "VisL", "XL", "YL", "VisR",
                                         "XR", "YR", "Vis3D", "X", "Y", "Z", "Distance", "Speed"]
    with3d = [r for r in rows if r["Vis3D"] == "1"]
    assert len(with3d) >= N - 5
    # Disparity 10 px at f = 300 px and baseline 0.3 m puts the dot at Z = 9 m.
    z = np.median([float(r["Z"]) for r in with3d])
    assert z == pytest.approx(9.0, rel=0.05)


def test_track_pairs_by_timestamps(tmp_path):
    frames, _ = moving_dot_frames()
    write_video(tmp_path / "l.avi", frames)
    write_video(tmp_path / "r.avi", frames)
    make_rig_for().save(tmp_path / "rig.yaml")
    # The right camera started 2 frames later: its frame j was taken at left time (j + 2) / 30.
    for name, shift in (("lt.csv", 0), ("rt.csv", 2)):
        with open(tmp_path / name, "w") as fh:
            fh.write("Frame,Visibility,Timestamp\n")
            for i in range(N):
                fh.write(f"{i},0,{(i + shift) / 30.0}\n")
    out = tmp_path / "track.csv"
    assert main(["track", "--left", str(tmp_path / "l.avi"), "--right", str(tmp_path / "r.avi"),
                 "--calib", str(tmp_path / "rig.yaml"), "-o", str(out), "--quiet",
                 "--left-times", str(tmp_path / "lt.csv"), "--right-times", str(tmp_path / "rt.csv")]) == 0
    rows = list(csv.DictReader(out.open()))
    assert [int(r["FrameR"]) for r in rows[5:10]] == [3, 4, 5, 6, 7]
    assert int(rows[0]["FrameR"]) == 0


def test_track_scores_itself_against_labels_its_timestamp_files_carry(tmp_path, capsys):
    """NYCU-style CSVs (Frame,Visibility,X,Y,Timestamp) are timestamps and labels at once: the
    summary gives each camera's accuracy with the benchmarks' protocol; plain ones give none."""
    frames_l, truth_l = moving_dot_frames()
    frames_r, truth_r = moving_dot_frames(offset=-10.0)
    write_video(tmp_path / "l.avi", frames_l)
    write_video(tmp_path / "r.avi", frames_r)
    make_rig_for().save(tmp_path / "rig.yaml")
    for name, truth in (("l.csv", truth_l), ("r.csv", truth_r)):
        with open(tmp_path / name, "w") as fh:
            fh.write("Frame,Visibility,X,Y,Timestamp\n")
            for i, (x, y) in enumerate(truth):
                fh.write(f"{i},1,{x},{y},{i / 30.0}\n")
    common = ["track", "--left", str(tmp_path / "l.avi"), "--right", str(tmp_path / "r.avi"),
              "--calib", str(tmp_path / "rig.yaml"), "-o", str(tmp_path / "t.csv"),
              "--left-times", str(tmp_path / "l.csv"), "--right-times", str(tmp_path / "r.csv")]
    assert main(common) == 0
    line = [s for s in capsys.readouterr().out.splitlines() if s.startswith("against the labels")]
    assert len(line) == 1 and "left " in line[0] and "right " in line[0]
    accuracy_left = float(line[0].split("left ")[1].split(" %")[0])
    assert accuracy_left >= 90.0           # the dot is found from its second or third frame


def test_track_pairs_by_the_videos_own_frame_times(tmp_path, capsys):
    """--video-times: the right camera recorded every other frame (15 fps against 30), as a camera
    that drops frames does; frame i of the left file was taken with right frame i / 2, not i."""
    frames, _ = moving_dot_frames()
    write_video(tmp_path / "l.avi", frames, fps=30.0)
    write_video(tmp_path / "r.avi", frames[::2], fps=15.0)
    make_rig_for().save(tmp_path / "rig.yaml")
    out = tmp_path / "track.csv"
    common = ["track", "--left", str(tmp_path / "l.avi"), "--right", str(tmp_path / "r.avi"),
              "--calib", str(tmp_path / "rig.yaml"), "-o", str(out), "--quiet"]
    assert main(common + ["--video-times"]) == 0
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == N
    assert [int(r["FrameR"]) for r in rows[0:12:2]] == [0, 1, 2, 3, 4, 5]
    assert float(rows[9]["Timestamp"]) == pytest.approx(9 / 30.0, abs=1e-3)
    # Frame by frame the right file runs out half way and pairs the wrong moments.
    assert main(common) == 0
    assert [int(r["FrameR"]) for r in list(csv.DictReader(out.open()))[0:12:2]] == [0, 2, 4, 6, 8, 10]
    capsys.readouterr()
    lt = tmp_path / "lt.csv"
    lt.write_text("Frame,Timestamp\n" + "".join(f"{i},{i / 30}\n" for i in range(N)))
    assert main(common + ["--video-times", "--left-times", str(lt), "--right-times", str(lt)]) != 0
    assert "not both" in capsys.readouterr().err


def test_import_calib_nycu_style(tmp_path, capsys):
    import json
    k = [[800.0, 0, 1024], [0, 800.0, 768], [0, 0, 1]]
    for name, ext in (("a.cfg", [[1, 0, 0, 0.1], [0, 0, -1, 1.5], [0, 1, 0, 8.0]]),
                      ("b.cfg", [[-1, 0, 0, 0.1], [0, 0, -1, 1.5], [0, -1, 0, 8.0]])):
        (tmp_path / name).write_text(
            "[Camera]\nfps = 119\nRecordResolution = (2048, 1536)\n\n[Other]\n"
            f"ks = {json.dumps(k)}\ndist = [[-0.2, 0.04, 0.0, 0.0, 0.0]]\n"
            f"extrinsic_mat = {json.dumps(ext)}\n")
    out = tmp_path / "rig.yaml"
    assert main(["import-calib", "--nycu", str(tmp_path / "a.cfg"), str(tmp_path / "b.cfg"), "-o", str(out)]) == 0
    rig = StereoRig.load(out)
    assert rig.has_court_pose and rig.image_size == (2048, 1536)
    centres = rig.camera_centres()
    np.testing.assert_allclose(centres[0], [-0.1, -8.0, 1.5], atol=1e-9)
    np.testing.assert_allclose(centres[1], [0.1, 8.0, 1.5], atol=1e-9)
    assert rig.baseline == pytest.approx(np.linalg.norm([0.2, 16.0, 0.0]))


# ---- bad input: one clear line on stderr, exit status 2, no traceback -----------------------

def run_error(args, capsys):
    code = main(args)
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err
    assert err.count("\n") == 1, err
    return err


def test_missing_video(tmp_path, capsys):
    err = run_error(["detect", str(tmp_path / "none.mp4"), "-o", str(tmp_path / "o.csv")], capsys)
    assert "video not found" in err


def test_truncated_video(tmp_path, capsys, dot_video):
    video, _, _ = dot_video
    broken = tmp_path / "broken.mp4"
    broken.write_bytes(video.read_bytes()[:200])
    err = run_error(["detect", str(broken), "-o", str(tmp_path / "o.csv")], capsys)
    assert "cannot read" in err and "broken.mp4" in err


def test_rig_for_another_resolution(tmp_path, capsys, dot_video):
    video, _, _ = dot_video
    make_rig_for((1280, 720)).save(tmp_path / "rig.yaml")
    err = run_error(["track", "--left", str(video), "--right", str(video), "--calib",
                     str(tmp_path / "rig.yaml"), "-o", str(tmp_path / "o.csv")], capsys)
    assert "calibrated for 1280×720" in err and "320×240" in err


def test_malformed_csv(tmp_path, capsys, dot_video):
    video, labels, _ = dot_video
    bad = tmp_path / "bad.csv"
    bad.write_text("Frame,Visibility,X,Y\n0,1,12.5,oops\n")
    err = run_error(["eval", str(labels), str(bad), "--width", "320"], capsys)
    assert "line 2" in err and "oops" in err
    bad.write_text("Frame,Vis,X\n0,1,2\n")
    err = run_error(["eval", str(labels), str(bad), "--width", "320"], capsys)
    assert "lacks the column" in err
    times = tmp_path / "t.csv"
    times.write_text("Frame,Timestamp\n0,0.0\n1,abc\n")
    make_rig_for().save(tmp_path / "rig.yaml")
    err = run_error(["track", "--left", str(video), "--right", str(video), "--calib", str(tmp_path / "rig.yaml"),
                     "-o", str(tmp_path / "o.csv"), "--left-times", str(times), "--right-times", str(times)], capsys)
    assert "Timestamp" in err and "abc" in err


def test_missing_rig_and_unknown_preset(tmp_path, capsys, dot_video):
    video, _, _ = dot_video
    err = run_error(["track", "--left", str(video), "--right", str(video), "--calib",
                     str(tmp_path / "none.yaml"), "-o", str(tmp_path / "o.csv")], capsys)
    assert "rig file not found" in err
    err = run_error(["detect", str(video), "-o", str(tmp_path / "o.csv"), "--preset", "nope"], capsys)
    assert "no preset 'nope'" in err


def test_unwritable_output(tmp_path, capsys, dot_video):
    video, _, _ = dot_video
    blocker = tmp_path / "file"
    blocker.write_text("x")
    err = run_error(["detect", str(video), "-o", str(blocker / "sub" / "o.csv"), "--quiet"], capsys)
    assert "cannot write" in err


def test_presets_command_lists_default(capsys):
    assert main(["presets"]) == 0
    assert "default" in capsys.readouterr().out


def test_detect_adapts_to_the_recording_when_asked(dot_video, tmp_path, capsys):
    video, _labels, truth = dot_video
    out = tmp_path / "adapted.csv"
    assert main(["detect", str(video), "-o", str(out), "--adapt"]) == 0
    text = capsys.readouterr().out
    assert "adapted to the recording: 1 runs" in text
    hits = [r for r in csv.DictReader(out.open()) if r["Visibility"] == "1"]
    assert len(hits) >= N - 5
    for r in hits:
        x, y = truth[int(r["Frame"])]
        assert abs(float(r["X"]) - x) < 2.0 and abs(float(r["Y"]) - y) < 2.0
    # --no-adapt, presets with it off (the broadcast preset too: its classifier saw every venue),
    # and the live readout: one pass, no adaptation line.
    for extra in (["--no-adapt"], ["--preset", "broadcast", "--lookahead", "0"],
                  ["--preset", "broadcast"], []):
        assert main(["detect", str(video), "-o", str(out)] + extra) == 0
        assert "adapted to the recording" not in capsys.readouterr().out
    assert main(["detect", str(video), "-o", str(out), "--preset", "broadcast", "--adapt"]) == 0
    assert "adapt" in capsys.readouterr().out   # adapted, or no run long enough on this tiny video

"""`badminton-track render` end to end on a small demo court, the drawing it shares with the GUI,
and its answers to bad input, a Cancel and Ctrl-C."""

import csv
import math

import cv2
import numpy as np
import pytest

from badminton_gui.cli import main
from badminton_gui.core import overlay_draw as od
from badminton_gui.io.render_video import (RenderError, read_render_csv, render_video,
                                           shown_steps)

W, H, N = 640, 360, 48
STRIP = 120            # the readouts' strip under feeds 360 px tall: its 120-px minimum


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """A 48-pair demo court at 640×360 and its track CSV (3D in court coordinates)."""
    out = tmp_path_factory.mktemp("demo")
    assert main(["demo", "--frames", str(N), "--size", f"{W}x{H}", "--out", str(out)]) == 0
    assert main(["track", "--left", str(out / "left.mp4"), "--right", str(out / "right.mp4"),
                 "--calib", str(out / "rig.yaml"), "-o", str(out / "track.csv"), "--quiet"]) == 0
    return out


def pair_args(demo):
    return ["--left", str(demo / "left.mp4"), "--right", str(demo / "right.mp4")]


def decode(path):
    cap = cv2.VideoCapture(str(path))
    assert cap.isOpened()
    frames = []
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        frames.append(frame)
    cap.release()
    return frames


def track_rows(demo):
    return list(csv.DictReader((demo / "track.csv").open()))


def ring_redness(image, cx, cy, radius):
    """Median of red minus the larger of green and blue on a ring around (cx, cy)."""
    a = np.linspace(0, 2 * math.pi, 48, endpoint=False)
    xs = np.clip(np.round(cx + radius * np.cos(a)).astype(int), 0, image.shape[1] - 1)
    ys = np.clip(np.round(cy + radius * np.sin(a)).astype(int), 0, image.shape[0] - 1)
    px = image[ys, xs].astype(int)
    return float(np.median(px[:, 2] - np.maximum(px[:, 0], px[:, 1])))


def leftovers(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


# ---- the clip ---------------------------------------------------------------------------------

def test_render_both_from_csv_circles_the_csv_position(demo, tmp_path):
    out = tmp_path / "both.mp4"
    assert main(["render", *pair_args(demo), "--csv", str(demo / "track.csv"),
                 "--calib", str(demo / "rig.yaml"), "-o", str(out), "--quiet"]) == 0
    frames = decode(out)
    rows = track_rows(demo)
    assert len(frames) == len(rows) == N
    assert frames[0].shape == (H + STRIP, 2 * W, 3)      # two feeds side by side, readouts + plan under
    source = decode(demo / "left.mp4")
    checked = 0
    for k, row in enumerate(rows):
        if row["VisL"] != "1" or row["VisR"] != "1":
            continue
        xl, yl = float(row["XL"]), float(row["YL"])
        xr, yr = float(row["XR"]), float(row["YR"])
        assert ring_redness(frames[k], xl, yl, od.CIRCLE_RADIUS) > 90, f"no red circle in left frame {k}"
        assert ring_redness(frames[k], W + xr, yr, od.CIRCLE_RADIUS) > 90, f"no red circle in right frame {k}"
        assert ring_redness(source[k], xl, yl, od.CIRCLE_RADIUS) < 40       # the video had none
        checked += 1
    assert checked >= 20
    # The court plan sits at the strip's right: court lines (light grey) are drawn there.
    strip = frames[-1][H:]
    assert (strip[:, -od.plan_size(STRIP)[0]:] > 180).all(axis=2).sum() > 200
    assert (strip[:, :W] > 180).all(axis=2).sum() > 100          # the readouts' text


def test_render_on_the_fly_gives_the_clip_of_the_csv(demo, tmp_path):
    """Tracking now runs `track`'s own loop: the same rows, so the same clip."""
    from_csv, now = tmp_path / "csv.mp4", tmp_path / "now.mp4"
    assert main(["render", *pair_args(demo), "--csv", str(demo / "track.csv"), "--calib",
                 str(demo / "rig.yaml"), "-o", str(from_csv), "--quiet"]) == 0
    assert main(["render", *pair_args(demo), "--calib", str(demo / "rig.yaml"), "-o", str(now),
                 "--quiet"]) == 0
    a, b = decode(from_csv), decode(now)
    assert len(a) == len(b) == N
    assert max(np.abs(x.astype(int) - y.astype(int)).mean() for x, y in zip(a, b)) < 0.5
    assert leftovers(tmp_path) == []


def test_render_one_camera_scaled_into_a_new_folder(demo, tmp_path):
    out = tmp_path / "clips" / "left.mp4"
    assert main(["render", "--left", str(demo / "left.mp4"), "--csv", str(demo / "track.csv"),
                 "--width", "320", "-o", str(out), "--quiet"]) == 0
    frames = decode(out)
    assert len(frames) == N
    assert frames[0].shape == (180 + STRIP, 320, 3)
    row = next(r for r in track_rows(demo)[20:] if r["VisL"] == "1")
    k = int(row["Frame"])
    assert ring_redness(frames[k], float(row["XL"]) / 2, float(row["YL"]) / 2, od.CIRCLE_RADIUS) > 90


def test_render_one_video_detected_now(demo, tmp_path):
    """One video without a CSV: `detect`'s loop; no 3D, so no strip under the picture."""
    out = tmp_path / "one.mp4"
    assert main(["render", "--right", str(demo / "right.mp4"), "-o", str(out), "--quiet",
                 "--preset", "default"]) == 0
    frames = decode(out)
    assert len(frames) == N
    assert frames[0].shape == (H, W, 3)


def test_render_from_detect_csv_circles_its_rows(demo, tmp_path):
    det = tmp_path / "det.csv"
    assert main(["detect", str(demo / "left.mp4"), "-o", str(det), "--quiet"]) == 0
    out = tmp_path / "det.mp4"
    assert main(["render", "--left", str(demo / "left.mp4"), "--csv", str(det), "-o", str(out),
                 "--fps", "30", "--quiet"]) == 0
    frames = decode(out)
    assert len(frames) == N and frames[0].shape == (H, W, 3)
    assert cv2.VideoCapture(str(out)).get(cv2.CAP_PROP_FPS) == pytest.approx(30)
    rows = [r for r in csv.DictReader(det.open()) if r["Visibility"] == "1"]
    assert rows
    for r in rows[::5]:
        assert ring_redness(frames[int(r["Frame"])], float(r["X"]), float(r["Y"]), od.CIRCLE_RADIUS) > 90


# ---- cancel, Ctrl-C, bad input ------------------------------------------------------------------

def test_cancel_leaves_no_file_and_keeps_an_existing_one(demo, tmp_path):
    out = tmp_path / "clip.mp4"
    out.write_bytes(b"an older clip")
    track = read_render_csv(demo / "track.csv", 120.0)
    done = []
    summary = render_video(track, {0: demo / "left.mp4", 1: demo / "right.mp4"}, out, cameras=(0, 1),
                           progress=lambda stage, n, total: done.append(n),
                           should_stop=lambda: len(done) >= 5)
    assert summary.cancelled and summary.frames == 5
    assert out.read_bytes() == b"an older clip"
    assert leftovers(tmp_path) == []


def test_ctrl_c_removes_the_partial_clip(demo, tmp_path, monkeypatch):
    import badminton_gui.io.render_video as rv
    calls = []
    real = rv.compose_frame

    def interrupted(*args, **kwargs):
        calls.append(1)
        if len(calls) == 4:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(rv, "compose_frame", interrupted)
    out = tmp_path / "clip.mp4"
    assert main(["render", *pair_args(demo), "--csv", str(demo / "track.csv"), "-o", str(out),
                 "--quiet"]) == 130
    assert len(calls) == 4
    assert not out.exists()
    assert leftovers(tmp_path) == []


def _bad_csv(demo, tmp_path, change):
    rows = track_rows(demo)
    path = tmp_path / "bad.csv"
    with path.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        for row in change(rows):
            w.writerow(row)
    return path


def _not_a_video(tmp_path):
    path = tmp_path / "notes.mp4"
    path.write_text("not a video")
    return path


def _longer(rows):
    extra = [dict(rows[-1], Frame=str(N + k), FrameR=str(N + k)) for k in range(100)]
    return rows + extra


def _wider(rows):
    return [dict(r, XL=f"{float(r['XL']) * 4:.2f}") if r["VisL"] == "1" else r for r in rows]


@pytest.mark.parametrize("case, expected", [
    ("missing video", "video not found"),
    ("unreadable video", "cannot read"),
    ("longer csv", "another video"),
    ("wider csv", "another video"),
    ("output is an input", "one of the inputs"),
    ("not mp4", "must end in .mp4"),
    ("both from one camera's csv", "one camera"),
    ("pair without rig", "--calib"),
    ("camera not given", "--camera right needs --right"),
    ("bad scale", "scale must be"),
])
def test_bad_input_is_one_line_and_exit_2(demo, tmp_path, capsys, case, expected):
    out = str(tmp_path / "clip.mp4")
    csv_path = str(demo / "track.csv")
    args = {
        "missing video": ["--left", str(tmp_path / "nope.mp4"), "--csv", csv_path, "-o", out],
        "unreadable video": ["--left", str(_not_a_video(tmp_path)), "--csv", csv_path, "-o", out],
        "longer csv": [*pair_args(demo), "--csv", str(_bad_csv(demo, tmp_path, _longer)), "-o", out],
        "wider csv": [*pair_args(demo), "--csv", str(_bad_csv(demo, tmp_path, _wider)), "-o", out],
        "output is an input": [*pair_args(demo), "--csv", csv_path, "-o", str(demo / "left.mp4")],
        "not mp4": [*pair_args(demo), "--csv", csv_path, "-o", str(tmp_path / "clip.avi")],
        "both from one camera's csv": [*pair_args(demo), "--csv", str(demo / "left_labels.csv"),
                                       "--camera", "both", "-o", out],
        "pair without rig": [*pair_args(demo), "-o", out],
        "camera not given": ["--left", str(demo / "left.mp4"), "--camera", "right", "--csv", csv_path,
                             "-o", out],
        "bad scale": [*pair_args(demo), "--csv", csv_path, "--scale", "0", "-o", out],
    }[case]
    assert main(["render", *args, "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("badminton-track render: error:")
    assert expected in err
    assert not (tmp_path / "clip.mp4").exists()
    assert leftovers(tmp_path) == []


# ---- the drawing ----------------------------------------------------------------------------------

def test_trail_fades_with_age_and_does_not_join_a_hop():
    image = np.zeros((200, 400, 3), np.uint8)
    trail = np.array([[0.00, 20, 100], [0.10, 40, 100], [0.20, 60, 100], [0.30, 80, 100],
                      [0.40, 100, 100], [0.45, 350, 100]])        # the last point hopped away
    od.draw_trail(image, trail, 1.0)
    red = image[..., 2].astype(int)
    assert 0 < red[100, 30] < red[100, 90]          # older segments are fainter
    assert red[100, 220] == 0                        # the hop is not drawn as a line
    assert red[100, 350] == 0                        # the newest point is the circle's, not a dot


def test_history_keeps_half_a_second_and_each_frame_once():
    history = od.OverlayHistory()
    for i in range(60):
        history.push(od.ShuttleStep(i // 2, i, i / 100, left=(float(i), 0.0), right=(float(i), 1.0)))
    left, right = history.trail(0), history.trail(1)
    assert right[:, 0].min() >= 0.59 - od.TRAIL_SECONDS - 1e-9 and len(right) == 51
    assert len(left) == 25                           # a left frame repeated in two steps counts once


def test_plan_marks_the_shuttle_and_calls_the_landing():
    step = od.ShuttleStep(0, 0, 0.0, point=(1.0, -2.0, 1.5), landing=(-1.0, 5.0, 0.8))
    plan = od.draw_plan(200, step, np.zeros((0, 4)))
    w, h = od.plan_size(200)
    assert plan.shape == (h, w, 3)

    def at(x, y):
        col = (y + od.PLAN_RANGE_Y) / (2 * od.PLAN_RANGE_Y) * w
        row = (od.PLAN_RANGE_X - x) / (2 * od.PLAN_RANGE_X) * h
        return plan[int(round(row)), int(round(col))]

    assert tuple(at(1.0, -2.0)) == od.POSITION_COLOUR
    assert tuple(at(-1.0, 5.0)) == od.IN_COLOUR
    plan = od.draw_plan(200, od.ShuttleStep(0, 0, 0.0, landing=(2.0, 7.2, 0.8)), np.zeros((0, 4)))
    assert tuple(at(2.0, 7.2)) == od.OUT_COLOUR               # beyond the back line
    assert od.landing_call(3.2, 5.0) == "out" and od.landing_call(-1.0, 5.0) == "in"
    assert [r[1] for r in od.readout_lines(step)][:2] == ["-", "-"]


def test_shown_steps_one_per_frame_of_the_camera():
    steps = tuple(od.ShuttleStep(i, j, t) for t, (i, j) in enumerate([(0, 0), (1, 1), (1, 2), (2, 3), (3, 3)]))
    from badminton_gui.io.render_video import RenderTrack
    track = RenderTrack(steps, True, "t.csv")
    assert shown_steps(track, (0,)) == [0, 1, 3, 4]
    assert shown_steps(track, (1,)) == [0, 1, 2, 3]
    assert shown_steps(track, (0, 1)) == [0, 1, 2, 3, 4]


def test_read_render_csv_rejects_a_broken_row(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("Frame,FrameR,Timestamp,VisL,XL,YL,VisR,XR,YR,Vis3D,X,Y,Z,Distance,Speed,LandX,LandY,LandT\n"
                    "0,0,0.0,1,,,0,,,0,,,,,,,,\n")
    with pytest.raises(ValueError, match="line 2"):
        read_render_csv(path, 30.0)
    with pytest.raises(RenderError, match="not found"):
        read_render_csv(tmp_path / "none.csv", 30.0)

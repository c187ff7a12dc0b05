"""Tests of the synthetic demo court (io/demo_scene.py, demo_rally.py, demo_render.py) and the
``demo`` CLI command: determinism, exact truth, the shuttle drawn where the truth says, flights
that obey the drag model, and the files the CLI writes. No Qt."""

from __future__ import annotations

import csv
import math
from collections import defaultdict

import cv2
import numpy as np
import pytest

from badminton_gui.cli import main as cli_main
from badminton_gui.core import court, physics
from badminton_gui.core.rig import StereoRig
from badminton_gui.io.demo_scene import (LABEL_HEADER, TRUTH_HEADER, DemoScene, make_rig,
                                          write_truth_csv)
from badminton_gui.io.demo_rally import _hermite
from badminton_gui.io.sources import FrameSource

SMALL = (320, 240)


@pytest.fixture(scope="module")
def scene_hd():
    return DemoScene(seed=1, size=(1280, 720), noise=False, flicker=False)


@pytest.fixture(scope="module")
def flights():
    scene = DemoScene(seed=2, size=SMALL)
    scene.script.ensure(60.0)
    return [s for s in scene.script.segments if s.kind == "flight"]


def test_source_protocol_and_end():
    scene = DemoScene(seed=0, size=SMALL, n_frames=3, fps=60.0)
    assert isinstance(scene, FrameSource)
    assert scene.image_size == SMALL and scene.fps == 60.0
    assert "binocular" in scene.name and "seed 0" in scene.name
    frames = []
    while (f := scene.read()) is not None:
        frames.append(f)
    assert [f.index for f in frames] == [0, 1, 2]
    assert [f.index_right for f in frames] == [0, 1, 2]
    assert frames[2].t_left == frames[2].t_right == pytest.approx(2 / 60.0)
    assert frames[0].left.shape == (240, 320, 3) and frames[0].left.dtype == np.uint8
    scene.close()


def test_deterministic_for_a_seed():
    a, b = DemoScene(seed=5, size=SMALL), DemoScene(seed=5, size=SMALL)
    c = DemoScene(seed=6, size=SMALL)
    for index in (10, 400, 77):          # random access in any order
        la, ra = a.render(index)
        lb, rb = b.render(index)
        assert np.array_equal(la, lb) and np.array_equal(ra, rb)
        assert a.truth(index) == b.truth(index)
    assert any(a.truth(i).position != c.truth(i).position for i in range(100, 400, 50))


def test_truth_uv_is_the_rig_projection():
    for rig_kind in ("binocular", "ends"):
        scene = DemoScene(seed=0, size=SMALL, rig=rig_kind)
        checked = 0
        for index in range(0, 1200, 11):
            tr = scene.truth(index)
            if tr.position is None:
                assert tr.uv_left is None and not tr.visible_left and tr.shot_kind == ""
                continue
            for cam, uv in ((0, tr.uv_left), (1, tr.uv_right)):
                if uv is None:
                    continue
                expected = scene.rig.project(cam, np.array([tr.position]))[0]
                assert np.allclose(uv, expected, atol=1e-9)
                checked += 1
        assert checked > 50


def test_truth_velocity_matches_positions():
    scene = DemoScene(seed=0, size=SMALL)
    fps = scene.fps
    n = 0
    for index in range(1, 1500, 3):
        a, b, c = scene.truth(index - 1), scene.truth(index), scene.truth(index + 1)
        if not (a.position and b.position and c.position) or len({a.shot_index, b.shot_index,
                                                                   c.shot_index}) > 1:
            continue
        if b.shot_kind == "smash" or min(np.linalg.norm(x.velocity) for x in (a, b, c)) < 0.1:
            continue                  # smashes decelerate too fast for a central difference
        central = (np.array(c.position) - np.array(a.position)) * fps / 2
        assert np.allclose(central, b.velocity, rtol=0.05, atol=0.15)
        n += 1
    assert n > 100


def test_shuttle_is_drawn_at_the_truth(scene_hd):
    bg = scene_hd._backgrounds[0].astype(int)
    drawn = hidden = 0
    for index in range(30, 2400, 23):
        tr = scene_hd.truth(index)
        if tr.uv_left is None or tr.position is None:
            continue
        u, v = tr.uv_left
        if not (5 <= u < 1275 and 5 <= v < 715):
            continue
        left, _ = scene_hd.render(index)
        ui, vi = int(round(u)), int(round(v))
        patch = left[vi - 2:vi + 3, ui - 2:ui + 3].astype(int)
        gain = patch.min(axis=2) - bg[vi - 2:vi + 3, ui - 2:ui + 3].min(axis=2)
        if tr.visible_left:
            if bg[vi - 2:vi + 3, ui - 2:ui + 3].max() > 180:
                continue              # in front of a light or a line: nothing to compare
            # A bright, grey-white blob right at the truth (a 3 px window, blur included).
            assert gain.max() > 25, (index, tr)
            drawn += 1
        else:
            # Hidden behind a player: the pixel under the truth is the player's, not white.
            pixel = left[vi, ui].astype(int)
            assert pixel.min() < 160                                  # not the white shuttle
            assert np.abs(pixel - bg[vi, ui]).sum() > 20              # but a body part
            hidden += 1
    assert drawn > 20 and hidden >= 1, (drawn, hidden)      # seed 1: 78 drawn, 2 hidden


def test_occlusion_marks_are_plausible():
    scene = DemoScene(seed=0, size=SMALL)
    in_image = occluded = 0
    for index in range(0, 120 * 40, 5):
        tr = scene.truth(index)
        if tr.position is None or tr.uv_left is None:
            continue
        u, v = tr.uv_left
        if -0.5 <= u < SMALL[0] - 0.5 and -0.5 <= v < SMALL[1] - 0.5:
            in_image += 1
            occluded += not tr.visible_left
        else:
            assert not tr.visible_left
    assert in_image > 200
    assert 0 < occluded < 0.15 * in_image


def test_subpixel_rendering_follows_the_truth():
    """A shuttle moved by 0.1 px moves its rendered centroid by 0.1 px (±0.03)."""
    from badminton_gui.io import demo_render as dr
    rig = make_rig("binocular")
    cam = dr.PinholeCamera.from_rig(rig, 0)
    base = np.array([0.0, -3.0, 2.0])
    shifts, moved = [], []
    for k in range(6):
        p = base + k * 0.002 * cam.R[0]           # ~0.1 px steps along the image x axis
        img = np.zeros((720, 1280, 3), np.uint8)
        dr.draw_shuttle(img, cam, p[None], cam.R[2][None], 1.0)
        g = img[..., 1].astype(float)
        ys, xs = np.nonzero(g)
        w = g[ys, xs]
        moved.append((xs * w).sum() / w.sum())
        shifts.append(rig.project(0, p[None])[0, 0])
    assert np.allclose(np.diff(moved), np.diff(shifts), atol=0.03)


def test_flights_obey_the_drag_model(flights):
    for seg in flights[:8]:
        t, p, _ = physics.simulate(seg.pos[0], seg.vel[0], seg.t1 - seg.t0 + 0.01, dt=1e-3,
                                   aero_length=physics.DEFAULT_AERO_LENGTH)
        n = min(len(p), len(seg.pos)) - 1      # the last sample may be cut onto the floor
        assert np.allclose(seg.times[:n] - seg.t0, np.arange(n) * 1e-3, atol=1e-9)
        assert np.allclose(p[:n], seg.pos[:n], atol=1e-6)
        # Frame times fall between the 1 ms samples: the interpolation is exact to < 1 µm.
        mid_t = 0.0005 * (2 * (n // 2) + 1)
        steps = round(mid_t / 1e-4)
        fine = physics.simulate(seg.pos[0], seg.vel[0], mid_t, dt=mid_t / steps, floor_z=None)
        assert len(fine[0]) == steps + 1
        interp, _ = _hermite(seg.times, seg.pos, seg.vel, seg.t0 + mid_t)
        assert np.allclose(interp, fine[1][-1], atol=1e-6)


def test_shots_land_in_the_opponents_court_with_plausible_speeds(flights):
    speeds = defaultdict(list)
    landed_in = 0
    for seg in flights:
        speeds[seg.shot_kind].append(float(np.linalg.norm(seg.vel[0])))
        land = physics.landing(seg.pos[0], seg.vel[0])
        assert land is not None
        (x, y, _), _ = land
        opponent_side = np.sign(seg.pos[0][1]) != np.sign(y)
        landed_in += court.is_in(x, y) and opponent_side
        # Every shot clears the net where it crosses Y = 0.
        cross = np.flatnonzero(np.sign(seg.pos[:, 1]) != np.sign(seg.pos[0, 1]))
        if len(cross):
            assert seg.pos[cross[0], 2] > court.NET_HEIGHT_POSTS
    assert landed_in >= 0.9 * len(flights)
    assert set(speeds) >= {"serve", "clear", "drop", "smash"}
    med = {k: float(np.median(v)) for k, v in speeds.items()}
    assert med["smash"] > 55 and min(speeds["smash"]) > 45
    assert med["drop"] < 25
    assert med["smash"] > med["clear"] > med["drop"]


def test_rig_has_court_pose_and_round_trips(tmp_path):
    for kind in ("binocular", "ends"):
        rig = make_rig(kind, SMALL)
        assert rig.has_court_pose
        assert np.allclose(rig.D1, 0) and np.allclose(rig.D2, 0)
        if kind == "binocular":
            assert 0.2 <= rig.baseline <= 0.6 + 1e-9
        # The net centre is in front of and inside both cameras.
        centre = np.array([[0.0, 0.0, court.NET_HEIGHT_CENTRE]])
        for cam in (0, 1):
            assert rig.depth(cam, centre)[0] > 0
            u, v = rig.project(cam, centre)[0]
            assert 0 <= u < SMALL[0] and 0 <= v < SMALL[1]
        path = tmp_path / f"{kind}.yaml"
        rig.save(path)
        back = StereoRig.load(path)
        assert back.image_size == rig.image_size
        for key in ("M1", "M2", "D1", "D2", "R", "T", "R_court", "T_court"):
            assert np.allclose(getattr(back, key), getattr(rig, key), atol=1e-9), key
        # Triangulating the projections gives the point back (court frame).
        pts = np.array([[0.5, -2.0, 2.5], [-1.0, -4.0, 1.0]])
        xyz = back.to_output(back.triangulate(back.project(0, pts), back.project(1, pts)))
        assert np.allclose(xyz, pts, atol=1e-6)


def test_intrinsics_scale_with_size():
    a, b = make_rig("binocular", (1280, 720)), make_rig("binocular", (640, 360))
    assert b.M1[0, 0] == pytest.approx(a.M1[0, 0] / 2)
    p = np.array([[0.3, -3.0, 2.0]])
    assert np.allclose((a.project(0, p) + 0.5) / 2, b.project(0, p) + 0.5)


def test_write_truth_csv(tmp_path):
    scene = DemoScene(seed=0, size=SMALL)
    truths = [scene.truth(i) for i in range(0, 200, 10)]
    write_truth_csv(tmp_path / "t.csv", truths)
    rows = list(csv.reader(open(tmp_path / "t.csv")))
    assert rows[0] == TRUTH_HEADER
    assert len(rows) == len(truths) + 1
    in_play = [r for r in rows[1:] if r[2] == "1"]
    assert in_play and all(r[3] and r[16] for r in in_play)


def test_cli_writes_the_files(tmp_path):
    out = tmp_path / "demo"
    code = cli_main(["demo", "--frames", "30", "--size", "320x240", "--out", str(out),
                     "--seed", "3", "--rig", "ends"])
    assert code == 0
    for name in ("left.mp4", "right.mp4", "rig.yaml", "truth.csv", "left_labels.csv",
                 "right_labels.csv"):
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    rig = StereoRig.load(out / "rig.yaml")
    assert rig.image_size == (320, 240) and rig.has_court_pose
    truth = list(csv.reader(open(out / "truth.csv")))
    assert truth[0] == TRUTH_HEADER and len(truth) == 31
    labels = list(csv.reader(open(out / "left_labels.csv")))
    assert labels[0] == LABEL_HEADER and len(labels) == 31
    cap = cv2.VideoCapture(str(out / "left.mp4"))
    n = 0
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        assert frame.shape == (240, 320, 3)
        n += 1
    cap.release()
    assert n == 30


def test_cli_unwritable_output_is_a_user_error(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    code = cli_main(["demo", "--frames", "2", "--out", str(blocker)])
    assert code == 2
    err = capsys.readouterr().err
    assert "not a folder" in err and err.count("\n") == 1


# ---- the scalar fast paths are the numpy formulations, bit for bit ---------------------------
# demo_rally/demo_render evaluate per-frame geometry on Python floats for speed (numpy's
# per-call overhead on 2- and 3-vectors dominated); frames must stay identical, so each fast
# path is checked here against the array expression it replaced, with ``==`` not ``allclose``.

def test_hermite_is_the_array_formula_exactly(flights):
    def reference(times, pos, vel, t):
        i = int(np.clip(np.searchsorted(times, t) - 1, 0, len(times) - 2))
        t0, t1 = times[i], times[i + 1]
        h = t1 - t0
        s = float(np.clip((t - t0) / h, 0.0, 1.0))
        p0, p1, m0, m1 = pos[i], pos[i + 1], vel[i] * h, vel[i + 1] * h
        s2, s3 = s * s, s * s * s
        p = (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * p1 + (s3 - s2) * m1
        dp = ((6 * s2 - 6 * s) * p0 + (3 * s2 - 4 * s + 1) * m0 + (-6 * s2 + 6 * s) * p1
              + (3 * s2 - 2 * s) * m1) / h
        return p, dp

    rng = np.random.default_rng(3)
    for seg in flights[:6]:
        for t in rng.uniform(seg.t0 - 0.01, seg.t1 + 0.01, 200):
            p, dp = _hermite(seg.times, seg.pos, seg.vel, float(t))
            p_ref, dp_ref = reference(seg.times, seg.pos, seg.vel, float(t))
            assert np.array_equal(p, p_ref) and np.array_equal(dp, dp_ref)


def test_player_pose_is_the_array_formula_exactly():
    from badminton_gui.io import demo_rally as rally

    def unit(v):
        n = np.linalg.norm(v)
        return v / n if n > 1e-12 else v

    def blend(a, b, u):
        return unit(a + (b - a) * rally._smoothstep(u))

    def reference(script, player, t):          # the array formulation (racket arm only)
        fwd, right = rally._frame_of(player)
        up = np.array([0.0, 0.0, 1.0])
        body_xy = rally.player_body(script, player, t)
        prev, nxt = script.contacts_of(player, t)
        jump = 0.0
        for c in (prev, nxt):
            if c is not None and abs(t - c.t) < 0.25:
                jump = max(jump, rally._jump_height(c) * math.cos(math.pi * (t - c.t) / 0.5) ** 2)
        body = np.array([body_xy[0], body_xy[1], jump])
        shoulder = body + rally.SHOULDER_HEIGHT * up + rally.SHOULDER_HALF_WIDTH * right
        rest = unit(0.55 * fwd + 0.35 * right - 0.45 * up)
        direction = rest
        for c in (nxt, prev):
            if c is None or not -0.35 <= t - c.t <= 0.3:
                continue
            u = t - c.t
            at = unit(np.asarray(c.point) - (np.array([*rally._body_for_contact(player, c),
                                                       rally._jump_height(c)])
                                             + rally.SHOULDER_HEIGHT * up
                                             + rally.SHOULDER_HALF_WIDTH * right))
            windup = (unit(-0.7 * fwd + 0.2 * right + 0.7 * up) if c.overhead
                      else unit(-0.6 * fwd + 0.7 * right - 0.2 * up))
            follow = unit(0.7 * fwd - 0.3 * right - 0.6 * up)
            if u < -0.18:
                direction = blend(rest, windup, (u + 0.35) / 0.17)
            elif u < 0:
                direction = blend(windup, at, (u + 0.18) / 0.18)
            elif u < 0.12:
                direction = blend(at, follow, u / 0.12)
            else:
                direction = blend(follow, rest, (u - 0.12) / 0.18)
            break
        vel_xy = (rally.player_body(script, player, t + 0.01)
                  - rally.player_body(script, player, t - 0.01)) / 0.02
        speed = float(np.hypot(*vel_xy))
        stride_dir = np.array([*(unit(vel_xy) if speed > 0.2 else fwd[:2]), 0.0])
        stride = min(speed / 4.0, 1.0) * 0.28 * math.sin(2 * math.pi * 2.2 * t)
        foot = body + 0.15 * right + stride * stride_dir + 0.05 * up
        return foot, shoulder, shoulder + rally.REACH * direction

    script = rally.RallyScript(4)
    swings = 0
    for t in np.arange(0.0, 12.0, 1 / 120):
        for player in (rally.NEAR, rally.FAR):
            caps = rally.player_capsules(script, player, float(t))
            foot, shoulder, racket_centre = reference(script, player, float(t))
            arm, head = caps[-3], caps[-1]
            assert caps[1].b == tuple(foot.tolist())
            assert arm.a == tuple(shoulder.tolist())
            assert head.a == tuple(racket_centre.tolist())
            swings += any(c is not None and -0.35 <= t - c.t <= 0.3
                          for c in script.contacts_of(player, float(t)))
    assert swings > 400, swings       # seed 4: 834 frames mid-swing


def test_occlusion_prefilter_keeps_the_exact_decision():
    from badminton_gui.io import demo_render as dr

    def reference(caps, uv, depth):
        for c in caps:
            if not c.occludes:
                continue
            cuv = np.array(c.uv)
            d = cuv[1] - cuv[0]
            n2 = float(d @ d)
            s = float(np.clip((uv - cuv[0]) @ d / n2, 0.0, 1.0)) if n2 > 1e-12 else 0.0
            closest = cuv[0] + s * d
            radius = c.r[0] + s * (c.r[1] - c.r[0])
            part_depth = c.depth[0] + s * (c.depth[1] - c.depth[0])
            if np.hypot(*(uv - closest)) <= radius and part_depth < depth:
                return True
        return False

    scene = DemoScene(seed=0, size=SMALL)
    rng = np.random.default_rng(0)
    hits = 0
    for index in range(0, 1200, 40):
        players = scene._truth_and_players(index)[1][0]
        for c in players:
            if not c.occludes:
                continue
            # Points around each part, many right at its edge, at depths either side of it.
            centre = np.array(c.uv).mean(axis=0)
            for _ in range(10):
                uv = centre + rng.normal(0, max(c.r) + 3, 2)
                depth = float(rng.uniform(min(c.depth) - 0.5, max(c.depth) + 0.5))
                got = dr.occluded_by(players, uv, depth)
                assert got == reference(players, uv, depth)
                hits += got
    assert hits > 300, hits           # seed 0: 723


def test_lying_shuttle_rests_on_cork_and_rim():
    """A shuttle on the floor touches it with its cork and its skirt's rim: no part below it."""
    from badminton_gui.io import demo_render as dr
    from badminton_gui.io.demo_rally import CORK_RADIUS

    h = np.array([0.6, -0.8, 0.0])
    d = dr.lying_direction(h)
    assert np.linalg.norm(d) == pytest.approx(1.0)
    assert np.allclose(d[:2] / np.linalg.norm(d[:2]), h[:2])
    cork = np.array([0.0, 0.0, CORK_RADIUS])
    rim_centre = cork - dr.SKIRT_LENGTH * d
    # The rim's lowest point: its centre minus the radius times the cosine of the axis' tilt.
    lowest = rim_centre[2] - dr.SKIRT_RADIUS * math.hypot(d[0], d[1])
    assert lowest == pytest.approx(0.0, abs=1e-9)
    assert rim_centre[2] > cork[2]           # the skirt's end is held up

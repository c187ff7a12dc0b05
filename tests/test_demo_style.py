"""Randomised demo courts (io/demo_style.py) and their benchmark (benchmarks/scenes.py)."""

from __future__ import annotations

import hashlib
import importlib.util
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from badminton_gui.core import court
from badminton_gui.core.types import FlightInfo, LandingPrediction
from badminton_gui.io.demo_scene import DemoScene
from badminton_gui.io.demo_style import (BENCHMARK_SEEDS_FROM, FAMILIES, FOV_RANGE, FRAME_RATES, SIZES,
                                         sample_scene)

ROOT = Path(__file__).resolve().parents[1]


def _bench(name: str):
    sys.path.insert(0, str(ROOT / "benchmarks"))
    spec = importlib.util.spec_from_file_location(f"{name}_tool", ROOT / "benchmarks" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module          # its dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def _small_seed(family: str, max_pixels: int = 1280 * 960) -> int:
    """A tuning seed of the family whose images are small (the tests render them)."""
    for seed in range(200):
        w, h = sample_scene(family, seed).size
        if w * h <= max_pixels:
            return seed
    raise AssertionError(f"no small scene in {family}")


def _digest(scene: DemoScene, indices) -> str:
    d = hashlib.sha256()
    for i in indices:
        left, right = scene.render(i)
        d.update(left.tobytes())
        d.update(right.tobytes())
    return d.hexdigest()[:16]


def test_the_default_scene_renders_what_it_always_rendered():
    # Digests of the scene before the randomised styles existed: the goldens, demo_accuracy's
    # figures and every earlier demo number were taken on these pixels.
    assert _digest(DemoScene(seed=0, size=(320, 240)), (0, 40, 133)) == "141158ec63bf3f06"
    assert _digest(DemoScene(seed=1, size=(320, 240), rig="ends"), (5, 90, 211)) == "83ddd513d13a9b0f"
    assert _digest(DemoScene(seed=2, size=(640, 360), noise=False, flicker=False), (70,)) == "7ecb8464257eb37e"


@pytest.mark.parametrize("family", FAMILIES)
def test_a_family_renders_the_same_frames_for_a_seed(family):
    seed = _small_seed(family, 800 * 600)
    style = sample_scene(family, seed)
    assert style == sample_scene(family, seed)
    assert style != sample_scene(family, seed + 1)
    a, b = DemoScene(seed=seed, style=style), DemoScene(seed=seed, style=sample_scene(family, seed))
    assert _digest(a, (3, 77)) == _digest(b, (3, 77))
    assert a.image_size == style.size and a.fps == style.fps


@pytest.mark.parametrize("family", FAMILIES)
def test_styles_stay_in_their_ranges_and_both_cameras_see_the_court(family):
    w, hl = court.HALF_WIDTH_DOUBLES, court.HALF_LENGTH
    near = np.array([(-w, -hl, 0), (w, -hl, 0), (-w, 0, 0), (w, 0, 0)], float)
    for seed in range(BENCHMARK_SEEDS_FROM - 6, BENCHMARK_SEEDS_FROM):
        style = sample_scene(family, seed)
        assert style.size in SIZES and style.fps in FRAME_RATES
        assert FOV_RANGE[0] <= style.hfov_deg <= FOV_RANGE[1]
        rig = style.rig()
        assert rig.has_court_pose and rig.image_size == style.size
        for cam in (0, 1):
            uv = rig.project(cam, near)
            assert np.all(rig.depth(cam, near) > 0)
            assert np.all((uv >= 0) & (uv < np.array(style.size))), (family, seed, cam, uv)
        hx, hy, hz = style.hall
        assert all(abs(c[0]) < hx and abs(c[1]) < hy and 0 < c[2] < hz for c in style.centres)


def test_an_unknown_family_is_refused():
    with pytest.raises(ValueError, match="side-near"):
        sample_scene("balcony", 1)


@pytest.mark.parametrize("family", FAMILIES)
def test_the_rig_projects_the_truth_onto_the_drawn_shuttle(family):
    seed = _small_seed(family)
    style = sample_scene(family, seed)
    scene = DemoScene(seed=seed, style=style)
    rig = scene.rig
    bg = scene.background(0).astype(int)
    w, h = style.size
    checked = near_truth = 0
    for index in range(0, int(6 * style.fps), max(1, int(style.fps / 25))):
        tr = scene.truth(index)
        if not tr.visible_left or tr.velocity is None or np.linalg.norm(tr.velocity) > 10.0:
            continue
        u, v = tr.uv_left
        ui, vi = int(round(u)), int(round(v))
        if not (8 <= ui < w - 8 and 8 <= vi < h - 8):
            continue
        if bg[vi - 5:vi + 6, ui - 5:ui + 6].max() > 170:
            continue            # a light, a line or a white wall behind it: nothing to compare
        left, _ = scene.render(index)
        gain = (left[vi - 5:vi + 6, ui - 5:ui + 6].astype(int).min(axis=2)
                - bg[vi - 5:vi + 6, ui - 5:ui + 6].min(axis=2))
        dy, dx = np.unravel_index(int(np.argmax(gain)), gain.shape)
        cork_px = rig.M1[0, 0] * 0.013 * style.shuttle_scale / float(rig.depth(0, np.array([tr.position]))[0])
        checked += 1
        near_truth += gain.max() > 20 and math.hypot(dx - 5, dy - 5) <= max(2.0, cork_px + 1.5)
        if checked >= 20:
            break
    assert checked >= 5, (family, seed, checked)
    assert near_truth >= 0.9 * checked, (family, seed, near_truth, checked)


def test_the_led_board_changes_from_frame_to_frame():
    for seed in range(50):
        style = sample_scene("side-far", seed)
        if style.board is not None and style.size[0] <= 1280:
            break
    board = style.board
    a, b = board.texture(0.0), board.texture(board.period * 1.5)
    assert a.shape == b.shape == (board.texels[1], board.texels[0], 3)
    assert np.abs(a.astype(int) - b).max() > 100         # a bright, changing picture
    assert a.max() == 255                                 # with its white dot


def test_prediction_before_takes_the_last_prediction_of_the_shot():
    landing = _bench("landing")
    pred = LandingPrediction(x=1.0, y=2.0, t=3.0, radius=0.1)
    history = [(0.0, FlightInfo(shot_index=0, in_flight=True, prediction=pred), "a"),
               (0.1, FlightInfo(shot_index=0, in_flight=False, prediction=pred), "b"),
               (0.2, FlightInfo(shot_index=1, in_flight=False), "c")]
    assert landing.prediction_before(history, 0.0, 0.15) == (pred, "b")    # lost, same shot: kept
    assert landing.prediction_before(history, 0.05, 0.15) == (None, "b")   # not followed in this shot
    assert landing.prediction_before(history, 0.0, 0.25) == (None, "c")
    assert landing.prediction_before(history, 0.5, 0.6) == (None, None)


def test_a_tiny_scenes_benchmark_run(capsys):
    scenes = _bench("scenes")
    seed = _small_seed("side-far", 800 * 600)
    assert scenes.main(["--families", "side-far", "--seeds", "1", "--first-seed", str(seed),
                        "--seconds", "0.5", "--max-frames", "40", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    fam = out["families"]["side-far"]
    assert fam["clips"] == 1 and fam["frames"] == 40
    assert 0.0 <= fam["acc_left"] <= 1.0 and 0.0 <= fam["acc_right"] <= 1.0
    assert set(out["goals"]["side-far"]) == {g[0] for g in scenes.GOALS}
    assert out["goals"]["side-far"]["landing median ≤ 5 cm"] is None      # no landing in 40 frames
    clip = out["clips"][0]
    assert clip["seed"] == seed and sum(clip["left"].values()) == 40
    # The census counts every wrong camera-frame once.
    wrong = sum(clip[side][k] for side in ("left", "right") for k in ("fp1", "fp2", "fn"))
    assert sum(clip["census"].values()) == wrong
    # The tables print too.
    assert scenes.main(["--families", "side-far", "--seeds", "1", "--first-seed", str(seed),
                        "--seconds", "0.5", "--max-frames", "20", "--census"]) == 0
    printed = capsys.readouterr().out
    assert "goal check" in printed and "wrong camera-frames by cause" in printed


def test_a_seen_landing_without_prediction_makes_the_p95_infinite_not_nan():
    scenes = _bench("scenes")
    counts = {"tp": 1, "tn": 0, "fp1": 0, "fp2": 0, "fn": 0}

    def clip(errors):
        return {"left": counts, "right": counts, "errors_3d": [0.01], "both_visible": 1,
                "both_with_point": 1, "frames": 1, "pairs_per_s": 1.0,
                "landings": [{"seen": True, "error": e} for e in errors]}

    missing = scenes.summarise([clip([0.01, 0.02, 0.03, None])])
    assert missing["landing_p95"] == math.inf and missing["landing_median"] == pytest.approx(0.025)
    assert missing["landings_predicted"] == 3 and missing["landings_seen"] == 4
    assert scenes.goal_check(missing)["landing p95 ≤ 15 cm"] is False
    found = scenes.summarise([clip([0.01, 0.02, 0.03, 0.04])])
    assert found["landing_p95"] == pytest.approx(np.percentile([0.01, 0.02, 0.03, 0.04], 95))

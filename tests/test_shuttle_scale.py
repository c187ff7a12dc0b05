"""The shuttle's image size and speed from the camera's geometry (core/detect/shuttle_scale.py),
against pinhole cases computed by hand, and the gates of filters 1, 2 and 4 that follow them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from badminton_gui.core.detect.params import ShuttleScaleParams
from badminton_gui.core.detect.shuttle_scale import from_image, from_rig, ray_box
from badminton_gui.core.detector import CameraDetector
from badminton_gui.core.params import TrackerParams
from badminton_gui.core.rig import StereoRig


def _down_looking_rig(f: float = 500.0, height: float = 20.0, size=(640, 480)) -> StereoRig:
    """A pinhole looking straight down at the court centre from ``height`` m: the image's x
    along the court's X, its y along −Y; no distortion."""
    m = np.array([[f, 0, size[0] / 2], [0, f, size[1] / 2], [0, 0, 1.0]])
    # Camera frame → court frame: x → X, y → −Y, z (forward) → −Z.
    r_court = np.diag([1.0, -1.0, -1.0])
    return StereoRig(M1=m, D1=np.zeros(5), M2=m, D2=np.zeros(5), R=np.eye(3),
                     T=np.array([-0.5, 0.0, 0.0]), image_size=size,
                     R_court=r_court, T_court=np.array([0.0, 0.0, height]))


def test_ray_box_entry_and_exit():
    entry, exit_ = ray_box(np.array([0.0, 0.0, 20.0]), np.array([[0.0, 0.0, -1.0], [1.0, 0.0, 0.0]]),
                           np.array([-1.0, -1.0, 0.0]), np.array([1.0, 1.0, 10.0]))
    assert entry[0] == pytest.approx(10.0) and exit_[0] == pytest.approx(20.0)
    assert entry[1] > exit_[1]          # a level ray at 20 m height misses the box


def test_rig_map_at_the_image_centre_is_the_pinhole_by_hand():
    f, height = 500.0, 20.0
    p = ShuttleScaleParams(ceiling=10.0, court_margin=2.0, nearest=1.0, max_speed=100.0)
    shuttle_map = from_rig(_down_looking_rig(f, height), 0, p)
    # Straight down the nearest shuttle is at the ceiling (10 m away), the farthest on the
    # floor (20 m): px per metre f / d.
    small, big, speed = (float(v[0]) for v in shuttle_map.at([320.0], [240.0]))
    assert big == pytest.approx(f / 10.0 * p.length, rel=0.03)
    assert small == pytest.approx(f / 20.0 * p.cork_diameter, rel=0.03)
    assert speed == pytest.approx(f / 10.0 * p.max_speed, rel=0.03)


def test_nearer_volume_gives_larger_shuttle():
    low = from_rig(_down_looking_rig(height=12.0), 0, ShuttleScaleParams())
    high = from_rig(_down_looking_rig(height=30.0), 0, ShuttleScaleParams())
    assert low.max_size[6, 8] > 2 * high.max_size[6, 8]


def test_image_map_by_hand():
    p = ShuttleScaleParams(fov=90.0, nearest=2.0, farthest=20.0, max_speed=50.0)
    shuttle_map = from_image(1000, 500, p)
    f = 500.0   # half the width at 45°
    # The cell at the image's centre: sampled a little off the axis, so within a few percent.
    row, col = shuttle_map.cells([500.0], [250.0])
    assert shuttle_map.max_size[row[0], col[0]] == pytest.approx(f / 2.0 * p.length, rel=0.05)
    assert shuttle_map.min_size[row[0], col[0]] == pytest.approx(f / 20.0 * p.cork_diameter, rel=0.05)
    assert shuttle_map.max_speed[row[0], col[0]] == pytest.approx(f / 2.0 * p.max_speed, rel=0.05)
    # A corner: at angle θ off the axis the scale across the line of sight is f / (d cos²θ)
    # radially (nearest) and f / (d cos θ) around (farthest); the corner cell's samples are
    # nearer the axis, so the map stays within those bounds.
    r = math.hypot(500.0, 250.0) / f
    cos = 1 / math.sqrt(1 + r * r)
    assert shuttle_map.max_size[0, 0] <= f / (2.0 * cos * cos) * p.length
    assert shuttle_map.max_size[0, 0] > shuttle_map.max_size[row[0], col[0]]


def test_half_the_resolution_halves_the_gates():
    p = ShuttleScaleParams()
    full = from_image(1280, 720, p).gate_scale(p.reference_scale)
    half = from_image(640, 360, p).gate_scale(p.reference_scale)
    assert half.at([320.0], [180.0])[0] == pytest.approx(0.5 * full.at([640.0], [360.0])[0])
    assert half.at1(320.0, 180.0) == pytest.approx(half.at([320.0], [180.0])[0])
    one = from_image(640, 360, p).gate_scale(p.reference_scale, per_position=False)
    assert np.ptp(one.factor) == 0


def test_detector_map_follows_params_and_rig():
    rig = _down_looking_rig()
    # The map exists with the gates off too: the far shuttle's size picks the model's scale.
    off = CameraDetector(TrackerParams(), (rig, 0))
    assert off.scale_map(640, 480).source == "rig"
    params = TrackerParams().with_value("shuttle_scale.enabled", True)
    on = CameraDetector(params, (rig, 0))
    assert on.scale_map(640, 480).source == "rig"
    # Frames of another size than the rig's, or no rig: the image alone.
    assert on.scale_map(320, 240).source == "image"
    assert CameraDetector(params).scale_map(640, 480).source == "image"


def test_stereo_tracker_hands_each_camera_its_rig():
    from badminton_gui.core.tracker import StereoTracker
    from badminton_gui.io.demo_scene import make_rig

    rig = make_rig("binocular", (640, 360))
    tracker = StereoTracker(rig, TrackerParams().with_value("shuttle_scale.enabled", True))
    try:
        left, right = tracker.left.scale_map(640, 360), tracker.right.scale_map(640, 360)
        assert left.source == right.source == "rig"
        # The demo's side rack at 640 px sees the shuttle at under the reference scale: the
        # pixel gates shrink there.
        p = ShuttleScaleParams()
        assert np.median(left.gate_scale(p.reference_scale).factor) < 0.6
    finally:
        tracker.close()

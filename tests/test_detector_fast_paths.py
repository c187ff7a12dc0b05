"""The detector's fast paths give the values of the plain numpy formulas they replaced.

Why this file exists: the appearance features feed trained classifiers
(``resources/candidate_classifier*.json``), so a faster implementation must not move them, and a
later "simplification" must not either. The reference functions below are the original numpy
code, kept verbatim; the fast code is compared with them on synthetic blobs that reach every
branch (window clipped by the image edge, no mask pixel inside, nothing brighter than the border,
mask windows that need resizing) and, when ../shared/data is present, on real NYCU frames.
"""

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from badminton_gui.core import detector as detector_module
from badminton_gui.core.detect.measure import N_APPEARANCE, REFINE_MARGIN, measure_blobs, window_maxima
from badminton_gui.core.detect.segmentation import ModelGrey
from badminton_gui.core.detector import CameraDetector
from badminton_gui.io.presets import load_preset

_GROW = np.ones((3, 3), np.uint8)
DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
NYCU_LEFT = DATA / "nycu-stereo" / "rally_11-46-04" / "CameraReader_1.mp4"


def reference_measure(frame, mask, box, sx, sy, head_fraction=0.5):
    """The per-blob measurement as first written (numpy reductions), the values' definition."""
    h, w = frame.shape[:2]
    x0 = max(box[0] - REFINE_MARGIN, 0)
    y0 = max(box[1] - REFINE_MARGIN, 0)
    x1 = min(box[0] + box[2] + REFINE_MARGIN, w)
    y1 = min(box[1] + box[3] + REFINE_MARGIN, h)
    crop = frame[y0:y1, x0:x1]
    features = np.zeros(N_APPEARANCE, dtype=np.float32)
    if crop.size == 0:
        return box[0] + box[2] / 2, box[1] + box[3] / 2, 0.0, 255.0, features
    mx0, my0 = int(x0 / sx), int(y0 / sy)
    mx1, my1 = max(int(math.ceil(x1 / sx)), mx0 + 1), max(int(math.ceil(y1 / sy)), my0 + 1)
    mcrop = mask[my0:my1, mx0:mx1]
    if mcrop.shape[:2] != crop.shape[:2]:
        mcrop = cv2.resize(mcrop, (crop.shape[1], crop.shape[0]), interpolation=cv2.INTER_NEAREST)
    inside = mcrop > 0
    cmin = crop.min(axis=2)
    cmax = crop.max(axis=2)
    if inside.any():
        whiteness = float(cmin[inside].mean())
        saturation = float((cmax[inside].astype(np.int16) - cmin[inside]).mean())
    else:
        whiteness, saturation = 0.0, 255.0
    gray = crop.astype(np.float32).mean(axis=2)
    border = np.concatenate([gray[0], gray[-1], gray[:, 0], gray[:, -1]])
    background = float(np.median(border))
    excess = gray - background
    peak = float(excess.max())
    bright = excess > 0.5 * peak
    n_bright = int(bright.sum())
    border_bright = np.concatenate([bright[0], bright[-1], bright[:, 0], bright[:, -1]])
    spill = float(border_bright.mean())
    peak_sat = float(cmax.max()) - float(cmin.max())
    features[:] = (peak, background, math.log1p(n_bright), spill, whiteness, saturation,
                   math.log1p(inside.sum()), peak_sat, float(gray.std()))
    if peak <= 0:
        ys, xs = np.nonzero(inside)
        if len(xs) == 0:
            return box[0] + box[2] / 2, box[1] + box[3] / 2, whiteness, saturation, features
        return x0 + xs.mean(), y0 + ys.mean(), whiteness, saturation, features
    support = inside
    if support.any():
        support = cv2.dilate(support.astype(np.uint8), _GROW) > 0
    blob_excess = np.where(support, excess, 0.0)
    blob_peak = float(blob_excess.max())
    if blob_peak <= 0:
        blob_excess = np.clip(excess, 0, None)
        blob_peak = peak
    weights = np.clip(blob_excess - head_fraction * blob_peak, 0, None)
    total = float(weights.sum())
    if total <= 0:
        weights = np.clip(blob_excess, 0, None)
        total = float(weights.sum())
    ys, xs = np.mgrid[0:crop.shape[0], 0:crop.shape[1]]
    cx = float((weights * xs).sum() / total) + x0
    cy = float((weights * ys).sum() / total) + y0
    return cx, cy, whiteness, saturation, features


def _as_vector(measured):
    x, y, whiteness, saturation, features = measured
    return np.array([x, y, whiteness, saturation, *features], dtype=float)


def assert_same_measure(frame, mask, box, sx, sy, head_fraction=0.5):
    ref = _as_vector(reference_measure(frame, mask, box, sx, sy, head_fraction))
    x, y, whiteness, saturation, features = measure_blobs(frame, mask, [box], sx, sy, head_fraction)
    fast = _as_vector((x[0], y[0], whiteness[0], saturation[0], features[0]))
    # Sums of integer data are exact in both; the window's std and the centroid's sums are
    # accumulated in double instead of float32 (~1e-7 relative).
    np.testing.assert_allclose(fast, ref, rtol=1e-5, atol=1e-5, err_msg=f"box {box}")


def _synthetic_frame(seed):
    rng = np.random.default_rng(seed)
    frame = cv2.add(np.full((240, 320, 3), 30, np.uint8), rng.integers(0, 8, (240, 320, 3), dtype=np.uint8))
    cv2.rectangle(frame, (150, 40), (190, 70), (250, 250, 250), -1)          # a light
    cv2.circle(frame, (172, 82), 3, (210, 215, 205), -1)                     # a shuttle beside it
    cv2.circle(frame, (2, 3), 3, (230, 230, 230), -1)                        # one in a corner
    cv2.ellipse(frame, (250, 190), (12, 4), 30, 0, 360, (60, 90, 200), -1)   # a coloured shoe
    cv2.circle(frame, (60, 200), 4, (200, 200, 200), -1)
    return frame


def _thresholded(frame, scale):
    """The frame's grey image and a bright-blob mask at ``scale``, with the mask→frame scale factors."""
    gray = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    if scale < 1.0:
        gray = cv2.resize(gray, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    mask = cv2.threshold(gray, 120, 255, cv2.THRESH_BINARY)[1]
    return gray, mask, frame.shape[1] / mask.shape[1], frame.shape[0] / mask.shape[0]


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("scale", [0.25, 0.5, 1.0])   # 0.25: the coarse preset's mask, resized ×4
def test_measure_equals_the_numpy_formulas_on_synthetic_blobs(seed, scale):
    frame = _synthetic_frame(seed)
    gray, mask, sx, sy = _thresholded(frame, scale)
    boxes = [(168, 78, 9, 9), (148, 38, 45, 35), (0, 0, 6, 7), (238, 184, 25, 13), (56, 196, 9, 9),
             (100, 120, 8, 8),            # nothing in the mask: no support, plain background
             (315, 235, 5, 5),            # clipped by the bottom-right corner
             (90, 90, 1, 1)]              # the smallest window
    for box in boxes:
        for head_fraction in (0.0, 0.5, 0.9):
            assert_same_measure(frame, mask, box, sx, sy, head_fraction)


def test_measure_on_a_window_darker_than_its_border():
    # peak <= 0: the position falls back to the mask's centroid (or the box centre).
    frame = np.full((60, 80, 3), 200, np.uint8)
    frame[20:30, 30:40] = 50
    mask = np.zeros((60, 80), np.uint8)
    mask[22:28, 32:38] = 255
    assert_same_measure(frame, mask, (30, 20, 10, 10), 1.0, 1.0)
    assert_same_measure(frame, np.zeros_like(mask), (30, 20, 10, 10), 1.0, 1.0)


def test_measure_on_a_two_pixel_wide_window():
    # cv2.moments would read an (N, 2) float array as N contour points: the fast path must not.
    frame = np.full((12, 2, 3), 40, np.uint8)
    frame[5:7, :] = 220
    frame[6, 1] = 250
    mask = np.zeros((12, 2), np.uint8)
    mask[5:7, :] = 255
    assert_same_measure(frame, mask, (0, 5, 2, 2), 1.0, 1.0)


def assert_same_batch(frame, mask, boxes, sx, sy, head_fraction=0.5):
    """All boxes measured together (one canvas) equal each box measured alone by the reference."""
    batch = measure_blobs(frame, mask, boxes, sx, sy, head_fraction)
    for k, box in enumerate(boxes):
        ref = _as_vector(reference_measure(frame, mask, box, sx, sy, head_fraction))
        fast = _as_vector(tuple(part[k] for part in batch))
        np.testing.assert_allclose(fast, ref, rtol=1e-5, atol=1e-5, err_msg=f"box {box}")


@pytest.mark.parametrize("scale", [0.25, 0.5, 1.0])
def test_windows_measured_together_do_not_interact(scale):
    # Neighbouring windows in the shared canvas (different widths, a mask touching a window's
    # last row, empty and clipped windows in between) must give each its own values.
    frame = _synthetic_frame(3)
    gray, mask, sx, sy = _thresholded(frame, scale)
    boxes = [(148, 38, 45, 35), (168, 78, 9, 9), (100, 120, 8, 8), (315, 235, 5, 5),
             (0, 0, 6, 7), (238, 184, 25, 13), (56, 196, 9, 9), (170, 60, 10, 30),
             (400, 400, 5, 5)]   # entirely outside the frame: an empty window
    for head_fraction in (0.0, 0.5):
        assert_same_batch(frame, mask, boxes, sx, sy, head_fraction)


def _single_and_canvas(frame, mask, box, sx, sy, head_fraction):
    """The box measured alone (the single-window path) and on the shared canvas (the same box
    followed by an empty one outside the frame: the canvas path, with one window)."""
    alone = measure_blobs(frame, mask, [box], sx, sy, head_fraction)
    shared = measure_blobs(frame, mask, [box, (10_000, 10_000, 5, 5)], sx, sy, head_fraction)
    return alone, tuple(part[:1] for part in shared)


@pytest.mark.parametrize("scale", [0.25, 0.5, 1.0])
def test_a_single_blob_is_measured_bit_for_bit_as_on_the_shared_canvas(scale):
    """The single-window path (a windowed frame's usual case) is exact, not just close: the
    classifier and the position see the very same numbers (track CSVs stay identical)."""
    rng = np.random.default_rng(7)
    cases = []
    for seed in (0, 1, 2):
        frame = _synthetic_frame(seed)
        _, mask, sx, sy = _thresholded(frame, scale)
        boxes = [(168, 78, 9, 9), (148, 38, 45, 35), (0, 0, 6, 7), (238, 184, 25, 13), (56, 196, 9, 9),
                 (100, 120, 8, 8), (315, 235, 5, 5), (90, 90, 1, 1)]
        boxes += [(int(rng.integers(0, 310)), int(rng.integers(0, 230)), int(rng.integers(1, 30)),
                   int(rng.integers(1, 30))) for _ in range(20)]
        cases += [(frame, mask, box, sx, sy) for box in boxes]
    dark = np.full((60, 80, 3), 200, np.uint8)   # nothing brighter than the border
    dark[20:30, 30:40] = 50
    dark_mask = np.zeros((60, 80), np.uint8)
    dark_mask[22:28, 32:38] = 255
    cases += [(dark, dark_mask, (30, 20, 10, 10), 1.0, 1.0), (dark, dark_mask * 0, (30, 20, 10, 10), 1.0, 1.0)]
    for frame, mask, box, sx, sy in cases:
        for head_fraction in (0.0, 0.5, 0.9):
            alone, shared = _single_and_canvas(frame, mask, box, sx, sy, head_fraction)
            for a, b in zip(alone, shared):
                assert a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True), (box, head_fraction, a, b)


@pytest.mark.skipif(not NYCU_LEFT.is_file(), reason="real data (../shared/data) not available")
def test_measure_equals_the_numpy_formulas_on_real_frames(monkeypatch):
    seen = []
    original = detector_module.measure_blobs

    def recording(frame, mask, boxes, sx, sy, head_fraction=0.5):
        seen.append((frame, mask.copy(), list(boxes), sx, sy, head_fraction))
        return original(frame, mask, boxes, sx, sy, head_fraction)

    monkeypatch.setattr(detector_module, "measure_blobs", recording)
    det = CameraDetector(load_preset("default"))
    cap = cv2.VideoCapture(str(NYCU_LEFT))
    for i in range(25):
        ok, frame = cap.read()
        assert ok
        det.process(frame, i / 119.0, keep_mask=False)
    cap.release()
    assert sum(len(args[2]) for args in seen) > 100
    for args in seen:
        assert_same_batch(*args)


class ReferenceBrighterThanAverage:
    """The brighter-than-average background model as first written (numpy, fresh arrays)."""

    def __init__(self, bg, binarize):
        self.bg, self.bin = bg, binarize
        self.average = None
        self.last_difference = None

    def apply(self, gray):
        if self.average is None:
            self.average = gray.astype(np.float32)
            return np.zeros_like(gray)
        current = gray.astype(np.float32)
        gain = 1.0
        if self.bg.compensate_gain:
            avg_s = self.average[::8, ::8]
            cur_s = current[::8, ::8]
            lit = avg_s > 20
            if np.count_nonzero(lit) > 50:
                gain = float(np.median(cur_s[lit] / avg_s[lit]))
        reference = self.average
        k = int(self.bg.shake_tolerance)
        if k > 0:
            reference = cv2.dilate(reference, cv2.getStructuringElement(cv2.MORPH_RECT, (2 * k + 1, 2 * k + 1)))
        diff = cv2.subtract(current, reference * gain) if gain != 1.0 else cv2.subtract(current, reference)
        if self.bin.max_background < 255:
            diff[self.average >= float(self.bin.max_background)] = 0
        self.last_difference = diff
        _, mask = cv2.threshold(diff, float(self.bin.diff_threshold), 255, cv2.THRESH_BINARY)
        mask = mask.astype(np.uint8)
        alpha = float(self.bg.learning_rate)
        if alpha > 0:
            cv2.accumulateWeighted(gray, self.average, alpha, mask=cv2.bitwise_not(mask))
            cv2.accumulateWeighted(gray, self.average, alpha * 0.1, mask=mask)
        # BackgroundModel.apply's post-processing, unchanged.
        k = int(self.bin.open_kernel)
        if k >= 2:
            mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k)))
        if self.bin.dilate_iterations > 0:
            mask = cv2.dilate(mask, None, iterations=int(self.bin.dilate_iterations))
        return mask


@pytest.mark.parametrize("overrides", [
    {},
    {"binarize.max_background": 255, "background.compensate_gain": False},
    {"background.shake_tolerance": 2, "binarize.diff_threshold": 12.5},
    {"background.shake_tolerance": 0, "binarize.max_background": 120},
    {"binarize.dilate_iterations": 0, "binarize.open_kernel": 3},
])
def test_background_model_equals_the_numpy_formulas(overrides):
    from badminton_gui.core.background import BackgroundModel
    from badminton_gui.core.params import TrackerParams

    p = TrackerParams()
    for key, value in overrides.items():
        p = p.with_value(key, value)
    fast = BackgroundModel(p.background, p.binarize)
    ref = ReferenceBrighterThanAverage(p.background, p.binarize)
    rng = np.random.default_rng(5)
    base = cv2.GaussianBlur(rng.integers(0, 200, (120, 160), dtype=np.uint8), (5, 5), 0)
    cv2.rectangle(base, (20, 20), (40, 30), 250, -1)          # a light
    foreground = 0
    for i in range(40):
        gain = 1.0 + 0.06 * math.sin(i)                          # flicker
        frame = np.clip(base * gain + rng.normal(0, 3, base.shape), 0, 255).astype(np.uint8)
        cv2.circle(frame, (30 + 3 * i, 60 + i), 2, 240, -1)       # something bright moving
        mask_fast = fast.apply(frame)
        mask_ref = ref.apply(frame)
        assert np.array_equal(mask_fast, mask_ref), f"frame {i}"
        foreground += int(np.count_nonzero(mask_ref))
        if ref.last_difference is not None:
            diff = fast.last_difference
            if fast.last_unlit is not None:
                diff = np.where(fast.last_unlit > 0, diff, 0)
            assert np.array_equal(diff, ref.last_difference), f"frame {i}"
    assert foreground > 0


def test_model_grey_at_half_scale_is_the_area_resize():
    # The default path: INTER_AREA of the colour frame, then grey (what the model was tuned on).
    frame = _synthetic_frame(4)
    expected = cv2.cvtColor(cv2.resize(frame, (160, 120), interpolation=cv2.INTER_AREA), cv2.COLOR_BGR2GRAY)
    assert np.array_equal(ModelGrey()(frame, 0.5), expected)


def test_quarter_scale_model_grey_averages_every_other_row():
    # The row-sampled quarter path: each model pixel is the mean of rows 4k and 4k + 2 of its
    # 4×4 block, four columns each, in grey (three rounding steps: within 1.5 grey levels).
    frame = cv2.add(_synthetic_frame(5), np.random.default_rng(5).integers(0, 60, (240, 320, 3), dtype=np.uint8))
    gray = ModelGrey()(frame, 0.25)
    assert gray.shape == (60, 80)
    full = frame.astype(np.float64) @ np.array([0.114, 0.587, 0.299])
    blocks = full.reshape(60, 4, 80, 4)[:, [0, 2]].mean(axis=(1, 3))
    assert np.abs(gray - blocks).max() <= 1.5


def test_the_far_shuttle_size_decides_the_coarser_model():
    from badminton_gui.core.detector import model_scale

    default = load_preset("default").background
    assert default.coarse_from_width == 0 and default.coarse_shuttle_px == 0   # off: see model_scale
    assert model_scale(default, 2048, far_shuttle_px=50.0) == 0.5
    bg = default.__class__(**{**_fields(default), "coarse_shuttle_px": 2.0})
    # A far shuttle 10 px long at full resolution still spans 2.5 px of a quarter-scale model.
    assert model_scale(bg, 2048, far_shuttle_px=10.0) == 0.25
    # NYCU's (5.6 px at 2048) and the demo's keep half scale; no size known: the processing scale.
    assert model_scale(bg, 2048, far_shuttle_px=5.6) == 0.5
    assert model_scale(bg, 1280, far_shuttle_px=2.7) == 0.5
    assert model_scale(bg, 2048) == 0.5
    assert model_scale(bg.__class__(**{**_fields(bg), "coarse_shuttle_px": 0.0}), 2048, 50.0) == 0.5
    # The fixed width rule (the coarse preset) replaces the size rule.
    fixed = bg.__class__(**{**_fields(bg), "coarse_from_width": 1600})
    assert model_scale(fixed, 2048) == 0.25
    assert model_scale(fixed, 1280, far_shuttle_px=50.0) == 0.5
    fast = load_preset("coarse")
    assert model_scale(fast.background, 2048) == 0.25
    assert fast.classifier.model == "candidate_classifier_coarse"


def _fields(group) -> dict:
    import dataclasses
    return {f.name: getattr(group, f.name) for f in dataclasses.fields(group)}


def test_a_camera_far_from_the_court_runs_coarser_with_the_coarse_classifier():
    from badminton_gui.io.demo_scene import make_rig

    p = load_preset("default")
    p = (p.with_value("classifier.coarse_model", "candidate_classifier_coarse")
         .with_value("background.coarse_shuttle_px", 2.0))
    behind = make_rig("ends", (2048, 1536))        # behind the baselines: far shuttle ≈ 8.8 px
    beside = make_rig("binocular", (2048, 1536))   # beside the near half: ≈ 6 px
    far_det, near_det = CameraDetector(p, (behind, 0)), CameraDetector(p, (beside, 0))
    assert far_det.scale_map(2048, 1536).far_length > near_det.scale_map(2048, 1536).far_length
    assert far_det.model_scale(2048, 1536) == 0.25 and near_det.model_scale(2048, 1536) == 0.5
    frame = cv2.resize(_synthetic_frame(6), (2048, 1536))
    far_result = far_det.find_candidates(frame, 0.0)
    near_result = near_det.find_candidates(frame, 0.0)
    assert far_result.mask_scale == 0.25 and near_result.mask_scale == 0.5
    assert far_det.classifier.name == p.classifier.coarse_model
    assert near_det.classifier.name == p.classifier.model
    # A classifier given for this recording (court adaptation) is kept at either scale.
    given = near_det.classifier
    far_det.use_classifier(given)
    far_det.find_candidates(frame, 1 / 120)
    assert far_det.classifier is given


def test_coarse_from_width_halves_the_model_of_wide_frames():
    p = load_preset("default")
    det = CameraDetector(p.with_value("background.coarse_from_width", 256))
    frame = _synthetic_frame(6)
    for i in range(3):
        result = det.find_candidates(frame, i / 119.0)
    assert result.mask.shape == (60, 80) and result.mask_scale == 0.25


def test_window_maxima_of_several_images_share_the_windows():
    # The ranking reads the difference (counted as 0 where ``counts_where`` is 0) and the grey
    # image in the same windows: each maximum is the plain per-window numpy maximum.
    rng = np.random.default_rng(5)
    diff = rng.normal(0, 20, (40, 60)).astype(np.float32)
    gray = rng.integers(0, 256, (40, 60), dtype=np.uint8)
    unlit = np.where(rng.random((40, 60)) < 0.3, 0, 255).astype(np.uint8)
    x0, y0 = np.array([0, 10, 55, 30]), np.array([0, 5, 35, 20])
    width, height = np.array([1, 7, 5, 12]), np.array([1, 9, 5, 3])
    diff_max, gray_max = window_maxima((diff, gray), x0, y0, width, height, unlit)
    for k in range(len(x0)):
        window = np.s_[y0[k]:y0[k] + height[k], x0[k]:x0[k] + width[k]]
        assert diff_max[k] == np.where(unlit[window] != 0, diff[window], np.float32(0)).max()
        assert gray_max[k] == gray[window].max()
    assert diff_max.dtype == np.float32 and gray_max.dtype == np.uint8

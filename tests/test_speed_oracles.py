"""Small hot-path rewrites (issue #7) give exactly what the plain code they replaced gave.

Why this file exists: each function below was rewritten to make fewer numpy calls per frame
(they run with the GIL held, so the two camera threads queue on them). The plain formulas are
kept here as the reference, and the fast ones must match them bit for bit: track outputs are
compared byte for byte before and after such a change.
"""

import math

import cv2
import numpy as np
import pytest

from badminton_gui.core.association import Tracklet, TrackletAssociator
from badminton_gui.core.background import median_float32
from badminton_gui.core.detect.measure import scaled_boxes
from badminton_gui.core.params import TrackerParams


@pytest.mark.parametrize("size", [1, 2, 3, 51, 52, 3071, 3072])
def test_median_float32_is_numpys_median(size):
    rng = np.random.default_rng(size)
    for trial in range(20):
        values = (rng.random(size) * rng.choice([0.5, 2.0, 300.0])).astype(np.float32)
        if trial % 3 == 0:
            values = np.round(values, 1)          # ties
        expected = float(np.median(values))
        got = median_float32(values.copy())
        assert got == expected and type(got) is float


def test_scaled_boxes_are_the_per_column_floor_and_ceil():
    rng = np.random.default_rng(3)
    rects = rng.integers(0, 500, (40, 4)).astype(float)
    for sx, sy in ((2.0, 2.0), (4.0, 4.0), (2048 / 1023, 1536 / 767), (1.0, 1.0)):
        bx, by, bw, bh = rects[:, 0], rects[:, 1], rects[:, 2], rects[:, 3]
        expected = np.stack([np.floor(bx * sx), np.floor(by * sy), np.ceil(bw * sx),
                             np.ceil(bh * sy)], axis=1).astype(np.int64)
        got = scaled_boxes(rects, sx, sy)
        assert got.dtype == np.int64 and np.array_equal(got, expected)
    assert scaled_boxes(np.zeros((0, 4)), 2.0, 2.0).shape == (0, 4)


def test_match_costs_are_the_per_tracklet_formulas():
    p = TrackerParams()
    assoc = TrackletAssociator(p.motion, p.association)
    rng = np.random.default_rng(7)
    for k in range(30):
        tr = Tracklet(k, *rng.random(2) * 2000, rng.random() * 0.05, 0.0, 0.0,
                      vx=rng.normal(0, 3000), vy=rng.normal(0, 3000), hits=int(rng.integers(1, 40)),
                      misses=int(rng.integers(0, 4)), velocity_known=bool(k % 3))
        assoc.tracklets.append(tr)
    t = 0.05
    positions = rng.random((12, 2)) * 2000
    # The plain code: one comprehension per quantity.
    preds = np.array([tr.predict(t) for tr in assoc.tracklets])
    gates = np.array([assoc.gate(tr, max(t - tr.t, 1e-3)) for tr in assoc.tracklets])
    d = np.hypot(preds[:, None, 0] - positions[None, :, 0], preds[:, None, 1] - positions[None, :, 1])
    cost = d / gates[:, None]
    cost = cost - 0.5 * np.minimum(np.array([tr.hits for tr in assoc.tracklets]), 20)[:, None] / 20
    got_d, got_gates, got_cost = assoc.match_costs(t, positions)
    assert np.array_equal(got_d, d) and np.array_equal(got_gates, gates)
    assert np.array_equal(got_cost, cost)
    assert not math.isnan(float(got_cost.sum()))


def test_make_candidate_builds_the_same_candidate():
    import dataclasses

    from badminton_gui.core.types import CANDIDATE_FIELDS, Candidate, make_candidate

    # A field added to Candidate must be added to the fast constructor too.
    assert CANDIDATE_FIELDS == tuple(f.name for f in dataclasses.fields(Candidate))
    for args, kwargs in (((1.5, 2.0, 30.0, 4.0, math.nan, 50.0, math.nan, 0.0, "length"), {}),
                         ((1.5, 2.0, 30.0, 4.0, 200.0, 50.0, 3.0, 0.7), {}),
                         ((1.5, 2.0, math.nan, math.nan, math.nan, math.nan, 0.0, 1.2, None),
                          {"predicted": True})):
        fast, plain = make_candidate(*args, **kwargs), Candidate(*args, **kwargs)
        assert type(fast) is Candidate and repr(fast) == repr(plain)
        assert dataclasses.replace(fast, x=3.0) == dataclasses.replace(plain, x=3.0) or math.isnan(plain.whiteness)
        with pytest.raises(dataclasses.FrozenInstanceError):
            fast.x = 0.0


def test_epipolar_median_kept_sorted_is_numpys_median_of_the_samples():
    """The tracker's running median of its epipolar samples (a sorted copy beside the deque)
    equals np.median of the deque after every sample: filling, full (the oldest leaves),
    ties, a NaN entering and leaving, and after a reset."""
    from badminton_gui.core.tracker import StereoTracker
    from badminton_gui.io.demo_scene import make_rig

    tracker = StereoTracker(make_rig("binocular", (1280, 720)), TrackerParams(), parallel=False)
    rng = np.random.default_rng(7)
    try:
        for phase in range(2):
            values = np.round(rng.gamma(2.0, 1.5, 1500), 2 if phase else 12)
            values[[10, 700]] = np.nan
            for k, v in enumerate(values.tolist()):
                tracker.gate.add_sample(v)
                expected = float(np.median(tracker.gate.samples()))
                got = tracker.gate.median()
                assert got == expected or (math.isnan(got) and math.isnan(expected)), k
            assert len(tracker.gate.samples()) == 600
            tracker.reset()
            assert not tracker.gate.samples() and not tracker.gate.learnt
    finally:
        tracker.close()


def _propagate_plain(state, k, duration, h_max=0.01):
    """The drag model's propagation as a plain loop (shot_filter._propagate before its steps
    were kept): the reference."""
    from badminton_gui.core.flight.shot_filter import _rk4, _step_size

    if duration == 0.0:
        return state
    sign = 1.0 if duration > 0 else -1.0
    remaining = abs(duration)
    s = state
    while remaining > 1e-12:
        h = min(_step_size(s[3], s[4], s[5], k, h_max), remaining)
        s = _rk4(*s, k, sign * h)
        remaining -= h
    return s


def test_propagate_with_kept_steps_is_the_plain_loop_bit_for_bit():
    """Repeated calls from the same states (longer, shorter, backwards, exactly a step, zero,
    tiny), more start states than the cache keeps, and NaN: the same tuples as the plain loop."""
    from badminton_gui.core.flight import shot_filter

    rng = np.random.default_rng(11)
    starts = [tuple(float(v) for v in np.concatenate([rng.uniform(-5, 5, 2), rng.uniform(0, 4, 1),
                                                      rng.uniform(-60, 60, 3)]))
              for _ in range(shot_filter._CHAINS_MAX + 6)]
    starts.append((0.0, 0.0, 1.0, float("nan"), 2.0, 3.0))
    starts.append((0.0, -0.0, 1.0, 0.0, -0.0, 0.0))
    checked = 0
    for rep in range(2):
        for n, state in enumerate(starts):
            k = float(rng.uniform(0.05, 0.6))
            if rep:
                k = 0.2   # the second pass revisits evicted and kept chains alike
            durations = list(rng.uniform(-0.4, 0.4, 6)) + [0.0, 1e-13, 0.01, -0.01, 0.02, 0.9]
            rng.shuffle(durations)
            for d in [float(x) for x in durations] + [0.1 * i / 8 for i in range(9)]:
                for h_max in (0.01, 0.025):
                    got = shot_filter._propagate(state, k, d, h_max)
                    want = _propagate_plain(state, k, d, h_max)
                    assert len(got) == 6
                    assert all((a == b and math.copysign(1, a) == math.copysign(1, b))
                               or (math.isnan(a) and math.isnan(b)) for a, b in zip(got, want)), (n, d)
                    checked += 1
    assert checked > 3000 and len(shot_filter._CHAINS) <= shot_filter._CHAINS_MAX


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_masked_and_of_floats_is_numpys_where(seed):
    """measure_blobs' blob excess: a masked AND of the float image with itself into zeros is
    np.where(grown mask > 0, excess, float32(0)) bit for bit, -inf padding and -0.0 included."""
    rng = np.random.default_rng(seed)
    excess = rng.normal(0, 30, (37, 23)).astype(np.float32)
    excess[rng.random(excess.shape) < 0.1] = -np.inf
    excess[rng.random(excess.shape) < 0.05] = -0.0
    inside = np.where(rng.random(excess.shape) < 0.2, 255, 0).astype(np.uint8)
    grown = cv2.dilate(inside, np.ones((3, 3), np.uint8))
    fast = np.zeros_like(excess)
    cv2.bitwise_and(excess, excess, dst=fast, mask=grown)
    plain = np.where(grown > 0, excess, np.float32(0))
    assert fast.dtype == plain.dtype
    assert np.array_equal(fast.view(np.uint32), plain.view(np.uint32))


@pytest.mark.parametrize("windowed", [False, True])
def test_two_camera_threads_track_exactly_as_one_thread(windowed):
    """``StereoTracker`` runs the cameras' image halves side by side and their measuring halves
    in turn (``CameraDetector.segment`` / ``candidates_from``); one-threaded it runs each whole
    camera in turn. The results must be the same to the bit, with windows or without (a whole
    frame in one camera beside a windowed one is the mixed case the split serves)."""
    import dataclasses

    from badminton_gui.core.tracker import StereoTracker
    from badminton_gui.io.demo_scene import DemoScene, make_rig

    params = TrackerParams()
    if windowed:
        params = dataclasses.replace(params, window=dataclasses.replace(
            params.window, enabled=True, full_every=4, min_quality=0.0))
    scene = DemoScene(seed=2, size=(1280, 720))
    frames = [scene.render(i) + (scene.time_of(i),) for i in range(20, 140)]
    outputs = []
    for parallel in (True, False):
        tracker = StereoTracker(make_rig("binocular", (1280, 720)), params, parallel=parallel)
        try:
            rows = []
            for left, right, t in frames:
                r = tracker.process(left, right, t, keep_masks=False)
                rows.append((r.point, r.measured_point, r.left.window, r.right.window,
                             r.left.candidates, r.right.candidates))
            outputs.append(rows)
        finally:
            tracker.close()
    assert repr(outputs[0]) == repr(outputs[1])
    if windowed:
        assert any(row[2] is not None for row in outputs[0])   # windows were used
        assert any(row[2] is None for row in outputs[0])
    assert sum(row[0] is not None for row in outputs[0]) > 60     # and the shuttle was tracked

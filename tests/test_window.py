"""Windowed tracking (core/window.py): where the window goes, how often the frame is whole, and
that a window covering the frame changes nothing."""

from __future__ import annotations

import copy
import math
import threading

import cv2
import numpy as np
import pytest

from badminton_gui.core import window as window_module
from badminton_gui.core.background import BackgroundModel
from badminton_gui.core.detect.segmentation import ModelGrey
from badminton_gui.core.detector import CameraDetector
from badminton_gui.core.params import TrackerParams
from badminton_gui.core.window import ALIGN, WindowTracker, crop_grey, followed_tracklet

from tests.test_detector import FPS, _scene


def _params(**overrides):
    p = TrackerParams().with_value("classifier.enabled", False).with_value("window.enabled", True)
    for k, v in overrides.items():
        p = p.with_value(k.replace("__", "."), v)
    return p


def _key(result):
    return [(c.x, c.y, c.length, c.short_side, c.whiteness, c.area, c.motion, c.score,
             c.rejected_by, c.predicted) for c in result.candidates]


@pytest.mark.parametrize("coarse", [False, True])
def test_a_window_covering_the_frame_changes_nothing(monkeypatch, coarse):
    """Oracle: every frame 'windowed' with the whole frame as its window gives the candidates,
    mask and detection of whole-frame processing, frame after frame (the model learns the same)."""
    frames, _ = _scene(60)
    extra = {"background__coarse_from_width": 640} if coarse else {}
    whole = CameraDetector(_params(window__enabled=False, **extra))
    windowed = CameraDetector(_params(**extra))
    h, w = frames[0].shape[:2]
    monkeypatch.setattr(WindowTracker, "_choose", lambda self, *a: (0, 0, w, h))
    n_windowed = 0
    for i, img in enumerate(frames):
        a = whole.process(img, i / FPS)
        before = windowed.window_tracker.windowed
        b = windowed.process(img, i / FPS)
        n_windowed += windowed.window_tracker.windowed - before
        assert _key(a) == _key(b), i
        assert np.array_equal(a.mask, b.mask), i
        assert (a.detection is None) == (b.detection is None)
    assert n_windowed == len(frames) - 1   # the first frame initialises the model, whole


@pytest.mark.parametrize("scale", [1.0, 0.5, 0.25])
def test_a_windows_grey_and_mask_are_the_whole_frames_pixels(scale):
    """Inside a window away from its edges the grey image, difference and mask are those of
    whole-frame processing (same model state before)."""
    frames, _ = _scene(12)
    p = _params()
    whole = BackgroundModel(p.background, p.binarize)
    det = CameraDetector(p)
    win = (128, 96, 416, 328)
    for i, img in enumerate(frames):
        g = ModelGrey()(img, scale)
        mx0, my0 = int(win[0] * scale), int(win[1] * scale)
        gw = crop_grey(img, scale, win)
        assert np.array_equal(gw, g[my0:my0 + gw.shape[0], mx0:mx0 + gw.shape[1]])
        # the second model starts each frame as the whole-frame one (it saw the whole frames)
        part = copy.deepcopy(whole)
        mask = whole.apply(g)
        if i == 0:
            continue
        before = part.average.copy()
        mw = part.apply_window(gw, mx0, my0)
        inner = (slice(2, -2), slice(2, -2))   # the dilation reads across the window's edge
        assert np.array_equal(mw[inner], mask[my0:my0 + gw.shape[0], mx0:mx0 + gw.shape[1]][inner])
        # identical model inside the window (it learnt the same), unchanged outside
        inside = (slice(my0 + 2, my0 + gw.shape[0] - 2), slice(mx0 + 2, mx0 + gw.shape[1] - 2))
        assert np.array_equal(part.average[inside], whole.average[inside])
        outside = np.ones(before.shape, bool)
        outside[my0:my0 + gw.shape[0], mx0:mx0 + gw.shape[1]] = False
        assert np.array_equal(part.average[outside], before[outside])


def _run(params, frames, truth):
    det = CameraDetector(params)
    log = []
    for i, (img, xy) in enumerate(zip(frames, truth)):
        t = i / FPS
        tr = followed_tracklet(det.associator)
        predicted = tr.predict(t) if tr is not None else None
        res = det.process(img, t, keep_mask=False)
        log.append((det.window_tracker.last_window, predicted, xy, res.detection))
    return det, log


def test_the_window_is_around_the_prediction_and_the_flying_dot():
    frames, truth = _scene(160)
    p = _params(window__full_every=8, window__max_fraction=0.125)
    det, log = _run(p, frames, truth)
    h, w = frames[0].shape[:2]
    windowed = [entry for entry in log if entry[0] is not None]
    assert len(windowed) >= 0.6 * len(log)
    for (x0, y0, x1, y1), predicted, (x, y), _ in windowed:
        assert (x1 - x0) * (y1 - y0) <= 0.125 * w * h + 4 * ALIGN * (x1 - x0 + y1 - y0)
        assert all(v % ALIGN == 0 for v in (x0, y0, x1, y1))
        px, py = min(max(predicted[0], 0), w - 1), min(max(predicted[1], 0), h - 1)   # may leave the frame
        assert x0 <= px < x1 and y0 <= py < y1
        # the dot itself, well inside (or the window reaches the frame's edge there)
        assert (x0 == 0 or x0 + 10 <= x) and (x1 == w or x < x1 - 10)
        assert (y0 == 0 or y0 + 10 <= y) and (y1 == h or y < y1 - 10)
    # and it still follows the dot as well as whole frames do
    _, whole = _run(p.with_value("window.enabled", False), frames, truth)
    good = [sum(1 for *_, (x, y), d in run[20:] if d is not None and math.hypot(d.x - x, d.y - y) <= 6)
            for run in (log, whole)]
    assert good[0] >= good[1] - 2


@pytest.mark.parametrize("full_every", [1, 2, 5, 8])
def test_a_whole_frame_every_full_every_frames(full_every):
    frames, truth = _scene(120)
    _, log = _run(_params(window__full_every=full_every), frames, truth)
    run = longest = 0
    for window, *_ in log:
        run = run + 1 if window is not None else 0
        longest = max(longest, run)
    assert longest <= full_every - 1
    if full_every > 1:
        assert longest == full_every - 1   # the dot is followed: the window is used up to the limit


def test_keep_whole_processes_the_whole_frame_while_it_is_set():
    """The stereo tracker sets ``keep_whole`` while it holds a landed shuttle for the camera:
    those frames are whole though the followed dot would be windowed, and the window comes
    back once it is cleared."""
    frames, truth = _scene(120)
    det = CameraDetector(_params(window__full_every=8))
    windows = []
    for i, img in enumerate(frames):
        det.keep_whole = 60 <= i < 80
        det.process(img, i / FPS, keep_mask=False)
        windows.append(det.window_tracker.last_window)
    assert all(w is None for w in windows[60:80])
    assert sum(w is not None for w in windows[40:60]) >= 15 and sum(w is not None for w in windows[90:]) >= 20


def test_never_windowed_when_off_or_not_following():
    frames, truth = _scene(60)
    _, log = _run(_params(window__enabled=False), frames, truth)
    assert all(window is None for window, *_ in log)
    # nothing followed: a blank scene never gets a window
    blank = [np.full_like(frames[0], 25) for _ in range(30)]
    _, log = _run(_params(), blank, [(0, 0)] * 30)
    assert all(window is None for window, *_ in log)


def test_the_window_is_clipped_to_its_largest_area():
    class Assoc:
        def gate(self, tr, dt):
            return 5000.0   # far larger than the frame

    class Tr:
        t = 0.0

        def predict(self, t):
            return 1000.0, 700.0

    win = window_module.window_around(Assoc(), Tr(), 1 / 120, 2048, 1536, 48.0, 1 / 8)
    x0, y0, x1, y1 = win
    assert (x1 - x0) * (y1 - y0) <= (math.sqrt(2048 * 1536 / 8) + 2 * ALIGN) ** 2
    assert x0 <= 1000 < x1 and y0 <= 700 < y1
    assert abs((x0 + x1) / 2 - 1000) <= ALIGN and abs((y0 + y1) / 2 - 700) <= ALIGN


@pytest.mark.parametrize("k", [1, 3, 7])
def test_catch_up_teaches_the_missed_pixels_what_the_missed_frames_would_have(k):
    """Pixels outside the windows for k frames, then a whole frame with ``catch_up``: the
    running average is where k + 1 whole frames would have left it (inside the window too)."""
    p = _params(background__compensate_gain=False)
    whole, part = BackgroundModel(p.background, p.binarize), BackgroundModel(p.background, p.binarize)
    g0 = np.full((96, 128), 40, np.uint8)
    g1 = np.full((96, 128), 48, np.uint8)   # brighter by less than diff_threshold: still
    for m in (whole, part):
        m.apply(g0)
    for _ in range(k + 1):
        whole.apply(g1)
    missed = np.full(g0.shape, 255, np.uint8)
    for _ in range(k):
        part.apply_window(g1[16:48, 32:80], 32, 16)
    missed[16:48, 32:80] = 0
    part.catch_up(missed, k)
    part.apply(g1)
    assert np.allclose(part.average, whole.average, atol=1e-3)
    # without it the pixels outside learn k times slower
    slow = BackgroundModel(p.background, p.binarize)
    slow.apply(g0)
    for _ in range(k):
        slow.apply_window(g1[16:48, 32:80], 32, 16)
    slow.apply(g1)
    assert not np.allclose(slow.average[0, 0], whole.average[0, 0], atol=1e-3)


@pytest.mark.parametrize("changed", [False, True])
@pytest.mark.parametrize("k", [1, 3, 7])
def test_catch_up_fades_a_ghost_outside_the_windows_as_whole_frames_do(k, changed):
    """A dark player stood long enough to be learnt, then left: the court where he stood is
    brighter than the average, foreground (a ghost), learning at α/10. Outside the windows for
    k frames, then a whole frame with ``catch_up``: the ghost has faded as far as on k + 1
    whole frames, not k + 1 times less (it would outlast the whole frames' masks by
    ``full_every`` × and merge with a shuttle landing beside it), also where the grey value
    changed since the last whole frame (the player moving about beside his ghost)."""
    p = _params(background__compensate_gain=False)
    whole, part = BackgroundModel(p.background, p.binarize), BackgroundModel(p.background, p.binarize)
    player = np.full((96, 128), 40, np.uint8)
    court = np.full((96, 128), 100, np.uint8)   # brighter by far more than diff_threshold
    for m in (whole, part):
        m.apply(player)
    for _ in range(k + 1):
        assert whole.apply(court)[0, 0] == 255    # the ghost stays foreground throughout
    missed = np.full(court.shape, 255, np.uint8)
    for _ in range(k):
        part.apply_window(court[16:48, 32:80], 32, 16)
    missed[16:48, 32:80] = 0
    part.catch_up(missed, k, np.full(court.shape, 255 if changed else 0, np.uint8))
    assert part.apply(court)[0, 0] == 255
    assert np.allclose(part.average, whole.average, atol=1e-3)


def test_catch_up_leaves_out_what_changed_between_the_whole_frames(monkeypatch):
    """A dark player reaches a spot outside the windows just as the next whole frame comes:
    the frames missed there showed the court, which the catch-up cannot know. Taking the whole
    frame's player as what the missed frames showed, the average there fell k + 1 times as far
    as on whole frames, and once the player moved on the court was foreground: a ghost of a
    place he touched on one frame (beside a moving player, pieces of it broke his blob). Pixels
    whose grey value changed since the last whole frame learn only from this frame; those that
    stayed put still catch up: the ghost where another player stood at the start fades as on
    whole frames."""
    court = np.full((192, 256, 3), 100, np.uint8)
    start = court.copy()
    start[:32, 64:96] = 86           # learnt at once: the court there is a ghost, fading
    player = court.copy()
    player[16:48, 16:48] = 40        # darker: learnt at α (never foreground)
    k = 7
    frames = [start] + [court] * 3 + [court] * k + [player] + [court] * 40
    windowed = range(5, 5 + k)       # frame counts (1-based) processed in a window
    window = (128, 96, 256, 192)     # away from the player and the ghost
    monkeypatch.setattr(WindowTracker, "_choose",
                        lambda self, *a: window if self.frames in windowed else None)
    # No shake tolerance: it erodes a ghost from its edge, pixel by pixel, which no catch-up
    # reproduces (the rate of a pixel there changes within the missed frames).
    p = _params(window__catch_up=True, background__compensate_gain=False,
                background__shake_tolerance=0)
    whole = CameraDetector(p.with_value("window.enabled", False))
    part = CameraDetector(p)
    ghost = []
    for i, img in enumerate(frames):
        a = whole.process(img, i / FPS)
        b = part.process(img, i / FPS)
        assert (part.window_tracker.last_window is not None) == (i + 1 in windowed), i
        if i + 1 not in windowed:
            assert np.array_equal(a.mask, b.mask), i
        ghost.append(bool(a.mask[:16, 32:48].any()))
    assert ghost[1] and not ghost[-1]                   # the ghost faded within the clip
    assert ghost.index(False, 1) > 5 + k                # ... after the windowed frames
    s = a.mask_scale
    assert not a.mask[int(16 * s):int(48 * s), int(16 * s):int(48 * s)].any()


def test_both_cameras_windowed_run_in_turn_else_side_by_side(monkeypatch):
    """When both cameras process this frame in a window the tracker runs them in turn on its own
    thread (windowed frames are mostly Python holding the GIL); when either takes a whole frame
    the right camera goes to the pool, side by side with the left."""
    from badminton_gui.core.detector import CameraDetector
    from badminton_gui.core.tracker import StereoTracker
    from badminton_gui.io.demo_scene import make_rig

    frame = np.zeros((720, 1280, 3), np.uint8)
    real_plan, real_segment = CameraDetector.plan_window, CameraDetector.segment
    threads: list[str] = []   # the thread each right-camera image half ran on

    def segment(self, *args, **kwargs):
        if self is tracker.right:
            threads.append(threading.current_thread().name)
        return real_segment(self, *args, **kwargs)

    monkeypatch.setattr(CameraDetector, "segment", segment)
    # (left windowed, right windowed) on this frame → side by side (the right on another thread)?
    for plans, side_by_side in (((False, False), True), ((True, False), True), ((False, True), True),
                                ((True, True), False)):
        def plan(self, frame_bgr, t, _plans=plans):
            real_plan(self, frame_bgr, t)
            return _plans[0] if self is tracker.left else _plans[1]
        monkeypatch.setattr(CameraDetector, "plan_window", plan)
        tracker = StereoTracker(make_rig("binocular", (1280, 720)))
        threads.clear()
        for i in range(2):
            tracker.process(frame, frame, i / 120)
        here = threading.current_thread().name
        assert len(threads) == 2, plans
        assert all((name != here) == side_by_side for name in threads), (plans, threads)
        tracker.close()


def test_staggered_cameras_never_take_a_scheduled_whole_frame_together():
    """``window.stagger``: both cameras follow the dot; their whole frames on the fixed clock
    fall half a period apart (never on the same pair while both follow), and a camera's
    windowed runs still never exceed ``full_every − 1`` frames."""
    frames, truth = _scene(120)
    full_every = 8
    p = _params(window__full_every=full_every, window__stagger=True)
    left, right = CameraDetector(p), CameraDetector(p)
    right.set_window_phase(0.5)
    modes = []
    for i, img in enumerate(frames):
        for det in (left, right):
            det.process(img, i / FPS)
        modes.append((left.window_tracker.last_window is not None, right.window_tracker.last_window is not None))
    following = [i for i, (a, b) in enumerate(modes) if i >= 30 and (a or b)]
    assert len(following) >= 60
    both_whole = [i for i in range(following[0], len(modes)) if not modes[i][0] and not modes[i][1]]
    assert both_whole == []
    for cam in (0, 1):
        run = longest = 0
        for m in modes:
            run = run + 1 if m[cam] else 0
            longest = max(longest, run)
        assert longest == full_every - 1
    # without the stagger the same two cameras take their whole frames together
    p = p.with_value("window.stagger", False)
    left, right = CameraDetector(p), CameraDetector(p)
    together = 0
    for i, img in enumerate(frames):
        for det in (left, right):
            det.process(img, i / FPS)
        together += i >= following[0] and left.window_tracker.last_window is None and right.window_tracker.last_window is None
    assert together >= 5


@pytest.mark.parametrize("flight_travel", [0.0, 100.0, 5000.0])
def test_a_window_only_around_a_tracklet_that_has_flown(flight_travel):
    """The window follows a flight: a followed tracklet that has not travelled
    ``association.flight_travel`` px (a held shuttle, clutter taken up after the shuttle was
    lost, a path just struck) keeps the frames whole, so the tracklets outside a window are
    not starved of their candidates (the lost shuttle's own ends after ``max_misses``
    windowed frames, and its history with it)."""
    frames, truth = _scene(120)
    det = CameraDetector(_params(window__full_every=8, association__flight_travel=flight_travel))
    travel_before = None   # the followed tracklet's travel when this frame's window was chosen
    windowed = 0
    for i, img in enumerate(frames):
        det.process(img, i / FPS, keep_mask=False)
        if det.window_tracker.last_window is not None:
            windowed += 1
            assert travel_before is not None and travel_before >= flight_travel, i
        followed = followed_tracklet(det.associator)
        travel_before = None if followed is None else followed.travel
    if flight_travel < 5000:
        assert windowed >= 0.6 * len(frames)   # the dot flies ~6 px a frame: windowed soon
    else:
        assert windowed == 0


def test_the_result_says_which_box_was_processed():
    """CameraResult.window is the window of a windowed frame (the views draw it) and None on a
    whole frame, so an empty mask outside it is not read as "nothing moved"."""
    frames, truth = _scene(60)
    det = CameraDetector(_params(window__full_every=4))
    seen = set()
    for i, img in enumerate(frames):
        res = det.process(img, i / FPS, keep_mask=True)
        assert res.window == det.window_tracker.last_window
        if res.window is not None:
            x0, y0, x1, y1 = res.window
            k = res.mask_scale
            outside = res.mask.copy()
            outside[int(y0 * k):int(y1 * k), int(x0 * k):int(x1 * k)] = 0
            assert not outside.any()
        seen.add(res.window is None)
    assert seen == {True, False}


def test_no_window_while_the_followed_tracklet_looks_poor():
    """``window.min_quality``: a frame is windowed only when the followed tracklet's running
    quality reaches it (a clutter track followed before the serve keeps the frames whole, so the
    serve is seen at once); 1.0 never windows, 0.0 windows as before."""
    frames, _ = _scene(120)
    qualities = []
    for min_quality in (0.0, 1.0):
        det = CameraDetector(_params(window__full_every=8, window__min_quality=min_quality))
        windowed = 0
        for i, img in enumerate(frames):
            det.process(img, i / FPS, keep_mask=False)
            windowed += det.window_tracker.last_window is not None
            tr = followed_tracklet(det.associator)
            if tr is not None and min_quality == 0.0:
                qualities.append(tr.quality)
        assert (windowed > 40) if min_quality == 0.0 else (windowed == 0)
    threshold = float(np.median(qualities))
    det = CameraDetector(_params(window__full_every=8, window__min_quality=threshold))
    seen = set()
    for i, img in enumerate(frames):
        tr = followed_tracklet(det.associator)
        before = None if tr is None else tr.quality
        det.process(img, i / FPS, keep_mask=False)
        if det.window_tracker.last_window is not None:
            assert before is not None and before >= threshold
        seen.add(det.window_tracker.last_window is not None)
    assert seen == {True, False}


def test_a_shuttle_merged_with_a_wide_blob_is_split_off_it_in_windows_too():
    """The merged-blob split (``contour_length.split_min_length``) works on windowed frames:
    the previous frame's window overlaps this one's around the followed shuttle, and there the
    brightened part of the long blob is the shuttle (coarse lost rally_11-48-00 left 483–492)."""
    from tests.test_detector import _flight_across_a_wide_blob

    frames, truth = _flight_across_a_wide_blob()
    found, split_in_window = [], 0
    for split in (0.0, 100.0):
        det = CameraDetector(_params(contour_length__split_min_length=split, window__full_every=100))
        hits = []
        for i, img in enumerate(frames):
            before = det.window_tracker.windowed
            res = det.process(img, i / FPS, keep_mask=False)
            if 30 <= i <= 40:
                d = res.detection
                hits.append(d is not None and math.hypot(d.x - truth[i][0], d.y - truth[i][1]) <= 6)
                if split and det.window_tracker.windowed > before and det.last_split:
                    split_in_window += 1
        found.append(hits)
    assert split_in_window >= 8
    assert all(found[1])
    assert sum(found[0]) < len(found[0]) // 2     # without the split it is lost in the blob


def _struck_beside_a_player(n=70, hit=40):
    """A dot flies right at 8 px a frame towards a player (a large, flickering blob: too large for
    a shuttle) and is struck beside him at frame ``hit``: it leaves up and back at 30 px a frame
    while the racket head (a dot of its own) goes on the old path, slower, into the player."""
    from tests.test_detector import _noisy_frame

    rng = np.random.default_rng(5)
    frames, shuttle = [], []
    for i in range(n):
        img = _noisy_frame(rng, 30, (480, 640))
        # The player: a large patch whose pixels change every frame, so it stays in the mask.
        img[200:400, 440:500] = rng.integers(40, 160, (200, 60, 1), dtype=np.uint8)
        if i <= hit:
            x, y = 100 + 8 * (i - 0), 240
        else:
            x, y = 100 + 8 * hit - 30 * (i - hit), 240 - 10 * (i - hit)
            racket = (100 + 8 * hit + 5 * (i - hit), 240 + (i - hit))
            if racket[0] < 440:
                cv2.circle(img, racket, 3, (235, 235, 235), -1)
        if x > 0:
            cv2.circle(img, (int(x), int(y)), 3, (245, 245, 245), -1)
        frames.append(img)
        shuttle.append((x, y))
    return frames, shuttle


@pytest.mark.parametrize("near_large", [0.0, 48.0])
def test_beside_a_player_the_frames_are_whole_so_the_struck_shuttle_is_seen_at_once(near_large):
    """``window.near_large``: while the followed shuttle is predicted near a blob too large for a
    shuttle on the last whole frame (a player, a racket), the frames are whole, so the shuttle
    struck there is a candidate on every frame after the hit, although the followed tracklet goes
    on with the racket; without it the window stays with the racket and the struck shuttle leaves
    it. Far from the player the window is used as before."""
    hit = 40
    frames, shuttle = _struck_beside_a_player(hit=hit)
    det = CameraDetector(_params(window__full_every=8, window__stagger=False,
                                 window__near_large=near_large))
    seen, windowed_far = [], 0
    for i, img in enumerate(frames):
        res = det.process(img, i / FPS, keep_mask=False)
        x, y = shuttle[i]
        if 15 <= i <= 30:   # far from the player (≥ 100 px)
            windowed_far += det.window_tracker.last_window is not None
        if hit < i <= hit + 8 and x > 20:
            seen.append(any(math.hypot(c.x - x, c.y - y) <= 8 for c in res.candidates))
    assert windowed_far >= 8
    if near_large > 0:
        assert all(seen), seen
    else:
        assert not all(seen)   # the window stayed with the racket: the struck shuttle missed

"""The per-camera detector and its multi-frame association, on small synthetic sequences.

A white dot flies a parabola over a dark, noisy background while a light flickers in place and
a bright blob lies still (a shuttle on the floor): the detector must follow the dot, and every
candidate it drops must say which filter dropped it.
"""

import dataclasses
import math

import numpy as np
import pytest

from badminton_gui.core.association import TrackletAssociator
from badminton_gui.core.classifier import load_classifier, train_ensemble, train_mlp
from badminton_gui.core.detector import (FEATURE_NAMES, PATCH_CELLS, PATCH_HALF, PATCH_NAMES, CameraDetector,
                                         patch_features)
from badminton_gui.core.params import TrackerParams
from badminton_gui.core.types import REJECT_REASONS

import cv2

FPS = 120.0


def _noisy_frame(rng, level, size=(360, 640)):
    """A flat grey frame with 0–5 grey levels of sensor noise."""
    img = np.full((*size, 3), level, np.uint8)
    return cv2.add(img, rng.integers(0, 6, img.shape, dtype=np.uint8))


def _scene(n=160, seed=0):
    rng = np.random.default_rng(seed)
    frames, truth = [], []
    for i in range(n):
        img = _noisy_frame(rng, 25, (480, 640))
        # A flickering light (static) and a bright blob lying still.
        level = 255 if i % 2 else 150
        cv2.circle(img, (80, 60), 6, (level, level, level), -1)
        cv2.circle(img, (560, 420), 4, (230, 230, 230), -1)
        t = i / FPS
        x = 100 + 300 * t
        y = 400 - 600 * t + 500 * t * t
        cv2.circle(img, (int(round(x)), int(round(y))), 3, (235, 235, 235), -1)
        frames.append(img)
        truth.append((x, y))
    return frames, truth


def _params(**overrides):
    p = TrackerParams().with_value("classifier.enabled", False)
    for k, v in overrides.items():
        p = p.with_value(k.replace("__", "."), v)
    return p


def test_follows_the_flying_dot_not_the_clutter():
    frames, truth = _scene()
    det = CameraDetector(_params())
    hits = wrong = 0
    for i, (img, (x, y)) in enumerate(zip(frames, truth)):
        res = det.process(img, i / FPS, keep_mask=False)
        if i < 20:
            continue  # background warm-up and confirmation
        d = res.detection
        if d is None:
            continue
        if math.hypot(d.x - x, d.y - y) <= 6:
            hits += 1
        else:
            wrong += 1
    assert wrong == 0
    assert hits >= 0.9 * (len(frames) - 20)


def test_every_dropped_candidate_names_its_filter():
    frames, _ = _scene(60)
    det = CameraDetector(_params())
    for i, img in enumerate(frames):
        res = det.process(img, i / FPS, keep_mask=False)
    assert res.candidates
    accepted = [c for c in res.candidates if c.rejected_by is None]
    assert len(accepted) <= 1 and (res.detection is None or accepted == [res.detection])
    assert all(c.rejected_by in REJECT_REASONS for c in res.candidates if c.rejected_by)
    # The flickering light never travels: the association (filter 4) rejects it.
    light = [c for c in res.candidates if math.hypot(c.x - 80, c.y - 60) < 12]
    assert light and all(c.rejected_by is not None for c in light)


def test_stationary_blob_is_never_the_detection():
    frames, _ = _scene(120)
    det = CameraDetector(_params())
    for i, img in enumerate(frames):
        d = det.process(img, i / FPS, keep_mask=False).detection
        assert d is None or math.hypot(d.x - 560, d.y - 420) > 10


def test_association_speed_aware_gate_keeps_a_fast_track():
    p = TrackerParams()
    assoc = TrackletAssociator(p.motion, p.association)
    # 40 px per frame at 120 fps (4800 px/s), plus a static distractor.
    for i in range(12):
        pos = np.array([[100.0 + 40 * i, 300.0], [500.0, 100.0]])
        out = assoc.update(i / FPS, pos, np.array([0.9, 0.9]))
    ident_fast, _, merit_fast = out[0]
    _, _, merit_static = out[1]
    assert merit_fast >= 0 and merit_static < 0
    track = next(t for t in assoc.tracklets if t.ident == ident_fast)
    assert track.hits == 12


def test_followed_tracklet_loses_its_hysteresis_on_a_blob_that_does_not_look_like_a_shuttle():
    """After a racket contact the followed tracklet goes on with the racket, whose running
    quality still remembers the shuttle: its hysteresis holds only while this frame's candidate
    scores at least ``association.hysteresis_min_quality`` (0 = always, the old behaviour)."""
    for gate in (0.1, 0.0):
        # (this frame's own quality term off: the merit compared is the tracklet's alone)
        p = (TrackerParams().with_value("association.hysteresis_min_quality", gate)
             .with_value("association.candidate_weight", 0.0))
        assoc = TrackletAssociator(p.motion, p.association)
        for i in range(12):
            out = assoc.update(i / FPS, np.array([[100.0 + 10 * i, 300.0]]), np.array([0.9]))
        assoc.select(out[0][0])
        # The same tracklet, this frame on a blob that scores 0.02 (a racket's frame).
        ident, _, merit = assoc.update(12 / FPS, np.array([[220.0, 300.0]]), np.array([0.02]))[0]
        track = next(t for t in assoc.tracklets if t.ident == ident)
        without = assoc.merit(track, 0.02)
        with_bonus = assoc.merit(track, 0.9)
        assert merit == pytest.approx(without)
        if gate > 0:
            assert with_bonus == pytest.approx(without + p.association.hysteresis)
        else:
            assert with_bonus == pytest.approx(without)


def test_a_path_break_forgets_the_old_residual():
    """A tracklet that jitters (clutter) and is then taken over by a smooth flight: after the
    break (a step beyond ``association.jump_residual``) its residual starts afresh, unless
    ``jump_resets_residual`` is off."""
    for reset in (True, False):
        p = TrackerParams().with_value("association.jump_resets_residual", reset)
        assoc = TrackletAssociator(p.motion, p.association)
        rng = np.random.default_rng(1)
        for i in range(20):     # clutter jittering by ±12 px around (300, 300)
            out = assoc.update(i / FPS, np.array([[300.0, 300.0] + rng.uniform(-12, 12, 2)]), np.array([0.2]))
        ident = out[0][0]
        jittery = next(t for t in assoc.tracklets if t.ident == ident).residual
        assert jittery > 3.0
        # The shuttle leaves from there: 40 px away, then 12 px a frame in a straight line.
        for k in range(4):
            out = assoc.update((20 + k) / FPS, np.array([[340.0 + 12 * k, 300.0]]), np.array([0.9]))
        track = next(t for t in assoc.tracklets if t.ident == out[0][0])
        assert track.ident == ident
        if reset:
            assert track.residual < 0.5 * jittery
        else:
            assert track.residual > 0.5 * jittery


@pytest.mark.parametrize("model", ["candidate_classifier", "candidate_classifier_broadcast",
                                   "candidate_classifier_coarse"])
def test_shipped_classifiers_load_and_score_in_unit_interval(model):
    clf = load_classifier(model)
    # Each file names the features it was trained on: the hand-made ones, then the patch.
    assert clf.feature_names in (FEATURE_NAMES, FEATURE_NAMES + PATCH_NAMES)
    assert clf.mean.shape == (len(clf.feature_names),)
    p = clf.probability(np.tile(clf.mean, (3, 1)))
    assert np.all((p >= 0) & (p <= 1))


def test_mlp_training_separates_a_simple_rule(tmp_path):
    rng = np.random.default_rng(1)
    x = rng.normal(size=(2000, 3))
    y = x[:, 0] + 0.5 * x[:, 1] > 0.3
    clf = train_mlp(x, y, hidden=8, epochs=200)
    assert np.mean((clf.probability(x) > 0.5) == y) > 0.95
    clf.save(tmp_path / "m.json")
    again = load_classifier(str(tmp_path / "m.json"))
    assert np.allclose(again.probability(x[:5]), clf.probability(x[:5]))


def test_ensemble_is_the_mean_of_its_members_logits():
    rng = np.random.default_rng(2)
    x = rng.normal(size=(800, 4))
    y = x[:, 0] - x[:, 2] > 0.0
    ens = train_ensemble(x, y, members=3, hidden=6, epochs=60, seed=4)
    members = [train_mlp(x, y, hidden=6, epochs=60, seed=4000 + k) for k in range(3)]
    logit = np.mean([np.log(m.probability(x) / (1 - m.probability(x))) for m in members], axis=0)
    assert ens.weights[0].shape == (4, 18)
    assert np.allclose(ens.probability(x), 1 / (1 + np.exp(-logit)), atol=1e-9)


def test_patch_features_are_the_area_averaged_luma_around_the_point():
    rng = np.random.default_rng(5)
    frame = rng.integers(0, 256, (720, 1280, 3), dtype=np.uint8)
    x, y = 400.4, 300.6
    got = patch_features(frame, np.array([x]), np.array([y]))[0]
    # The reference, plainly: the 16 × 16 px square's luma (0.299 R + 0.587 G + 0.114 B), the
    # mean of each 2 × 2 block, normalised by the median cell and the peak above it.
    xi, yi = round(x), round(y)
    crop = frame[yi - PATCH_HALF:yi + PATCH_HALF, xi - PATCH_HALF:xi + PATCH_HALF].astype(float)
    luma = crop @ [0.114, 0.587, 0.299]
    cells = luma.reshape(PATCH_CELLS, 2, PATCH_CELLS, 2).mean(axis=(1, 3)).ravel()
    ref = (cells - np.median(cells)) / max(cells.max() - np.median(cells), 8.0)
    assert got.shape == (len(PATCH_NAMES),)
    assert np.abs(got - ref).max() < 1e-4


def test_patch_features_tell_a_spot_from_a_line_and_survive_the_border():
    frame = np.full((720, 1280, 3), 40, np.uint8)
    cv2.circle(frame, (300, 300), 3, (255, 255, 255), -1)
    cv2.line(frame, (600, 200), (600, 400), (255, 255, 255), 3)
    cv2.circle(frame, (2, 3), 3, (255, 255, 255), -1)
    spot, line, corner, flat = patch_features(frame, np.array([300.0, 600.0, 2.0, 900.0]),
                                              np.array([300.0, 300.0, 3.0, 600.0]))
    grid = spot.reshape(PATCH_CELLS, PATCH_CELLS)
    assert grid[3:5, 3:5].min() > 0.5 and grid[0].max() < 0.05 and grid[:, 0].max() < 0.05
    column = line.reshape(PATCH_CELLS, PATCH_CELLS)[:, 3:5]
    assert column.min() > 0.3                    # bright from the top of the patch to its bottom
    assert np.isfinite(corner).all() and corner.max() == pytest.approx(1.0)
    assert np.allclose(flat, 0.0)                # nothing brighter: no shape invented
    # The square scales with the frame: at 2560 px width it spans twice the pixels.
    big = cv2.resize(frame, (2560, 1440), interpolation=cv2.INTER_NEAREST)
    assert np.abs(patch_features(big, np.array([600.0]), np.array([600.0]))[0] - spot).max() < 0.1


def test_a_classifier_trained_with_patches_reads_them():
    """The detector appends each blob's patch to its features only for a classifier that was
    trained on them (every shipped classifier is one), in PATCH_NAMES order."""
    frames, _ = _scene(12)

    class Spy:
        def __init__(self, names):
            self.name, self.feature_names, self.seen = "spy", names, []

        def probability(self, features):
            self.seen.append(np.array(features))
            return np.full(len(features), 0.9)

    for names in (FEATURE_NAMES, FEATURE_NAMES + PATCH_NAMES):
        det = CameraDetector(_params())
        spy = Spy(names)
        det.use_classifier(spy)   # as train_classifier.py --leave-one-out does
        for i, img in enumerate(frames):
            det.process(img, i / FPS)
        seen = spy.seen[-1]
        assert np.array_equal(det.last_scored[1], seen)   # what adaptation reads: the rows scored
        assert seen.shape[1] == len(names)
        if len(names) > len(FEATURE_NAMES):
            xs = np.array([f[0] for f in det.last_features])
            ys = np.array([f[1] for f in det.last_features])
            assert np.allclose(seen[:, len(FEATURE_NAMES):], patch_features(frames[-1], xs, ys))
    # Every shipped model reads the patch (the coarse one too); a model without it (the Spy
    # above) is still served the hand-made features alone.
    for model in ("candidate_classifier", "candidate_classifier_broadcast", "candidate_classifier_coarse"):
        assert load_classifier(model).feature_names == FEATURE_NAMES + PATCH_NAMES
        det = CameraDetector(_params(classifier__enabled=True, classifier__model=model))
        for i, img in enumerate(frames):
            det.process(img, i / FPS)
        assert len(det.last_features) and det.last_scored[1].shape[1] == len(FEATURE_NAMES + PATCH_NAMES)


@pytest.mark.parametrize("method", ["mog2", "frame_diff", "bright_diff"])
def test_every_background_method_runs(method):
    frames, _ = _scene(30)
    det = CameraDetector(_params(background__method=method))
    for i, img in enumerate(frames):
        res = det.process(img, i / FPS)
    assert res.mask is not None and res.mask.dtype == np.uint8


def _bar_scene(n=90):
    """A dot flies left to right across a static white bar (a light, a court line)."""
    rng = np.random.default_rng(1)
    frames, truth = [], []
    for i in range(n):
        img = _noisy_frame(rng, 25, (360, 640))
        cv2.rectangle(img, (300, 0), (339, 359), (250, 250, 250), -1)
        x = 60 + 6.0 * i
        y = 180.0
        if not 296 <= x <= 343:   # white on white: nothing of the dot shows on the bar
            cv2.circle(img, (int(round(x)), int(round(y))), 3, (235, 235, 235), -1)
        frames.append(img)
        truth.append((x, y))
    return frames, truth


@pytest.mark.parametrize("coast", [0, 10])
def test_track_coasts_through_a_blind_spot_and_only_there(coast):
    frames, truth = _bar_scene()
    det = CameraDetector(_params(motion__coast_blind=coast))
    predicted, misses_on_bar = [], 0
    for i, (img, (x, y)) in enumerate(zip(frames, truth)):
        d = det.process(img, i / FPS, keep_mask=False).detection
        on_bar = 296 <= x <= 343
        if d is not None and d.predicted:
            predicted.append(i)
            assert on_bar, f"frame {i}: a prediction away from the blind spot"
            # Carried on the last velocity, measured as the dot entered the bar.
            assert math.hypot(d.x - x, d.y - y) <= 10.0
        if on_bar and (d is None or not d.predicted):
            misses_on_bar += 1
    if coast:
        assert len(predicted) >= 6 and misses_on_bar <= 2
    else:
        assert not predicted


def test_head_position_is_not_pulled_towards_a_nearby_light():
    # A small bright blob next to a large, brighter static light: the measured position must
    # stay on the blob (it used to be dragged 6–7 px towards the light once the light was
    # inside the measuring window, 8 px away).
    rng = np.random.default_rng(2)
    det = CameraDetector(_params(colour__head_lead=0.0))   # the measured centroid itself
    errors = []
    for i in range(62):
        img = _noisy_frame(rng, 40, (360, 640))
        cv2.rectangle(img, (330, 150), (380, 190), (252, 252, 252), -1)
        x, y = 200 + 2.0 * i, 160.0 + 0.5 * i
        cv2.circle(img, (int(round(x)), int(round(y))), 2, (200, 200, 200), -1)
        res = det.process(img, i / FPS, keep_mask=False)
        for c in res.candidates:
            if math.isfinite(c.whiteness) and math.hypot(c.x - x, c.y - y) < 20 and 300 <= x <= 322:
                errors.append(math.hypot(c.x - round(x), c.y - round(y)))
    assert errors and max(errors) <= 1.0, errors


def _shuttle_flight(n=70):
    """A cork (small, brightest) with a dimmer skirt trailing behind it, flying right and down."""
    rng = np.random.default_rng(4)
    frames, corks = [], []
    for i in range(n):
        img = _noisy_frame(rng, 30, (360, 640))
        x, y = 80.0 + 7.0 * i, 60.0 + 3.0 * i
        direction = np.array([7.0, 3.0]) / math.hypot(7.0, 3.0)
        skirt = (x - 5 * direction[0], y - 5 * direction[1])
        angle = math.degrees(math.atan2(direction[1], direction[0]))
        cv2.ellipse(img, (int(round(skirt[0])), int(round(skirt[1]))), (6, 3), angle, 0, 360,
                    (205, 205, 205), -1)
        cv2.circle(img, (int(round(x)), int(round(y))), 2, (250, 250, 250), -1)
        frames.append(img)
        corks.append((round(x), round(y)))
    return frames, corks


def test_a_moving_detection_is_led_forward_to_the_cork():
    frames, corks = _shuttle_flight()
    runs = {}
    for lead in (0.0, 0.5):
        det = CameraDetector(_params(colour__head_lead=lead))
        rows = []
        for i, img in enumerate(frames):
            res = det.process(img, i / FPS, keep_mask=False)
            d = res.detection
            rows.append(None if d is None else (d.x, d.y))
            # The moved detection is the one in the candidate list, and still the accepted one.
            assert d is None or sum(c is d for c in res.candidates) == 1
        runs[lead] = rows
    # The lead changes what is reported, never what is tracked: same frames detected.
    assert [r is None for r in runs[0.0]] == [r is None for r in runs[0.5]]
    errors = {lead: [math.hypot(r[0] - cx, r[1] - cy) for r, (cx, cy) in zip(rows, corks)
                     if r is not None] for lead, rows in runs.items()}
    assert len(errors[0.0]) >= 40
    # The bright centroid trails the cork; the led position is on it.
    assert np.median(errors[0.0]) >= 2.0
    assert np.median(errors[0.5]) <= 0.5 * np.median(errors[0.0])


def test_a_cork_led_out_of_the_image_is_not_reported():
    """Leaving the image, the skirt still shows at the border after the cork has gone: the
    detection whose led position falls outside the frame is dropped, never reported outside."""
    frames, corks = _shuttle_flight(n=86)      # x = 80 + 7 i: the cork leaves at i ≈ 80
    runs = {}
    for lead in (0.0, 0.5):
        det = CameraDetector(_params(colour__head_lead=lead))
        runs[lead] = [det.process(img, i / FPS, keep_mask=False).detection for i, img in enumerate(frames)]
    for d in runs[0.5]:
        assert d is None or (-0.5 <= d.x < 639.5 and -0.5 <= d.y < 359.5)
    dropped = [i for i, (a, b) in enumerate(zip(runs[0.0], runs[0.5])) if a is not None and b is None]
    assert dropped and all(corks[i][0] >= 630 for i in dropped)


def test_a_shuttle_merged_with_a_wider_blob_is_led_by_its_own_width():
    """A shuttle crossing a racket or an arm merges with it into a much wider blob whose
    brightest part is still the shuttle: the lead (half the shuttle's width) must not grow with
    the merged blob's width (``colour.head_lead_width_frames``)."""
    frames, corks = _shuttle_flight()
    merged = range(40, 44)       # shorter than the 5 frames remembered
    for i in merged:
        # A dull grey patch (below half the cork's contrast: outside the measured bright part)
        # touching the shuttle from below, moving with it.
        x, y = corks[i]
        cv2.rectangle(frames[i], (x - 16, y + 3), (x + 6, y + 26), (110, 110, 110), -1)
    errors = {}
    for frames_kept in (1, 5):
        det = CameraDetector(_params(colour__head_lead_width_frames=frames_kept))
        errs = []
        for i, img in enumerate(frames):
            d = det.process(img, i / FPS, keep_mask=False).detection
            if i in merged:
                assert d is not None
                errs.append(math.hypot(d.x - corks[i][0], d.y - corks[i][1]))
        errors[frames_kept] = errs
    assert max(errors[1]) >= 6.0, errors          # led by the merged blob's width: past the cork
    assert max(errors[5]) <= 3.0, errors          # led by the shuttle's own recent width


def _followed_along_a_row(p, score):
    """An associator whose selected tracklet has followed a blob of classifier ``score`` 10 px a
    frame along y = 300 for 12 frames (x 100 … 210): (associator, the tracklet's ident)."""
    assoc = TrackletAssociator(p.motion, p.association)
    for i in range(12):
        out = assoc.update(i / FPS, np.array([[100.0 + 10 * i, 300.0]]), np.array([score]))
    followed = out[0][0]
    assoc.select(followed)
    return assoc, followed


def test_followed_tracklet_takes_the_shuttle_like_blob_over_a_nearer_racket():
    """After a hit the racket (or the hand) is the blob nearest the followed path and the
    shuttle leaves 20 px off it: with ``association.followed_swap_margin`` the followed tracklet
    takes the blob that scores far higher; 1 (off) keeps the nearest."""
    for margin in (1.0, 0.6):
        p = TrackerParams().with_value("association.followed_swap_margin", margin)
        assoc, followed = _followed_along_a_row(p, score=0.9)
        racket, shuttle = assoc.update(12 / FPS, np.array([[220.0, 302.0], [214.0, 281.0]]),
                                       np.array([0.1, 0.95]))
        if margin < 1.0:
            assert shuttle[0] == followed and shuttle[2] >= 0 and racket[0] != followed
        else:
            assert racket[0] == followed and shuttle[0] != followed and shuttle[2] < 0


def test_a_path_break_of_the_followed_shuttle_keeps_its_start():
    """The followed shuttle struck back by the racket: the step leaves the predicted path
    (``jump_residual``), and with ``association.jump_anchor_quality`` the new path's travel
    counts from the contact, so a slow return flight is moving at once; without it, the travel
    starts afresh and the tracklet waits for ``min_travel`` px."""
    merits = {}
    for anchor in (1.0, 0.8):
        p = TrackerParams().with_value("association.jump_anchor_quality", anchor)
        assoc = TrackletAssociator(p.motion, p.association)
        for i in range(12):
            out = assoc.update(i / FPS, np.array([[100.0 + 10 * i, 300.0]]), np.array([0.9]))
        assoc.select(out[0][0])
        rows = []
        for k in range(4):    # back up-left from the contact, 40 px off the path, then 3 px a frame
            pos = np.array([[200.0 - 3 * k, 262.0 - 3 * k]])
            rows.append(assoc.update((12 + k) / FPS, pos, np.array([0.95]))[0])
        assert all(r[0] == out[0][0] for r in rows)        # the same (followed) tracklet throughout
        merits[anchor] = [r[2] for r in rows]
    assert all(m >= 0 for m in merits[0.8]), merits
    assert any(m < 0 for m in merits[1.0]), merits


def test_followed_tracklet_sliding_over_clutter_does_not_swap():
    """A followed tracklet whose running quality is already low (sliding over clutter after the
    shuttle left the view) does not jump onto a shuttle-like blob nearby
    (``association.followed_swap_track_quality``)."""
    for min_quality in (0.0, 0.5):
        p = (TrackerParams().with_value("association.followed_swap_margin", 0.6)
             .with_value("association.followed_swap_track_quality", min_quality))
        assoc, followed = _followed_along_a_row(p, score=0.3)
        near, bright = assoc.update(12 / FPS, np.array([[220.0, 302.0], [214.0, 281.0]]),
                                    np.array([0.05, 0.95]))
        assert (bright[0] == followed) == (min_quality == 0.0)
        assert (near[0] == followed) == (min_quality > 0.0)


@pytest.mark.parametrize("blind_gate", [0.0, 30.0])
def test_in_a_blind_spot_the_followed_track_coasts_rather_than_take_a_far_blob(blind_gate):
    """``association.blind_gate``: the followed track predicted where the detector is blind
    takes only a blob within the gate of its prediction (a hand 45 px away, inside its usual
    gate, would take it over) and coasts instead; outside a blind spot the usual gate holds.
    (The hand scores below ``min_track_quality``, as on the demo court: a shuttle-like blob
    near the lost track would still inherit its history, ``rebirth_radius``.)"""
    p = TrackerParams()
    a = TrackletAssociator(p.motion, dataclasses.replace(p.association, blind_gate=blind_gate))
    for i in range(10):
        (ident, _, merit), = a.update(i / FPS, np.array([[100.0 + 3 * i, 200.0]]), np.array([0.9]))
    assert merit >= 0
    a.select(ident)
    t = 10 / FPS
    hand = np.array([[130.0, 245.0]])                       # 45 px below the prediction (130, 200)
    (hit, _, _), = a.update(t, hand, np.array([0.1]), blind=lambda x, y: True)
    if blind_gate:
        assert hit != ident
        assert a.coasting(t, lambda x, y: True)[0].ident == ident
    else:
        assert hit == ident
    b = TrackletAssociator(p.motion, a.params)
    for i in range(10):
        (ident_b, _, _), = b.update(i / FPS, np.array([[100.0 + 3 * i, 200.0]]), np.array([0.9]))
    b.select(ident_b)
    (hit_b, _, _), = b.update(t, hand, np.array([0.1]), blind=lambda x, y: False)
    assert hit_b == ident_b


def test_a_shuttle_clipped_by_the_edge_it_leaves_is_not_reported():
    """Leaving the image, the visible part of a clipped shuttle keeps its bright centroid inside
    the frame after the cork has gone: a detection near the edge its track moves towards, whose
    blob lost a good part of its usual area, is dropped (``colour.edge_exit``)."""
    frames, corks = _shuttle_flight(n=86)      # x = 80 + 7 i: the cork leaves at i ≈ 80
    runs = {}
    for edge_exit in (0.0, 12.0):
        det = CameraDetector(_params(colour__head_lead=0.0, colour__edge_exit=edge_exit))
        runs[edge_exit] = [det.process(img, i / FPS, keep_mask=False).detection for i, img in enumerate(frames)]
    # (a cork half a pixel out, with most of the shuttle in view, may still be reported)
    outside = [i for i, d in enumerate(runs[0.0]) if d is not None and corks[i][0] > 642]
    assert outside                                   # without it: reported while the cork is out
    for i, d in enumerate(runs[12.0]):
        assert d is None or corks[i][0] <= 642
    # Only the frames at the edge change.
    changed = [i for i, (a, b) in enumerate(zip(runs[0.0], runs[12.0])) if (a is None) != (b is None)]
    assert changed and all(corks[i][0] >= 625 for i in changed)


def test_leaving_edge_needs_the_motion_towards_that_edge():
    from badminton_gui.core.detector import _leaving_edge
    assert _leaving_edge(1.0, 100.0, (-50.0, 0.0), 640, 360, 2.0)
    assert not _leaving_edge(1.0, 100.0, (50.0, 0.0), 640, 360, 2.0)      # coming in
    assert not _leaving_edge(5.0, 100.0, (-50.0, 0.0), 640, 360, 2.0)     # not near it
    assert _leaving_edge(300.0, 358.0, (0.0, 20.0), 640, 360, 2.0)        # the bottom edge
    assert _leaving_edge(638.0, 100.0, (10.0, 0.0), 640, 360, 2.0)        # the right edge


def _small_dot_flight(n=60, small=range(30, 34)):
    """A dot flying right; in the ``small`` frames it shrinks to 2 × 2 px (a far, edge-on
    shuttle: a 3 × 3 blob of the half-scale mask, shorter than the contour-length minimum).
    A static 2 × 2 dot far from the path is there in those frames too."""
    rng = np.random.default_rng(7)
    frames, truth = [], []
    for i in range(n):
        img = _noisy_frame(rng, 30, (360, 640))
        x, y = 60.0 + 8.0 * i, 180.0
        xi, yi = int(round(x)), int(round(y))
        if i in small:
            img[yi:yi + 2, xi:xi + 2] = 240
            img[300:302, 100:102] = 240
        else:
            cv2.circle(img, (xi, yi), 3, (240, 240, 240), -1)
        frames.append(img)
        truth.append((xi + 0.5 if i in small else xi, yi + 0.5 if i in small else yi))
    return frames, truth


def test_a_short_blob_passes_filter_1_only_where_the_followed_shuttle_is_predicted():
    frames, truth = _small_dot_flight()
    small = range(30, 34)
    found = {}
    for guided in (0.0, 14.0):
        det = CameraDetector(_params(contour_length__guided_min_length=guided))
        hits = []
        for i, img in enumerate(frames):
            res = det.process(img, i / FPS, keep_mask=False)
            if i in small:
                d = res.detection
                hits.append(d is not None and math.hypot(d.x - truth[i][0], d.y - truth[i][1]) <= 3)
                # The static dot far from the path stays rejected by filter 1.
                far = [c for c in res.candidates if math.hypot(c.x - 100.5, c.y - 300.5) <= 3]
                assert far and all(c.rejected_by == "length" for c in far)
        found[guided] = hits
    assert not any(found[0.0])
    assert all(found[14.0])


def _flight_across_a_wide_blob(n=50):
    """A dot flying right at 8 px a frame crosses a wide grey patch that appeared just before
    (in the mask, too wide for filter 2: the shuttle merges with it, as with an arm or a racket
    head, frames ~29–41)."""
    rng = np.random.default_rng(11)
    frames, truth = [], []
    for i in range(n):
        img = _noisy_frame(rng, 30, (360, 640))
        if i >= 20:
            x0 = 290 + (i - 20)      # creeping: it stays in the mask
            cv2.rectangle(img, (x0, 168), (x0 + 70, 200), (150, 150, 150), -1)
        x, y = 60 + 8 * i, 180
        cv2.circle(img, (x, y), 3, (250, 250, 250), -1)
        frames.append(img)
        truth.append((x, y))
    return frames, truth


@pytest.mark.parametrize("split", [0.0, 100.0])
def test_a_shuttle_merged_with_a_wide_blob_is_split_off_it(split):
    """The part of a long blob that brightened since the previous frame, near the followed
    shuttle's prediction, is a candidate of its own (``contour_length.split_min_length``)."""
    frames, truth = _flight_across_a_wide_blob()
    det = CameraDetector(_params(contour_length__split_min_length=split))
    merged = range(30, 41)
    found = []
    for i, img in enumerate(frames):
        res = det.process(img, i / FPS, keep_mask=False)
        if i in merged:
            d = res.detection
            found.append(d is not None and math.hypot(d.x - truth[i][0], d.y - truth[i][1]) <= 6)
            assert (det.last_split > 0) == (split > 0)
    if split > 0:
        assert all(found)
    else:
        assert not any(found)      # lost inside the merged blob


def test_the_split_length_follows_the_width_not_the_shuttles_scale():
    """``contour_length.split_min_length`` is the size of what the shuttle merges with (a racket,
    an arm, a mark on the floor), px at 1280 px width: with the gates from geometry it stays
    scaled with the width where the camera sees the shuttle small (filters 1 and 2 shrink)."""
    frames, _truth = _flight_across_a_wide_blob()
    splits = {}
    for enabled in (False, True):
        for split in (100.0, 500.0):     # 50 / 250 px at 640 px width; the merged blob is ~210 px
            params = (_params().with_value("shuttle_scale.enabled", enabled)
                      .with_value("shuttle_scale.farthest", 42.0)
                      .with_value("contour_length.split_min_length", split))
            det = CameraDetector(params)
            if enabled:
                p = params.shuttle_scale
                factor = det.scale_map(640, 360).gate_scale(p.reference_scale).at([320.0], [180.0])[0]
                assert factor < 0.4      # the geometric factor would have split at 500
            n = 0
            for i, img in enumerate(frames):
                det.process(img, i / FPS, keep_mask=False)
                n += det.last_split
            splits[enabled, split] = n
    assert splits[False, 100.0] > 0 and splits[True, 100.0] > 0
    assert splits[False, 500.0] == splits[True, 500.0] == 0


@pytest.mark.parametrize("max_misses", [0, 50])
def test_no_split_around_a_track_that_lost_its_blob(max_misses):
    """A track whose blob has been missing for frames (the shuttle hidden behind a player) has a
    grown gate, in which a player's brightening hand or racket would be split off and taken for
    it: the split waits for a track seen in the previous frame (``split_max_misses``)."""
    frames, truth = _flight_across_a_wide_blob()
    hidden = range(26, 30)       # the dot is not drawn just before it reaches the patch
    rng = np.random.default_rng(11)
    for i in hidden:
        img = _noisy_frame(rng, 30, (360, 640))
        x0 = 290 + (i - 20)
        cv2.rectangle(img, (x0, 168), (x0 + 70, 200), (150, 150, 150), -1)
        frames[i] = img
    det = CameraDetector(_params(contour_length__split_min_length=100.0,
                                 contour_length__split_max_misses=max_misses))
    splits = []
    for i, img in enumerate(frames):
        det.process(img, i / FPS, keep_mask=False)
        if 30 <= i <= 41:
            splits.append(det.last_split)
    if max_misses == 0:
        assert not any(splits)
    else:
        assert any(splits)


@pytest.mark.parametrize("overrides", [{}, {"association__max_measured": 1, "motion__min_displacement": 1.0},
                                       {"contour_length__split_min_length": 30.0}])
def test_each_stage_counts_the_candidates_it_rejected(overrides):
    """``last_diagnostics``: per stage, the numbers the candidates' ``rejected_by`` show — filters
    1 and 2 and the measuring limit in the candidates stage, filter 3, the still-blob rule and the
    score in the scoring stage, filter 4 in the tracklets stage — and every contour (and split
    part) is one candidate."""
    from badminton_gui.core.types import (REJECT_LENGTH, REJECT_MOTION, REJECT_SCORE, REJECT_SHORT_SIDE,
                                          REJECT_WHITENESS)
    frames, _ = _scene(40)
    frames += _flight_across_a_wide_blob(40)[0]
    det = CameraDetector(_params(**overrides))
    seen = {"motion": 0, "still": 0, "whiteness": 0, "passed": 0}
    for i, img in enumerate(frames):
        result = det.find_candidates(img, i / FPS)
        d = det.last_diagnostics
        real = [c.rejected_by for c in result.candidates if not c.predicted]
        assert d.shapes.contours + d.shapes.split_parts == len(real), i
        assert real.count(REJECT_LENGTH) == d.shapes.rejected_length
        assert real.count(REJECT_SHORT_SIDE) == d.shapes.rejected_short_side
        assert real.count(REJECT_WHITENESS) == d.shapes.not_measured + d.scoring.rejected_whiteness
        assert real.count(REJECT_SCORE) == d.scoring.rejected_score
        assert real.count(REJECT_MOTION) == d.scoring.rejected_still + d.tracklets.rejected_motion
        assert real.count(None) == d.tracklets.passed
        assert d.tracklets.coasting == any(c.predicted for c in result.candidates)
        assert d.scoring.measured == d.tracklets.linked + d.scoring.rejected_whiteness \
            + d.scoring.rejected_still + d.scoring.rejected_score
        det.commit(det.choose(result.candidates), i / FPS)
        seen["motion"] += d.tracklets.rejected_motion
        seen["still"] += d.scoring.rejected_still
        seen["whiteness"] += d.scoring.rejected_whiteness + d.shapes.not_measured
        seen["passed"] += d.tracklets.passed
    # The scene exercises the stages: something passes, something waits for its tracklet.
    assert seen["passed"] > 0 and seen["motion"] > 0
    if overrides.get("motion__min_displacement"):
        assert seen["still"] > 0 and seen["whiteness"] > 0

"""The in-play score's frames at rest (core/evaluation.py ``at_rest_frames``) on synthetic labels."""

import numpy as np

from badminton_gui.core.evaluation import REST_AFTER, at_rest_frames, evaluate, in_play, tolerance_px

FPS = 30.0


def rally(held: int = 30, flight: int = 60, lying: int = 45, step: float = 12.0, jitter: float = 0.0,
          seed: int = 0) -> dict:
    """Labels of a shuttle held still for ``held`` frames, then flying ``step`` px a frame, then
    lying still, with the labeller's click ``jitter`` (px)."""
    rng = np.random.default_rng(seed)
    labels, x = {}, 200.0
    for f in range(held + flight + lying):
        if held <= f < held + flight:
            x += step
        dx, dy = rng.uniform(-jitter, jitter, 2) if jitter else (0.0, 0.0)
        labels[f] = (True, x + dx, 300.0 + dy)
    return labels


def test_held_before_the_serve_and_lying_after_half_a_second_are_at_rest():
    held, flight, lying = 30, 60, 45
    rest = at_rest_frames(rally(held, flight, lying), 1280, fps=FPS)
    # Held: at rest until 0.1 s before the first motion (the window sees the serve coming).
    assert set(range(held - 3)) <= rest
    assert not rest & set(range(held - 1, held + flight + 3))
    # Lying: in play for its first 0.5 s, at rest after.
    stop = held + flight
    assert not rest & set(range(stop, stop + int(REST_AFTER * FPS)))
    assert set(range(stop + int(REST_AFTER * FPS) + 5, stop + lying)) <= rest


def test_click_jitter_is_still_a_shuttle_in_flight_is_not():
    rest = at_rest_frames(rally(jitter=2.0), 1280, fps=FPS)
    assert set(range(27)) <= rest
    assert not rest & set(range(30, 90))


def test_stillness_scales_with_the_image_width():
    # 1.5 px a frame: 4.5 px in 0.1 s, still at 1280 px (limit 7.5 px), motion at 512 px (3 px).
    slow = {f: (True, 100 + 1.5 * f, 100.0) for f in range(60)}
    assert tolerance_px(1280, 3.0) > 4.5 > tolerance_px(512, 3.0)
    assert len(at_rest_frames(slow, 1280, fps=FPS)) == 60
    assert at_rest_frames(slow, 512, fps=FPS) == frozenset()


def test_timestamps_decide_the_half_second_not_the_frame_count():
    labels = rally(held=0, flight=60, lying=150)
    stop = 60
    at_120 = at_rest_frames(labels, 1280, times={f: f / 120.0 for f in labels})
    at_30 = at_rest_frames(labels, 1280, fps=FPS)
    # The lie's first 0.5 s: 60 frames at 120 fps, 15 at 30 fps.
    assert min(at_120) > stop + 60 - 1 and min(at_30) < stop + 60


def test_frames_not_labelled_visible_are_never_at_rest_and_a_lone_frame_is_not_still():
    labels = rally()
    for f in range(10, 15):
        labels[f] = (False, 0.0, 0.0)
    rest = at_rest_frames(labels, 1280, fps=FPS)
    assert not rest & set(range(10, 15))
    assert set(range(15, 27)) <= rest          # the hold goes on through the unlabelled frames
    assert at_rest_frames({5: (True, 10.0, 10.0)}, 1280, fps=FPS) == frozenset()
    assert at_rest_frames({}, 1280) == frozenset()


def test_a_shuttle_that_reappears_elsewhere_starts_a_new_stretch():
    # Lying at one place, picked up out of view, lying elsewhere: the second lie is in play for
    # its first 0.5 s like the first after the rally's motion.
    labels = rally(held=0, flight=30, lying=30)
    for f in range(60, 66):
        labels[f] = (False, 0.0, 0.0)
    for f in range(66, 96):
        labels[f] = (True, 900.0, 500.0)
    rest = at_rest_frames(labels, 1280, fps=FPS)
    assert not rest & set(range(66, 66 + int(REST_AFTER * FPS)))
    assert set(range(66 + int(REST_AFTER * FPS) + 1, 96)) <= rest


def test_the_in_play_score_leaves_the_frames_at_rest_out():
    labels = rally()
    rest = at_rest_frames(labels, 1280, fps=FPS)
    # A chain that never reports the held or lying shuttle: the protocol counts them as missed.
    pred = {f: (f not in rest, *labels[f][1:]) for f in labels}
    protocol = evaluate(pred, labels, tolerance_px(1280))
    assert protocol.fn == len(rest) and protocol.tp == len(labels) - len(rest)
    playing = evaluate(pred, in_play(labels, rest), tolerance_px(1280))
    assert playing.fn == 0 and playing.accuracy == 1.0

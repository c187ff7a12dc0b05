"""The five-outcome protocol (core/evaluation.py) counted by hand on small cases."""

import math

import pytest

from badminton_gui.core.evaluation import Outcomes, evaluate, tolerance_px


def test_tolerance_scales_with_width():
    assert tolerance_px(512) == 4.0
    assert tolerance_px(1280) == 10.0
    assert tolerance_px(2048) == 16.0


def test_each_outcome():
    labels = {0: (True, 100, 100), 1: (True, 100, 100), 2: (False, 0, 0), 3: (True, 50, 50), 4: (False, 0, 0)}
    pred = {0: (True, 103, 104), 1: (True, 120, 100), 2: (True, 5, 5), 3: (False, 0, 0), 4: (False, 0, 0)}
    out = evaluate(pred, labels, tolerance=5.0)
    assert out == Outcomes(tp=1, tn=1, fp1=1, fp2=1, fn=1)
    assert out.accuracy == pytest.approx(0.4)
    assert out.precision == pytest.approx(1 / 3)
    assert out.recall == pytest.approx(0.5)
    assert out.f1 == pytest.approx(2 * (1 / 3) * 0.5 / (1 / 3 + 0.5))


def test_missing_predictions_count_as_not_detected_and_extra_frames_are_ignored():
    labels = {0: (True, 1, 1), 1: (False, 0, 0)}
    out = evaluate({7: (True, 1, 1)}, labels, 4.0)
    assert out == Outcomes(fn=1, tn=1)
    assert (out + out).total == 4
    assert math.isnan(Outcomes().accuracy)


def test_one_frame_outcome_agrees_with_the_array_protocol():
    import numpy as np

    from badminton_gui.core.evaluation import classify, classify_one
    cases = [((True, 103, 104), (True, 100, 100)), ((True, 120, 100), (True, 100, 100)),
             ((True, 5, 5), (False, 0, 0)), ((False, 0, 0), (True, 50, 50)),
             ((False, 0, 0), (False, 0, 0)), ((True, 105, 100), (True, 100, 100))]
    for pred, label in cases:
        expected = classify(np.array([pred[0]]), np.array([pred[1:]]), np.array([label[0]]),
                            np.array([label[1:]]), 5.0)[0]
        assert classify_one(pred[0], pred[1], pred[2], label, 5.0) == expected


def test_live_score_counts_each_camera_skips_unlabelled_frames_and_resets():
    from badminton_gui.core.evaluation import LiveScore
    from badminton_gui.core.types import Candidate

    def report(x, y):
        return Candidate(x=x, y=y, length=30.0, short_side=4.0, whiteness=200.0, area=20.0,
                         motion=0.0, score=1.0)

    score = LiveScore(image_width=1280)          # 10 px tolerance
    assert score.add(0, report(100, 100), (True, 104.0, 103.0)) == "TP"
    assert score.add(0, report(100, 100), (True, 130.0, 100.0)) == "FP1"
    assert score.add(0, None, (False, 0.0, 0.0)) == "TN"
    assert score.add(0, report(1, 1), None) is None         # an unlabelled frame is not scored
    assert score.add(1, None, (True, 5.0, 5.0)) == "FN"
    assert score.outcomes(0) == Outcomes(tp=1, fp1=1, tn=1)
    assert score.outcomes(1) == Outcomes(fn=1)
    score.reset()
    assert score.outcomes(0).total == 0 and score.outcomes(1).total == 0

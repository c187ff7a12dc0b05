"""The five-outcome protocol (GUIDE §6) counted by hand on small cases."""

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

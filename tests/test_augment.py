"""What benchmarks/augment.py does to a picture and to its labels: they must move together.

Why this file exists: the study scores the detector on the tuned-on TV clips mirrored, zoomed,
darkened, noisier and softer, with the labels moved by each change's ``point``; a label that
did not follow its picture would score a correct detector as wrong and report a fragility that
is not there. The classifier's training (``train_classifier.py --augment``) moves its labels
the same way.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
sys.path.insert(0, str(BENCHMARKS))

import augment  # noqa: E402


def dot_frame(x: int, y: int) -> np.ndarray:
    frame = np.full((augment.HEIGHT, augment.WIDTH, 3), 40, np.uint8)
    frame[y - 2:y + 3, x - 2:x + 3] = 255
    return frame


def brightest(frame: np.ndarray) -> tuple[float, float]:
    grey = frame.astype(float).sum(axis=2)
    ys, xs = np.nonzero(grey >= grey.max() - 1e-6)
    return float(xs.mean()), float(ys.mean())


@pytest.mark.parametrize("name", ["mirror", "zoom-out-0.8", "zoom-in-1.25"])
@pytest.mark.parametrize("x, y", [(300, 200), (1000, 600), (641, 359)])
def test_a_label_moves_with_its_picture(name, x, y):
    change = augment.change_named(name)
    moved = change.point(float(x), float(y))
    assert moved is not None
    assert np.hypot(*(np.subtract(brightest(change.frame(dot_frame(x, y))), moved))) <= 1.0


def test_zooming_in_loses_the_labels_it_pushes_out_of_the_picture():
    zoom = augment.change_named("zoom-in-1.25")
    assert zoom.point(10.0, 10.0) is None and zoom.point(1270.0, 700.0) is None
    assert zoom.point(639.5, 359.5) == pytest.approx((639.5, 359.5))


def test_photometric_changes_keep_the_labels_and_the_size():
    frame = dot_frame(500, 300)
    for name in ("darker-0.7", "noise-6", "blur-1"):
        change = augment.change_named(name)
        assert change.point(500.0, 300.0) == (500.0, 300.0)
        out = change.frame(frame)
        assert out.shape == frame.shape and out.dtype == np.uint8
        assert not np.array_equal(out, frame)
    assert augment.change_named("darker-0.7").frame(frame).max() == round(255 * 0.7)


def test_an_unknown_change_is_named_in_the_error():
    with pytest.raises(ValueError, match="mirror"):
        augment.change_named("upside-down")

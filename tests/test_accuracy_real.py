"""A small slice of the real-court benchmark (benchmarks/accuracy.py), skipped without the data.

One tuned-on NYCU camera, frames 0–700 (the pre-serve part and the first exchanges): the
detector with the default preset must stay far above the paper's method written plainly
(12–30 % accuracy on these rallies). The bound is loose on purpose: this guards
against regressions, the benchmark gives the figures.
"""

from pathlib import Path

import cv2
import pytest

from badminton_gui.core.detector import CameraDetector
from badminton_gui.core.evaluation import evaluate, tolerance_px
from badminton_gui.io.labels import read_point_labels, read_timestamps
from badminton_gui.io.presets import load_preset

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
RALLY = DATA / "nycu-stereo" / "rally_11-46-04"

pytestmark = pytest.mark.skipif(not (RALLY / "CameraReader_1.mp4").is_file(),
                                reason="real data (../shared/data) not available")


def test_default_preset_on_a_real_rally_slice():
    labels_path = RALLY / "CameraReader_1.csv"
    labels = read_point_labels(labels_path).as_dict()
    times = read_timestamps(labels_path)[1]
    cap = cv2.VideoCapture(str(RALLY / "CameraReader_1.mp4"))
    det = CameraDetector(load_preset("default"))
    pred = {}
    for i in range(700):
        ok, frame = cap.read()
        if not ok:
            break
        d = det.process(frame, float(times[i]), keep_mask=False).detection
        pred[i] = (d is not None, d.x if d else 0.0, d.y if d else 0.0)
    cap.release()
    out = evaluate(pred, {f: v for f, v in labels.items() if f in pred}, tolerance_px(2048))
    assert out.accuracy >= 0.8, out.summary()

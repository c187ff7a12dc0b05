"""The core hooks the refine dialog relies on (core/calibrate/refine.py), tested without Qt.

Why this file exists: the dialog (gui/refine_dialog.py, tests/test_gui_refine.py) runs the refit on
a worker thread with a progress bar and Cancel, and shows the collection's spread against what the
refit needs. These tests pin the small core additions it uses: ``progress`` / ``cancel`` of
``refine_relative_pose`` (no change to its result without them) and ``image_spread``.
"""

import numpy as np
import pytest

from badminton_gui.core.calibrate.refine import (DEFAULT_MIN_SPREAD, RefineCancelled, image_spread,
                                           refine_relative_pose)
from badminton_gui.io.demo_scene import make_rig
from tests.test_rig_refine import rotated, visible_pairs


def test_the_core_refit_stops_when_cancelled_and_reports_its_stages():
    """The hook the dialog relies on: ``cancel`` stops refine_relative_pose, ``progress`` sees
    its stages in order; without them the result is what it always was."""
    truth = make_rig("binocular")
    wrong = rotated(truth, (1.0, 0.3, 0.2), 3.0)
    left, right = visible_pairs(truth, 300)
    stages = []
    refined, report = refine_relative_pose(wrong, left, right,
                                           progress=lambda f, what: stages.append(f))
    plain, plain_report = refine_relative_pose(wrong, left, right)
    assert report == plain_report and np.array_equal(refined.R, plain.R) and report.accepted
    assert stages == sorted(stages) and len(stages) >= 3
    calls = []

    def cancel_on_the_fifth_ask() -> bool:
        calls.append(1)
        return len(calls) >= 5
    with pytest.raises(RefineCancelled):
        refine_relative_pose(wrong, left, right, cancel=cancel_on_the_fifth_ask)
    assert len(calls) == 5



def test_image_spread_is_the_share_of_the_image_the_points_span():
    size = (1000, 500)
    xs = np.linspace(100, 600, 101)
    ys = np.linspace(200, 250, 101)
    wide, tall = image_spread(np.column_stack([xs, ys]), size)
    # 5th to 95th percentile: 90 % of the 500 px span, and of the 50 px one.
    assert wide == pytest.approx(0.45) and tall == pytest.approx(0.09)
    assert min(wide, tall) < DEFAULT_MIN_SPREAD
    assert image_spread(np.zeros((1, 2)), size) == (0.0, 0.0)
    # A few stray points do not stretch it.
    pts = np.column_stack([np.full(100, 500.0), np.full(100, 250.0)])
    pts[:3] = [[0, 0], [999, 499], [0, 499]]
    assert image_spread(pts, size) == (0.0, 0.0)

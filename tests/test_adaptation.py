"""Adapting the classifier to a recording from its own long runs (core/adaptation.py)."""

import numpy as np
import pytest

from badminton_gui.core.adaptation import RunHarvest, adapt_classifier, adapt_to_recording
from badminton_gui.core.classifier import CandidateClassifier, train_mlp
from badminton_gui.core.params import TrackerParams


def rows(n, x=0.0):
    """n candidates on a line at y = 0, the first at x; feature rows = their index."""
    return np.column_stack([x + 50.0 * np.arange(n), np.zeros(n)]), np.arange(n, dtype=float)[:, None]


def test_harvest_keeps_only_long_runs_and_labels_by_the_detection():
    harvest = RunHarvest(min_run=3, radius=8.0)
    for _ in range(2):                       # a run of two: too short, dropped when it ends
        harvest.add(*rows(3), detection=(50.0, 0.0))
    harvest.add(*rows(3), detection=None)
    for _ in range(3):                       # a run of three: kept
        harvest.add(*rows(3), detection=(105.0, 2.0))   # 5.4 px from the third candidate
    harvest.add(*rows(2), detection=None)
    harvest.add(*rows(3), detection=(0.0, 0.0))   # the last run, one frame: dropped at finish
    harvest.finish()
    assert harvest.runs == 1 and harvest.frames == 3
    assert harvest.features.shape == (9, 1)
    assert harvest.labels.tolist() == [False, False, True] * 3


def test_harvest_keeps_a_long_final_run_and_nothing_from_empty_frames():
    harvest = RunHarvest(min_run=2)
    harvest.add(np.zeros((0, 2)), np.zeros((0, 1)), detection=(1.0, 1.0))   # no candidates
    harvest.add(*rows(2), detection=(0.0, 0.0))
    harvest.finish()
    assert harvest.runs == 1 and harvest.frames == 2
    assert harvest.labels.tolist() == [True, False]


def test_adapted_classifier_learns_the_recordings_shuttle_and_keeps_the_rest():
    rng = np.random.default_rng(0)
    # The "shipped" classifier: the shuttle is bright (feature 0 high), whatever feature 1 says.
    x = rng.normal(size=(4000, 2))
    shipped = train_mlp(x, x[:, 0] > 0.5, hidden=8, epochs=300, seed=0, feature_names=("a", "b"))
    # This recording's shuttle is dim (feature 0 low) and has feature 1 high; its clutter the
    # reverse. The shipped classifier ranks them the wrong way round.
    shuttle = np.column_stack([rng.normal(-0.3, 0.1, 300), rng.normal(2.0, 0.2, 300)])
    clutter = np.column_stack([rng.normal(1.0, 0.1, 900), rng.normal(-1.0, 0.2, 900)])
    assert shipped.probability(shuttle).mean() < shipped.probability(clutter).mean()
    adapted = adapt_classifier(shipped, np.vstack([shuttle, clutter]),
                               np.r_[np.ones(300, bool), np.zeros(900, bool)], rehearsal=4000)
    assert isinstance(adapted, CandidateClassifier) and adapted.feature_names == ("a", "b")
    p_shuttle, p_clutter = adapted.probability(shuttle), adapted.probability(clutter)
    ranked_right = (p_shuttle[:, None] > p_clutter[None, :]).mean()
    assert ranked_right > 0.98 and p_shuttle.mean() > 0.8 and p_clutter.mean() < 0.2
    # Far from this recording's candidates the rehearsal keeps the shipped classifier's answer.
    probe = np.column_stack([np.linspace(-2.5, 2.5, 11), np.full(11, -2.5)])
    agree = (adapted.probability(probe) > 0.5) == (shipped.probability(probe) > 0.5)
    assert agree.mean() >= 0.8


def demo_frames(n=120):
    from badminton_gui.io.demo_scene import DemoScene

    def frames():
        scene = DemoScene(seed=3, size=(1280, 720), rig="binocular", n_frames=n)
        while (frame := scene.read()) is not None:
            yield frame.left, frame.t_left
    return frames


def test_adapt_to_recording_off_by_default_and_on_with_a_run_length():
    params = TrackerParams()
    assert params.classifier.adapt_min_run == 0
    assert adapt_to_recording(params, demo_frames(5)) == (None, None)
    on = params.with_value("classifier.adapt_min_run", 10)
    classifier, harvest = adapt_to_recording(on, demo_frames())
    assert classifier is not None and harvest.runs >= 1 and harvest.frames >= 10
    assert harvest.labels.any() and not harvest.labels.all()
    assert classifier.feature_names == harvest_feature_names(on)
    # Stopped: nothing adapted, the caller keeps its classifier.
    assert adapt_to_recording(on, demo_frames(), should_stop=lambda: True) == (None, None)


def harvest_feature_names(params):
    from badminton_gui.core.detector import CameraDetector
    return CameraDetector(params).classifier.feature_names


def test_no_run_long_enough_keeps_the_classifier():
    on = TrackerParams().with_value("classifier.adapt_min_run", 200)
    classifier, harvest = adapt_to_recording(on, demo_frames(40))
    assert classifier is None and harvest.runs == 0


@pytest.mark.parametrize("enabled", [False])
def test_disabled_classifier_is_not_adapted(enabled):
    params = (TrackerParams().with_value("classifier.adapt_min_run", 5)
              .with_value("classifier.enabled", enabled))
    assert adapt_to_recording(params, demo_frames(5)) == (None, None)


def test_the_first_pass_leads_in_only_up_to_a_report(monkeypatch):
    """The adaptation's pseudo-labels come from the lead-in that stops at any report
    (``lookahead.lead_in_through`` off) and no gap fill, whatever the preset says for the final
    readout."""
    from badminton_gui.core import adaptation
    from badminton_gui.io.presets import load_preset
    seen = []

    class Spy(adaptation.CameraLookahead):
        def __init__(self, params):
            seen.append((params.lookahead.lead_in_run, params.lookahead.lead_in_through,
                         params.lookahead.gap_fill_frames))
            super().__init__(params)
    monkeypatch.setattr(adaptation, "CameraLookahead", Spy)
    params = (load_preset("broadcast").with_value("lookahead.frames", 4)
              .with_value("classifier.adapt_min_run", 25))      # (the shipped preset does not adapt)
    assert params.lookahead.lead_in_through
    classifier, harvest = adapt_to_recording(params, lambda: iter(()))
    assert classifier is None and harvest.runs == 0          # (an empty recording: nothing to learn)
    assert seen == [(params.lookahead.lead_in_run, False, 0)]


def test_training_gives_up_when_asked_so_a_closing_window_never_waits_for_it():
    """The adaptation's training asks should_stop every few epochs (a window closed during a TV
    clip's adaptation pass must not wait for the rest of the training)."""
    from badminton_gui.core.classifier import TrainingStopped, train_ensemble
    rng = np.random.default_rng(0)
    x = rng.normal(size=(200, 4))
    y = (x[:, 0] > 0).astype(float)
    asked = []

    def stop() -> bool:
        asked.append(True)
        return len(asked) > 3
    with pytest.raises(TrainingStopped):
        train_ensemble(x, y, members=3, epochs=300, should_stop=stop)
    assert len(asked) == 4        # stopped at the fourth look, long before 3 × 300 epochs
    assert train_ensemble(x, y, members=1, epochs=20, should_stop=lambda: False).name

"""core/court_adaptation.py: the flights both cameras agree on label each camera's candidates, the
classifiers are retrained on them and swapped in between two steps; off, nothing changes."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from badminton_gui.cli import main
from badminton_gui.core.classifier import fine_tune
from badminton_gui.core.court_adaptation import (AdaptProgress, CourtAdaptation, StereoHarvest, adapt_pair,
                                                 fine_tune_camera)
from badminton_gui.core.detector import CameraDetector
from badminton_gui.core.params import CourtAdaptParams, TrackerParams
from badminton_gui.core.types import CameraResult, FlightInfo, TrackResult, make_candidate

from .test_track_file import write_pair

WIDTH = 1280


def _quick(harvest, classifiers, should_stop):
    """A short fine-tuning without the held-back guard (these tests' harvests are too short to
    hold anything back): the swap is what they check."""
    if not harvest.usable:
        return None
    return tuple(fine_tune(c, harvest.features(cam), harvest.labels(cam), epochs=5,
                           name=f"{c.name} (adapted)", should_stop=should_stop)
                 for cam, c in enumerate(classifiers))


def _result(t, shot, in_flight=True, det=(100.0, 100.0)):
    d = None if det is None else make_candidate(det[0], det[1], 20, 3, 200, 10, 0, 0.9)
    cam = CameraResult(d, image_size=(WIDTH, 720))
    return TrackResult(0, t, cam, cam, flight=FlightInfo(shot_index=shot, in_flight=shot >= 0),
                       pair_in_flight=in_flight)


def _scored(det=(100.0, 100.0)):
    """The shuttle 2 px off the report, a blob 20 px off (in between), a light 300 px off."""
    x, y = det
    positions = np.array([[x + 2, y], [x + 20, y], [x + 300, y]])
    features = np.arange(9, dtype=float).reshape(3, 3)
    return (positions, features), (positions, features)


def _flight(harvest, shot, frames, t0):
    for k in range(frames):
        harvest.add(_result(t0 + k / 100, shot), _scored())


def test_a_long_flight_labels_the_pair_as_the_shuttle_and_far_blobs_as_not():
    harvest = StereoHarvest(CourtAdaptParams(min_flight_points=5, target_flights=2,
                                                            target_positives=10))
    _flight(harvest, 0, 4, 0.0)          # too short: dropped when the next shot starts
    _flight(harvest, 1, 6, 1.0)
    harvest.add(_result(2.0, -1, in_flight=False), _scored())   # the flight ended
    assert harvest.flights == 1 and harvest.positives == [6, 6] and harvest.negatives == [6, 6]
    for cam in (0, 1):
        assert harvest.features(cam).shape == (12, 3)
        labels = harvest.labels(cam)
        # the blob 20 px off (between 8 and 40 px at 1280 wide) teaches nothing
        assert np.array_equal(harvest.features(cam)[labels][0], [0, 1, 2])
        assert np.array_equal(harvest.features(cam)[~labels][0], [6, 7, 8])
    assert harvest.fraction == pytest.approx(0.5)       # 1 of 2 flights, 6 of 10 positives


def test_steps_the_flight_refused_and_coasting_reports_teach_nothing():
    harvest = StereoHarvest(CourtAdaptParams(min_flight_points=3))
    for k in range(5):
        harvest.add(_result(k / 100, 0, in_flight=False), _scored())   # pairs the flight refused
    harvest.finish()
    assert harvest.flights == 0 and not harvest.usable
    for k in range(5):
        r = _result(k / 100 + 1, 1)
        coasting = CameraResult(make_candidate(100, 100, 0, 0, 0, 0, 0, 0, predicted=True),
                                image_size=(WIDTH, 720))
        harvest.add(TrackResult(0, r.timestamp, coasting, r.right, flight=r.flight, pair_in_flight=True),
                    _scored())
    harvest.finish()
    assert harvest.flights == 1 and harvest.positives == [0, 5]


def _light_steps(harvest, steps, light=(900.0, 500.0)):
    """Steps without a flight, a light at the same pixel in every one (and a blob moving past)."""
    for k in range(steps):
        positions = np.array([light, [100.0 + 7 * k, 300.0]])
        features = np.array([[5.0, 5.0, 5.0], [1.0, 1.0, 1.0]])
        harvest.add(_result(k / 100, -1, in_flight=False), ((positions, features), (positions, features)))


def test_a_blob_still_for_many_frames_far_from_every_flight_is_not_the_shuttle():
    harvest = StereoHarvest(CourtAdaptParams(min_flight_points=5, still_frames=40))
    _light_steps(harvest, 100)
    frames, still = harvest.still_rows(0)
    # One row every ten frames once it has stayed 40: frames 40, 50, ..., 100; the moving blob never.
    assert len(frames) == 7 and np.all(still == 5.0)
    features, labels, _frames = harvest.dataset(1)
    assert len(labels) == 7 and not labels.any()
    # A flight whose report passes over the light: the light is not taken as a negative any more.
    for k in range(6):
        scored = (np.array([[900.0, 500.0]]), np.array([[5.0, 5.0, 5.0]]))
        harvest.add(_result(2 + k / 100, 0, det=(905.0, 500.0)), (scored, scored))
    harvest.finish()
    assert harvest.flights == 1 and len(harvest.still_rows(0)[0]) == 0
    assert StereoHarvest(CourtAdaptParams(still_frames=0)).still_rows(0)[0].size == 0


def _guard_harvest(rng, flip_held_back):
    """A harvest of 200 steps of one long flight: the shuttle's rows stand out by +3 in every
    feature; with ``flip_held_back`` the held-back steps say the opposite (the report on a plain
    blob, the standing-out one far from it)."""
    n = len(CameraDetector(TrackerParams()).classifier.mean)
    harvest = StereoHarvest(CourtAdaptParams(min_flight_points=5, still_frames=0))
    for k in range(200):
        features = rng.normal(size=(4, n))
        features[0] += 3.0
        if flip_held_back and (k + 1) // 50 % 4 == 3:
            features[[0, 1]] = features[[1, 0]]
        positions = np.array([[100.0, 100.0], [600.0, 300.0], [700.0, 300.0], [800.0, 300.0]])
        harvest.add(_result(k / 100, 0), ((positions, features), (positions, features)))
    harvest.finish()
    return harvest


def test_fine_tuning_is_kept_only_when_it_wins_on_the_held_back_steps():
    shipped = CameraDetector(TrackerParams()).classifier
    rng = np.random.default_rng(1)
    tuned, judged = fine_tune_camera(shipped, _guard_harvest(rng, False), 0, epochs=60, learning_rate=3e-3)
    assert not judged.kept and tuned is not shipped and "(adapted)" in tuned.name
    assert judged.loss_after < judged.loss_before and judged.rows == 200
    kept, judged = fine_tune_camera(shipped, _guard_harvest(rng, True), 0, epochs=60, learning_rate=3e-3)
    assert judged.kept and kept is shipped
    pair = []
    assert adapt_pair(_guard_harvest(rng, True), (shipped, shipped), judged=pair, epochs=60,
                      learning_rate=3e-3) == (shipped, shipped)
    assert [j.kept for j in pair] == [True, True]


class _Tracker:
    """What ``CourtAdaptation.observe`` reads of a StereoTracker: its parameters and detectors."""

    def __init__(self, params):
        self.params = params
        self.left, self.right = CameraDetector(params), CameraDetector(params)


def _learnable_scored(rng):
    """Feature rows the shipped classifier reads (its length), the shuttle's unlike the rest."""
    n = len(CameraDetector(TrackerParams()).classifier.mean)
    positions = np.array([[100.0, 100.0]] + [[600.0 + 10 * k, 300.0] for k in range(5)])
    features = rng.normal(size=(6, n))
    features[0] += 3.0
    return (positions, features)


def _live_params():
    return (TrackerParams().with_value("adapt.enabled", True).with_value("adapt.min_flight_points", 5)
            .with_value("adapt.target_flights", 2).with_value("adapt.target_positives", 10))


def _three_flights(adaptation, tracker, rng):
    t = 0.0
    for shot in (0, 1, 2):
        for _ in range(8):
            tracker.left.last_scored = tracker.right.last_scored = _learnable_scored(rng)
            adaptation.observe(tracker, _result(t, shot))
            t += 0.01
    return t


def test_training_runs_beside_the_tracker_and_its_classifiers_go_in_at_a_later_step():
    params = _live_params()
    tracker = _Tracker(params)
    shipped = tracker.left.classifier
    adaptation = CourtAdaptation(params.adapt, train=_quick)
    rng = np.random.default_rng(1)
    t, step = 0.0, 0
    while adaptation.progress.state == "collecting":
        tracker.left.last_scored = tracker.right.last_scored = _learnable_scored(rng)
        adaptation.observe(tracker, _result(t, step // 8))       # flights of 8 pairs
        t, step = t + 0.01, step + 1
    assert adaptation.progress.state == "training" and adaptation.progress.fraction == 1.0
    assert adaptation.progress.flights == 2 and tracker.left.classifier is shipped
    adaptation.wait(120)
    assert adaptation.adapted is None       # not while the tracker may be inside a step
    adaptation.observe(tracker, _result(t, -1, in_flight=False))
    assert adaptation.progress.state == "adapted" and tracker.right.classifier is adaptation.adapted[1]


def test_live_adaptation_swaps_both_classifiers_between_steps():
    params = _live_params()
    tracker = _Tracker(params)
    shipped = tracker.left.classifier
    adaptation = CourtAdaptation(params.adapt, background=False, train=_quick)
    assert adaptation.progress.state == "collecting" and adaptation.progress.fraction == 0
    t = _three_flights(adaptation, tracker, np.random.default_rng(0))
    progress = adaptation.progress
    assert progress.state in ("training", "adapted") and progress.flights == 2
    adaptation.observe(tracker, _result(t, -1, in_flight=False))      # the swap, between two steps
    assert adaptation.progress.state == "adapted" and "adapted to the court" in adaptation.progress.text
    assert tracker.left.classifier is adaptation.adapted[0] and tracker.right.classifier is adaptation.adapted[1]
    assert tracker.left.classifier is not shipped
    assert "(adapted)" in tracker.left.classifier.name
    # A parameter snapshot puts the preset's file back in the detectors: the adapted ones return.
    tracker.left.set_params(params)
    tracker.right.set_params(params)
    adaptation.observe(tracker, _result(t + 0.01, -1, in_flight=False))
    assert tracker.left.classifier is adaptation.adapted[0]


def test_off_it_collects_nothing_and_says_nothing():
    tracker = _Tracker(TrackerParams())
    adaptation = CourtAdaptation(TrackerParams().adapt, background=False)
    for k in range(30):
        adaptation.observe(tracker, _result(k / 100, 0))
    assert adaptation.progress == AdaptProgress("off", 0, (0, 0), (0, 0), 0.0)
    assert adaptation.progress.text == ""


def test_the_tracker_adapts_on_the_demo_court():
    """A StereoTracker with ``adapt`` on, on the demo court: its flights reach the target and both
    detectors score with the adapted classifiers while it keeps tracking."""
    from badminton_gui.core.tracker import StereoTracker
    from badminton_gui.io.demo_scene import DemoScene

    params = (TrackerParams().with_value("adapt.enabled", True).with_value("adapt.target_flights", 1)
              .with_value("adapt.target_positives", 30))
    scene = DemoScene(seed=3, size=(640, 360), rig="binocular", n_frames=260)
    tracker = StereoTracker(scene.rig, params, parallel=False)
    tracker.adaptation = CourtAdaptation(params.adapt, background=False, train=_quick)
    shipped = tracker.left.classifier
    in_flight = 0
    for _ in range(260):
        result = tracker.process_frame(scene.read(), keep_masks=False)
        in_flight += result.pair_in_flight
    tracker.close()
    assert in_flight >= 30
    assert tracker.adaptation.progress.state == "adapted", tracker.adaptation.progress
    assert tracker.left.classifier is tracker.adaptation.adapted[0] is not shipped


def test_track_adapt_without_a_flight_keeps_the_presets_classifiers(tmp_path, caplog):
    """The moving dot's rig has no court pose, so no drag-model flight: `track --adapt` says it had
    nothing to learn from and writes the rows `track` writes."""
    write_pair(tmp_path, 40)
    common = ["track", "--left", str(tmp_path / "l.avi"), "--right", str(tmp_path / "r.avi"),
              "--calib", str(tmp_path / "rig.yaml"), "--quiet"]
    assert main(common + ["-o", str(tmp_path / "plain.csv")]) == 0
    assert main(common + ["-o", str(tmp_path / "adapt.csv"), "--adapt"]) == 0
    assert "nothing to learn from" in caplog.text

    def rows(name):
        with open(tmp_path / name, newline="") as fh:
            return list(csv.reader(fh))
    assert rows("adapt.csv") == rows("plain.csv")

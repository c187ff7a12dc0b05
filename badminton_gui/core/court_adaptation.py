"""Adapting each camera's candidate classifier to a new court, from the flights both cameras agree on.

Why this file exists: the two-camera classifier learnt the shuttle's looks on one hall; in another
(other lights, LED boards, floor, resolution) it ranks the shuttle first less often. Adapting each
camera from its own long runs (``core/adaptation.py`` ``RunHarvest``) lost on the two-camera rig:
a camera's run may follow a shoe or a line as well as the shuttle. A pair of reports whose 3D
point the drag-model flight filter took, on a flight it followed for at least
``adapt.min_flight_points`` pairs, is much surer evidence: two cameras would have to make the same
mistake at the same place in 3D, on a path a shuttle flies. So ``StereoHarvest`` labels, on each
such pair's frame, each camera's candidates near its report as the shuttle and those far from it
(lights, boards, lines, players' shoes) as not; candidates in between, and frames the flight did
not take, teach nothing.

``CourtAdaptation`` drives it live: fed every step's result, it reports its progress (a GUI shows
"adapting: 40 %"), trains each camera's classifier (``adapt_classifier``: the pseudo-labels plus
pseudo-rehearsal of the classifier it starts from) once the harvest reaches its target, on a
background thread, and swaps the classifiers into the tracker's detectors between two steps.
``adapt_to_stereo_recording`` is the offline form: one pass over a recording, the classifiers from
everything it collected (``track --adapt`` tracks a second pass with them).

What it gains and costs, hence off by default (``adapt.enabled``): on a held-out rally of the
NYCU rig (rally_11-48-10, first pass: 7 flights, ~720 shuttle candidates a camera) it lost,
95.02 / 75.99 -> 91.53 / 72.60 % per camera, mostly by new reports where the labels have none;
on the demo court at 640×360 (seed 5) 97.80 / 96.90 -> 97.70 / 97.90 %
(``benchmarks/court_adaptation.py``). Most of that loss is the retraining recipe, not the
labels: the shipped classifier retrained on its pseudo-rehearsal alone (no harvested rows)
already scores 91.79 / 74.04 % on that rally — the TV recipe's rehearsal does not reproduce the
two-camera classifier, so a better start (its own weights, fine-tuned) is the next thing to try.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from .adaptation import adapt_classifier
from .classifier import CandidateClassifier, TrainingStopped
from .errors import TrackerInputError
from .stereo.params import CourtAdaptParams
from .types import Candidate, StereoFrame, TrackResult

# The image width the radii are given at (px at 1280 wide, like the association's gates).
REFERENCE_WIDTH = 1280.0


@dataclass(frozen=True)
class AdaptProgress:
    """How far the court adaptation is: the flights and candidates collected, and its state."""

    state: str = "off"                   # off / collecting / training / adapted / failed
    flights: int = 0                     # flights that labelled their frames
    positives: tuple[int, int] = (0, 0)  # shuttle candidates per camera
    negatives: tuple[int, int] = (0, 0)  # candidates labelled not the shuttle per camera
    fraction: float = 0.0                # of the target (1.0 once reached)

    @property
    def text(self) -> str:
        """One short line for a status bar."""
        if self.state == "off":
            return ""
        if self.state == "collecting":
            return f"adapting to the court: {100 * self.fraction:.0f} %"
        if self.state == "training":
            return "adapting to the court: training"
        if self.state == "failed":
            return "not adapted to the court"
        return "adapted to the court"

    @property
    def detail(self) -> str:
        """What it learns from, one line (a tooltip)."""
        return (f"{self.flights} flight{'s' if self.flights != 1 else ''} both cameras agreed on; shuttle "
                f"candidates {self.positives[0]} / {self.positives[1]}, others {self.negatives[0]} / "
                f"{self.negatives[1]} (left / right)")


class StereoHarvest:
    """Each camera's candidates (classifier feature rows) labelled by the flights both cameras agree on.

    Feed it every step, in order (``add``): the step's result and each camera's scored candidates
    as the classifier saw them (``CameraDetector.last_scored``: positions (N, 2), feature rows
    (N, F)). A flight's frames are kept once it ends (another shot, or no flight) with at least
    ``min_flight_points`` pairs taken; a shorter one's are dropped.
    """

    def __init__(self, params: CourtAdaptParams) -> None:
        self.params = params
        self._features: tuple[list[np.ndarray], list[np.ndarray]] = ([], [])
        self._labels: tuple[list[np.ndarray], list[np.ndarray]] = ([], [])
        self._flight: list[tuple[int, np.ndarray, np.ndarray]] = []   # (camera, features, labels)
        self._shot = -1
        self._taken = 0                       # pairs of the current flight the filter took
        self._last_t = -math.inf
        self.flights = 0
        self.positives = [0, 0]
        self.negatives = [0, 0]

    def add(self, result: TrackResult, scored: Sequence[tuple[np.ndarray, np.ndarray]]) -> None:
        flight = result.flight
        shot = flight.shot_index if flight.in_flight else -1
        if shot != self._shot or result.timestamp < self._last_t:
            self._end_flight()
            self._shot = shot
        self._last_t = result.timestamp
        if shot < 0 or not result.pair_in_flight:
            return
        self._taken += 1
        for cam, res in enumerate((result.left, result.right)):
            labelled = self._label(res.detection, res.image_size[0], *scored[cam])
            if labelled is not None:
                self._flight.append((cam, *labelled))

    def _label(self, det: Candidate | None, width: int, positions: np.ndarray,
               features: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """This frame's candidates with a label (True: the shuttle), those in between left out."""
        positions = np.asarray(positions, float).reshape(-1, 2)
        if det is None or det.predicted or not len(positions) or width <= 0:
            return None
        scale = width / REFERENCE_WIDTH
        d = np.hypot(positions[:, 0] - det.x, positions[:, 1] - det.y)
        near = d <= self.params.radius * scale
        far = d >= self.params.far_radius * scale
        if np.count_nonzero(near) > 1:
            # Two blobs at the report (a shuttle split in two, or beside a line): only the nearest.
            near = d == d.min()
        keep = near | far
        if not keep.any():
            return None
        return np.asarray(features, float)[keep], near[keep]

    def finish(self) -> None:
        """The recording ended, or the harvest is to be used now: keep the flight in progress if
        it is long enough already."""
        self._end_flight()
        self._shot = -1

    def _end_flight(self) -> None:
        if self._taken >= self.params.min_flight_points and self._flight:
            for cam, features, labels in self._flight:
                self._features[cam].append(features)
                self._labels[cam].append(labels)
                self.positives[cam] += int(np.count_nonzero(labels))
                self.negatives[cam] += int(len(labels) - np.count_nonzero(labels))
            self.flights += 1
        self._flight = []
        self._taken = 0

    def features(self, cam: int) -> np.ndarray:
        return np.vstack(self._features[cam]) if self._features[cam] else np.zeros((0, 0))

    def labels(self, cam: int) -> np.ndarray:
        return np.concatenate(self._labels[cam]) if self._labels[cam] else np.zeros(0, bool)

    @property
    def fraction(self) -> float:
        """How far towards the target (flights and shuttle candidates per camera), 0…1."""
        p = self.params
        return min(1.0, self.flights / max(p.target_flights, 1),
                   min(self.positives) / max(p.target_positives, 1))

    @property
    def usable(self) -> bool:
        """Both cameras have shuttle and non-shuttle candidates to learn from."""
        return min(self.positives) > 0 and min(self.negatives) > 0


def adapt_pair(harvest: StereoHarvest, classifiers: Sequence[CandidateClassifier | None],
               should_stop: Callable[[], bool] | None = None, **training
               ) -> tuple[CandidateClassifier, CandidateClassifier] | None:
    """Each camera's classifier retrained on its harvest (``adapt_classifier``, ``training`` its
    options), or None when the harvest cannot teach (a camera without positives or negatives), a
    camera has no classifier (the hand-made score), or ``should_stop`` said so."""
    if not harvest.usable or any(c is None for c in classifiers):
        return None
    try:
        return tuple(adapt_classifier(classifiers[cam], harvest.features(cam), harvest.labels(cam),
                                      should_stop=should_stop, **training) for cam in (0, 1))
    except TrainingStopped:
        return None


class CourtAdaptation:
    """The live adaptation of a ``StereoTracker``: ``observe`` after every step.

    Off (``adapt.enabled`` False) it does nothing. On, it harvests until the target, trains both
    cameras' classifiers on a background thread (``background`` False: at once, in ``observe``)
    while the tracker runs on, and swaps them into the detectors at the first step after. It
    adapts once per court: a new parameter snapshot that changes the classifier group or the
    adaptation's own starts over; any other keeps the adapted classifiers in use.
    """

    def __init__(self, params: CourtAdaptParams, background: bool = True,
                 train: Callable = adapt_pair) -> None:
        self.background = background
        self._train_pair = train        # ``adapt_pair``'s signature (a test's shorter training)
        self._params = params
        self._restart()

    def _restart(self) -> None:
        self.harvest = StereoHarvest(self._params)
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._trained: tuple[CandidateClassifier, CandidateClassifier] | None = None
        self.adapted: tuple[CandidateClassifier, CandidateClassifier] | None = None
        self._failed = False
        self._classifier_params = None

    def restart(self) -> None:
        """A new court: forget the harvest; the detectors keep the classifiers they have until
        the next parameter snapshot."""
        self._stop.set()
        self._restart()

    @property
    def progress(self) -> AdaptProgress:
        h = self.harvest
        if not self._params.enabled:
            state = "off"
        elif self.adapted is not None:
            state = "adapted"
        elif self._failed:
            state = "failed"
        elif self._thread is not None:
            state = "training"
        else:
            state = "collecting"
        return AdaptProgress(state, h.flights, tuple(h.positives), tuple(h.negatives), h.fraction)

    def observe(self, tracker, result: TrackResult) -> None:
        """After each of ``tracker``'s steps (a ``StereoTracker``): harvest, train, swap."""
        params = tracker.params
        if params.adapt != self._params:
            self._params = params.adapt
            self.restart()
        if not self._params.enabled:
            return
        detectors = (tracker.left, tracker.right)
        if self.adapted is not None:
            if params.classifier != self._classifier_params:
                self.restart()          # another model or its switch: adapt that one anew
            elif detectors[0].classifier is not self.adapted[0]:
                # A parameter snapshot put the preset's file back in the detectors.
                for det, c in zip(detectors, self.adapted):
                    det.use_classifier(c)
            return
        if self._trained is not None:
            self._swap(detectors, params)
            return
        if self._failed:
            self._thread = None
        if self._thread is not None or self._failed:
            return
        self.harvest.add(result, (detectors[0].last_scored, detectors[1].last_scored))
        if self.harvest.fraction >= 1.0:
            self.harvest.finish()
            self._train([det.classifier for det in detectors], params)

    def _train(self, start: list, params) -> None:
        self._classifier_params = params.classifier
        stop = self._stop

        def work() -> None:
            trained = self._train_pair(self.harvest, start, stop.is_set)
            if not stop.is_set():
                self._failed = trained is None
                self._trained = trained

        if self.background:
            self._thread = threading.Thread(target=work, name="court-adaptation", daemon=True)
            self._thread.start()
        else:
            work()

    def _swap(self, detectors, params) -> None:
        self._thread = None
        if params.classifier != self._classifier_params:
            self.restart()
            return
        self.adapted, self._trained = self._trained, None
        for det, c in zip(detectors, self.adapted):
            det.use_classifier(c)

    def wait(self, timeout: float | None = None) -> None:
        """Until a training in progress has finished (its classifiers go in at the next step)."""
        thread = self._thread
        if thread is not None:
            thread.join(timeout)

    def close(self) -> None:
        """Stop a training in progress (the tracker closes)."""
        self._stop.set()


def adapt_to_stereo_recording(tracker, frames: Iterable[StereoFrame],
                              should_stop: Callable[[], bool] = lambda: False,
                              params: CourtAdaptParams | None = None
                              ) -> tuple[tuple[CandidateClassifier, CandidateClassifier] | None, StereoHarvest]:
    """One pass of ``tracker`` (a fresh ``StereoTracker``) over a recording's steps, harvesting
    every flight both cameras agree on, and each camera's classifier trained on it (None: the
    harvest could not teach, or ``should_stop`` said so; the caller keeps the classifiers it had).
    ``params``: the harvest's (default: the tracker's ``adapt`` group). The tracker's own live
    adaptation should be off (``adapt.enabled`` False): the classifiers stay the ones it started
    with for the whole pass. A step the tracker refuses (``TrackerInputError``) is skipped."""
    harvest = StereoHarvest(params or tracker.params.adapt)
    detectors = (tracker.left, tracker.right)
    for frame in frames:
        if should_stop():
            return None, harvest
        try:
            result = tracker.process_frame(frame, keep_masks=False)
        except TrackerInputError:
            continue
        harvest.add(result, (detectors[0].last_scored, detectors[1].last_scored))
    harvest.finish()
    return adapt_pair(harvest, [det.classifier for det in detectors], should_stop), harvest

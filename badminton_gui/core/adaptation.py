"""Adapting the candidate classifier to the recording in front of it, from its own long tracks.

Why this file exists: the TV classifier learnt the shuttle's looks from three labelled matches. On
a match it has not seen it ranks the shuttle first less often: trained on two tuned-on clips and
scored on the third, 74.6–77.8 % against 87.5 % on clips it saw. What the readout follows for a
long unbroken run of frames is nearly always the shuttle, so a first pass over a *recording* labels
that recording's own candidates: in every frame of a run of at least ``min_run`` consecutive
detections, the candidates at the detection are the shuttle and the frame's other candidates are
not (``RunHarvest``). A new classifier is trained on them (``adapt_classifier``), and a second pass
uses it (``adapt_to_recording``).

Training on the pseudo-labels alone would forget what the shipped classifier knew of the frames the
runs do not cover (players, the crowd, the shuttle in the other half-court). Its training data
cannot be shipped (crops of third-party footage), so it is *rehearsed* instead: random feature
vectors drawn from the shipped classifier's own standardisation (its per-feature mean and scale)
labelled with its probabilities join the training set — pseudo-rehearsal (Robins, 1995).

What it gains and costs: on a TV clip the classifier has not seen (``benchmarks/train_classifier.py
--kind broadcast --leave-one-out --seed S``, against ``--no-adapt``) 76.09 / 79.52 / 78.48 % at
seeds 0 / 1 / 2 instead of 74.64 / 75.68 / 77.75 %; with the shipped classifier the held-out clips
77.40 -> 80.31 %. On the three clips the shipped classifier was trained on it *costs* (87.53 ->
82.74 %): there the classifier knew the true labels, and the adaptation trades that memory for
pseudo-labels. No shipped preset turns it on (``classifier.adapt_min_run``; ``detect --adapt``): the
broadcast preset did while its classifier knew two venues, but the one trained on all five scores
venues it never saw better as trained (leave-one-venue-out, benchmarks/generalise.py --venues
against --adapt: 74.44 against 72.26 %).

Offline only: it needs the recording twice (CLI ``detect``; broadcast_census.py, accuracy.py).
The live readout and the GUI keep the shipped classifier. Two cameras have surer evidence than a
run of one camera's detections — the flights both agree on — and ``core/court_adaptation.py``
adapts from that (fine-tuning the shipped weights instead of this file's retraining). On the
two-camera rig this file's runs were measured and not used (``train_classifier.py --kind stereo
--leave-one-out --scan classifier.adapt_min_run=25,60``): each camera adapted from its own
runs, every tuned-on rally tracked with a classifier trained without it went 97.58 -> 96.08 /
96.25 % — there the shipped classifier already ranks an unseen rally's shuttle well, and the
pseudo-labels' mistakes cost more than they teach.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterable

import numpy as np

from .classifier import CandidateClassifier, TrainingStopped, train_ensemble
from .detector import CameraDetector
from .lookahead import CameraLookahead
from .params import TrackerParams

# px at 1280 px width: a candidate this close to a run's detection is the shuttle. The readout's
# position is moved to the cork head (``colour.head_lead_width_frames``), a few px from the blob's
# centroid the candidate carries; at 3 px a third of the runs' frames had no positive (a trial).
PSEUDO_LABEL_RADIUS = 8.0
# frames: the run length when adaptation is asked for (``detect --adapt``) under a preset that has
# it off; chosen leave-one-clip-out for the three-clip TV classifier (train_classifier.py).
DEFAULT_MIN_RUN = 25


class RunHarvest:
    """Candidates of the frames on long runs of detections, labelled by the detection.

    Feed it frame by frame, in order, with each frame's scored candidates (positions and the
    classifier's feature rows, ``CameraDetector.last_scored``) and that frame's final detection
    (None: none, or only a coasting prediction). A run's frames are kept once the run reaches
    ``min_run`` frames; a shorter run's are dropped when it ends.
    """

    def __init__(self, min_run: int, radius: float = PSEUDO_LABEL_RADIUS) -> None:
        self.min_run = max(int(min_run), 1)
        self.radius = float(radius)
        self._run: list[tuple[np.ndarray, np.ndarray]] = []
        self._features: list[np.ndarray] = []
        self._labels: list[np.ndarray] = []
        self.frames = 0          # frames kept
        self.runs = 0            # runs kept

    def add(self, positions: np.ndarray, features: np.ndarray,
            detection: tuple[float, float] | None) -> None:
        if detection is None:
            self._end_run()
            return
        positions = np.asarray(positions, float).reshape(-1, 2)
        near = np.hypot(positions[:, 0] - detection[0], positions[:, 1] - detection[1]) <= self.radius
        self._run.append((np.asarray(features, float), near))

    def finish(self) -> None:
        """The recording ended: keep the last run if it is long enough."""
        self._end_run()

    def _end_run(self) -> None:
        if len(self._run) >= self.min_run:
            for features, near in self._run:
                if len(near):
                    self._features.append(features)
                    self._labels.append(near)
            self.frames += len(self._run)
            self.runs += 1
        self._run = []

    @property
    def features(self) -> np.ndarray:
        return np.vstack(self._features) if self._features else np.zeros((0, 0))

    @property
    def labels(self) -> np.ndarray:
        return np.concatenate(self._labels) if self._labels else np.zeros(0, bool)


def adapt_classifier(classifier: CandidateClassifier, features: np.ndarray, labels: np.ndarray, *,
                     rehearsal: int = 20000, max_rows: int = 20000, members: int = 3,
                     hidden: int = 16, epochs: int = 300, seed: int = 0,
                     should_stop: Callable[[], bool] | None = None) -> CandidateClassifier:
    """A classifier trained on ``features``/``labels`` and on ``rehearsal`` random feature vectors
    drawn from ``classifier``'s standardisation and labelled with its probabilities.

    The shape (members × hidden, epochs) is the shipped TV classifier's (train_classifier.py).
    More than ``max_rows`` candidates (a long recording) are subsampled to that many.
    Trained in float32 (2.4x faster than float64, ≈ 7 s for 26,000 rows; leave-one-clip-out the
    same within the seeds' spread). Why this recipe (trial scripts; seed 0, 74.6 % unadapted):
    fine-tuning the shipped weights on the pseudo-labels alone 75.4 %, anew on the pseudo-labels
    and 20,000 rehearsed vectors 78.2 % (5,000: 76.5 %), anew with the true training data instead
    of rehearsal 79.0 %.
    """
    rng = np.random.default_rng(seed)
    features = np.asarray(features, float).reshape(-1, len(classifier.mean))
    labels = np.asarray(labels, bool)
    if len(labels) > max_rows:
        # A long recording: its candidates subsampled, so training stays seconds, not minutes.
        keep = np.sort(rng.choice(len(labels), max_rows, replace=False))
        features, labels = features[keep], labels[keep]
    rehearsed = classifier.mean + classifier.scale * rng.normal(size=(rehearsal, len(classifier.mean)))
    x = np.vstack([features, rehearsed])
    # Soft targets: the cross-entropy's gradient (p - y) takes a probability as well as a label.
    y = np.concatenate([labels.astype(float), classifier.probability(rehearsed)])
    return train_ensemble(x, y, members=members, hidden=hidden, epochs=epochs, seed=seed,
                          name=f"{classifier.name} (adapted)", feature_names=classifier.feature_names,
                          dtype=np.float32, should_stop=should_stop)


def adapt_to_recording(params: TrackerParams, frames: Callable[[], Iterable[tuple[np.ndarray, float]]],
                       classifier: CandidateClassifier | None = None,
                       should_stop: Callable[[], bool] = lambda: False
                       ) -> tuple[CandidateClassifier | None, RunHarvest | None]:
    """One pass over one camera's recording that labels its long runs, and the classifier
    trained on them (``adapt_classifier``).

    ``frames()`` yields the recording's (image, time) from its start. ``classifier``: the one to
    start from (None: the preset's). Returns the adapted classifier and the pass's harvest, or
    None for the classifier when adaptation is off (``classifier.adapt_min_run`` 0), the
    classifier is disabled, no run is long enough, or ``should_stop`` said so; the caller then
    keeps the classifier it had. It adapts once: a second adaptation, relabelling the runs with the adapted
    classifier and rehearsing it, undid the gain (a trial script, seed 0: 78.2 -> 74.6 %).
    """
    cp = params.classifier
    if cp.adapt_min_run <= 0 or not cp.enabled:
        return None, None
    # Its pseudo-labels take the lead-in that stops at any report (``lead_in_through`` off): the
    # frames the other one replaces are its least sure, and learnt from they cost more than the
    # final readout gains (leave-one-clip-out: with it here 80.46 / 79.94 % at seeds 0 / 1,
    # without 83.26 / 84.10 %; no lead-in here at all 77.86 / 81.19 %).
    detector = CameraDetector(params)
    # Nor does it fill gaps: a filled frame is a guess along a line, not a sure label.
    lookahead = CameraLookahead(params.with_value("lookahead.lead_in_through", False)
                                .with_value("lookahead.gap_fill_frames", 0))
    if classifier is not None:
        detector.use_classifier(classifier)
    start = detector.classifier
    harvest = RunHarvest(cp.adapt_min_run)
    # The look-ahead hands each frame back, in order, ``lookahead.frames`` frames later: its
    # candidates wait here until then (a recording's worth would be ~20 kB a frame).
    scored: deque[tuple[np.ndarray, np.ndarray]] = deque()

    def take(results) -> None:
        for res in results:
            positions, features = scored.popleft()
            d = res.detection
            harvest.add(positions, features, (d.x, d.y) if d is not None and not d.predicted else None)

    for image, t in frames():
        if should_stop():
            return None, None
        res = detector.process(image, t, keep_mask=False)
        scored.append(detector.last_scored)
        take(lookahead.push(res, t))
    take(lookahead.flush())
    harvest.finish()
    if harvest.runs == 0 or not harvest.labels.any():
        return None, harvest
    try:
        return adapt_classifier(start, harvest.features, harvest.labels, should_stop=should_stop), harvest
    except TrainingStopped:
        return None, None

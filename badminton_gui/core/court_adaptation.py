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

Two more kinds of rows come from every step, flight or not: a blob that stays at one pixel for
``adapt.still_frames`` frames (a light, an LED board, a line's end, a shuttle at rest) and lies
far from every report of the flights kept is not the shuttle either (``StillBlobs``); and a
sample of all the court's candidates, unlabelled, is what the training rehearses.

How it trains (``fine_tune_camera``): the camera's shipped classifier is *fine-tuned*, not
trained anew — a few full-batch Adam steps at a small rate from its own weights
(``classifier.fine_tune``), on the harvest's labelled rows and on the sample of this court's
candidates with the starting classifier's probabilities as soft targets, so that what it knew of
everything the flights do not show stays. Retrained from scratch with pseudo-rehearsal of random
feature vectors (``core/adaptation.py``'s TV recipe) it lost on the rig: the shipped classifier
retrained on that rehearsal alone already lost ~3 points on a held-out rally. A guard then
scores both classifiers on held-back steps of the harvest (every fourth block of 50 steps, left
out of the training): the fine-tuned one is used only when its weighted cross-entropy is lower
and it ranks the shuttle above the step's other labelled rows at least as often; otherwise the
camera keeps the classifier it had.

``CourtAdaptation`` drives it live: fed every step's result, it reports its progress (a GUI shows
"adapting: 40 %"), fine-tunes each camera's classifier once the harvest reaches its target, on
a background thread, and swaps the classifiers into the tracker's detectors between two steps.
``adapt_to_stereo_recording`` is the offline form: one pass over a recording, the classifiers from
everything it collected (``track --adapt`` tracks a second pass with them).

What it gains and costs, hence still off by default (``adapt.enabled``): on the three held-out
NYCU rallies (``benchmarks/accuracy.py --track-only --adapt``) it neither wins nor loses
measurably — all together 91.53 -> 91.43 % (in play 94.99 -> 94.89 %); rally_11-48-10, where the
old from-scratch recipe fell 95.02 / 75.99 -> 91.53 / 72.60 %, now 95.02 / 75.99 -> 95.09 /
75.99 %. On randomised courts it never saw (``benchmarks/scenes.py --families side-near --seeds
4 --seconds 4 --adapt``) 92.69 / 93.33 -> 93.14 / 94.04 % per camera, ``--families high``
89.35 / 87.69 -> 89.46 / 89.05 % (but a 3D point on 90.2 % of the frames, not 90.7); on the demo court at
640×360 (seed 5) 97.80 / 96.90 -> 97.70 / 96.90 %. A win on a new hall is not shown yet, and a
held-out rally loses a few frames, so it stays an option.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from .classifier import CandidateClassifier, TrainingStopped, fine_tune
from .errors import TrackerInputError
from .stereo.params import CourtAdaptParams
from .types import Candidate, StereoFrame, TrackResult

# The image width the radii are given at (px at 1280 wide, like the association's gates).
REFERENCE_WIDTH = 1280.0
# The fine-tuning: full-batch Adam steps from the starting weights, and their size.
FINE_TUNE_EPOCHS = 40
FINE_TUNE_RATE = 1e-3


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


class StillBlobs:
    """Which of one camera's candidates have stayed in one place for many frames.

    A light, an LED board's edge, a line's bright end or a shuttle lying on the floor shows up as a
    candidate at the same pixel frame after frame; a flying shuttle never does. Each candidate is
    matched to an anchor within ``radius`` px (the nearest); an anchor not matched for more than
    ``max_gap`` frames is forgotten, so a blob is still once it was matched ``frames`` times
    with no longer gap."""

    def __init__(self, frames: int, radius: float, max_gap: int = 10) -> None:
        self.frames = int(frames)
        self.radius = float(radius)
        self.max_gap = int(max_gap)
        self._at = np.zeros((0, 2))
        self._count = np.zeros(0, int)
        self._last = np.zeros(0, int)

    def update(self, positions: np.ndarray, frame: int) -> np.ndarray:
        """This frame's candidates (N, 2) → (N,) how many frames each has stayed where it is."""
        alive = frame - self._last <= self.max_gap
        self._at, self._count, self._last = self._at[alive], self._count[alive], self._last[alive]
        counts = np.zeros(len(positions), int)
        for k, (x, y) in enumerate(positions):
            if len(self._at):
                d = np.hypot(self._at[:, 0] - x, self._at[:, 1] - y)
                j = int(np.argmin(d))
                if d[j] <= self.radius and self._last[j] != frame:
                    self._count[j] += 1
                    self._last[j] = frame
                    counts[k] = self._count[j]
                    continue
            self._at = np.vstack([self._at, [[x, y]]])
            self._count = np.append(self._count, 1)
            self._last = np.append(self._last, frame)
            counts[k] = 1
        return counts


class StereoHarvest:
    """Each camera's candidates (classifier feature rows) labelled by the flights both cameras agree on.

    Feed it every step, in order (``add``): the step's result and each camera's scored candidates
    as the classifier saw them (``CameraDetector.last_scored``: positions (N, 2), feature rows
    (N, F)). A flight's frames are kept once it ends (another shot, or no flight) with at least
    ``min_flight_points`` pairs taken; a shorter one's are dropped.

    Two more kinds of rows, from every step: still blobs (``StillBlobs``, ``still_frames``) are
    not the shuttle when they lie far from every report of the flights kept; and a sample of all
    candidates (``rehearsal``, unlabelled) on which the fine-tuning rehearses what the starting
    classifier said of this court.
    """

    # Frames of a still blob between two rows it gives (one light must not outweigh the flights).
    STILL_EVERY = 10
    # Candidate rows of the court kept for rehearsal per camera (a sample of every step's).
    REHEARSAL_ROWS = 20000

    def __init__(self, params: CourtAdaptParams, seed: int = 0) -> None:
        self.params = params
        self._rng = np.random.default_rng(seed)
        self._rows: tuple[list, list] = ([], [])      # (frame, features, labels) of kept flights
        self._still: tuple[list, list] = ([], [])     # (frame, positions, features) of still blobs
        self._reports: tuple[list, list] = ([], [])   # each kept flight pair's report (x, y)
        self._sample: tuple[list, list] = ([], [])    # rehearsal rows, one array per sampled row set
        self._sampled = [0, 0]
        self._stills = (None, None)
        self._flight: list[tuple[int, int, np.ndarray, np.ndarray, tuple[float, float]]] = []
        self._shot = -1
        self._taken = 0                       # pairs of the current flight the filter took
        self._last_t = -math.inf
        self._frame = 0
        self._width = [0, 0]
        self.flights = 0
        self.positives = [0, 0]
        self.negatives = [0, 0]

    def add(self, result: TrackResult, scored: Sequence[tuple[np.ndarray, np.ndarray]]) -> None:
        self._frame += 1
        for cam, res in enumerate((result.left, result.right)):
            self._watch(cam, res.image_size[0], *scored[cam])
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
                self._flight.append((cam, self._frame, *labelled, (res.detection.x, res.detection.y)))

    def _watch(self, cam: int, width: int, positions: np.ndarray, features: np.ndarray) -> None:
        """Every step's candidates: the still ones kept aside, a sample for rehearsal."""
        positions = np.asarray(positions, float).reshape(-1, 2)
        if not len(positions) or width <= 0:
            return
        features = np.asarray(features, float)
        self._width[cam] = width
        # Reservoir sampling of the steps, so the sample spans the whole recording.
        self._sampled[cam] += 1
        room = self.REHEARSAL_ROWS // 10          # steps kept (a step has a few candidates)
        if len(self._sample[cam]) < room:
            self._sample[cam].append(features)
        else:
            j = int(self._rng.integers(self._sampled[cam]))
            if j < room:
                self._sample[cam][j] = features
        if self.params.still_frames <= 0:
            return
        if self._stills[cam] is None:
            stills = list(self._stills)
            stills[cam] = StillBlobs(self.params.still_frames, 3.0 * width / REFERENCE_WIDTH)
            self._stills = tuple(stills)
        counts = self._stills[cam].update(positions, self._frame)
        pick = (counts >= self.params.still_frames) & (counts % self.STILL_EVERY == 0)
        if pick.any():
            self._still[cam].append((self._frame, positions[pick], features[pick]))

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
            for cam, frame, features, labels, report in self._flight:
                self._rows[cam].append((frame, features, labels))
                self._reports[cam].append(report)
                self.positives[cam] += int(np.count_nonzero(labels))
                self.negatives[cam] += int(len(labels) - np.count_nonzero(labels))
            self.flights += 1
        self._flight = []
        self._taken = 0

    def still_rows(self, cam: int) -> tuple[np.ndarray, np.ndarray]:
        """(frames, features) of the still blobs far from every report of the kept flights."""
        if not self._still[cam]:
            return np.zeros(0, int), np.zeros((0, 0))
        frames = np.concatenate([np.full(len(p), f) for f, p, _x in self._still[cam]])
        positions = np.vstack([p for _f, p, _x in self._still[cam]])
        features = np.vstack([x for _f, _p, x in self._still[cam]])
        if self._reports[cam]:
            reports = np.asarray(self._reports[cam], float)
            far = self.params.far_radius * self._width[cam] / REFERENCE_WIDTH
            d = np.hypot(positions[:, None, 0] - reports[None, :, 0], positions[:, None, 1] - reports[None, :, 1])
            keep = d.min(axis=1) >= far
            frames, features = frames[keep], features[keep]
        return frames, features

    def dataset(self, cam: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(features, labels, frames): the flights' labelled rows and the still blobs' (not the
        shuttle), with the step each came from."""
        parts = self._rows[cam]
        still_frames, still = self.still_rows(cam)
        if not parts and not len(still_frames):
            return np.zeros((0, 0)), np.zeros(0, bool), np.zeros(0, int)
        features = [x for _f, x, _y in parts] + ([still] if len(still_frames) else [])
        labels = [y for _f, _x, y in parts] + [np.zeros(len(still_frames), bool)]
        frames = [np.full(len(y), f) for f, _x, y in parts] + [still_frames]
        return np.vstack(features), np.concatenate(labels), np.concatenate(frames).astype(int)

    def features(self, cam: int) -> np.ndarray:
        return self.dataset(cam)[0]

    def labels(self, cam: int) -> np.ndarray:
        return self.dataset(cam)[1]

    def rehearsal(self, cam: int) -> np.ndarray:
        """A sample of every step's candidates of this camera (unlabelled)."""
        return np.vstack(self._sample[cam]) if self._sample[cam] else np.zeros((0, 0))

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


@dataclass(frozen=True)
class HeldBack:
    """How the starting and the fine-tuned classifier score one camera's held-back harvest."""

    rows: int
    loss_before: float        # weighted cross-entropy (as trained)
    loss_after: float
    top_before: float         # of held-back steps with a shuttle row: it scores above the others
    top_after: float
    kept: bool                # the starting classifier kept (the fine-tuned one was not better)


def held_back(frames: np.ndarray) -> np.ndarray:
    """The rows held back to judge the fine-tuning: every fourth block of 50 steps (blocks, so a
    flight's neighbouring frames do not sit on both sides)."""
    return (np.asarray(frames) // 50) % 4 == 3


def _judge(classifier: CandidateClassifier, x: np.ndarray, y: np.ndarray,
           frames: np.ndarray) -> tuple[float, float]:
    """(weighted cross-entropy, share of steps whose shuttle row scores above their other rows)."""
    p = np.clip(classifier.probability(x), 1e-6, 1 - 1e-6)
    w = np.where(y, max((1 - y.mean()) / max(y.mean(), 1e-6), 1.0) ** 0.5, 1.0)
    loss = float(np.sum(-w * (y * np.log(p) + (~y) * np.log(1 - p))) / w.sum())
    wins = total = 0
    for f in np.unique(frames[y]):
        at = frames == f
        if np.count_nonzero(at & ~y):
            total += 1
            wins += int(p[at & y].max() > p[at & ~y].max())
    return loss, (wins / total if total else 1.0)


def fine_tune_camera(classifier: CandidateClassifier, harvest: StereoHarvest, cam: int,
                     should_stop: Callable[[], bool] | None = None, epochs: int = FINE_TUNE_EPOCHS,
                     learning_rate: float = FINE_TUNE_RATE) -> tuple[CandidateClassifier, HeldBack]:
    """One camera's classifier fine-tuned on its harvest (``classifier.fine_tune``), or the
    starting one when the fine-tuned scores worse on the held-back rows (``held_back``).

    The training rows: the harvest's labelled rows not held back, and the sample of the court's
    candidates (``StereoHarvest.rehearsal``) with the starting classifier's probabilities as soft
    targets — what it said of this court's players, lines and lights, so that the steps on the
    flights' rows do not drift on everything else."""
    x, y, frames = harvest.dataset(cam)
    hold = held_back(frames)
    rehearse = harvest.rehearsal(cam)
    if len(rehearse) > harvest.REHEARSAL_ROWS:
        rehearse = rehearse[np.random.default_rng(cam).choice(len(rehearse), harvest.REHEARSAL_ROWS,
                                                             replace=False)]
    train_x = np.vstack([x[~hold]] + ([rehearse] if len(rehearse) else []))
    train_y = np.concatenate([y[~hold].astype(float)]
                             + ([classifier.probability(rehearse)] if len(rehearse) else []))
    if not np.count_nonzero(hold & y) or not np.count_nonzero(hold & ~y):
        # Nothing held back to judge by (a short harvest): keep what is known to work.
        return classifier, HeldBack(int(np.count_nonzero(hold)), math.nan, math.nan, math.nan, math.nan, True)
    tuned = fine_tune(classifier, train_x, train_y, epochs=epochs, learning_rate=learning_rate,
                      name=f"{classifier.name} (adapted)", should_stop=should_stop)
    before = _judge(classifier, x[hold], y[hold], frames[hold])
    after = _judge(tuned, x[hold], y[hold], frames[hold])
    kept = not (after[0] <= before[0] and after[1] >= before[1])
    judged = HeldBack(int(np.count_nonzero(hold)), before[0], after[0], before[1], after[1], kept)
    return (classifier if kept else tuned), judged


def adapt_pair(harvest: StereoHarvest, classifiers: Sequence[CandidateClassifier | None],
               should_stop: Callable[[], bool] | None = None, judged: list | None = None, **training
               ) -> tuple[CandidateClassifier, CandidateClassifier] | None:
    """Each camera's classifier fine-tuned on its harvest (``fine_tune_camera``, ``training`` its
    options; ``judged`` receives each camera's ``HeldBack``), or None when the harvest cannot
    teach (a camera without positives or negatives), a camera has no classifier (the hand-made
    score), or ``should_stop`` said so. A camera whose fine-tuning lost on its held-back rows
    keeps the classifier it had."""
    if not harvest.usable or any(c is None for c in classifiers):
        return None
    try:
        pairs = [fine_tune_camera(classifiers[cam], harvest, cam, should_stop, **training) for cam in (0, 1)]
    except TrainingStopped:
        return None
    if judged is not None:
        judged.extend(h for _c, h in pairs)
    return pairs[0][0], pairs[1][0]


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
                              params: CourtAdaptParams | None = None, judged: list | None = None
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
    return adapt_pair(harvest, [det.classifier for det in detectors], should_stop, judged), harvest

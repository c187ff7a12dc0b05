"""Error census of `detect` on the broadcast clips: why each wrong frame is wrong.

Why this file exists: the accuracy totals say how many frames are wrong, not what to attack.
This runs the one-camera detector in-process (the same chain and look-ahead as `detect`, so the
counts equal accuracy.py's) and gives each FP1 / FP2 / FN frame a cause read from that frame's
candidates and mask at the label:

* ``refused by <filter>``: a candidate lies within the tolerance of the label and a filter
  refused it — ``length`` / ``short_side`` (filters 1, 2), ``whiteness`` (filter 3, or not among
  the blobs measured), ``motion`` (the association: no confirmed, travelling tracklet),
  ``score`` (passed, but another candidate scored higher);
* ``inside a large blob``: the label is foreground of a blob too large for a shuttle (a player,
  or the brighter-than-average mask flooding the court a player left);
* ``not in mask``: nothing brightened at the label (the first frame, a shuttle absorbed);
* ``in mask, no candidate``: foreground there, but no candidate near it;
* FP2: reported while the label says not visible (``one-frame hole in the labels``: a single
  not-visible frame between two visible ones).

    .venv/bin/python benchmarks/broadcast_census.py                       # tuned-on clips, look-ahead 4
    .venv/bin/python benchmarks/broadcast_census.py --lookahead 0 --frames  # online, one line per error
    .venv/bin/python benchmarks/broadcast_census.py --set association.hop_distance=0  # one value changed
    .venv/bin/python benchmarks/broadcast_census.py --lone 0.75   # what association.lone_quality would report
    .venv/bin/python benchmarks/broadcast_census.py --no-adapt   # the shipped classifier, not adapted to each clip
    .venv/bin/python benchmarks/broadcast_census.py --oracle     # the ceiling: candidates scored from the labels
    .venv/bin/python benchmarks/broadcast_census.py --skip-disputed   # without the frames the clips' labels disagree on

Held-out clips are refused unless --held-out is given (they are for the final measurement only).
"""

from __future__ import annotations

import argparse
import collections
import math
import re
import sys
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from badminton_gui.core.adaptation import DEFAULT_MIN_RUN, adapt_to_recording  # noqa: E402
from badminton_gui.core.detector import CameraDetector  # noqa: E402
from badminton_gui.core.evaluation import tolerance_px  # noqa: E402
from badminton_gui.core.lookahead import CameraLookahead  # noqa: E402
from badminton_gui.io.labels import read_point_labels  # noqa: E402
from badminton_gui.io.presets import load_preset  # noqa: E402
from badminton_gui.io.video import VideoFile  # noqa: E402
from clips import DISPUTED_FRAMES, broadcast_clips  # noqa: E402

# px² of mask: a connected foreground region at the label larger than this is "a large blob"
# (a shuttle at 1280 px is at most ~15 × 15 px with the mask's dilation).
LARGE_AREA = 400


class LabelOracle:
    """A classifier that cannot be beaten: it scores each candidate from the labels (``SHUTTLE``
    within the protocol tolerance of a visible label, ``OTHER`` elsewhere and in every frame
    labelled not visible). What the chain scores with it is the ceiling of any classifier on the
    candidates the detector makes — the errors left are the candidates' and the association's,
    not the classifier's. For measuring only: it reads the labels at run time.

    Installed on one detector (``install``, through ``CameraDetector.use_score``, which hands it
    the measured blobs' positions); ``label`` is set before each frame.
    """
    SHUTTLE, OTHER = 0.99, 0.01

    def __init__(self, tol: float):
        self.tol = tol
        self.label: tuple[bool, float, float] = (False, 0.0, 0.0)

    def install(self, det: CameraDetector) -> None:
        det.use_classifier(None)
        det.use_score(self.scores)

    def scores(self, xs: np.ndarray, ys: np.ndarray, lengths: np.ndarray, contrasts: np.ndarray,
               features: np.ndarray) -> np.ndarray:
        """The blobs at (xs, ys) scored from the label of the frame."""
        visible, lx, ly = self.label
        if not visible:
            return np.full(len(xs), self.OTHER)
        return np.where(np.hypot(xs - lx, ys - ly) <= self.tol, self.SHUTTLE, self.OTHER)


def label_cause(det: CameraDetector, result, x: float, y: float, tol: float) -> str:
    """Why the shuttle labelled at (x, y) was not the detection (see the module docstring)."""
    near = [c for c in result.candidates if not c.predicted and math.hypot(c.x - x, c.y - y) <= tol]
    if near:
        # The candidate that came closest to being the detection.
        order = {None: 0, "score": 1, "motion": 2, "whiteness": 3, "short_side": 4, "length": 5}
        best = min(near, key=lambda c: order.get(c.rejected_by, 6))
        return f"refused by {best.rejected_by}" if best.rejected_by else "passed, not reported"
    mask = result.mask
    xi, yi = int(round(x * result.mask_scale)), int(round(y * result.mask_scale))
    h, w = mask.shape
    window = mask[max(yi - 2, 0):yi + 3, max(xi - 2, 0):xi + 3]
    if not (window > 0).any():
        return "not in mask"
    if det.is_merged(x, y):
        return "inside a large blob"
    r = 60
    y0, x0 = max(yi - r, 0), max(xi - r, 0)
    _, lab, stats, _ = cv2.connectedComponentsWithStats(mask[y0:yi + r + 1, x0:xi + r + 1], connectivity=8)
    ids = np.unique(lab[max(yi - 2, 0) - y0:yi + 3 - y0, max(xi - 2, 0) - x0:xi + 3 - x0])
    area = max((int(stats[k, cv2.CC_STAT_AREA]) for k in ids if k > 0), default=0)
    return "inside a large blob" if area > LARGE_AREA else "in mask, no candidate"


def census(clip, preset: str, lookahead: int, frames_out: list[str] | None,
           overrides: tuple[tuple[str, str], ...] = (), transform=None,
           classifier=None, adapt: bool | None = None, oracle: bool = False,
           skip_frames: frozenset[int] = frozenset(), at_rest: frozenset[int] = frozenset()
           ) -> collections.Counter:
    """Outcome counts of one clip, and (outcome, cause) counts of its wrong frames.

    ``transform``: an object with ``frame(image) -> image`` and ``point(x, y) -> (x, y) | None``
    (None: the label leaves the picture) applied to every frame and label first
    (benchmarks/augment.py). ``classifier``: a CandidateClassifier used instead of the preset's
    (a leave-one-clip-out study, ``train_classifier.py --leave-one-out``). ``adapt``: adapt that
    classifier to the clip first as `detect` does (core/adaptation.py); None: as the preset says,
    and never for the live readout (look-ahead 0: the GUI does not adapt). ``oracle``: score the
    candidates from the labels instead (``LabelOracle``; no adaptation). ``skip_frames``: frames
    left out of the counts (counted as ``skipped``: clips.DISPUTED_FRAMES). The in-play outcomes
    are counted too, as ``"in-play TP"`` and so on: every frame but ``at_rest``'s
    (core/evaluation.py ``at_rest_frames``)."""
    params = load_preset(preset).with_value("lookahead.frames", lookahead)
    for path, value in overrides:
        params = params.with_value(path, value)
    if adapt is None:
        adapt = lookahead > 0 and params.classifier.adapt_min_run > 0 and not oracle
    if adapt:
        if params.classifier.adapt_min_run <= 0:
            params = params.with_value("classifier.adapt_min_run", DEFAULT_MIN_RUN)

        def frames():
            video = VideoFile(clip.video)
            try:
                i = 0
                while (image := video.read()) is not None:
                    yield (transform.frame(image) if transform is not None else image), i / video.fps
                    i += 1
            finally:
                video.close()
        adapted, _harvest = adapt_to_recording(params, frames, classifier=classifier)
        classifier = adapted or classifier
    det, la = CameraDetector(params), CameraLookahead(params)
    if classifier is not None:
        det.use_classifier(classifier)
    tol = tolerance_px(1280)
    labels = read_point_labels(clip.labels).as_dict()
    if transform is not None:
        moved = {}
        for f, (visible, x, y) in labels.items():
            xy = transform.point(x, y) if visible else None
            moved[f] = (True, *xy) if xy is not None else (False, 0.0, 0.0)
        labels = moved
    video = VideoFile(clip.video)
    causes: dict[int, str] = {}
    decided = []
    i = 0
    judge = LabelOracle(tol) if oracle else None
    if judge is not None:
        judge.install(det)
    while (frame := video.read()) is not None:
        if transform is not None:
            frame = transform.frame(frame)
        visible, x, y = labels.get(i, (False, 0.0, 0.0))
        if judge is not None:
            judge.label = (visible, x, y)
        res = det.process(frame, i / video.fps, keep_mask=True)
        if visible:
            causes[i] = label_cause(det, res, x, y, tol)
        decided += la.push(dataclass_without_mask(res), i / video.fps)
        i += 1
    decided += la.flush()
    video.close()
    out = collections.Counter()
    for f, (visible, x, y) in sorted(labels.items()):
        if f in skip_frames:
            out["skipped"] += 1
            continue
        d = decided[f].detection if f < len(decided) else None
        if d is None:
            outcome = "FN" if visible else "TN"
        elif not visible:
            outcome = "FP2"
        else:
            outcome = "TP" if math.hypot(d.x - x, d.y - y) <= tol else "FP1"
        out[outcome] += 1
        if f not in at_rest:
            out[f"in-play {outcome}"] += 1
        if outcome in ("TP", "TN"):
            continue
        if visible:
            cause = causes[f]
        elif labels.get(f - 1, (False,))[0] and labels.get(f + 1, (False,))[0]:
            # One frame labelled not visible between two visible ones (bwf_00025 has 22): the
            # shuttle is in the picture on both sides, so this is the labeller's call, not clutter.
            cause = "one-frame hole in the labels"
        else:
            cause = "not labelled visible"
        out[(outcome, cause)] += 1
        if frames_out is not None:
            shown = f"({d.x:.0f}, {d.y:.0f})" if d is not None else "-"
            label = f"({x:.0f}, {y:.0f})" if visible else "-"
            frames_out.append(f"{clip.name:10s} {f:4d} {outcome:3s} label {label:12s} "
                              f"detection {shown:12s} {cause}")
    return out


def lone_candidates(clip, preset: str, quality: float) -> list[tuple[int, str, float]]:
    """The frames in which the online detector, ``association.lone_quality`` off, reports
    nothing while a blob the association refused scores ≥ ``quality``: (frame, where the best
    such blob lies — "at the label", "N px off the label", "nothing labelled" —, its score).
    The measurement behind the broadcast preset's ``lone_quality``."""
    params = (load_preset(preset).with_value("lookahead.frames", 0)
              .with_value("association.lone_quality", 1.0))
    det = CameraDetector(params)
    labels = read_point_labels(clip.labels).as_dict()
    video = VideoFile(clip.video)
    tol = tolerance_px(1280)
    rows = []
    i = 0
    while (frame := video.read()) is not None:
        res = det.process(frame, i / video.fps, keep_mask=False)
        refused = [c for c in res.candidates if c.rejected_by == "motion" and not c.predicted
                   and c.score >= quality]
        if res.detection is None and refused:
            best = max(refused, key=lambda c: c.score)
            visible, x, y = labels.get(i, (False, 0.0, 0.0))
            off = math.hypot(best.x - x, best.y - y)
            where = ("nothing labelled" if not visible else "at the label" if off <= tol
                     else f"{off:.0f} px off the label")
            rows.append((i, where, float(best.score)))
        i += 1
    video.close()
    return rows


def dataclass_without_mask(result):
    """The look-ahead keeps results for K frames: drop the mask (not needed there)."""
    import dataclasses
    return dataclasses.replace(result, mask=None)


def accuracy_of(total: collections.Counter) -> float:
    n = sum(total[k] for k in ("TP", "TN", "FP1", "FP2", "FN"))
    return (total["TP"] + total["TN"]) / n if n else 0.0


def summary(total: collections.Counter) -> str:
    n = sum(total[k] for k in ("TP", "TN", "FP1", "FP2", "FN"))
    return (f"{n} frames, accuracy {accuracy_of(total):.4f}  (TP {total['TP']} TN {total['TN']} "
            f"FP1 {total['FP1']} FP2 {total['FP2']} FN {total['FN']})")


def main() -> int:
    ap = argparse.ArgumentParser(description="why each wrong broadcast frame is wrong")
    ap.add_argument("--only", default=None, help="regex on clip names (default: the tuned-on clips)")
    ap.add_argument("--held-out", action="store_true", help="allow held-out clips (final measurement only)")
    ap.add_argument("--preset", default="broadcast", help="preset name or .json")
    ap.add_argument("--lookahead", type=int, default=4, help="frames of look-ahead (0 = online)")
    ap.add_argument("--frames", action="store_true", help="also print one line per wrong frame")
    ap.add_argument("--adapt", action=argparse.BooleanOptionalAction, default=None,
                    help="adapt the classifier to each clip first (default: as `detect`, the preset's "
                         "classifier.adapt_min_run, never with --lookahead 0)")
    ap.add_argument("--lone", type=float, default=None, metavar="Q",
                    help="instead: the frames with no report where a refused blob scores >= Q "
                         "(online, lone_quality off), and where that blob lies")
    ap.add_argument("--oracle", action="store_true",
                    help="score the candidates from the labels (a perfect classifier): the ceiling "
                         "the candidates and the association leave")
    ap.add_argument("--skip-disputed", action="store_true",
                    help="leave out the frames whose labels contradict another clip's "
                         "(clips.DISPUTED_FRAMES: a held serve labelled both ways)")
    ap.add_argument("--set", action="append", default=[], metavar="GROUP.NAME=VALUE",
                    help="override one preset value (repeatable), e.g. association.hop_distance=25")
    args = ap.parse_args()
    overrides = tuple(tuple(s.split("=", 1)) for s in args.set)
    clips = [c for c in broadcast_clips() if args.held_out or not c.held_out]
    if args.only:
        clips = [c for c in clips if re.search(args.only, c.name)]
    if not clips:
        print("no clips (held-out clips need --held-out)")
        return 1
    if args.lone is not None:
        where: collections.Counter = collections.Counter()
        for clip in clips:
            for frame, place, score in lone_candidates(clip, args.preset, args.lone):
                print(f"{clip.name:10s} {frame:4d}  score {score:.3f}  {place}")
                where["at the label" if place == "at the label" else
                      "nothing labelled" if place == "nothing labelled" else "off the label"] += 1
        print(f"frames with no report and a refused blob scoring >= {args.lone}: {sum(where.values())} "
              f"({', '.join(f'{k} {v}' for k, v in where.most_common())})")
        return 0
    total = collections.Counter()
    lines: list[str] | None = [] if args.frames else None
    per_clip = []
    for clip in clips:
        counts = census(clip, args.preset, args.lookahead, lines, overrides, adapt=args.adapt,
                        oracle=args.oracle, skip_frames=DISPUTED_FRAMES.get(clip.name, frozenset())
                        if args.skip_disputed else frozenset())
        per_clip.append(f"{clip.name} {summary(counts)}")
        total += counts
    if lines:
        print("\n".join(lines))
        print()
    print(f"{', '.join(c.name for c in clips)}: {summary(total)}")
    if len(clips) > 1:
        print("  per clip: " + "; ".join(per_clip))
    rows = sorted(((k, v) for k, v in total.items() if isinstance(k, tuple)), key=lambda kv: -kv[1])
    for (outcome, cause), count in rows:
        print(f"  {count:4d}  {outcome:3s}  {cause}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

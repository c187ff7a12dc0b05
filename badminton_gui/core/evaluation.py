"""The five-outcome evaluation protocol of TrackNet, so figures compare with the literature.

Why this file exists: `badminton-track eval`, the accuracy benchmark and the tests must count
TP / TN / FP1 / FP2 / FN the same way. Every labelled frame is one outcome:
TP (detected, labelled, within tolerance), FP1 (detected, labelled, too far), FP2 (detected, not
labelled), FN (labelled, not detected), TN (neither). The tolerance is 4 px at 512 px width,
scaled with the image width (10 px at 1280, 16 px at 2048).

Beside it, the *in-play* score (:func:`at_rest_frames`): the product reports the shuttle from its
first motion at the serve until it comes to rest after landing, not a shuttle held before the
serve or lying after the rally. Label files differ on those frames (a held serve is labelled
visible in one clip and not in another), so a figure that leaves them out is given beside the
protocol's, never instead of it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

REFERENCE_WIDTH = 512.0
DEFAULT_TOLERANCE = 4.0


def tolerance_px(image_width: int, tolerance_at_512: float = DEFAULT_TOLERANCE) -> float:
    return tolerance_at_512 * image_width / REFERENCE_WIDTH


@dataclass(frozen=True, slots=True)
class Outcomes:
    tp: int = 0
    tn: int = 0
    fp1: int = 0
    fp2: int = 0
    fn: int = 0

    @property
    def total(self) -> int:
        return self.tp + self.tn + self.fp1 + self.fp2 + self.fn

    @property
    def accuracy(self) -> float:
        return (self.tp + self.tn) / self.total if self.total else float("nan")

    @property
    def precision(self) -> float:
        d = self.tp + self.fp1 + self.fp2
        return self.tp / d if d else float("nan")

    @property
    def recall(self) -> float:
        d = self.tp + self.fn
        return self.tp / d if d else float("nan")

    @property
    def f1(self) -> float:
        p, r = self.precision, self.recall
        return 2 * p * r / (p + r) if (p + r) > 0 else float("nan")

    def __add__(self, other: "Outcomes") -> "Outcomes":
        return Outcomes(self.tp + other.tp, self.tn + other.tn, self.fp1 + other.fp1,
                        self.fp2 + other.fp2, self.fn + other.fn)

    def summary(self) -> str:
        return (f"TP {self.tp}  TN {self.tn}  FP1 {self.fp1}  FP2 {self.fp2}  FN {self.fn}  "
                f"accuracy {self.accuracy:.4f}  precision {self.precision:.4f}  "
                f"recall {self.recall:.4f}  F1 {self.f1:.4f}")


def classify(pred_visible: np.ndarray, pred_xy: np.ndarray, label_visible: np.ndarray,
             label_xy: np.ndarray, tolerance: float) -> np.ndarray:
    """Per-frame outcome codes ('TP', 'TN', 'FP1', 'FP2', 'FN') for aligned arrays."""
    pv = np.asarray(pred_visible, dtype=bool)
    lv = np.asarray(label_visible, dtype=bool)
    dist = np.hypot(*(np.asarray(pred_xy, float) - np.asarray(label_xy, float)).T)
    out = np.full(len(pv), "TN", dtype="<U3")
    out[pv & lv & (dist <= tolerance)] = "TP"
    out[pv & lv & ~(dist <= tolerance)] = "FP1"
    out[pv & ~lv] = "FP2"
    out[~pv & lv] = "FN"
    return out


def evaluate(pred: dict[int, tuple[bool, float, float]], labels: dict[int, tuple[bool, float, float]],
             tolerance: float) -> Outcomes:
    """Count outcomes over the labelled frames; a labelled frame with no prediction is 'not detected'."""
    frames = sorted(labels)
    pv = np.array([pred.get(f, (False, np.nan, np.nan))[0] for f in frames], dtype=bool)
    pxy = np.array([pred.get(f, (False, np.nan, np.nan))[1:] for f in frames], dtype=float).reshape(-1, 2)
    lv = np.array([labels[f][0] for f in frames], dtype=bool)
    lxy = np.array([labels[f][1:] for f in frames], dtype=float).reshape(-1, 2)
    codes = classify(pv, pxy, lv, lxy, tolerance)
    return Outcomes(tp=int((codes == "TP").sum()), tn=int((codes == "TN").sum()),
                    fp1=int((codes == "FP1").sum()), fp2=int((codes == "FP2").sum()),
                    fn=int((codes == "FN").sum()))


# "Still": the labelled shuttle moves less than this many px (at 512 px width, scaled like the
# tolerance) over STILL_WINDOW s. Labels carry no world scale, so stillness is judged in the
# image: a shuttle in flight crosses far more than this in 0.1 s, a held or lying one moves by
# the labeller's click jitter.
STILL_AT_512 = 3.0
STILL_WINDOW = 0.1
# A shuttle that stopped stays in play this long (it comes to rest after landing); still longer,
# it is at rest.
REST_AFTER = 0.5


def _still(times: np.ndarray, xy: np.ndarray, limit: float) -> tuple[np.ndarray, np.ndarray]:
    """(still, known) per visible frame: whether the labelled shuttle moves less than ``limit``
    px in STILL_WINDOW s, from the median position over the STILL_WINDOW s before the frame to the
    median over the STILL_WINDOW s after it (medians: a label's click jitter is a px or two a
    frame), scaled to the window where the clip's edge or a gap shortens one side (at most
    doubled). Seen over less than half the window, a frame is neither still nor moving: not
    ``known``."""
    still = np.zeros(len(times), dtype=bool)
    known = np.zeros(len(times), dtype=bool)
    lo = np.searchsorted(times, times - STILL_WINDOW, side="left")
    hi = np.searchsorted(times, times + STILL_WINDOW, side="right")
    for k in range(len(times)):
        if times[hi[k] - 1] - times[lo[k]] < STILL_WINDOW / 2:
            continue
        known[k] = True
        before, after = slice(lo[k], k + 1), slice(k, hi[k])
        moved = np.hypot(*(np.median(xy[after], axis=0) - np.median(xy[before], axis=0)))
        apart = np.median(times[after]) - np.median(times[before])
        still[k] = bool(moved * STILL_WINDOW / max(apart, STILL_WINDOW / 2) < limit)
    return still, known


def at_rest_frames(labels: dict[int, tuple[bool, float, float]], image_width: int,
                   times: dict[int, float] | None = None, fps: float = 30.0) -> frozenset[int]:
    """The labelled-visible frames whose shuttle is at rest: still before its first motion, or
    still for more than REST_AFTER s after it stopped. ``times``: frame -> seconds (default
    frame / ``fps``). A still stretch ends where the shuttle moves, or reappears more than the
    still limit away after frames without a label (picked up out of view); frames labelled not
    visible are never at rest (they score as they are)."""
    frames = np.array(sorted(f for f, (visible, _x, _y) in labels.items() if visible), dtype=np.int64)
    if len(frames) == 0:
        return frozenset()
    t = np.array([times[f] if times is not None and f in times else f / fps for f in frames], float)
    xy = np.array([labels[f][1:] for f in frames], dtype=float).reshape(-1, 2)
    limit = tolerance_px(image_width, STILL_AT_512)
    still, known = _still(t, xy, limit)
    moving = np.flatnonzero(known & ~still)
    first_motion = t[moving[0]] if len(moving) else math.inf
    rest: list[int] = []
    start = None
    for k in range(len(frames)):
        if not still[k]:
            start = None
            continue
        if start is None or np.hypot(*(xy[k] - xy[k - 1])) >= limit:
            start = k
        if t[start] < first_motion or t[k] - t[start] > REST_AFTER:
            rest.append(int(frames[k]))
    return frozenset(rest)


def in_play(labels: dict[int, tuple[bool, float, float]], rest: frozenset[int]
            ) -> dict[int, tuple[bool, float, float]]:
    """``labels`` without the frames at rest (:func:`at_rest_frames`): what the in-play score
    counts."""
    return {f: v for f, v in labels.items() if f not in rest}


# One camera's truth for one frame: (visible, x, y) in full-resolution pixels; None: the frame
# has no label (outside a label file's rows), so it is not scored.
Label = tuple[bool, float, float]


def classify_one(detected: bool, x: float, y: float, label: Label, tolerance: float) -> str:
    """One frame's outcome ('TP', 'TN', 'FP1', 'FP2', 'FN'): :func:`classify` without arrays,
    for the live score (a call per camera and frame on the tracking thread)."""
    visible, lx, ly = label
    if detected:
        if not visible:
            return "FP2"
        return "TP" if math.hypot(x - lx, y - ly) <= tolerance else "FP1"
    return "FN" if visible else "TN"


class LiveScore:
    """The readout scored frame by frame against a known truth, both cameras, since a reset.

    Why: an operator tuning the filters on a labelled recording (or on the demo court, whose
    truth is exact) sees at once what a slider did, in the same protocol as the benchmarks,
    instead of judging by eye. The owner resets it when the parameters change, so the figure
    always belongs to the settings on screen.
    """

    def __init__(self, image_width: int) -> None:
        self.tolerance = tolerance_px(image_width)
        self._counts = [dict.fromkeys(("TP", "TN", "FP1", "FP2", "FN"), 0) for _ in range(2)]

    def reset(self) -> None:
        for counts in self._counts:
            for key in counts:
                counts[key] = 0

    def add(self, camera: int, detection, label: Label | None) -> str | None:
        """Score one camera's report (a Candidate or None) against its label; None: unlabelled."""
        if label is None:
            return None
        found = detection is not None
        code = classify_one(found, detection.x if found else 0.0, detection.y if found else 0.0,
                            label, self.tolerance)
        self._counts[camera][code] += 1
        return code

    def outcomes(self, camera: int) -> Outcomes:
        c = self._counts[camera]
        return Outcomes(tp=c["TP"], tn=c["TN"], fp1=c["FP1"], fp2=c["FP2"], fn=c["FN"])

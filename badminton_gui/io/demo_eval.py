"""Ground-truth evaluation of the tracker on the demo court.

Why this file exists: the demo court knows exactly where the shuttle is, in 3D and in both
images, so it measures the whole pipeline (detection, stereo, triangulation) without labels.
The tests run it on a few hundred frames; ``benchmarks/demo_accuracy.py`` on 1000 frames × 3
seeds for the figures in the closing notes. ``delayed_right_errors`` plays the court to a rig
whose right camera is not triggered with the left (a free-running pair).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable

import cv2
import numpy as np

from ..core.evaluation import Outcomes, classify, tolerance_px
from ..core.params import TrackerParams
from ..core.track_lookahead import StereoLookahead
from ..core.tracker import StereoTracker
from ..core.types import StereoFrame
from .demo_scene import DemoScene


@dataclass(frozen=True, slots=True)
class DemoScore:
    left: Outcomes
    right: Outcomes
    errors_3d: np.ndarray       # (N,) metres, frames with a 3D point and a truth position
    ranges: np.ndarray          # (N,) distance of the truth from the left camera, metres
    pairs_per_s: float

    def rms_3d(self, max_range: float | None = None) -> float:
        sel = self.errors_3d if max_range is None else self.errors_3d[self.ranges <= max_range]
        return float(np.sqrt(np.mean(sel ** 2))) if len(sel) else float("nan")

    def median_3d(self, max_range: float | None = None) -> float:
        sel = self.errors_3d if max_range is None else self.errors_3d[self.ranges <= max_range]
        return float(np.median(sel)) if len(sel) else float("nan")


def _count(codes: np.ndarray) -> Outcomes:
    return Outcomes(tp=int((codes == "TP").sum()), tn=int((codes == "TN").sum()),
                    fp1=int((codes == "FP1").sum()), fp2=int((codes == "FP2").sum()),
                    fn=int((codes == "FN").sum()))


def evaluate_demo(seed: int = 0, frames: int = 1000, size: tuple[int, int] = (1280, 720),
                  rig: str = "binocular", params: TrackerParams | None = None,
                  warmup: int = 0,
                  on_frame: Callable[[object, object, tuple[str, str]], None] | None = None,
                  lookahead: int | None = None, classifiers: tuple | None = None) -> DemoScore:
    """Track ``frames`` demo frames and score them against the scene's truth.

    ``on_frame(result, truth, (code_left, code_right))`` is called for every scored frame
    (the per-frame error listing of ``benchmarks/demo_accuracy.py --errors``). ``lookahead``:
    frames of look-ahead of the scored readout (core/lookahead.py; None: ``params``' own).
    ``classifiers``: (left, right) candidate classifiers instead of the preset's (one adapted to
    the court, ``core/court_adaptation.py``).
    """
    ks = (None,) if lookahead is None else (lookahead,)
    return evaluate_demo_lookaheads(seed, frames, size, rig, params, warmup, on_frame, ks, classifiers)[ks[0]]


def evaluate_demo_lookaheads(seed: int = 0, frames: int = 1000, size: tuple[int, int] = (1280, 720),
                             rig: str = "binocular", params: TrackerParams | None = None,
                             warmup: int = 0,
                             on_frame: Callable[[object, object, tuple[str, str]], None] | None = None,
                             lookaheads: tuple[int | None, ...] = (0,),
                             classifiers: tuple | None = None) -> dict:
    """One tracking run scored with several look-aheads: {K: DemoScore} (the readout is only
    post-processed, so each K gives what a run with that K would). ``on_frame`` sees the first K's
    readout.
    """
    import time

    params = params or TrackerParams()
    scene = DemoScene(seed=seed, size=size, rig=rig, n_frames=frames + warmup)
    tracker = StereoTracker(scene.rig, params)
    if classifiers is not None:
        tracker.left.use_classifier(classifiers[0])
        tracker.right.use_classifier(classifiers[1])
    delays = {k: StereoLookahead(scene.rig, params if k is None else params.with_value("lookahead.frames", k),
                                 tracker.epipolar_tolerance) for k in lookaheads}
    tol = tolerance_px(size[0])
    codes = {k: {0: [], 1: []} for k in lookaheads}
    errors = {k: [] for k in lookaheads}
    ranges = {k: [] for k in lookaheads}
    centre_left = scene.rig.camera_centres()[0]
    elapsed = 0.0

    def score(k, result) -> None:
        if result.index < warmup:
            return
        truth = scene.truth(result.index)
        for cam, res, vis, uv in ((0, result.left, truth.visible_left, truth.uv_left),
                                  (1, result.right, truth.visible_right, truth.uv_right)):
            d = res.detection
            codes[k][cam].append(classify(np.array([d is not None]),
                                          np.array([[d.x, d.y] if d else [np.nan, np.nan]]),
                                          np.array([bool(vis)]),
                                          np.array([uv if (vis and uv) else [np.nan, np.nan]]),
                                          tol)[0])
        if on_frame is not None and k == lookaheads[0]:
            on_frame(result, truth, (codes[k][0][-1], codes[k][1][-1]))
        if result.point is not None and truth.position is not None:
            errors[k].append(float(np.linalg.norm(np.subtract(result.point, truth.position))))
            ranges[k].append(float(np.linalg.norm(np.subtract(truth.position, centre_left))))

    try:
        while True:
            frame = scene.read()
            if frame is None:
                break
            start = time.perf_counter()
            result = tracker.process_frame(frame, keep_masks=False)
            elapsed += time.perf_counter() - start
            for k, delay in delays.items():
                for decided in delay.push(result):
                    score(k, decided)
        for k, delay in delays.items():
            for decided in delay.flush():
                score(k, decided)
    finally:
        tracker.close()
        scene.close()
    out = {}
    for k in lookaheads:
        n = len(codes[k][0])
        out[k] = DemoScore(_count(np.array(codes[k][0])), _count(np.array(codes[k][1])),
                           np.asarray(errors[k]), np.asarray(ranges[k]), n / max(elapsed, 1e-9))
    return out


class _DelayedScene(DemoScene):
    """The demo court seen ``lag`` seconds earlier: the right camera of a rig whose cameras are
    not triggered together (frame i of this scene is taken at i / fps − lag)."""

    def __init__(self, lag: float, **kwargs) -> None:
        self._lag = float(lag)
        super().__init__(**kwargs)

    def time_of(self, index: int) -> float:
        return max(super().time_of(index) - self._lag, 0.0)


def delayed_right_errors(lag: float, frames: int = 400, seed: int = 3,
                         params: TrackerParams | None = None,
                         size: tuple[int, int] = (1280, 720)) -> tuple[np.ndarray, np.ndarray]:
    """3D errors (m) on the demo court when each right image is taken ``lag`` s before its left
    one (free-running cameras): (the measured triangulations, the reported points), over the
    frames that have one and a shuttle in play. Truth is the shuttle at the left image's time,
    the time every step carries."""
    params = params or TrackerParams()
    kwargs = dict(seed=seed, size=size, rig="binocular", n_frames=frames)
    left_scene, right_scene = DemoScene(**kwargs), _DelayedScene(lag, **kwargs)
    tracker = StereoTracker(left_scene.rig, params)
    measured, reported = [], []
    try:
        # Frame 0 would put the right image before the rally's start: begin at frame 1.
        for i in range(1, frames):
            frame = StereoFrame(left_scene.render(i)[0], right_scene.render(i)[1],
                                left_scene.time_of(i), right_scene.time_of(i), i, i)
            result = tracker.process_frame(frame, keep_masks=False)
            truth = left_scene.truth(i).position
            if truth is None:
                continue
            if result.measured_point is not None:
                measured.append(float(np.linalg.norm(np.subtract(result.measured_point, truth))))
            if result.point is not None:
                reported.append(float(np.linalg.norm(np.subtract(result.point, truth))))
    finally:
        tracker.close()
    return np.array(measured), np.array(reported)


# A free-running rig that drops frames (launcher-stereo's right camera lost 54 of 567): every 7th
# left image missing (right-only steps), four right images missing (left-only steps).
DROP_LEFT_EVERY = 7
DROP_RIGHT = frozenset({40, 90, 150, 220})


def dropped_frame_steps(scene: DemoScene, frames: int, drop_left: frozenset | set | None = None,
                        drop_right: frozenset | set = DROP_RIGHT):
    """The demo court's steps as a source whose cameras drop frames would deliver them
    (``io/video.py`` ``pairing_schedule``): a frame one camera dropped is a step that brings the
    other camera's image only, beside the last image of the camera that dropped it."""
    if drop_left is None:
        drop_left = set(range(DROP_LEFT_EVERY, frames, DROP_LEFT_EVERY))
    last = {}
    for i in range(frames):
        left, right = scene.render(i)
        t = scene.time_of(i)
        if i in drop_left and "left" in last:
            li, lt, limg = last["left"]
            yield StereoFrame(limg, right, lt, t, li, i, False, True)
            last["right"] = (i, t, right)
        elif i in drop_right and "right" in last:
            ri, rt, rimg = last["right"]
            yield StereoFrame(left, rimg, t, rt, i, ri, True, False)
            last["left"] = (i, t, left)
        else:
            yield StereoFrame(left, right, t, t, i, i)
            last["left"], last["right"] = (i, t, left), (i, t, right)


def dropped_frame_errors(params: TrackerParams | None = None, frames: int = 300, seed: int = 3,
                         size: tuple[int, int] = (1280, 720), rig_error_deg: float = 0.0
                         ) -> tuple[np.ndarray, np.ndarray, int]:
    """3D errors (m) of the reported points on the demo court when the cameras drop frames
    (``dropped_frame_steps``): (on the steps of two images, on the steps of one image, how many
    one-image steps had the shuttle in play). Truth is the shuttle at each step's new image.
    ``rig_error_deg``: the tracker's rig has the right camera tilted by this much about its
    horizontal axis against the cameras that filmed: a rough calibration (as the NYCU rig's),
    whose two rays to the shuttle miss each other."""
    params = params or TrackerParams()
    scene = DemoScene(seed=seed, size=size, rig="binocular", n_frames=frames)
    rig = scene.rig
    if rig_error_deg:
        turn = cv2.Rodrigues(np.array([np.radians(rig_error_deg), 0.0, 0.0]))[0]
        rig = dataclasses.replace(rig, R=turn @ rig.R, _cache={})
    tracker = StereoTracker(rig, params, parallel=False)
    pairs, alone, alone_in_play = [], [], 0
    try:
        for step in dropped_frame_steps(scene, frames):
            result = tracker.process_frame(step, keep_masks=False)
            both = step.fresh_left and step.fresh_right
            truth = scene.truth(step.index if step.fresh_left else step.index_right).position
            if truth is None:
                continue
            alone_in_play += not both
            if result.point is not None:
                (pairs if both else alone).append(float(np.linalg.norm(np.subtract(result.point, truth))))
    finally:
        tracker.close()
        scene.close()
    return np.array(pairs), np.array(alone), alone_in_play

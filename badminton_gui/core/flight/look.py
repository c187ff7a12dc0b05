"""Where the 3D flight projects in a camera's image: the guided look, the coast on the flight,
and the shuttle leaving a camera's view.

Why this file exists: a camera that lost the shuttle (hidden, dim, merged with a player, its
track slid onto clutter) can find it again where the followed flight projects
(``stereo.guided_search``), or report that projection while its mask cannot show it
(``stereo.guided_coast``); and a detection at the image's border, or a weak lone one, is no
shuttle when the flight has already left that camera's view (``stereo.exit_margin``,
``stereo.out_of_view_weak``). All of them project the flight into one camera: that is this stage.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from collections.abc import Callable

from ..detector import CameraDetector
from ..guided import find_spot, white_near
from ..params import TrackerParams
from ..rig import StereoRig
from ..step import Step
from ..stereo.look import ImagePaths
from ..types import REJECT_STEREO, CameraResult, Candidate

# px at 1280 px width: how near the flight's projection a white pixel must show for a shuttle
# merged with a larger blob (wider, a shoulder's edge next to a hidden cork passed on the demo).
MERGED_WHITE_RADIUS = 2.0
# px at 1280 px width: how near an unpaired detection at the border the flight's projection
# outside the image must lie for the detection to be taken as the shuttle leaving (``gone_out``).
EXIT_NEAR = 20.0

Guide = tuple[np.ndarray, np.ndarray]   # the flight's (position, covariance) at a time, court frame


class FlightLook:
    """Projects the followed flight into each camera; keeps no state."""

    def __init__(self, rig: StereoRig, params: TrackerParams,
                 detectors: tuple[CameraDetector, CameraDetector]) -> None:
        self.rig = rig
        self.params = params
        self.detectors = detectors

    def _projection(self, camera: int, position: np.ndarray) -> tuple[float, float] | None:
        """Where ``position`` (court frame) projects in ``camera``, None when behind it."""
        if float(self.rig.depth(camera, position[None])[0]) <= 0.1:
            return None
        u, v = (float(c) for c in self.rig.project(camera, position[None])[0])
        return u, v

    def weak_lone(self, detection: Candidate | None, paired: bool) -> bool:
        """A detection with no stereo partner scoring below ``stereo.guided_weak_score``: the
        guided look may replace it by a spot at the flight's projection (a confirmed track
        followed with its hysteresis scores ≥ ~3 on the demo court; one that slid onto a player
        after the shuttle's own track was lost, 0.2–2)."""
        sp = self.params.stereo
        return (not paired and sp.guided_weak_score > 0 and detection is not None
                and not detection.predicted and detection.score < sp.guided_weak_score)

    def guided(self, camera: int, frame: np.ndarray, previous: np.ndarray | None,
               detection: Candidate | None, guide: Guide, override: bool = False) -> Candidate | None:
        """A spot found where the flight projects, when this camera's detection is not there
        (a detection is looked past with ``guided_override``, or ``override``: a weak one).
        ``previous``: this camera's last image."""
        sp = self.params.stereo
        position, covariance = guide
        depth = float(self.rig.depth(camera, position[None])[0])
        if depth <= 0.1:
            return None
        u, v = self.rig.project(camera, position[None])[0]
        h, w = frame.shape[:2]
        if not (0 <= u < w and 0 <= v < h):
            return None
        focal = float((self.rig.M1 if camera == 0 else self.rig.M2)[0, 0])
        sigma_px = focal * math.sqrt(max(float(np.trace(covariance)) / 3.0, 0.0)) / depth
        radius = min(3.0 * sigma_px + 3.0 * w / 1280.0, 0.02 * w)
        if detection is not None and (not (sp.guided_override or override)
                                      or math.hypot(detection.x - u, detection.y - v) <= radius):
            return None
        skirt_px = focal * 0.065 / depth            # a shuttle's skirt is 6.5 cm across
        max_area = 4.0 * skirt_px * skirt_px + 12.0
        spot = find_spot(frame, u, v, radius, sp.guided_min_contrast, max_area, previous)
        if spot is None:
            return None
        x, y, contrast, area = spot
        return Candidate(x=x, y=y, length=float("nan"), short_side=float("nan"), whiteness=contrast,
                         area=area, motion=math.hypot(x - u, y - v), score=0.0)

    def coast(self, camera: int, frame: np.ndarray, result: CameraResult,
              detection: Candidate | None, guide: Guide) -> tuple[CameraResult, Candidate | None]:
        """Where the 3D flight projects, for a camera that cannot see the shuttle there.

        A camera's own coasting (``motion.coast_blind``) carries its tracklet on a straight image
        path at constant speed; the 3D flight (drag and gravity, fed by both cameras) knows the
        curve, so a coasting prediction is moved to the flight's projection. A camera with no
        detection at all whose flight projection lies in its blind spot (a light, a white line:
        the mask cannot show the shuttle there) reports that projection too — the followed
        tracklet may have been taken by clutter, or the blind stretch outlasted ``coast_blind``
        — and so does one whose projection falls on a blob too large for a shuttle where a white
        pixel shows (``stereo.guided_merged``: the shuttle crossing a player's arm or a racket
        merges with it; one hidden behind the player shows no white). Both are flagged
        ``predicted`` (never triangulated); a projection outside the image, or on plain
        background with no detection, gives nothing (nothing is invented where the detector
        could have seen the shuttle).
        """
        if detection is not None and not detection.predicted:
            return result, detection
        at = self._projection(camera, guide[0])
        if at is None:
            return result, detection
        u, v = at
        w, h = result.image_size
        if not (0 <= u < w and 0 <= v < h):
            return result, detection
        detector = self.detectors[camera]
        if detection is None:
            sp = self.params.stereo
            merged = (sp.guided_merged and detector.is_merged(u, v)
                      and white_near(frame, u, v, MERGED_WHITE_RADIUS * w / 1280.0, sp.guided_min_contrast))
            if not (merged or detector.is_blind(u, v)):
                return result, None
            moved = Candidate(u, v, math.nan, math.nan, math.nan, math.nan, 0.0, 0.0, None, predicted=True)
            return dataclasses.replace(result, candidates=result.candidates + (moved,)), moved
        moved = dataclasses.replace(detection, x=u, y=v)
        candidates = tuple(moved if c is detection else c for c in result.candidates)
        return dataclasses.replace(result, candidates=candidates), moved

    def out_of_view(self, camera: int, frame: np.ndarray, position: np.ndarray) -> bool:
        """The 3D flight's position projects outside this camera's image (or behind it)."""
        at = self._projection(camera, position)
        if at is None:
            return True
        h, w = frame.shape[:2]
        return not (0 <= at[0] < w and 0 <= at[1] < h)

    def near_border(self, detection: Candidate | None, frame: np.ndarray) -> bool:
        """The detection lies within ``stereo.exit_margin`` px of the image's border."""
        m = float(self.params.stereo.exit_margin)
        if detection is None or m <= 0:
            return False
        h, w = frame.shape[:2]
        return min(detection.x, detection.y, w - 1 - detection.x, h - 1 - detection.y) <= m

    def gone_out(self, camera: int, detection: Candidate, frame: np.ndarray, position: np.ndarray) -> bool:
        """The 3D flight puts the shuttle outside this camera's image, just past the unpaired
        detection at its border (within ``EXIT_NEAR`` px): the blob is the skirt's end, clipped
        by the border, or a prediction coasting out; the cork itself is out of view."""
        at = self._projection(camera, position)
        if at is None:
            return False
        u, v = at
        h, w = frame.shape[:2]
        if 0 <= u < w and 0 <= v < h:
            return False
        return math.hypot(detection.x - u, detection.y - v) <= EXIT_NEAR * w / 1280.0

    # ---- the stage: one step's look and exits ----------------------------------------------
    def look(self, step: Step, previous: list[np.ndarray | None],
             pair_point: Callable[[Candidate | None, Candidate | None], tuple]) -> None:
        """A pair step's guided look (``stereo.guided_search``, ``guided_coast``) for a camera with
        no detection, or a weak lone one (the flight's RK4 prediction is skipped when both cameras
        have a sure one); a spot found re-pairs the two reports (``pair_point``). ``previous``:
        each camera's last image."""
        sp = self.params.stereo
        unseen = [det is None or det.predicted for det in step.dets]
        weak = [self.weak_lone(det, step.point is not None) for det in step.dets]
        if not (sp.guided_search and (sp.guided_override or any(unseen) or any(weak))):
            return
        guide = step.guide.get()
        if guide is None:
            return
        found = [self.guided(cam, step.frames[cam], previous[cam], step.dets[cam], guide, weak[cam])
                 for cam in (0, 1)]
        if found[0] is not None or found[1] is not None:
            for cam in (0, 1):
                if found[cam] is not None:
                    step.add(cam, found[cam])
                    step.fired("guided_search", cam)
            step.point, step.epi = pair_point(step.dets[0], step.dets[1])
        if sp.guided_coast:
            for cam in (0, 1):
                self._coast_step(step, cam, guide)

    def look_one(self, step: Step, cam: int, previous: np.ndarray | None) -> None:
        """``look`` for a step with camera ``cam``'s image only (no pair to re-make)."""
        sp = self.params.stereo
        det = step.dets[cam]
        weak = self.weak_lone(det, False)
        if not (sp.guided_search and (det is None or det.predicted or weak)):
            return
        guide = step.guide.get()
        if guide is None:
            return
        found = self.guided(cam, step.frames[cam], previous, det, guide, weak)
        if found is not None:
            step.add(cam, found)
            step.fired("guided_search", cam)
        if sp.guided_coast:
            self._coast_step(step, cam, guide)

    def _coast_step(self, step: Step, cam: int, guide: Guide) -> None:
        before = step.dets[cam]
        step.results[cam], step.dets[cam] = self.coast(cam, step.frames[cam], step.results[cam], before, guide)
        if step.dets[cam] is not before:
            step.fired("guided_coast", cam)

    def exits(self, step: Step, paths: ImagePaths, cameras: tuple[int, ...] = (0, 1)) -> None:
        """No report where the shuttle has left the camera's view: a detection at the border
        (its clipped skirt: a pair made with it is biased too), or a weak lone one while the
        flight is out of this camera's view (``stereo.exit_margin``, ``exit_by_path``,
        ``out_of_view_weak``)."""
        sp = self.params.stereo
        if not (sp.exit_margin > 0 or (sp.out_of_view_weak and step.point is None)):
            return
        for cam in cameras:
            det, frame = step.dets[cam], step.frames[cam]
            border = self.near_border(det, frame) and (step.point is None or sp.exit_by_path)
            weak_now = sp.out_of_view_weak and self.weak_lone(det, step.point is not None)
            if not (border or weak_now):
                continue
            guide = step.guide.get()
            if ((border and sp.exit_by_path and paths.leaves(cam, frame, step.t))
                    or (guide is not None
                        and ((border and self.gone_out(cam, det, frame, guide[0]))
                             or (weak_now and self.out_of_view(cam, frame, guide[0]))))):
                step.dets[cam] = None
                # Marked as the two-camera rules' refusal: left unmarked, the step's end labelled
                # it "score" (another candidate better), which the overlay then showed.
                step.results[cam] = dataclasses.replace(step.results[cam], candidates=tuple(
                    dataclasses.replace(c, rejected_by=REJECT_STEREO) if c is det else c
                    for c in step.results[cam].candidates))
                step.point, step.epi = None, None
                step.fired("exit", cam)

"""One camera's line of sight: the flight moved by a camera that alone sees the shuttle.

Why this file exists: when one camera sees the shuttle and the other not (hidden, merged with a
player, lost by its detector, or its readout on something else), that camera's line of sight
still moves the 3D flight, so the robot keeps a 3D point (``stereo.one_camera_rays``), and the
camera that lost it shows the flight's projection where its image shows something there
(``stereo.guided_other``). A rig whose cameras' rays miss each other (the NYCU rig imported from
its ``.cfg`` files, ≈ 10° off) puts each camera's sight centimetres off the triangulated flight:
the sight is moved back by where that camera's recent pairs' detections lay from their points.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque

import numpy as np

from ..guided import bright_near
from ..params import TrackerParams
from ..rig import StereoRig
from .trajectory import Trajectory
from ..types import CameraResult, Candidate
from .look import MERGED_WHITE_RADIUS

# s: how recent a pair's reprojection miss must be to correct a one-camera step's line of sight
# (``SightOfCamera.offset``); the rig's miss changes slowly with where the shuttle is in the image,
# so an older pair's miss still serves, up to SIGHT_OFFSET_MEMORY, while the shuttle is within
# SIGHT_OFFSET_REACH (× image width) of where that pair saw it (a slow flight one camera lost).
SIGHT_OFFSET_AGE = 0.1
SIGHT_OFFSET_PAIRS = 5       # ... averaged over this many recent pairs (one pair's is its detection noise)
SIGHT_OFFSET_MEMORY = 0.5
SIGHT_OFFSET_REACH = 0.05
# × image width: with both cameras' detections and no pair, the one off the flight's projection
# by more than this is taken for something else, and the other camera's sight moves the flight.
SIGHT_PICK_FAR = 0.05
# × the points' pixel noise: a sight on a pair step whose other camera lost the shuttle is less
# sure than a free-running camera's lone image (the shuttle half hidden, merging with a player):
# at 1 the demo court's 3D RMS within 6 m went 0.91 → 0.98 cm, at 2 0.94, at 3 0.93 cm.
PAIRED_SIGHT_NOISE = 3.0


class SightOfCamera:
    """Feeds the flight one camera's sight; remembers each camera's last pairs' misses."""

    def __init__(self, rig: StereoRig, params: TrackerParams, trajectory: Trajectory) -> None:
        self.rig = rig
        self.params = params
        self.trajectory = trajectory
        # Per camera, the last pairs': (time, x, y, detection − projection of its point, px).
        self._miss: tuple[deque, deque] = (deque(maxlen=SIGHT_OFFSET_PAIRS), deque(maxlen=SIGHT_OFFSET_PAIRS))

    def note_pair(self, t: float, blob_output: np.ndarray, seen: tuple[tuple[float, float], tuple[float, float]]
                  ) -> None:
        """A pair the flight took: where each camera saw it (``seen``, left then right, px)
        against where its triangulated point ``blob_output`` (output frame) projects."""
        for cam, (x, y) in enumerate(seen):
            u, v = (float(c) for c in self.rig.project(cam, blob_output)[0])
            self.note_miss(cam, t, x, y, x - u, y - v)

    def note_miss(self, cam: int, t: float, x: float, y: float, dx: float, dy: float) -> None:
        """Camera ``cam`` saw a pair's shuttle at (x, y) at ``t``, (dx, dy) px from where the
        pair's point projects (the oldest of SIGHT_OFFSET_PAIRS leaves)."""
        self._miss[cam].append((t, x, y, dx, dy))

    def offset(self, cam: int, t: float, x: float, y: float) -> tuple[float, float]:
        """How far (px) this camera's detections lay from where the triangulated points project,
        over the last pairs the flight took (``SIGHT_OFFSET_PAIRS`` within ``SIGHT_OFFSET_AGE``, or
        older, up to ``SIGHT_OFFSET_MEMORY``, when seen near (x, y), the detection now); else
        (0, 0). On an exact rig it is the detection noise (a fraction of a px on the demo court);
        on launcher-stereo, whose rig is the NYCU one imported from the .cfg files, a single
        camera's sight missed the triangulated flight by 5–23 cm and the flight refused every one."""
        reach = SIGHT_OFFSET_REACH * self.rig.image_size[0]
        recent = [(dx, dy) for t_pair, x_pair, y_pair, dx, dy in self._miss[cam]
                  if 0.0 <= t - t_pair <= SIGHT_OFFSET_AGE
                  or (t - t_pair <= SIGHT_OFFSET_MEMORY and math.hypot(x - x_pair, y - y_pair) <= reach)]
        if not recent:
            return 0.0, 0.0
        dx, dy = np.mean(recent, axis=0)
        return float(dx), float(dy)

    def camera(self, det_left: Candidate | None, det_right: Candidate | None, t: float) -> int | None:
        """The camera whose sight may move the flight on a step with no pair: the one camera
        with a measured detection; with two (their pair refused), the one whose detection lies
        nearer the flight's projection, the other's being off it by more than SIGHT_PICK_FAR ×
        the image width (the detector took something else, the shuttle lost against a
        player); else None."""
        real = [det is not None and not det.predicted for det in (det_left, det_right)]
        if real[0] != real[1]:
            return 0 if real[0] else 1
        if not real[0]:
            return None
        guide = self.trajectory.guide(t)
        if guide is None:
            return None
        at = guide[0][None]
        off = []
        for cam, det in ((0, det_left), (1, det_right)):
            if float(self.rig.depth(cam, at)[0]) <= 0.1:
                return None
            u, v = self.rig.project(cam, at)[0]
            off.append(math.hypot(det.x - float(u), det.y - float(v)))
        far = SIGHT_PICK_FAR * self.rig.image_size[0]
        if max(off) <= far:
            return None
        return 0 if off[0] < off[1] else 1

    def feed(self, cam: int, det: Candidate, t: float, noise_scale: float = 1.0):
        """Feed the flight this camera's line of sight to ``det`` at ``t`` (``update_ray``).

        The blob's centroid is used, as the pairs are triangulated; the cork leads it along the
        flight by ``head_offset`` (``stereo/cork.py``), which the flight applies to the ray; the
        sight is first moved by where this camera's recent detections lay from the pairs' points."""
        sp = self.params.stereo
        dx, dy = self.offset(cam, t, det.x, det.y)
        centre, direction = self.rig.rays(cam, [[det.x - dx, det.y - dy]])
        m = self.rig.M1 if cam == 0 else self.rig.M2
        return self.trajectory.update_ray(t, centre, direction[0], noise_scale / float(m[0, 0]),
                                          lead=sp.head_offset, lead_min_speed=sp.head_min_speed)

    def projected_readout(self, cam: int, position, t: float, result: CameraResult,
                          frame: np.ndarray) -> CameraResult | None:
        """This camera's readout at the flight's ``position`` (court frame, the cork), which the
        other camera's sight has just moved while this camera found nothing: the projection moved
        by where this camera's last pairs' detections lay from their points (``offset``),
        flagged ``predicted`` (drawn dashed, never triangulated). None when the camera has a
        detection, when the projection is behind it or outside its image (the shuttle out of
        view), or when nothing brighter than its surroundings lies there (``bright_near``: the
        shuttle hidden, which the labels call not visible; one lost against a player's shirt or
        in the detector's mask still shows)."""
        if result.detection is not None:
            return None
        at = np.asarray(position, dtype=float)[None]
        if float(self.rig.depth(cam, at)[0]) <= 0.1:
            return None
        u, v = (float(c) for c in self.rig.project(cam, at)[0])
        dx, dy = self.offset(cam, t, u, v)
        u, v = u + dx, v + dy
        w, h = result.image_size
        if not (0 <= u < w and 0 <= v < h):
            return None
        if not bright_near(frame, u, v, MERGED_WHITE_RADIUS * w / 1280.0, self.params.stereo.guided_min_contrast):
            return None
        shown = Candidate(u, v, math.nan, math.nan, math.nan, math.nan, 0.0, 0.0, None, predicted=True)
        return dataclasses.replace(result, detection=shown, candidates=result.candidates + (shown,))

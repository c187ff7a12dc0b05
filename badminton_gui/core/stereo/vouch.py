"""The stereo vouch: a candidate one camera's association held back, let through because the
other camera agrees.

Why this file exists: one camera alone needs ``association.min_hits`` frames and ``min_travel``
px to tell a shuttle from clutter, so a serve's or a hit's first frames, or a shuttle coming back
slowly into view, are lost; the other camera is the evidence that camera lacks. This stage runs
between the per-camera candidates and the pairing (``stereo.stereo_vouch``, ``stereo.vouch_lone``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..detector import CameraDetector
from ..params import TrackerParams
from ..rig import StereoRig
from ..types import CameraResult, Candidate
from .epipolar import EpipolarGate
from .pairing import in_play_volume

# s: how far back the two tracks' image velocities are followed to check that a held-back pair
# moves consistently in 3D: a few frames at 120 fps, long enough for a slow shuttle to move a few px.
VOUCH_DT = 0.02
# px/s at 1280 px width: how fast both tracks of a vouched pair must move in the image for the
# gate widened to the rig's error (``stereo.vouch_rig_factor``): 2 px a frame at 119 fps; a
# shuttle lying on the floor, a light, a still shoe move less.
VOUCH_WIDE_IMAGE_SPEED = 250.0
# m/s: the fastest 3D motion a vouched pair may show (smashes leave the racket at ≤ ~157 m/s).
VOUCH_MAX_SPEED = 160.0


class StereoVouch:
    """Lets through held-back candidates the other camera confirms; keeps no state."""

    def __init__(self, rig: StereoRig, params: TrackerParams, gate: EpipolarGate,
                 detectors: tuple[CameraDetector, CameraDetector]) -> None:
        self.rig = rig
        self.params = params
        self.gate = gate
        self.detectors = detectors

    def apply(self, res_left: CameraResult, res_right: CameraResult
              ) -> tuple[CameraResult, CameraResult]:
        """Let through a candidate the association held back when the other camera agrees.

        The other camera's partner lies on the epipolar line (a tight fixed tolerance,
        ``stereo.vouch_max_epipolar``, widened to ``vouch_rig_factor`` × the rig's measured error
        for two tracks that both move in the image: on the roughly calibrated NYCU rig sure pairs
        miss by ~30 px and the fixed gate never fired) and its track moves the same way — the two
        image velocities, followed back ``VOUCH_DT``, meet their epipolar lines too and
        triangulate to a 3D velocity of at least ``vouch_min_speed`` (a light, a shuttle at rest
        do not move; two unrelated blobs rarely move consistently). Only a camera with no
        surviving candidate is helped; its partner is the other camera's survivor, or, when
        neither has one, a held-back candidate of the other camera (both pass); the partner
        survivor is the other camera's own choice. The candidate keeps its own quality as its
        score, below any confirmed track's merit.

        ``stereo.vouch_lone``: a camera whose survivors have no stereo partner among the other
        camera's (within the epipolar tolerance in use) is helped too, its partner being the other
        camera's own choice: the shuttle's own track held back at a racket contact while a
        clutter track passes. ``stereo.vouch_position_quality``: a held-back candidate scoring
        at least this by its looks is vouched for by position alone when the two tracks'
        smoothed velocities disagree (they mix the old and the new flight just after a hit).
        """
        sp = self.params.stereo
        # A camera coasting through a blind spot (a predicted candidate) is not helped: its
        # followed track still knows where the shuttle is.
        survivors = [[c for c in res.candidates if c.rejected_by is None] for res in (res_left, res_right)]
        need = [not s for s in survivors]
        results = [res_left, res_right]
        if any(need):
            pair = self.best_pair(results, need)
            if pair is not None:
                for cam in (0, 1):
                    if need[cam]:
                        results[cam] = self._pass(cam, results[cam], pair[cam])
        elif sp.vouch_lone and all(not any(c.predicted for c in s) for s in survivors):
            pl = np.array([[c.x, c.y] for c in survivors[0]])
            pr = np.array([[c.x, c.y] for c in survivors[1]])
            if not (self.rig.epipolar_errors(pl, pr) <= self.gate.tolerance()).any():
                picks = [self.best_pair(results, [cam == 0, cam == 1]) for cam in (0, 1)]
                for cam in (0, 1):
                    if picks[cam] is not None:
                        results[cam] = self._pass(cam, results[cam], picks[cam][cam])
        return results[0], results[1]

    def _pass(self, cam: int, result: CameraResult, pick: Candidate) -> CameraResult:
        """``result`` with the held-back ``pick`` let through (it keeps its own score)."""
        passed = self.detectors[cam].vouch(pick, pick.score)
        return dataclasses.replace(result, candidates=tuple(passed if c is pick else c
                                                            for c in result.candidates))

    def _pools(self, results: list[CameraResult], need: list[bool]) -> list[list[tuple]] | None:
        """Per camera, the vouch's candidates: (candidate, image velocity, by position alone if
        need be, a weak first sighting, sure enough to partner a weak first sighting); None when
        a camera has none."""
        sp = self.params.stereo
        first_floor = min(sp.vouch_first_quality, sp.vouch_first_partner_quality)
        pools = []
        for cam in (0, 1):
            detector = self.detectors[cam]
            pool = []
            if need[cam]:
                for c in results[cam].candidates:
                    v = detector.vouchable(c, sp.vouch_min_quality)
                    strong = c.score >= sp.vouch_first_quality
                    if v is not None:
                        pool.append((c, v, c.score >= sp.vouch_position_quality, False, strong))
                    elif sp.vouch_first_quality < 1.0 and detector.first_sighting(c, first_floor):
                        pool.append((c, None, True, not strong, strong))
            else:
                # The partner is that camera's own choice (its best track), nothing else.
                own = detector.choose(results[cam].candidates)
                v = None if own is None or own.predicted else detector.tracklet_velocity(own)
                if v is not None:
                    pool.append((own, v, True, False, True))
            if not pool:
                return None
            pools.append(pool)
        return pools

    def best_pair(self, results: list[CameraResult], need: list[bool]
                  ) -> tuple[Candidate, Candidate] | None:
        """The best (left, right) pair: held-back candidates of the cameras in ``need``, the
        other camera's own choice otherwise; None when no pair agrees."""
        sp = self.params.stereo
        pools = self._pools(results, need)
        if pools is None:
            return None
        left, right = pools
        now_l = np.array([[e[0].x, e[0].y] for e in left])
        now_r = np.array([[e[0].x, e[0].y] for e in right])
        tol = self.gate.vouch_tolerance()
        fixed = float(sp.vouch_max_epipolar)
        wide_speed = VOUCH_WIDE_IMAGE_SPEED * results[0].image_size[0] / 1280.0
        epi = self.rig.epipolar_errors(now_l, now_r)
        if not (epi <= tol).any():
            return None
        back_l = now_l - VOUCH_DT * np.array([(0.0, 0.0) if e[1] is None else e[1] for e in left])
        back_r = now_r - VOUCH_DT * np.array([(0.0, 0.0) if e[1] is None else e[1] for e in right])
        best = None
        for i, j in zip(*np.nonzero(epi <= tol)):
            # A first sighting has no velocity: its pair is checked by position alone, and
            # one that looks little like a shuttle needs a partner that does.
            if (left[i][3] and not right[j][4]) or (right[j][3] and not left[i][4]):
                continue
            moving = left[i][1] is not None and right[j][1] is not None
            if moving and float(self.rig.epipolar_errors(back_l[i:i + 1], back_r[j:j + 1])[0, 0]) > 2.0 * tol:
                if not (left[i][2] and right[j][2]):
                    continue
                moving = False      # two shuttle-like blobs: by position alone
            if epi[i, j] > fixed and not (moving and min(math.hypot(*left[i][1]), math.hypot(*right[j][1]))
                                           >= wide_speed):
                # Beyond the fixed gate only two tracks that both move in the image: on a
                # roughly calibrated rig the widened gate lets chance alignments through (a
                # lying shuttle beside a shoe, a noisy 3D speed from still blobs).
                continue
            pts = self.rig.triangulate(np.stack([now_l[i], back_l[i]]), np.stack([now_r[j], back_r[j]]))
            dist = float(np.linalg.norm(pts[0]))
            if pts[0][2] <= 0 or not (sp.min_distance <= dist <= sp.max_distance):
                continue
            if (self.rig.depth(1, self.rig.to_output(pts[:1]))[0] <= 0
                    or not in_play_volume(self.rig, self.params, pts[0])):
                continue
            speed = float(np.linalg.norm(pts[0] - pts[1])) / VOUCH_DT
            if moving and not (sp.vouch_min_speed <= speed <= VOUCH_MAX_SPEED):
                continue
            merit = left[i][0].score + right[j][0].score - float(epi[i, j]) / tol
            if best is None or merit > best[0]:
                best = (merit, i, j)
        if best is None:
            return None
        _, i, j = best
        return left[i][0], right[j][0]


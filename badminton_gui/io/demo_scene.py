"""The synthetic demo court: a stereo frame source with exact ground truth.

Why this file exists: anyone must be able to run, test and tune the tracker without cameras.
``DemoScene`` implements the ``FrameSource`` protocol (``io/sources.py``) over a synthetic
badminton hall: court lines at true dimensions (``core/court.py``), net and posts, bright lights,
two articulated players, and a shuttle flying under the quadratic-drag model of
``core/physics.py`` (the rally script is ``demo_rally.py``, the drawing ``demo_render.py``).
Its ``rig`` is the exact ``StereoRig`` (with court pose) that the frames were rendered with, and
``truth(index)`` gives the shuttle's position, velocity, per-camera projection and visibility.

Two rigs: ``"binocular"`` (two cameras 0.6 m apart beside the near half of the court, where
the robot plays) and ``"ends"`` (one camera high behind each baseline, like the NYCU rig).
A ``SceneStyle`` (``demo_style.py``) replaces the hall, rig, lens, camera, shuttle and players
by a randomised one; without it the scene is the demo court every earlier figure was taken on.
"""

from __future__ import annotations

import csv
import math
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import cv2
import numpy as np

from ..core import court
from ..core.rig import StereoRig
from ..core.types import StereoFrame
from . import demo_render as dr
from .demo_rally import FAR, NEAR, RallyScript, player_capsules

if TYPE_CHECKING:
    from .demo_style import SceneStyle

RIG_KINDS = ("binocular", "ends")
REFERENCE_SIZE = (1280, 720)
BINOCULAR_BASELINE = 0.6          # m
EXPOSURE = 0.002                  # s, centred on the frame time
NOISE_MEAN = 8                    # uint8 noise is N(NOISE_MEAN, NOISE_SIGMA), subtracted back
NOISE_SIGMA = 2.5
NOISE_PAD = 32                    # the noise buffer has this many spare rows; frames start at shifted offsets

TRUTH_HEADER = ["Frame", "Timestamp", "Visible", "X", "Y", "Z", "VX", "VY", "VZ",
                "VisL", "XL", "YL", "VisR", "XR", "YR", "Shot", "Kind"]
LABEL_HEADER = ["Frame", "Visibility", "X", "Y"]


@dataclass(frozen=True, slots=True)
class FrameTruth:
    """Ground truth of one frame pair (court frame, metres; pixels of each camera)."""

    index: int
    t: float
    position: tuple[float, float, float] | None      # cork centre; None: no shuttle in play
    visible_left: bool                                # in the image, not occluded, in play
    visible_right: bool
    uv_left: tuple[float, float] | None              # exact projection when in front of the camera
    uv_right: tuple[float, float] | None
    shot_index: int
    shot_kind: str                                    # "serve"/"clear"/"drop"/"drive"/"smash"/""
    velocity: tuple[float, float, float] | None


# ---- rigs ------------------------------------------------------------------------------------

def _fit_focal(rotations, centres, points, size, margin: float = 0.94) -> float:
    """Largest focal length (px) that keeps every point inside both images."""
    w, h = size
    f = math.inf
    for r, c in zip(rotations, centres):
        pc = (np.asarray(points, float) - c) @ r.T
        xn, yn = np.abs(pc[:, 0] / pc[:, 2]), np.abs(pc[:, 1] / pc[:, 2])
        f = min(f, float(np.min(margin * (w - 1) / 2 / np.maximum(xn, 1e-9))),
                float(np.min(margin * (h - 1) / 2 / np.maximum(yn, 1e-9))))
    return f


def _rig_geometry(kind: str) -> tuple[list[np.ndarray], list[np.ndarray], np.ndarray]:
    """Rotations, centres and the points that must be in view, for a rig kind."""
    w, hl = court.HALF_WIDTH_DOUBLES, court.HALF_LENGTH
    net = [(-w, 0, 0), (w, 0, 0), (-w, 0, court.NET_HEIGHT_POSTS), (w, 0, court.NET_HEIGHT_POSTS)]
    if kind == "binocular":
        # Beside the near half, 2 m outside the left doubles sideline, on a 3.5 m stand, aimed
        # at the air above the near half. Seeing the whole near half from this close needs a
        # wide lens (f ≈ 340 px at 1280 px, ~124° horizontal); from further away less of the
        # flight is within 6 m of the rig (see the report of this module's author).
        mid = np.array([-5.0, -3.4, 3.5])
        aim = np.array([1.0, -3.2, 1.5])
        r_mid = dr.look_at(mid, aim)
        x_axis = r_mid[0]
        far_aim = mid + 12.0 * (aim - mid) / np.linalg.norm(aim - mid)   # slight toe-in
        centres = [mid - 0.5 * BINOCULAR_BASELINE * x_axis, mid + 0.5 * BINOCULAR_BASELINE * x_axis]
        rotations = [dr.look_at(c, far_aim) for c in centres]
        required = np.array([(-w, -hl, 0), (w, -hl, 0), *net])
        return rotations, centres, required
    if kind == "ends":
        centres = [np.array([0.0, -hl - 3.2, 5.0]), np.array([0.0, hl + 3.2, 5.0])]
        rotations = [dr.look_at(centres[0], (0.0, -0.5, 0.0)), dr.look_at(centres[1], (0.0, 0.5, 0.0))]
        required = np.array([(-w, -hl, 0), (w, -hl, 0), (-w, hl, 0), (w, hl, 0), *net])
        return rotations, centres, required
    raise ValueError(f"unknown demo rig {kind!r}: choose one of {', '.join(RIG_KINDS)}")


def make_rig(kind: str = "binocular", size: tuple[int, int] = REFERENCE_SIZE) -> StereoRig:
    """The exact StereoRig of a demo rig kind, at an image size (intrinsics scale with width)."""
    rotations, centres, required = _rig_geometry(kind)
    f_ref = _fit_focal(rotations, centres, required, REFERENCE_SIZE)
    w, h = int(size[0]), int(size[1])
    f = f_ref * w / REFERENCE_SIZE[0]
    k = np.array([[f, 0, (w - 1) / 2], [0, f, (h - 1) / 2], [0, 0, 1]])
    t = [-r @ c for r, c in zip(rotations, centres)]
    r_rel = rotations[1] @ rotations[0].T
    t_rel = t[1] - r_rel @ t[0]
    return StereoRig(M1=k, D1=np.zeros(5), M2=k.copy(), D2=np.zeros(5), R=r_rel, T=t_rel,
                     image_size=(w, h), R_court=rotations[0].T, T_court=centres[0])


# ---- the source ------------------------------------------------------------------------------

class DemoScene:
    """Synthetic stereo source over a rally script; implements ``FrameSource``."""

    def __init__(self, seed: int = 0, size: tuple[int, int] = REFERENCE_SIZE,
                 rig: str = "binocular", fps: float = 120.0, n_frames: int | None = None,
                 noise: bool = True, flicker: bool = True,
                 style: "SceneStyle | None" = None) -> None:
        """``style``: a randomised scene (``demo_style.sample_scene``); it decides the rig, the
        image size and the frame rate, so ``size``, ``rig`` and ``fps`` are not used with it."""
        self.style = style
        if style is not None:
            rig, size, fps = style.family, style.size, style.fps
        elif rig not in RIG_KINDS:
            raise ValueError(f"unknown demo rig {rig!r}: choose one of {', '.join(RIG_KINDS)}")
        if fps <= 0:
            raise ValueError(f"fps must be positive, got {fps}")
        self.seed = int(seed)
        self.rig_kind = rig
        self.name = f"Demo court ({rig}, seed {self.seed})"
        self.rig: StereoRig = make_rig(rig, size) if style is None else style.rig()
        self._fps = float(fps)
        self.n_frames = n_frames
        self.noise = noise
        self.flicker = flicker
        self.exposure = EXPOSURE if style is None else style.exposure
        self.script = (RallyScript(self.seed) if style is None
                       else RallyScript(self.seed, shots=style.rally_shots))
        self.cameras = [dr.PinholeCamera.from_rig(self.rig, i) for i in (0, 1)]
        self._look = None if style is None else style.look(self.cameras)
        self._clothes = (None, None) if style is None else style.clothes()
        self._backgrounds = ([dr.render_background(c) for c in self.cameras] if style is None
                             else list(self._look.backgrounds))
        w, h = self.rig.image_size
        self._noise = []
        if noise:
            sigma = NOISE_SIGMA if style is None else style.noise_sigma
            for cam in (0, 1):
                rng = np.random.default_rng([self.seed, 1000 + cam])
                # One flat buffer: every frame's noise is a *contiguous* slice of it, so cv2.add
                # reads it in place (a 2-D window of a wider array is copied first: 4 ms a frame).
                buf = rng.normal(NOISE_MEAN, sigma, (h + NOISE_PAD + 1) * w * 3)
                self._noise.append(np.clip(np.round(buf), 0, 255).astype(np.uint8))
        self._truth_cache: OrderedDict[int, tuple[FrameTruth, list]] = OrderedDict()
        self._next = 0

    # -- FrameSource --
    @property
    def image_size(self) -> tuple[int, int]:
        return self.rig.image_size

    @property
    def fps(self) -> float:
        return self._fps

    def read(self) -> StereoFrame | None:
        if self.n_frames is not None and self._next >= self.n_frames:
            return None
        index = self._next
        self._next += 1
        left, right = self.render(index)
        t = self.time_of(index)
        return StereoFrame(left, right, t, t, index, index)

    def close(self) -> None:
        self._truth_cache.clear()

    def __len__(self) -> int:
        if self.n_frames is None:
            raise TypeError("an endless demo scene has no length")
        return self.n_frames

    # -- truth --
    def time_of(self, index: int) -> float:
        if int(index) != index or index < 0:
            raise ValueError(f"frame index must be a non-negative integer, got {index!r}")
        return int(index) / self._fps

    def background(self, camera: int) -> np.ndarray:
        """A copy of the static image of camera 0 (left) or 1 (right): no flicker, noise, boards,
        players or shuttle."""
        return self._backgrounds[camera].copy()

    def _players(self, t: float) -> list[list]:
        """Projected body parts of both players, per camera."""
        caps = [player_capsules(self.script, p, t) for p in (NEAR, FAR)]
        clothes = self._clothes
        return [[pc for p in (NEAR, FAR) for pc in dr.project_capsules(cam, caps[p], p, clothes[p])]
                for cam in self.cameras]

    def _truth_and_players(self, index: int) -> tuple[FrameTruth, list]:
        hit = self._truth_cache.get(index)
        if hit is not None:
            self._truth_cache.move_to_end(index)
            return hit
        t = self.time_of(index)
        pos, vel, seg = self.script.state(t)
        players = self._players(t)
        uv: list[tuple[float, float] | None] = [None, None]
        vis = [False, False]
        w, h = self.rig.image_size
        if pos is not None:
            for cam in (0, 1):
                depth = float(self.rig.depth(cam, pos[None])[0])
                if depth <= dr.NEAR_PLANE:
                    continue
                p = self.rig.project(cam, pos[None])[0]
                uv[cam] = (float(p[0]), float(p[1]))
                inside = -0.5 <= p[0] < w - 0.5 and -0.5 <= p[1] < h - 0.5
                vis[cam] = bool(inside and not dr.occluded_by(players[cam], p, depth))
        truth = FrameTruth(
            index=index, t=t,
            position=None if pos is None else tuple(float(c) for c in pos),
            visible_left=vis[0], visible_right=vis[1], uv_left=uv[0], uv_right=uv[1],
            shot_index=seg.shot_index if pos is not None else -1,
            shot_kind=seg.shot_kind if pos is not None else "",
            velocity=None if vel is None else tuple(float(c) for c in vel))
        self._truth_cache[index] = (truth, players)
        if len(self._truth_cache) > 256:
            self._truth_cache.popitem(last=False)
        return truth, players

    def truth(self, index: int) -> FrameTruth:
        return self._truth_and_players(index)[0]

    # -- rendering --
    def flicker_gain(self, index: int) -> float:
        """Global brightness gain: 100 Hz mains ripple aliased by the frame rate, plus drift."""
        if not self.flicker:
            return 1.0
        t = self.time_of(index)
        if self.style is not None:
            return self.style.flicker_gain(t)
        return 1.0 + 0.02 * math.sin(2 * math.pi * 100.0 * t) + 0.01 * math.sin(2 * math.pi * 0.37 * t + self.seed)

    def _exposure_samples(self, t: float) -> tuple[np.ndarray, np.ndarray] | None:
        """Cork positions and flight directions across the exposure (None: nothing to draw)."""
        # The shutter integrates only while the shuttle is in play: at a rally's first frame
        # the exposure may open before the serve (the frame's truth has a position, so the
        # shuttle must be drawn, over the part of the exposure after the serve).
        probes = t + (np.linspace(0.0, 1.0, 9) - 0.5) * self.exposure
        # In play = not an "off" segment (``state`` would interpolate a position only to test
        # it against None: 9 interpolations a frame for nothing).
        live = [ts for ts in probes.tolist() if self.script.segment_at(ts).kind != "off"]
        if not live:
            return None
        lo, hi = live[0], live[-1]
        # The ends are sampled again below (linspace returns lo and hi exactly): keep them.
        states = {lo: self.script.state(lo), hi: self.script.state(hi)}
        p_start, p_end = states[lo][0], states[hi][0]
        streak = 0.0
        for cam in self.cameras:
            pc = cam.to_camera(np.stack([p_start, p_end]))
            if np.all(pc[:, 2] > dr.NEAR_PLANE):
                uv = cam.project_camera(pc)
                streak = max(streak, float(np.hypot(*(uv[1] - uv[0]))))
        n = int(np.clip(math.ceil(streak / 0.5) + 1, 1, 48))
        times = [t] if n == 1 or hi <= lo else np.linspace(lo, hi, n)
        positions, directions = [], []
        for ts in times:
            ts = float(ts)
            p, v, seg = states[ts] if ts in states else self.script.state(ts)
            if p is None:
                continue
            speed = float(np.linalg.norm(v))
            d = v / speed if speed > 0.3 else dr.lying_direction(seg.rest_dir)
            positions.append(p)
            directions.append(d)
        if not positions:
            return None
        return np.array(positions), np.array(directions)

    def render(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """Both camera images of frame ``index`` (BGR uint8), by random access."""
        truth, players = self._truth_and_players(index)
        gain = self.flicker_gain(index)
        samples = self._exposure_samples(truth.t) if truth.position is not None else None
        images = []
        for cam_i, cam in enumerate(self.cameras):
            bg = self._backgrounds[cam_i]
            beta = -NOISE_MEAN if self.noise else 0
            if gain != 1.0 or beta:
                img = cv2.convertScaleAbs(bg, alpha=gain, beta=beta)
            else:
                img = bg.copy()
            if self._look is not None:
                self._look.draw_boards(img, cam_i, truth.t)
            # Painter's order: body parts and the shuttle from far to near.
            items = [(pc.mean_depth, 0, pc) for pc in players[cam_i]]
            if samples is not None:
                shuttle_depth = float(cam.to_camera(truth.position)[0, 2])
                items.append((shuttle_depth, 1, None))
            items.sort(key=lambda it: -it[0])
            for _, is_shuttle, pc in items:
                if is_shuttle:
                    if self.style is None:
                        dr.draw_shuttle(img, cam, samples[0], samples[1], gain)
                    else:
                        dr.draw_shuttle(img, cam, samples[0], samples[1], gain,
                                        self.style.shuttle_scale, self.style.shuttle_brightness)
                else:
                    dr.draw_capsule(img, pc, gain)
            if self.noise:
                w, h = self.rig.image_size
                start = (((index * 53 + cam_i * 7) % NOISE_PAD) * w
                         + (index * 37 + cam_i * 11) % NOISE_PAD) * 3
                noise = self._noise[cam_i][start:start + h * w * 3].reshape(h, w, 3)
                cv2.add(img, noise, dst=img)
            images.append(img)
        return images[0], images[1]


# ---- truth files -----------------------------------------------------------------------------

def _fmt(v: float | None, digits: int = 4) -> str:
    return "" if v is None else f"{v:.{digits}f}"


def write_truth_csv(path: str | Path, truths) -> None:
    """Write the ground truth of frames (court frame, m, m/s; pixels) to one CSV."""
    with open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(TRUTH_HEADER)
        for tr in truths:
            p = tr.position or (None, None, None)
            v = tr.velocity or (None, None, None)
            ul = tr.uv_left or (None, None)
            ur = tr.uv_right or (None, None)
            writer.writerow([tr.index, f"{tr.t:.6f}", int(tr.position is not None),
                             *(_fmt(c) for c in p), *(_fmt(c, 3) for c in v),
                             int(tr.visible_left), *(_fmt(c, 3) for c in ul),
                             int(tr.visible_right), *(_fmt(c, 3) for c in ur),
                             tr.shot_index, tr.shot_kind])


def write_label_csv(path: str | Path, truths, camera: int) -> None:
    """Per-camera TrackNet labels ``Frame,Visibility,X,Y`` (pixels; 0,0 when not visible)."""
    with open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(LABEL_HEADER)
        for tr in truths:
            vis = tr.visible_left if camera == 0 else tr.visible_right
            uv = tr.uv_left if camera == 0 else tr.uv_right
            if vis and uv is not None:
                writer.writerow([tr.index, 1, f"{uv[0]:.3f}", f"{uv[1]:.3f}"])
            else:
                writer.writerow([tr.index, 0, 0, 0])

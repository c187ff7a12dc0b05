"""How large and how fast the shuttle can look at each position of one camera's image.

Why this file exists: the paper's filters 1, 2 and 4 (contour length, the tilted rectangle's
short side, the motion gate) were numbers in pixels, tuned for one rig at one resolution; a
near shuttle on a side rack, or the same court at half the resolution, fell outside them. The
shuttle itself has a fixed size (about 6.5 cm long, a 6.5 cm skirt, a 2.5–2.8 cm cork) and a
top speed (a smash, ~110 m/s): with the camera's geometry those give, at every image position,
the range of sizes and the largest image speed the shuttle can have there. This module computes
them once per camera on a coarse grid (``ShuttleScaleMap``), cheap to look up per candidate:

* from a calibrated camera with the court pose (``from_rig``): each cell's lines of sight are
  cut with the play volume (the court plus a margin, from the floor up to a ceiling height);
  the nearest and farthest points of the volume on them, projected with the camera's own
  lens (distortion included), give the largest and smallest image scale (px per metre);
* from the image alone (``from_image``, one camera without calibration): a pinhole of an
  assumed horizontal field of view, the shuttle between a nearest and a farthest distance.

Everything is in full-resolution pixels of the camera image; numpy and OpenCV only.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..court import HALF_LENGTH, HALF_WIDTH_DOUBLES
from .params import ShuttleScaleParams

GRID = (16, 12)          # cells across and down
_SAMPLES = 3             # lines of sight per cell and axis (its corners' side and middle)
_STEP = 0.01             # m: the finite difference of the image scale
_REPROJECTION = 1.0      # px: a line of sight must project back this close to its pixel


@dataclasses.dataclass(frozen=True, slots=True)
class ShuttleScaleMap:
    """Per grid cell, the image scale (px per metre across the line of sight) of the nearest
    and of the farthest shuttle on the cell's lines of sight, and what it makes of the shuttle:
    its smallest and largest image size and its largest image speed."""

    image_size: tuple[int, int]       # (width, height) of the camera image
    near_scale: np.ndarray            # (ny, nx) px/m: the largest scale (the nearest shuttle)
    far_scale: np.ndarray             # (ny, nx) px/m: the smallest scale (the farthest shuttle)
    params: ShuttleScaleParams
    source: str = "rig"               # "rig" (calibrated) or "image" (assumed field of view)

    @property
    def grid(self) -> tuple[int, int]:
        """(cells across, cells down)."""
        return self.near_scale.shape[1], self.near_scale.shape[0]

    @property
    def min_size(self) -> np.ndarray:
        """(ny, nx) px: the cork of the farthest shuttle."""
        return self.far_scale * self.params.cork_diameter

    @property
    def max_size(self) -> np.ndarray:
        """(ny, nx) px: the whole length of the nearest shuttle."""
        return self.near_scale * self.params.length

    @property
    def far_length(self) -> float:
        """px: the farthest shuttle's whole length, the median over the cells: what the
        background model must still show (``segmentation.model_scale``)."""
        far = self.far_scale[np.isfinite(self.far_scale)]
        return float(np.median(far)) * self.params.length if far.size else 0.0

    @property
    def max_speed(self) -> np.ndarray:
        """(ny, nx) px/s: the nearest shuttle at the top speed."""
        return self.near_scale * self.params.max_speed

    @property
    def typical_scale(self) -> np.ndarray:
        """(ny, nx) px/m: the geometric middle of the near and far scales, the scale of a
        shuttle halfway (in image size) between its nearest and farthest."""
        return np.sqrt(self.near_scale * self.far_scale)

    def cells(self, xs, ys) -> tuple[np.ndarray, np.ndarray]:
        """(row, column) of the cells holding image points ``xs``, ``ys`` (clipped to the grid)."""
        nx, ny = self.grid
        w, h = self.image_size
        col = np.clip((np.asarray(xs, dtype=float) * nx / w).astype(np.int64), 0, nx - 1)
        row = np.clip((np.asarray(ys, dtype=float) * ny / h).astype(np.int64), 0, ny - 1)
        return row, col

    def at(self, xs, ys) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(smallest size, largest size, largest speed) at image points ``xs``, ``ys``."""
        row, col = self.cells(xs, ys)
        return self.min_size[row, col], self.max_size[row, col], self.max_speed[row, col]

    def gate_scale(self, reference: float, per_position: bool = True) -> "GateScale":
        """The factor by which pixel gates tuned at image scale ``reference`` (px/m) grow or
        shrink at each image position here (or, not ``per_position``, the camera's median)."""
        factor = self.typical_scale / float(reference)
        speed = self.max_speed
        if not per_position:
            factor = np.full_like(factor, float(np.median(factor)))
            speed = np.full_like(speed, float(np.median(speed)))
        return GateScale(self.image_size, factor, speed)


@dataclasses.dataclass(frozen=True, slots=True)
class GateScale:
    """A factor per grid cell for the pixel gates of filters 1, 2 and 4, and the shuttle's
    largest image speed there; cheap to look up for many points at once (``at``) or one at a
    time (``at1``, ``speed_at1``: plain Python)."""

    image_size: tuple[int, int]
    factor: np.ndarray                # (ny, nx)
    speed: np.ndarray                 # (ny, nx) px/s
    _rows: tuple = dataclasses.field(default=(), repr=False, compare=False)
    _speed_rows: tuple = dataclasses.field(default=(), repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_rows", tuple(tuple(r) for r in self.factor.tolist()))
        object.__setattr__(self, "_speed_rows", tuple(tuple(r) for r in self.speed.tolist()))

    def at(self, xs, ys) -> np.ndarray:
        """The factors at image points ``xs``, ``ys``."""
        ny, nx = self.factor.shape
        w, h = self.image_size
        col = np.clip((np.asarray(xs, dtype=float) * nx / w).astype(np.int64), 0, nx - 1)
        row = np.clip((np.asarray(ys, dtype=float) * ny / h).astype(np.int64), 0, ny - 1)
        return self.factor[row, col]

    def _cell1(self, x: float, y: float) -> tuple[int, int]:
        ny, nx = self.factor.shape
        w, h = self.image_size
        col = min(max(int(x * nx / w), 0), nx - 1) if math.isfinite(x) else 0
        row = min(max(int(y * ny / h), 0), ny - 1) if math.isfinite(y) else 0
        return row, col

    def at1(self, x: float, y: float) -> float:
        """The factor at one image point."""
        row, col = self._cell1(x, y)
        return self._rows[row][col]

    def speed_at1(self, x: float, y: float) -> float:
        """The shuttle's largest image speed (px/s) at one image point."""
        row, col = self._cell1(x, y)
        return self._speed_rows[row][col]


def _cell_samples(width: int, height: int, grid: tuple[int, int]) -> np.ndarray:
    """(ny, nx, S, 2) image points spread over each cell (S = ``_SAMPLES``²)."""
    nx, ny = grid
    fr = (np.arange(_SAMPLES) + 0.5) / _SAMPLES
    xs = (np.arange(nx)[:, None] + fr[None, :]) * width / nx        # (nx, S)
    ys = (np.arange(ny)[:, None] + fr[None, :]) * height / ny       # (ny, S)
    gx = np.broadcast_to(xs[None, :, None, :], (ny, nx, _SAMPLES, _SAMPLES))
    gy = np.broadcast_to(ys[:, None, :, None], (ny, nx, _SAMPLES, _SAMPLES))
    return np.stack([gx, gy], axis=-1).reshape(ny, nx, _SAMPLES * _SAMPLES, 2)


def play_volume(params: ShuttleScaleParams) -> tuple[np.ndarray, np.ndarray]:
    """(lowest corner, highest corner) of the box the shuttle flies in, court frame (m)."""
    m = params.court_margin
    hi = np.array([HALF_WIDTH_DOUBLES + m, HALF_LENGTH + m, params.ceiling])
    lo = np.array([-hi[0], -hi[1], 0.0])
    return lo, hi


def ray_box(origin: np.ndarray, dirs: np.ndarray, lo: np.ndarray, hi: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
    """(entry, exit) distances of rays ``origin + t·dirs`` (dirs (N, 3)) through the box
    [lo, hi]; entry > exit where a ray misses it. Entry is at least 0 (the camera may stand
    inside the box)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / dirs
        t0 = (lo[None, :] - origin[None, :]) * inv
        t1 = (hi[None, :] - origin[None, :]) * inv
    # A direction parallel to a slab: inside it the slab does not bound the ray, outside it
    # the ray misses the box.
    flat = dirs == 0
    inside = ((origin >= lo) & (origin <= hi))[None, :]
    lower = np.where(flat, np.where(inside, -np.inf, np.inf), np.minimum(t0, t1))
    upper = np.where(flat, np.where(inside, np.inf, -np.inf), np.maximum(t0, t1))
    return np.maximum(lower.max(axis=1), 0.0), upper.min(axis=1)


def image_scales(project, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(largest, smallest) image scale (px per metre) of small displacements across the line
    of sight at 3D ``points`` (N, 3): the two singular values of the projection's Jacobian.
    ``project`` maps (M, 3) points to (M, 2) pixels (the lens included)."""
    n = len(points)
    steps = np.vstack([np.zeros(3), np.eye(3) * _STEP])                    # (4, 3)
    pix = project((points[:, None, :] + steps[None, :, :]).reshape(-1, 3)).reshape(n, 4, 2)
    jac = (pix[:, 1:, :] - pix[:, :1, :]).transpose(0, 2, 1) / _STEP      # (N, 2, 3)
    sv = np.linalg.svd(jac, compute_uv=False)                              # (N, 2)
    return sv[:, 0], sv[:, 1]


def from_rig(rig, camera: int, params: ShuttleScaleParams, grid: tuple[int, int] = GRID) -> ShuttleScaleMap:
    """The map of camera ``camera`` (0 left, 1 right) of a calibrated ``rig`` with its court
    pose (``rig.has_court_pose``)."""
    if not rig.has_court_pose:
        raise ValueError("the shuttle's image scale needs the rig's court pose")
    w, h = rig.image_size
    nx, ny = grid
    pts = _cell_samples(w, h, grid).reshape(-1, 2)
    origin, dirs = rig.rays(camera, pts)
    lo, hi = play_volume(params)
    origin = np.asarray(origin, dtype=float)
    entry, exit_ = ray_box(origin, dirs, lo, hi)
    near = np.maximum(entry, params.nearest)
    far = np.maximum(exit_, near)

    def project(p: np.ndarray) -> np.ndarray:
        return rig.project(camera, p)

    # A strong barrel lens's polynomial folds back beyond the calibrated part of the image
    # (the corners): a line of sight that does not project back onto its own pixel there is
    # not trusted, and its cell gets the widest range of the others.
    back = project(origin[None, :] + dirs * far[:, None])
    seen = (exit_ > max(params.nearest, 1e-3)) & (np.hypot(*(back - pts).T) <= _REPROJECTION)
    big, _ = image_scales(project, origin[None, :] + dirs * near[:, None])
    _, small = image_scales(project, origin[None, :] + dirs * far[:, None])
    return _fill(w, h, grid, big.reshape(ny, nx, -1), small.reshape(ny, nx, -1),
                 seen.reshape(ny, nx, -1), params, "rig")


def from_image(width: int, height: int, params: ShuttleScaleParams, grid: tuple[int, int] = GRID
               ) -> ShuttleScaleMap:
    """The map of one camera without calibration: a pinhole of horizontal field of view
    ``params.fov`` at the image's centre, the shuttle between ``params.nearest`` and
    ``params.farthest`` metres from it."""
    nx, ny = grid
    f = 0.5 * width / math.tan(math.radians(params.fov) / 2)
    pts = _cell_samples(width, height, grid).reshape(-1, 2)
    # Pinhole: at distance d along a line of sight making angle θ with the axis, depth is
    # d·cosθ; across the line of sight the image scale is f / (d·cos²θ) along the radius
    # and f / (d·cosθ) around it.
    r = np.hypot(pts[:, 0] - width / 2, pts[:, 1] - height / 2) / f
    cos = 1.0 / np.sqrt(1.0 + r * r)
    big = f / (params.nearest * cos * cos)
    small = f / (params.farthest * cos)
    shape = (ny, nx, -1)
    return _fill(width, height, grid, big.reshape(shape), small.reshape(shape),
                 np.ones(big.shape, bool).reshape(shape), params, "image")


def _fill(w: int, h: int, grid: tuple[int, int], big: np.ndarray, small: np.ndarray,
          seen: np.ndarray, params: ShuttleScaleParams, source: str) -> ShuttleScaleMap:
    """The map from each cell's samples' image scales (px/m, (ny, nx, S)): a cell none of whose
    lines of sight meet the play volume gets the widest range of the cells that do (the
    shuttle may still pass there, above the assumed ceiling or off the margin)."""
    any_seen = seen.any()
    big = np.where(seen, big, -np.inf).max(axis=2)
    small = np.where(seen, small, np.inf).min(axis=2)
    covered = np.isfinite(big) & np.isfinite(small)
    if any_seen and not covered.all():
        big = np.where(covered, big, big[covered].max())
        small = np.where(covered, small, small[covered].min())
    elif not any_seen:
        raise ValueError("no line of sight of this camera meets the play volume")
    return ShuttleScaleMap((int(w), int(h)), big, small, params, source)

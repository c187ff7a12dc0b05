"""Drawing the demo court: static hall per camera, articulated players, motion-blurred shuttle.

Why this file exists: the demo scene (``demo_scene.py``) must render both cameras faster than
real time at 1280×720, so everything that does not move is drawn once per camera
(``render_background``: 3D polygons clipped to the near plane, projected, ``fillPoly`` with
sub-pixel ``shift`` and anti-aliasing), and each frame only copies that image with a flicker
gain, draws the players (capsules, painter's order with the shuttle) and the shuttle, and adds
pre-generated sensor noise. The shuttle is drawn in a 4× supersampled patch, integrated over
the exposure interval centred on the frame time, so a detector can localise it to ~0.1 px and
the centre of its blur streak is the truth position.

The per-frame geometry (~32 body parts and a handful of exposure samples per camera) is
computed on Python floats, not (2,) arrays: numpy's per-call overhead on such tiny arrays cost
more than the drawing. The arithmetic is the same element-wise operations in the same order,
so the frames are bit-identical to the array formulation (``tests/test_demo_scene.py`` pins
the fast paths to it).

Cameras here are pinhole (the demo rig has D = 0); ``PinholeCamera`` is derived from the
``StereoRig`` so that drawing and ``StereoRig.project`` agree exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import NamedTuple

import cv2
import numpy as np

from ..core import court
from ..core.rig import StereoRig
from .demo_rally import CORK_RADIUS, Capsule

NEAR_PLANE = 0.05          # m: polygons are clipped here before projection
SHIFT = 4                  # sub-pixel bits for cv2 drawing
SCALE = float(1 << SHIFT)
SKIRT_LENGTH = 0.06        # cork centre to the skirt's open end (m)
SKIRT_RADIUS = 0.032       # radius of the skirt's open end (m)
# A shuttle lying on the floor rests on its cork and on its skirt's rim, so its axis rises
# towards the skirt: SKIRT_RADIUS·cos θ − SKIRT_LENGTH·sin θ = CORK_RADIUS (≈ 17°). Drawn with a
# level axis, half the skirt was below the floor and the blob's stereo point was 2.6 cm off in
# depth (the two views cut the sunken skirt differently).
REST_TILT = (math.acos(CORK_RADIUS / math.hypot(SKIRT_RADIUS, SKIRT_LENGTH))
             - math.atan2(SKIRT_LENGTH, SKIRT_RADIUS))
SUPERSAMPLE = 4

# BGR colours.
COLOURS = {
    "ceiling": (38, 36, 34), "wall": (62, 56, 52), "back_wall": (70, 62, 55),
    "floor": (52, 70, 92), "mat": (62, 112, 48), "line": (232, 236, 236),
    "light": (252, 252, 252), "post": (40, 90, 40), "net": (25, 25, 25), "tape": (240, 242, 242),
}
PLAYER_COLOURS = [
    {"shirt": (170, 90, 30), "shorts": (30, 30, 30), "skin": (120, 150, 200), "hair": (25, 30, 40),
     "racket": (30, 30, 160), "racket_head": (40, 40, 170)},
    {"shirt": (40, 40, 190), "shorts": (60, 50, 40), "skin": (105, 135, 180), "hair": (20, 20, 25),
     "racket": (150, 60, 20), "racket_head": (160, 80, 30)},
]


def look_at(centre, target) -> np.ndarray:
    """Court → camera rotation of a camera at ``centre`` looking at ``target`` (Z up)."""
    z = np.asarray(target, float) - np.asarray(centre, float)
    z /= np.linalg.norm(z)
    x = np.cross(z, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.stack([x, y, z])


@dataclass(frozen=True)
class PinholeCamera:
    """World (court) → camera transform and intrinsics of one camera of the rig."""

    R: np.ndarray          # court → camera rotation
    t: np.ndarray          # court → camera translation
    K: np.ndarray
    size: tuple[int, int]

    @classmethod
    def from_rig(cls, rig: StereoRig, camera: int) -> "PinholeCamera":
        r_l = rig.R_court.T                       # court → left
        t_l = -r_l @ rig.T_court
        if camera == 0:
            return cls(r_l, t_l, rig.M1, rig.image_size)
        return cls(rig.R @ r_l, rig.R @ t_l + rig.T, rig.M2, rig.image_size)

    @property
    def focal(self) -> float:
        return float(self.K[0, 0])

    def to_camera(self, pts) -> np.ndarray:
        return np.asarray(pts, dtype=float).reshape(-1, 3) @ self.R.T + self.t

    def project_camera(self, pc: np.ndarray) -> np.ndarray:
        """Camera-frame points (N, 3), z > 0 → pixels (N, 2)."""
        z = pc[:, 2:3]
        return (pc[:, :2] / z) @ self.K[:2, :2].T + self.K[:2, 2]


# ---- static background ----------------------------------------------------------------------

def _clip_near(poly_cam: np.ndarray) -> np.ndarray:
    """Sutherland–Hodgman clip of a camera-frame polygon to z ≥ NEAR_PLANE."""
    out = []
    n = len(poly_cam)
    for i in range(n):
        a, b = poly_cam[i], poly_cam[(i + 1) % n]
        a_in, b_in = a[2] >= NEAR_PLANE, b[2] >= NEAR_PLANE
        if a_in:
            out.append(a)
        if a_in != b_in:
            s = (NEAR_PLANE - a[2]) / (b[2] - a[2])
            out.append(a + s * (b - a))
    return np.array(out) if out else np.zeros((0, 3))


def _fill_polygon(img: np.ndarray, cam: PinholeCamera, poly_world, colour) -> None:
    pc = _clip_near(cam.to_camera(poly_world))
    if len(pc) < 3:
        return
    uv = np.clip(cam.project_camera(pc), -1e5, 1e5)
    pts = np.round(uv * SCALE).astype(np.int32).reshape(-1, 1, 2)
    cv2.fillPoly(img, [pts], colour, cv2.LINE_AA, SHIFT)


def _quad_xy(x0, y0, x1, y1, z=0.0) -> np.ndarray:
    return np.array([[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]], dtype=float)


def _hall_polygons() -> list[tuple[np.ndarray, str]]:
    """Ceiling, walls with light panels, floor, mat and lines, in painter's order."""
    hx, hy, hz = 8.0, 11.0, 9.0
    polys: list[tuple[np.ndarray, str]] = []
    polys.append((_quad_xy(-hx, -hy, hx, hy, hz), "ceiling"))
    for sx in (-1, 1):      # side walls
        polys.append((np.array([[sx * hx, -hy, 0], [sx * hx, hy, 0], [sx * hx, hy, hz],
                                [sx * hx, -hy, hz]], float), "wall"))
    for sy in (-1, 1):      # back walls (behind each baseline)
        polys.append((np.array([[-hx, sy * hy, 0], [hx, sy * hy, 0], [hx, sy * hy, hz],
                                [-hx, sy * hy, hz]], float), "back_wall"))
    # Bright lights: panels high on every wall and rows on the ceiling.
    for sy in (-1, 1):
        for x in (-5.0, -1.5, 2.0, 5.5):
            y = sy * (hy - 0.01)
            polys.append((np.array([[x, y, 6.2], [x + 1.2, y, 6.2], [x + 1.2, y, 6.9],
                                    [x, y, 6.9]], float), "light"))
        for x in (-6.5, -2.5, 1.5, 5.0):        # a lower row of floodlights, seen from the ends
            y = sy * (hy - 0.01)
            polys.append((np.array([[x, y, 2.9], [x + 1.4, y, 2.9], [x + 1.4, y, 3.4],
                                    [x, y, 3.4]], float), "light"))
    for sx in (-1, 1):
        for y in (-8.0, -3.5, 1.0, 5.5):
            x = sx * (hx - 0.01)
            polys.append((np.array([[x, y, 6.4], [x, y + 1.6, 6.4], [x, y + 1.6, 6.9],
                                    [x, y, 6.9]], float), "light"))
    for x in (-4.5, 4.5):
        for y in (-7.5, -2.5, 2.5, 7.5):
            polys.append((_quad_xy(x - 0.5, y - 0.9, x + 0.5, y + 0.9, hz - 0.01), "light"))
    polys.append((_quad_xy(-hx, -hy, hx, hy, 0.0), "floor"))
    w, h = court.HALF_WIDTH_DOUBLES + 0.6, court.HALF_LENGTH + 1.2
    polys.append((_quad_xy(-w, -h, w, h, 0.0), "mat"))
    half = court.LINE_WIDTH / 2
    for line in court.court_lines():
        (x0, y0), (x1, y1) = line.start, line.end
        if abs(x0 - x1) < 1e-9:      # along Y
            polys.append((_quad_xy(x0 - half, min(y0, y1) - half, x0 + half, max(y0, y1) + half,
                                   0.0), "line"))
        else:
            polys.append((_quad_xy(min(x0, x1) - half, y0 - half, max(x0, x1) + half, y0 + half,
                                   0.0), "line"))
    return polys


def _net_top(x: float) -> float:
    """Height of the tape: 1.55 m at the posts, sagging to 1.524 m at the centre."""
    frac = abs(x) / court.HALF_WIDTH_DOUBLES
    return court.NET_HEIGHT_CENTRE + (court.NET_HEIGHT_POSTS - court.NET_HEIGHT_CENTRE) * frac


def render_background(cam: PinholeCamera, polygons=None, colours=None, net: bool = True
                      ) -> np.ndarray:
    """The static hall, court, posts and net as this camera sees them (BGR uint8).

    ``polygons``: (3D polygon, colour key or BGR tuple) in painter's order, instead of the demo
    hall's (a randomised hall, ``demo_style.py``); ``colours``: the keys' colours, net and posts
    included (default ``COLOURS``); ``net=False``: the hall alone, without net and posts.
    """
    colours = COLOURS if colours is None else colours
    w, h = cam.size
    img = np.zeros((h, w, 3), np.uint8)
    for poly, key in (_hall_polygons() if polygons is None else polygons):
        _fill_polygon(img, cam, poly, colours[key] if isinstance(key, str) else key)
    if not net:
        return img
    # Net: translucent dark mesh with a grid, then the white tape, then the posts.
    xs = np.linspace(-court.HALF_WIDTH_DOUBLES, court.HALF_WIDTH_DOUBLES, 9)
    overlay = img.copy()
    for x0, x1 in zip(xs[:-1], xs[1:]):
        top0, top1 = _net_top(x0), _net_top(x1)
        quad = np.array([[x0, 0, top0 - court.NET_TOP_OF_MESH_DROP], [x1, 0, top1 - court.NET_TOP_OF_MESH_DROP],
                         [x1, 0, top1], [x0, 0, top0]])
        _fill_polygon(overlay, cam, quad, colours["net"])
    img[:] = cv2.addWeighted(overlay, 0.45, img, 0.55, 0)
    grid = img.copy()
    for x in np.arange(-court.HALF_WIDTH_DOUBLES, court.HALF_WIDTH_DOUBLES + 1e-6, 0.15):
        top = _net_top(x)
        _draw_segment(grid, cam, (x, 0, top - court.NET_TOP_OF_MESH_DROP), (x, 0, top), colours["net"], 1)
    for dz in np.arange(0.0, court.NET_TOP_OF_MESH_DROP, 0.15):
        for x0, x1 in zip(xs[:-1], xs[1:]):
            _draw_segment(grid, cam, (x0, 0, _net_top(x0) - dz), (x1, 0, _net_top(x1) - dz),
                          colours["net"], 1)
    img[:] = cv2.addWeighted(grid, 0.5, img, 0.5, 0)
    for x0, x1 in zip(xs[:-1], xs[1:]):
        quad = np.array([[x0, 0, _net_top(x0) - 0.075], [x1, 0, _net_top(x1) - 0.075],
                         [x1, 0, _net_top(x1)], [x0, 0, _net_top(x0)]])
        _fill_polygon(img, cam, quad, colours["tape"])
    for bottom, top in court.net_posts():
        _draw_capsule(img, cam, bottom, top, 0.02, 0.02, colours["post"])
    return img


def _draw_segment(img, cam: PinholeCamera, a, b, colour, thickness: int) -> None:
    pc = cam.to_camera([a, b])
    if pc[0, 2] < NEAR_PLANE and pc[1, 2] < NEAR_PLANE:
        return
    if pc[0, 2] < NEAR_PLANE or pc[1, 2] < NEAR_PLANE:
        i_in = 0 if pc[0, 2] >= NEAR_PLANE else 1
        s = (NEAR_PLANE - pc[i_in, 2]) / (pc[1 - i_in, 2] - pc[i_in, 2])
        pc[1 - i_in] = pc[i_in] + s * (pc[1 - i_in] - pc[i_in])
    uv = np.clip(cam.project_camera(pc), -1e5, 1e5)
    p = np.round(uv * SCALE).astype(np.int32)
    cv2.line(img, tuple(map(int, p[0])), tuple(map(int, p[1])), colour, thickness, cv2.LINE_AA, SHIFT)


# ---- players ---------------------------------------------------------------------------------

def _draw_capsule(img, cam: PinholeCamera, a, b, ra, rb, colour) -> None:
    pc = cam.to_camera([a, b])
    if pc[0, 2] < NEAR_PLANE or pc[1, 2] < NEAR_PLANE:
        return
    (u0, v0), (u1, v1) = cam.project_camera(pc).tolist()
    r0, r1 = (cam.focal * np.array([ra, rb]) / pc[:, 2]).tolist()
    _draw_capsule_2d(img, u0, v0, u1, v1, r0, r1, colour)


def _draw_capsule_2d(img, u0: float, v0: float, u1: float, v1: float, r0: float, r1: float,
                     colour) -> None:
    """Two end discs and the tangent quad between them (pixels, radii in pixels).

    ~32 of these per frame pair: on Python floats rather than (2,) arrays, because numpy's
    per-call overhead was most of the time. The arithmetic is the element-wise arithmetic of
    the array version, in the same order; ``round`` rounds half to even like ``np.round``.
    """
    dx, dy = u1 - u0, v1 - v0
    # np.hypot, not math.hypot: CPython's own algorithm may differ from libm's in the last bit.
    n = float(np.hypot(dx, dy))
    cv2.circle(img, (round(u0 * SCALE), round(v0 * SCALE)), max(round(r0 * SCALE), 1), colour,
               -1, cv2.LINE_AA, SHIFT)
    cv2.circle(img, (round(u1 * SCALE), round(v1 * SCALE)), max(round(r1 * SCALE), 1), colour,
               -1, cv2.LINE_AA, SHIFT)
    if n > 1e-6:
        px, py = -dy / n, dx / n
        quad = np.array([[round((u0 + px * r0) * SCALE), round((v0 + py * r0) * SCALE)],
                         [round((u1 + px * r1) * SCALE), round((v1 + py * r1) * SCALE)],
                         [round((u1 - px * r1) * SCALE), round((v1 - py * r1) * SCALE)],
                         [round((u0 - px * r0) * SCALE), round((v0 - py * r0) * SCALE)]],
                        np.int32)
        cv2.fillConvexPoly(img, quad, colour, cv2.LINE_AA, SHIFT)


class ProjectedCapsule(NamedTuple):
    """A body part in one camera, as Python floats (built ~32 times a frame pair)."""

    uv: tuple[tuple[float, float], tuple[float, float]]   # pixels of the two ends
    r: tuple[float, float]          # pixel radii
    depth: tuple[float, float]      # camera depths of the two ends (m)
    colour: tuple[int, int, int]
    part: str
    occludes: bool
    mean_depth: float               # (depth[0] + depth[1]) / 2, the painter's-order key


def project_capsules(cam: PinholeCamera, capsules: list[Capsule], player: int,
                     colours: dict | None = None) -> list[ProjectedCapsule]:
    """The player's body parts in this camera; ``colours``: their clothing (default
    ``PLAYER_COLOURS[player]``)."""
    if not capsules:
        return []
    ends = np.array([[c.a, c.b] for c in capsules], float).reshape(-1, 3)
    pc = cam.to_camera(ends)
    in_front = (pc[:, 2] >= NEAR_PLANE).reshape(-1, 2).all(axis=1).tolist()
    uv = cam.project_camera(np.where(pc[:, 2:3] >= NEAR_PLANE, pc, 1.0)).reshape(-1, 2, 2).tolist()
    depth = pc[:, 2].reshape(-1, 2).tolist()
    focal = cam.focal
    colours = PLAYER_COLOURS[player] if colours is None else colours
    out = []
    for i, c in enumerate(capsules):
        if not in_front[i]:
            continue
        d0, d1 = depth[i]
        (u0, v0), (u1, v1) = uv[i]
        out.append(ProjectedCapsule(((u0, v0), (u1, v1)), (focal * c.ra / d0, focal * c.rb / d1),
                                    (d0, d1), colours[c.part], c.part, c.occludes,
                                    (d0 + d1) / 2))
    return out


def occluded_by(caps: list[ProjectedCapsule], uv: np.ndarray, depth: float) -> bool:
    """True when the point (pixel ``uv`` at camera ``depth``) lies inside a nearer body part."""
    uv = np.asarray(uv, float)
    x, y = float(uv[0]), float(uv[1])
    for c in caps:
        if not c.occludes:
            continue
        (u0, v0), (u1, v1) = c.uv
        # Cheap rejection first (most parts are nowhere near the shuttle): the closest point
        # lies within the ends' box, and the disc there within max(r) of it. The 1 px and 1e-9
        # margins only make the test conservative; the decision below is the exact one.
        reach = max(c.r) + 1.0
        if (x < min(u0, u1) - reach or x > max(u0, u1) + reach or y < min(v0, v1) - reach
                or y > max(v0, v1) + reach or min(c.depth) >= depth + 1e-9):
            continue
        # The decision itself stays in numpy: ``@`` is a BLAS dot product whose rounding a
        # scalar re-write would not be guaranteed to reproduce (visibility is truth).
        cuv = np.array(c.uv)
        d = cuv[1] - cuv[0]
        n2 = float(d @ d)
        s = float(np.clip((uv - cuv[0]) @ d / n2, 0.0, 1.0)) if n2 > 1e-12 else 0.0
        closest = cuv[0] + s * d
        radius = c.r[0] + s * (c.r[1] - c.r[0])
        part_depth = c.depth[0] + s * (c.depth[1] - c.depth[0])
        if np.hypot(*(uv - closest)) <= radius and part_depth < depth:
            return True
    return False


@lru_cache(maxsize=1024)
def _gained(colour: tuple[int, int, int], gain: float) -> tuple[int, int, int]:
    # One gain per frame and ~10 part colours: cached rather than rebuilt ~32 times a pair.
    return tuple(min(255, int(v * gain)) for v in colour)


def draw_capsule(img, c: ProjectedCapsule, gain: float) -> None:
    colour = _gained(c.colour, gain)
    (u0, v0), (u1, v1) = c.uv
    r0, r1 = c.r
    if c.part == "racket_head":
        axes = (max(round(r0 * 0.8 * SCALE), 1), max(round(r0 * SCALE), 1))
        cv2.ellipse(img, (round(u0 * SCALE), round(v0 * SCALE)), axes, 0, 0, 360, colour,
                    max(1, int(r0 / 8)), cv2.LINE_AA, SHIFT)
        return
    _draw_capsule_2d(img, u0, v0, u1, v1, r0, r1, colour)


# ---- shuttle ---------------------------------------------------------------------------------

def lying_direction(horizontal) -> np.ndarray:
    """The axis direction (cork ahead, as ``draw_shuttle`` takes it) of a shuttle lying on the
    floor along the horizontal unit vector ``horizontal``: tilted by REST_TILT, skirt up."""
    h = np.asarray(horizontal, dtype=float)
    return np.array([h[0] * math.cos(REST_TILT), h[1] * math.cos(REST_TILT), -math.sin(REST_TILT)])


def draw_shuttle(img: np.ndarray, cam: PinholeCamera, positions: np.ndarray,
                 directions: np.ndarray, gain: float, scale: float = 1.0,
                 brightness: float = 1.0) -> None:
    """Composite a shuttle integrated over ``positions`` (K samples across the exposure).

    ``directions`` (K, 3) are unit flight directions: the skirt trails opposite to them.
    Drawn at 4× into a two-channel patch (coverage, premultiplied grey), averaged over the
    samples and reduced with INTER_AREA, so edges and blur are sub-pixel exact. ``scale``
    multiplies the shuttle's dimensions, ``brightness`` its grey (a worn or differently lit
    shuttle); at 1.0 both leave every product unchanged.
    """
    h_img, w_img = img.shape[:2]
    heads = cam.to_camera(positions)
    tails = cam.to_camera(positions - (SKIRT_LENGTH * scale) * directions)
    if np.any(heads[:, 2] < NEAR_PLANE) or np.any(tails[:, 2] < NEAR_PLANE):
        return
    uv_h = cam.project_camera(heads)
    uv_t = cam.project_camera(tails)
    r_h = cam.focal * (CORK_RADIUS * scale) / heads[:, 2]
    r_t = cam.focal * (SKIRT_RADIUS * scale) / tails[:, 2]
    margin = float(max(r_h.max(), r_t.max())) + 2.0
    allpts = np.vstack([uv_h, uv_t])
    x0 = int(np.floor(allpts[:, 0].min() - margin))
    y0 = int(np.floor(allpts[:, 1].min() - margin))
    x1 = int(np.ceil(allpts[:, 0].max() + margin)) + 1
    y1 = int(np.ceil(allpts[:, 1].max() + margin)) + 1
    x0c, y0c, x1c, y1c = max(x0, 0), max(y0, 0), min(x1, w_img), min(y1, h_img)
    if x0c >= x1c or y0c >= y1c or (x1 - x0) * (y1 - y0) > 400 * 400:
        return
    S = SUPERSAMPLE
    pw, ph = x1 - x0, y1 - y0
    acc = np.zeros((ph * S, pw * S, 2), np.float32)
    canvas = np.zeros((ph * S, pw * S, 2), np.uint8)
    ox, oy = float(x0), float(y0)

    # How much of the skirt's open end shows depends on the view angle to the shuttle axis.
    view = heads / np.linalg.norm(heads, axis=1, keepdims=True)
    axis_cam = directions @ cam.R.T
    end_on = np.abs(np.sum(view * axis_cam, axis=1)).tolist()
    # The per-sample geometry is a handful of scalars: Python floats instead of (2,) arrays
    # (numpy's per-call overhead was most of this function's time). Same element-wise
    # operations in the same order, ``round`` = ``np.round`` (half to even): same pixels.
    uv_h_l, uv_t_l = uv_h.tolist(), uv_t.tolist()
    r_h_l, r_t_l = r_h.tolist(), r_t.tolist()
    skirt_colour = (190, round(165 * brightness))   # coverage 0.75, grey 215 premultiplied
    cork_colour = (255, round(250 * brightness))
    for k in range(len(positions)):
        canvas.fill(0)
        (hx, hy), (tx, ty) = uv_h_l[k], uv_t_l[k]
        rh, rt = r_h_l[k] * S, r_t_l[k] * S
        dx, dy = tx - hx, ty - hy
        n = float(np.hypot(dx, dy))
        # Canvas coordinates, 1/16 px: ((p - origin + 0.5) * S - 0.5) * SCALE.
        chx, chy = ((hx - ox + 0.5) * S - 0.5) * SCALE, ((hy - oy + 0.5) * S - 0.5) * SCALE
        ctx, cty = ((tx - ox + 0.5) * S - 0.5) * SCALE, ((ty - oy + 0.5) * S - 0.5) * SCALE
        if n > 1e-6:
            px, py = -dy / n, dx / n
            hxo, hyo = px * rh * 0.9 * SCALE, py * rh * 0.9 * SCALE
            txo, tyo = px * rt * SCALE, py * rt * SCALE
            quad = np.array([[round(chx + hxo), round(chy + hyo)],
                             [round(ctx + txo), round(cty + tyo)],
                             [round(ctx - txo), round(cty - tyo)],
                             [round(chx - hxo), round(chy - hyo)]], np.int32)
            cv2.fillConvexPoly(canvas, quad, skirt_colour, cv2.LINE_AA, SHIFT)
        r_end = rt * max(0.3, end_on[k])
        cv2.circle(canvas, (round(ctx), round(cty)), max(round(r_end * SCALE), 1), skirt_colour,
                   -1, cv2.LINE_AA, SHIFT)
        cv2.circle(canvas, (round(chx), round(chy)), max(round(rh * SCALE), 1), cork_colour, -1,
                   cv2.LINE_AA, SHIFT)
        # cv2.accumulate: 3x faster than numpy's casting ``acc += canvas``; both add integers
        # below 2^24 in float32, which is exact, so the sums are the same.
        cv2.accumulate(canvas, acc)
    acc *= 1.0 / (255.0 * len(positions))
    small = cv2.resize(acc, (pw, ph), interpolation=cv2.INTER_AREA)
    small = small[y0c - y0:y1c - y0, x0c - x0:x1c - x0]
    alpha = small[..., 0:1]
    grey = small[..., 1:2] * (255.0 * gain)
    roi = img[y0c:y1c, x0c:x1c].astype(np.float32)
    img[y0c:y1c, x0c:x1c] = np.clip(roi * (1.0 - alpha) + grey, 0, 255).astype(np.uint8)

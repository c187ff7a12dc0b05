"""Randomised demo courts: families of halls, rigs, lenses, cameras, shuttles and players.

Why this file exists: a tracker tuned on one synthetic hall and one rig says little about the
next hall and the next rack. ``sample_scene(family, seed)`` draws a ``SceneStyle`` from a seeded
generator: the hall (size, colours, plank and panel textures, grain, light panels and their mains
flicker), an animated LED advertising board (bright, changing, with a moving white dot: the
trap that made the tracker follow a board on TV), the camera placement of a family, the
horizontal field of view (50–120°), the resolution (640×480 … 2048×1536), the frame rate
(60–240 fps), the exposure, the sensor noise, the shuttle's size and grey, and the players'
clothing. ``DemoScene(seed, style=...)`` renders it with the same physics, players and exact
truth as the demo court, and its ``rig`` is the exact rig (with court pose) the frames were
drawn with, so 2D and 3D can be scored.

Seeds: 0–999 are tuning seeds anyone may look at; seeds from ``BENCHMARK_SEEDS_FROM`` (1000)
on are reserved for ``benchmarks/scenes.py`` and are never used to choose a parameter.

Families (where the two cameras stand; each fits the court part it must see by moving the rig
away from the court until that part fits the field of view it drew):

* ``side-near``: a rack beside the near half, where the robot plays; wide lens; sees the near half.
* ``side-far``: a rack far out beside the court, narrow lens; sees the whole court.
* ``behind-baselines``: one camera high behind each baseline (the NYCU rig); the whole court.
* ``high``: a rack 6.5–8.5 m up beside the court, looking down; the whole court.
* ``low``: a rack 0.5–1.2 m above the floor beside the near half; players often hide the shuttle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

from ..core import court
from ..core.rig import StereoRig
from . import demo_render as dr

FAMILIES = ("side-near", "side-far", "behind-baselines", "high", "low")
BENCHMARK_SEEDS_FROM = 1000
SIZES = ((640, 480), (800, 600), (1024, 768), (1280, 720), (1280, 960), (1440, 1080),
         (1920, 1080), (2048, 1536))
FRAME_RATES = (60.0, 90.0, 100.0, 120.0, 150.0, 180.0, 240.0)
FOV_RANGE = (50.0, 120.0)          # degrees, horizontal
RALLY_SHOTS = (1, 4)               # short rallies: a landing every ~3 s of footage

# Per family: horizontal FOV range (deg), stereo baseline range (m), distance range from the
# court's edge (m), and which part of the court both cameras must see.
_FAMILY_RANGES = {
    "side-near": ((90.0, 120.0), (0.3, 0.9), (0.8, 6.0), "near"),
    "side-far": ((50.0, 80.0), (0.8, 2.0), (2.0, 25.0), "all"),
    "behind-baselines": ((50.0, 90.0), (0.0, 0.0), (1.5, 16.0), "all"),
    "high": ((60.0, 100.0), (1.0, 2.5), (0.3, 16.0), "all"),
    "low": ((80.0, 120.0), (0.3, 0.8), (0.8, 8.0), "near"),
}


@dataclass(frozen=True)
class LedBoard:
    """An advertising board standing on the floor outside the court, lit from within.

    ``corners``: bottom-left, bottom-right, top-right, top-left (court frame, m) as seen from the
    court. Its picture (``texture(t)``) scrolls, changes message and colours every ``period`` s,
    flashes, and carries a small white dot moving across it like a shuttle.
    """

    corners: tuple[tuple[float, float, float], ...]
    texels: tuple[int, int]               # picture width, height
    palette: tuple[tuple[int, int, int], ...]
    period: float                         # s between messages
    scroll: float                         # texels per second
    dot_speed: float                      # board widths per second of the white dot
    seed: int

    def texture(self, t: float) -> np.ndarray:
        tw, th = self.texels
        k = int(math.floor(t / self.period))
        img = _board_message(self.seed, k, tw, th, self.palette).copy()
        img = np.roll(img, -int(t * self.scroll) % tw, axis=1)
        phase = (t / self.period) % 1.0
        if phase < 0.08:                   # a flash at each new message
            img = cv2.add(img, np.full_like(img, 110))
        # The white dot bounces along the board at a shuttle-like image speed.
        u = (t * self.dot_speed) % 2.0
        x = (u if u < 1.0 else 2.0 - u) * (tw - 1)
        y = (0.5 + 0.3 * math.sin(2 * math.pi * 1.3 * t)) * (th - 1)
        cv2.circle(img, (round(x * 16), round(y * 16)), 16,
                   (255, 255, 255), -1, cv2.LINE_AA, 4)
        return img


@lru_cache(maxsize=64)
def _board_message(seed: int, k: int, tw: int, th: int, palette: tuple) -> np.ndarray:
    """The board's picture for message ``k``: coloured blocky glyphs on a dark or bright field."""
    rng = np.random.default_rng([seed, k])
    fg = palette[int(rng.integers(len(palette)))]
    bg = tuple(int(c) for c in rng.integers(0, 60, 3)) if rng.uniform() < 0.7 else \
        palette[int(rng.integers(len(palette)))]
    img = np.empty((th, tw, 3), np.uint8)
    img[:] = bg
    cell = max(th // 7, 1)
    glyphs = rng.uniform(size=(5, tw // cell)) < 0.45
    top = (th - 5 * cell) // 2
    for r, c in zip(*np.nonzero(glyphs)):
        if c % 4 == 3:
            continue                       # a gap between letters
        img[top + r * cell:top + (r + 1) * cell, c * cell:(c + 1) * cell] = fg
    return img


@dataclass(frozen=True)
class SceneStyle:
    """One randomised scene: everything ``DemoScene`` needs beyond the rally's seed."""

    family: str
    seed: int
    size: tuple[int, int]
    fps: float
    hfov_deg: float
    centres: tuple[tuple[float, float, float], tuple[float, float, float]]
    aims: tuple[tuple[float, float, float], tuple[float, float, float]]
    hall: tuple[float, float, float]      # half length along X, half along Y, height (m)
    colours: tuple[tuple[str, tuple[int, int, int]], ...]
    floor_texture: float                  # grey levels of plank-to-plank variation
    wall_texture: float                   # grey levels of panel-to-panel variation
    grain: float                          # grey levels of fine static texture
    lights: int                           # light panels on the walls and ceiling
    light_level: int                      # their brightness (grey)
    flicker: float                        # relative amplitude of the mains ripple
    mains_hz: float                       # 50 Hz mains: 100 Hz ripple; 60 Hz: 120 Hz
    board: LedBoard | None
    shuttle_scale: float
    shuttle_brightness: float
    player_colours: tuple[tuple[tuple[str, tuple[int, int, int]], ...], ...]   # per player
    noise_sigma: float
    exposure: float                       # s
    rally_shots: tuple[int, int] = RALLY_SHOTS
    detail_seed: int = 0                  # planks, panels, light positions, grain

    # -- the rig --
    def rig(self) -> StereoRig:
        """The exact rig the frames are drawn with (pinhole, court pose = the left camera's)."""
        w, h = self.size
        f = (w / 2) / math.tan(math.radians(self.hfov_deg) / 2)
        k = np.array([[f, 0, (w - 1) / 2], [0, f, (h - 1) / 2], [0, 0, 1]])
        rotations = [dr.look_at(c, a) for c, a in zip(self.centres, self.aims)]
        centres = [np.asarray(c, float) for c in self.centres]
        t = [-r @ c for r, c in zip(rotations, centres)]
        r_rel = rotations[1] @ rotations[0].T
        t_rel = t[1] - r_rel @ t[0]
        return StereoRig(M1=k, D1=np.zeros(5), M2=k.copy(), D2=np.zeros(5), R=r_rel, T=t_rel,
                         image_size=(w, h), R_court=rotations[0].T, T_court=centres[0])

    def flicker_gain(self, t: float) -> float:
        return (1.0 + self.flicker * math.sin(2 * math.pi * self.mains_hz * t)
                + 0.01 * math.sin(2 * math.pi * 0.37 * t + self.seed))

    def clothes(self) -> tuple[dict, dict]:
        """Each player's part → BGR colour (``demo_render.project_capsules``)."""
        return dict(self.player_colours[0]), dict(self.player_colours[1])

    def look(self, cameras) -> "StyledLook":
        return StyledLook(self, cameras)

    def describe(self) -> str:
        return (f"{self.family} seed {self.seed}: {self.size[0]}x{self.size[1]} {self.fps:g} fps, "
                f"FOV {self.hfov_deg:.0f}°, {self.lights} lights, "
                f"{'LED board' if self.board else 'no board'}, shuttle x{self.shuttle_scale:.2f}")


class StyledLook:
    """The per-camera drawing of a style: static backgrounds and the LED board's placement."""

    def __init__(self, style: SceneStyle, cameras) -> None:
        self.style = style
        colours = dict(dr.COLOURS)
        colours.update(dict(style.colours))
        polygons = _hall_polygons(style, colours)
        self.backgrounds = []
        no_net = []
        for cam in cameras:
            bg = dr.render_background(cam, polygons, colours)
            no_net.append(dr.render_background(cam, polygons, colours, net=False)
                          if style.board is not None else None)
            if style.grain > 0:
                rng = np.random.default_rng([style.detail_seed, 7])
                h, w = bg.shape[:2]
                grain = cv2.GaussianBlur(rng.normal(0.0, 1.0, (h, w)).astype(np.float32), (0, 0), 1.5)
                grain *= style.grain / max(float(grain.std()), 1e-6)
                bg = np.clip(bg.astype(np.float32) + grain[..., None], 0, 255).astype(np.uint8)
            self.backgrounds.append(bg)
        # Where the board shows in each camera: its homography from picture to image, the
        # image box it covers, and the pixels it covers that the net and posts do not hide.
        self._boards = []
        for cam, bg, plain in zip(cameras, self.backgrounds, no_net):
            self._boards.append(None if style.board is None else
                                _board_in_camera(style.board, cam, bg, plain))

    def draw_boards(self, img: np.ndarray, camera: int, t: float) -> None:
        placed = self._boards[camera]
        if placed is None:
            return
        h_roi, (x0, y0, x1, y1), mask = placed
        roi = img[y0:y1, x0:x1]
        warped = cv2.warpPerspective(self.style.board.texture(t), h_roi, (x1 - x0, y1 - y0),
                                     flags=cv2.INTER_LINEAR)
        np.copyto(roi, warped, where=mask)


def _board_in_camera(board: LedBoard, cam, bg, plain):
    corners = np.asarray(board.corners, float)
    pc = cam.to_camera(corners)
    if np.any(pc[:, 2] < 0.3):
        return None
    uv = cam.project_camera(pc)
    w, h = cam.size
    x0, y0 = max(int(np.floor(uv[:, 0].min())), 0), max(int(np.floor(uv[:, 1].min())), 0)
    x1, y1 = min(int(np.ceil(uv[:, 0].max())) + 1, w), min(int(np.ceil(uv[:, 1].max())) + 1, h)
    if x1 - x0 < 2 or y1 - y0 < 2:
        return None
    tw, th = board.texels
    src = np.float32([[0, th], [tw, th], [tw, 0], [0, 0]])
    hom = cv2.getPerspectiveTransform(src, np.float32(uv - [x0, y0]))
    cover = cv2.warpPerspective(np.full((th, tw), 255, np.uint8), hom, (x1 - x0, y1 - y0),
                                flags=cv2.INTER_NEAREST)
    # The net and posts are drawn over the hall: where they changed a pixel, the board stays behind.
    netted = np.any(cv2.absdiff(bg[y0:y1, x0:x1], plain[y0:y1, x0:x1]) > 12, axis=2)
    mask = ((cover > 0) & ~netted)[..., None]
    if not mask.any():
        return None
    return hom, (x0, y0, x1, y1), mask


# ---- geometry --------------------------------------------------------------------------------

def _required(part: str) -> np.ndarray:
    w, hl = court.HALF_WIDTH_DOUBLES, court.HALF_LENGTH
    net = [(-w, 0, 0), (w, 0, 0), (-w, 0, court.NET_HEIGHT_POSTS), (w, 0, court.NET_HEIGHT_POSTS)]
    if part == "near":
        return np.array([(-w, -hl, 0), (w, -hl, 0), *net], float)
    return np.array([(-w, -hl, 0), (w, -hl, 0), (-w, hl, 0), (w, hl, 0), *net], float)


def _fits(centres, aims, hfov_deg, size, points, margin=0.92) -> bool:
    w, h = size
    f = (w / 2) / math.tan(math.radians(hfov_deg) / 2)
    for c, a in zip(centres, aims):
        pc = (points - np.asarray(c)) @ dr.look_at(c, a).T
        if np.any(pc[:, 2] <= 0.2):
            return False
        if (np.any(np.abs(pc[:, 0] / pc[:, 2]) * f > margin * (w - 1) / 2)
                or np.any(np.abs(pc[:, 1] / pc[:, 2]) * f > margin * (h - 1) / 2)):
            return False
    return True


def _placement(family: str, rng: np.random.Generator):
    """A function distance → (centres, aims) for the family, drawn once from ``rng``."""
    w, hl = court.HALF_WIDTH_DOUBLES, court.HALF_LENGTH
    (_, _), (b_lo, b_hi), _, _ = _FAMILY_RANGES[family]
    baseline = rng.uniform(b_lo, b_hi)
    if family == "behind-baselines":
        xs = rng.uniform(-1.5, 1.5, 2)
        zs = rng.uniform(3.0, 6.0, 2)
        jitter = rng.uniform(-0.5, 0.5)

        def at(d):
            centres = [(xs[0], -hl - d, zs[0]), (xs[1], hl + d + jitter, zs[1])]
            aims = [(0.0, -0.5, 0.0), (0.0, 0.5, 0.0)]
            return centres, aims
        return at
    if family == "side-near":
        y0, z, aim = rng.uniform(-4.5, -2.0), rng.uniform(2.0, 4.0), \
            (rng.uniform(0.0, 2.0), rng.uniform(-4.0, -2.5), rng.uniform(1.2, 1.8))
    elif family == "low":
        y0, z, aim = rng.uniform(-4.5, -1.5), rng.uniform(0.5, 1.2), \
            (rng.uniform(0.0, 2.0), rng.uniform(-4.0, -2.5), rng.uniform(1.4, 2.0))
    elif family == "side-far":
        y0, z, aim = rng.uniform(-2.0, 0.5), rng.uniform(2.5, 5.0), \
            (rng.uniform(0.0, 1.5), rng.uniform(-1.0, 1.0), 1.0)
    else:   # high
        y0, z, aim = rng.uniform(-3.0, 0.0), rng.uniform(6.5, 8.5), \
            (rng.uniform(0.0, 1.5), rng.uniform(-1.5, 0.5), 0.5)
    aim = np.array(aim)

    def at(d):
        mid = np.array([-(w + d), y0, z])
        x_axis = dr.look_at(mid, aim)[0]
        far_aim = mid + 12.0 * (aim - mid) / np.linalg.norm(aim - mid)    # slight toe-in
        centres = [tuple(mid - 0.5 * baseline * x_axis), tuple(mid + 0.5 * baseline * x_axis)]
        return centres, [tuple(far_aim), tuple(far_aim)]
    return at


def _fit_rig(family: str, rng: np.random.Generator, size):
    """Field of view, centres and aims: the nearest distance at which the court part fits."""
    (f_lo, f_hi), _, (d_lo, d_hi), part = _FAMILY_RANGES[family]
    hfov = float(rng.uniform(f_lo, f_hi))
    at = _placement(family, rng)
    points = _required(part)
    while True:
        for d in np.geomspace(d_lo, d_hi, 60):
            centres, aims = at(float(d))
            if _fits(centres, aims, hfov, size, points):
                return hfov, centres, aims
        if hfov >= FOV_RANGE[1]:
            return hfov, *at(d_hi)        # the court part fits nowhere: keep the farthest
        hfov = min(hfov + 5.0, FOV_RANGE[1])


# ---- the hall --------------------------------------------------------------------------------

def _quad_xy(x0, y0, x1, y1, z=0.0) -> np.ndarray:
    return np.array([[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]], dtype=float)


def _grey_jitter(colour, delta) -> tuple[int, int, int]:
    return tuple(int(np.clip(c + delta, 0, 255)) for c in colour)


def _hall_polygons(style: SceneStyle, colours: dict) -> list:
    """Ceiling, textured walls, lights, planked floor, mat, lines and the board's frame."""
    rng = np.random.default_rng([style.detail_seed, 1])
    hx, hy, hz = style.hall
    quad = _quad_xy
    polys: list = [(quad(-hx, -hy, hx, hy, hz), "ceiling")]
    # Walls as vertical panels whose grey varies: a texture the background model must absorb.
    for sx in (-1, 1):
        edges = np.linspace(-hy, hy, int(rng.integers(6, 16)) + 1)
        for y0, y1 in zip(edges[:-1], edges[1:]):
            tone = _grey_jitter(colours["wall"], rng.normal(0.0, style.wall_texture))
            polys.append((np.array([[sx * hx, y0, 0], [sx * hx, y1, 0], [sx * hx, y1, hz],
                                    [sx * hx, y0, hz]], float), tone))
    for sy in (-1, 1):
        edges = np.linspace(-hx, hx, int(rng.integers(4, 12)) + 1)
        for x0, x1 in zip(edges[:-1], edges[1:]):
            tone = _grey_jitter(colours["back_wall"], rng.normal(0.0, style.wall_texture))
            polys.append((np.array([[x0, sy * hy, 0], [x1, sy * hy, 0], [x1, sy * hy, hz],
                                    [x0, sy * hy, hz]], float), tone))
    light = (style.light_level,) * 3
    for _ in range(style.lights):
        where = rng.uniform()
        lw, lh = rng.uniform(0.6, 1.8), rng.uniform(0.3, 0.9)
        if where < 0.4:          # ceiling
            x, y = rng.uniform(-hx + 1, hx - 1), rng.uniform(-hy + 1, hy - 1)
            polys.append((quad(x, y, x + lw, y + lh * 2, hz - 0.01), light))
        elif where < 0.7:        # side walls, high
            sx, y, z = rng.choice([-1, 1]), rng.uniform(-hy + 1, hy - 2), rng.uniform(2.5, hz - 1)
            x = sx * (hx - 0.01)
            polys.append((np.array([[x, y, z], [x, y + lw, z], [x, y + lw, z + lh],
                                    [x, y, z + lh]], float), light))
        else:                    # end walls
            sy, x, z = rng.choice([-1, 1]), rng.uniform(-hx + 1, hx - 2), rng.uniform(2.5, hz - 1)
            y = sy * (hy - 0.01)
            polys.append((np.array([[x, y, z], [x + lw, y, z], [x + lw, y, z + lh],
                                    [x, y, z + lh]], float), light))
    # Floor planks along Y whose grey varies.
    edges = np.arange(-hx, hx + 1e-9, rng.uniform(0.4, 1.2))
    for x0, x1 in zip(edges[:-1], edges[1:]):
        tone = _grey_jitter(colours["floor"], rng.normal(0.0, style.floor_texture))
        polys.append((quad(x0, -hy, x1, hy, 0.0), tone))
    mw, mh = court.HALF_WIDTH_DOUBLES + 0.6, court.HALF_LENGTH + 1.2
    polys.append((quad(-mw, -mh, mw, mh, 0.0), "mat"))
    half = court.LINE_WIDTH / 2
    for line in court.court_lines():
        (x0, y0), (x1, y1) = line.start, line.end
        if abs(x0 - x1) < 1e-9:
            polys.append((quad(x0 - half, min(y0, y1) - half, x0 + half, max(y0, y1) + half), "line"))
        else:
            polys.append((quad(min(x0, x1) - half, y0 - half, max(x0, x1) + half, y0 + half), "line"))
    if style.board is not None:
        polys.append((np.asarray(style.board.corners, float), (20, 20, 20)))
    return polys


def _board(rng: np.random.Generator, centres, hall, seed: int) -> LedBoard | None:
    """A board on the floor 1.5–3 m outside the court, on a side the cameras look towards."""
    w, hl = court.HALF_WIDTH_DOUBLES, court.HALF_LENGTH
    cam = np.mean(np.asarray(centres), axis=0)
    length, height = rng.uniform(3.0, 8.0), rng.uniform(0.6, 1.0)
    gap = rng.uniform(1.5, 3.0)
    # Only where every camera sees the players between itself and the board (painter's
    # order and the truth's occlusion test know nothing of a board in front of a player).
    options = []
    y = rng.uniform(-hl + length / 2, hl - length / 2)
    for sx in ((1,) if cam[0] < -w else (-1, 1)):        # the side away from a side rack
        x = sx * min(w + gap, hall[0] - 0.3)
        options.append(((x, y + sx * length / 2, 0), (x, y - sx * length / 2, 0)))
    if cam[0] < -w:                  # a side rack also sees behind both baselines
        for sy in (-1, 1):
            yb = sy * min(hl + gap, hall[1] - 0.3)
            x = rng.uniform(-w, w)
            options.append(((x - sy * length / 2, yb, 0), (x + sy * length / 2, yb, 0)))
    (a, b) = options[int(rng.integers(len(options)))]
    corners = (a, b, (b[0], b[1], height), (a[0], a[1], height))
    texels = (int(round(length / height * 16)), 16)
    palette = tuple(tuple(int(c) for c in rng.integers(0, 256, 3)) for _ in range(4)) + \
        ((255, 255, 255), (0, 230, 255), (40, 40, 255))
    return LedBoard(tuple(tuple(float(v) for v in p) for p in corners), texels, palette,
                    period=float(rng.uniform(0.6, 2.5)), scroll=float(rng.uniform(5.0, 40.0)),
                    dot_speed=float(rng.uniform(0.3, 1.5)), seed=seed)


def _colour(rng, lo, hi) -> tuple[int, int, int]:
    return tuple(int(c) for c in rng.integers(lo, hi, 3))


def sample_scene(family: str, seed: int) -> SceneStyle:
    """The scene of a family for a seed (the same style for the same arguments, always)."""
    if family not in FAMILIES:
        raise ValueError(f"unknown scene family {family!r}: choose one of {', '.join(FAMILIES)}")
    rng = np.random.default_rng([FAMILIES.index(family), int(seed), 40])
    size = SIZES[int(rng.integers(len(SIZES)))]
    fps = FRAME_RATES[int(rng.integers(len(FRAME_RATES)))]
    hfov, centres, aims = _fit_rig(family, rng, size)
    reach = np.abs(np.asarray(centres))
    hall = (max(float(rng.uniform(7.5, 12.0)), float(reach[:, 0].max()) + 1.0),
            max(float(rng.uniform(10.5, 15.0)), float(reach[:, 1].max()) + 1.0),
            max(float(rng.uniform(8.0, 12.0)), float(reach[:, 2].max()) + 1.0))
    mats = [(62, 112, 48), (120, 80, 40), (40, 50, 140), (90, 90, 90), (50, 100, 150)]
    colours = (("ceiling", _colour(rng, 15, 110)), ("wall", _colour(rng, 25, 150)),
               ("back_wall", _colour(rng, 25, 150)), ("floor", _colour(rng, 40, 140)),
               ("mat", _grey_jitter(mats[int(rng.integers(len(mats)))], rng.integers(-20, 20))),
               ("line", (int(rng.integers(215, 250)),) * 3))
    clothes = []
    for _ in range(2):
        shirt = (_colour(rng, 200, 256) if rng.uniform() < 0.25 else _colour(rng, 20, 220))
        clothes.append({"shirt": shirt, "shorts": _colour(rng, 10, 200),
                        "skin": _grey_jitter((110, 140, 185), rng.integers(-50, 30)),
                        "hair": _colour(rng, 10, 60), "racket": _colour(rng, 20, 200),
                        "racket_head": _colour(rng, 20, 200)})
    board = _board(rng, centres, hall, int(seed)) if rng.uniform() < 0.8 else None
    return SceneStyle(
        family=family, seed=int(seed), size=size, fps=fps, hfov_deg=hfov,
        centres=tuple(tuple(float(v) for v in c) for c in centres),
        aims=tuple(tuple(float(v) for v in a) for a in aims), hall=hall, colours=colours,
        floor_texture=float(rng.uniform(0.0, 14.0)), wall_texture=float(rng.uniform(0.0, 20.0)),
        grain=float(rng.uniform(0.0, 4.0)), lights=int(rng.integers(6, 30)),
        light_level=int(rng.integers(200, 256)), flicker=float(rng.uniform(0.0, 0.05)),
        mains_hz=float(rng.choice([100.0, 120.0])), board=board,
        shuttle_scale=float(rng.uniform(0.92, 1.08)),
        shuttle_brightness=float(rng.uniform(0.8, 1.0)),
        player_colours=tuple(tuple(c.items()) for c in clothes), noise_sigma=float(rng.uniform(1.5, 4.0)),
        exposure=float(min(rng.uniform(0.001, 0.003), 0.5 / fps)),
        detail_seed=int(rng.integers(2 ** 31)))

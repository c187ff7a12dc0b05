"""The values that flow through the pipeline, all frozen.

Why this file exists: sources, the tracker, the GUI worker, the CLI and the robot link exchange
only these types. They are frozen (caliscope's packets) so that a result handed to
the GUI thread can never be changed under its feet by the worker.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

# Names of the filters that can reject a candidate; the GUI colours rejected candidates by these.
REJECT_LENGTH = "length"          # filter 1: contour length out of range
REJECT_SHORT_SIDE = "short_side"  # filter 2: tilted rectangle's shortest side out of range
REJECT_WHITENESS = "whiteness"    # filter 3: not white enough / too saturated
REJECT_MOTION = "motion"          # filter 4: too far from the predicted position, or stationary
REJECT_STEREO = "stereo"          # withheld by the two-camera rules: no partner, unconfirmed, caught, gone out of view
REJECT_SCORE = "score"            # passed the filters but another candidate was better
REJECT_REASONS = (REJECT_LENGTH, REJECT_SHORT_SIDE, REJECT_WHITENESS, REJECT_MOTION,
                  REJECT_STEREO, REJECT_SCORE)


@dataclass(frozen=True, slots=True)
class StereoFrame:
    """One pair of frames as delivered by a source (BGR uint8 images)."""

    left: np.ndarray
    right: np.ndarray
    t_left: float          # seconds, the source's clock
    t_right: float
    index: int             # left frame index
    index_right: int = -1  # paired right frame index (-1: same as index)
    # Cameras without a common trigger (io/video.py ``VideoPair``): a step may bring a new
    # image from one camera only; the other's image is the one it already brought, which its
    # detector must not see twice (``StereoTracker.process_frame``).
    fresh_left: bool = True
    fresh_right: bool = True

    @property
    def timestamp(self) -> float:
        """The step's time: the left image's, or the right one's on a step only it brought."""
        return self.t_left if self.fresh_left else self.t_right


@dataclass(frozen=True, slots=True)
class Candidate:
    """A blob that the background difference found, with what the four filters measured.

    ``x, y`` are full-resolution pixel coordinates of the shuttle's estimated head.
    ``rejected_by`` is None for the accepted detection and otherwise names the filter (one of
    ``REJECT_REASONS``) that rejected it.
    """

    x: float
    y: float
    length: float        # contour perimeter, px
    short_side: float    # shortest side of the minimum-area rectangle, px
    whiteness: float     # mean min(B,G,R) inside the contour
    area: float          # contour area, px²
    motion: float        # distance from the predicted position, px (nan: no track)
    score: float         # higher is more shuttle-like
    rejected_by: str | None = None
    # True when no blob was seen: the followed track's prediction, carried through a spot
    # where the detector is blind (a light, a white line); never triangulated.
    predicted: bool = False
    # Ident of the tracklet (core/association.py) the candidate lies on, -1 when on none: stable
    # from frame to frame, so a later stage (core/lookahead.py) can follow a tracklet's future.
    tracklet: int = -1


def _candidate_maker():
    """A constructor of :class:`Candidate` for the detector's hot loops, ~2× cheaper.

    A frozen dataclass's ``__init__`` sets each field through ``object.__setattr__``; writing
    the slots directly gives the same object for half the cost (the detector makes a Candidate
    for every contour of every frame, ~110 a frame at 2048 px, with the GIL held).
    ``tests/test_speed_oracles.py`` checks it against ``Candidate(...)`` and its field list.
    """
    new = object.__new__
    (set_x, set_y, set_length, set_short_side, set_whiteness, set_area, set_motion, set_score,
     set_rejected_by, set_predicted, set_tracklet) = (getattr(Candidate, f).__set__ for f in CANDIDATE_FIELDS)

    def make_candidate(x: float, y: float, length: float, short_side: float, whiteness: float,
                       area: float, motion: float, score: float, rejected_by: str | None = None,
                       predicted: bool = False, tracklet: int = -1) -> Candidate:
        c = new(Candidate)
        set_x(c, x)
        set_y(c, y)
        set_length(c, length)
        set_short_side(c, short_side)
        set_whiteness(c, whiteness)
        set_area(c, area)
        set_motion(c, motion)
        set_score(c, score)
        set_rejected_by(c, rejected_by)
        set_predicted(c, predicted)
        set_tracklet(c, tracklet)
        return c

    return make_candidate


CANDIDATE_FIELDS = ("x", "y", "length", "short_side", "whiteness", "area", "motion", "score",
                    "rejected_by", "predicted", "tracklet")
make_candidate = _candidate_maker()


@dataclass(frozen=True, slots=True)
class CameraResult:
    """What one camera's detector concluded for one frame."""

    detection: Candidate | None
    candidates: tuple[Candidate, ...] = ()
    mask: np.ndarray | None = None     # binary foreground mask at processing scale (display)
    mask_scale: float = 1.0            # mask pixel = full-res pixel * mask_scale
    image_size: tuple[int, int] = (0, 0)  # (width, height) of the full-resolution frame
    # Windowed tracking (core/window.py): the full-resolution box (x0, y0, x1, y1) that was the
    # only part of this frame processed, None when the whole frame was. The views draw it, so a
    # mask that is empty outside it reads as "not looked at", not as "nothing moved".
    window: tuple[int, int, int, int] | None = None
    # ``association.exit_margin``: the tracklet that was seen leaving the picture through its top
    # edge this frame (-1: none). It was the shuttle: the look-ahead gives it its last frames.
    left_picture: int = -1

    @property
    def visible(self) -> bool:
        return self.detection is not None


@dataclass(frozen=True, slots=True)
class LandingPrediction:
    """Where and when the current flight will touch the floor (court frame)."""

    x: float
    y: float
    t: float               # absolute time of landing, the tracker's clock (s)
    radius: float          # 1-sigma-ish uncertainty radius on the floor (m)
    call: str = ""         # "in" / "out" / "" (unknown)
    aero_length: float = float("nan")  # fitted L of the drag model (m)


@dataclass(frozen=True, slots=True)
class FlightInfo:
    """Trajectory state derived from successive 3D points (filled by the trajectory module)."""

    shot_index: int = -1
    velocity: tuple[float, float, float] | None = None  # m/s
    peak_speed: float | None = None                     # m/s, of the current shot
    prediction: LandingPrediction | None = None
    withheld_reason: str = ""   # why there is no prediction (e.g. "no court pose")
    in_flight: bool = False     # a flight is being followed (False: idle, or landed / ended)
    # (t, x, y, z) for each point a new flight took up at this step from the track it grew out
    # of, on that track's fitted path: points of earlier frames, refused then (no flight
    # explained them yet), that the flight now vouches for. The look-ahead gives them to those
    # frames (``StereoLookahead``).
    confirmed: tuple = ()
    # The state, (t, x, y, z, vx, vy, vz, k), of that track at this step, or of the flight when
    # it took this step's point: with the drag model, where it puts the shuttle a moment earlier
    # (``flight.shot_filter.position_on_path``), for frames it refused just before. () otherwise.
    confirmed_path: tuple = ()


@dataclass(frozen=True, slots=True)
class TrackResult:
    """Everything the tracker knows after one frame pair."""

    index: int
    timestamp: float
    left: CameraResult
    right: CameraResult
    point: tuple[float, float, float] | None = None   # metres: the best estimate (filtered in a flight)
    in_court_frame: bool = False    # point is in court coordinates (else left-camera frame)
    distance: float | None = None   # metres from the left camera (the paper's readout)
    speed: float | None = None      # m/s
    epipolar_error: float | None = None  # px
    index_right: int = -1
    processing_ms: float = 0.0
    flight: FlightInfo = field(default_factory=FlightInfo)
    # The triangulated pair as measured (cork-corrected), even when the flight refused it.
    measured_point: tuple[float, float, float] | None = None
    # Metres from the left camera of where the followed flight puts the shuttle, on a frame with
    # no 3D point (one camera hidden or coasting): the readout shows it marked as predicted
    # rather than a dash in the middle of a flight. None whenever ``distance`` is set.
    predicted_distance: float | None = None
    # The rules that fired on this step, in order (``StereoTracker.trace``; empty unless enabled,
    # so a result stays cheap), e.g. ("guided_search:left", "landed_hold:right", "phase:landed").
    trace: tuple[str, ...] = ()
    # The pair's measured point extended the followed 3D flight (the drag-model filter took it):
    # both cameras' reports were the shuttle in flight (core/court_adaptation.py learns from them).
    pair_in_flight: bool = False

    @property
    def has_point(self) -> bool:
        return self.point is not None

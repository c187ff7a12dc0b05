"""Tracker parameters: frozen dataclasses whose fields carry their own range, unit and help.

Why this file exists: every threshold of the pipeline lives here, once. The tuning dialog,
presets, the CLI and the tests all read the same declarations, so adding a parameter needs no
GUI code (stytra's ``Param(default, (lo, hi))`` idea). Each group dataclass is one
box in the tuning dialog; :class:`TrackerParams` composes them.

All pixel quantities are in *full-resolution* pixels of the camera image, whatever resolution
the pipeline works at internally, so a preset means the same thing at any processing scale.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, ClassVar, Iterator


def param(default: Any, lo: float, hi: float, *, step: float | None = None, unit: str = "",
          label: str = "", help: str = "") -> Any:
    """A numeric dataclass field with its valid range, unit and a one-line explanation."""
    return field(default=default, metadata={
        "range": (lo, hi), "step": step, "unit": unit, "label": label, "help": help})


def choice(default: str, options: tuple[str, ...], *, label: str = "", help: str = "") -> Any:
    """A dataclass field restricted to a fixed set of strings."""
    return field(default=default, metadata={"options": options, "label": label, "help": help})


def flag(default: bool, *, label: str = "", help: str = "") -> Any:
    """A boolean dataclass field."""
    return field(default=default, metadata={"label": label, "help": help})


class ParamError(ValueError):
    """A parameter value outside its declared range, or an unknown parameter name."""


@dataclass(frozen=True, slots=True)
class ParamGroup:
    """Base of every parameter group; validates ranges on construction."""

    TITLE: ClassVar[str] = ""
    # False for a group only the file commands read (the live tuning dialog leaves it out: a
    # slider that changes nothing on screen would mislead the operator).
    LIVE: ClassVar[bool] = True

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            meta = f.metadata
            if "range" in meta:
                lo, hi = meta["range"]
                if not (lo <= value <= hi):
                    raise ParamError(f"{type(self).__name__}.{f.name} = {value!r} is outside "
                                     f"its range [{lo}, {hi}]")
            elif "options" in meta and value not in meta["options"]:
                raise ParamError(f"{type(self).__name__}.{f.name} = {value!r} is not one of "
                                 f"{', '.join(meta['options'])}")


@dataclass(frozen=True, slots=True)
class BackgroundParams(ParamGroup):
    """The paper's Gaussian-mixture background difference (OpenCV MOG2), or a frame difference."""

    TITLE: ClassVar[str] = "Background model"
    method: str = choice("bright_diff", ("mog2", "frame_diff", "bright_diff"), label="Method",
                         help="Gaussian mixture (MOG2), three-frame difference, or brighter-than-"
                              "running-average (a white shuttle in a dark hall; dark players drop out)")
    learning_rate: float = param(0.05, 0.0, 1.0, step=0.005, label="Learning rate α",
                                 help="How fast the background absorbs change (paper: ≈0.03)")
    history: int = param(200, 2, 5000, step=10, unit="frames", label="History",
                         help="MOG2 history length (used for initial learning)")
    n_mixtures: int = param(3, 1, 8, step=1, label="Gaussians K",
                            help="Gaussians per pixel (paper: 3–5)")
    var_threshold: float = param(16.0, 1.0, 200.0, step=1.0, label="Variance threshold",
                                 help="Squared Mahalanobis distance for a pixel to match a Gaussian")
    detect_shadows: bool = flag(False, label="Detect shadows",
                                help="Mark shadows (grey 127) so binarization can drop them")
    compensate_gain: bool = flag(True, label="Compensate flicker",
                                 help="Divide out a common brightness gain (light flicker, exposure drift) "
                                      "before the brighter-than-average difference")
    # TV footage: a player in dark or saturated clothes is darker than the bright court. At α the
    # running average learns him within ~20 frames where he stands; when he leaves, the court he
    # uncovers is brighter than that average and floods the mask (the shuttle merges into it)
    # for ~200 frames, kept by the slow learning under the foreground (α/10).
    dark_threshold: int = param(0, 0, 254, step=1, label="Darker learns slowly from",
                                help="Brighter-than-average: pixels darker than the average by more than this "
                                     "(a player, a shadow) learn at α/10 like the foreground, so a player "
                                     "who leaves leaves no bright ghost behind; 0 = off (they learn at α)")
    shake_tolerance: int = param(1, 0, 5, step=1, unit="px", label="Shake tolerance",
                                 help="Brighter-than-average: compare with the brightest average pixel within "
                                      "this radius (processing-scale px), so a shaking camera's edges stay quiet")
    processing_scale: float = param(0.5, 0.125, 1.0, step=0.125, label="Processing scale",
                                    help="Background model runs on the image scaled by this factor")
    coarse_from_width: int = param(0, 0, 8192, step=64, unit="px", label="Coarser from width",
                                   help="Frames at least this wide run the background model at half the "
                                        "processing scale (2048 px cameras: a 512 px model, ~45 % less CPU) "
                                        "at some accuracy (NYCU F1 −1.4 to −1.8 points with the shipped "
                                        "classifier); positions and features still come from the full-resolution "
                                        "windows. 0: never")


@dataclass(frozen=True, slots=True)
class BinarizeParams(ParamGroup):
    """Binarization of the difference image and morphological denoising."""

    TITLE: ClassVar[str] = "Binarization"
    threshold: int = param(150, 0, 254, step=1, label="Threshold T",
                           help="Mask values above T are foreground (paper: 140–160; drops shadows)")
    diff_threshold: int = param(12, 1, 254, step=1, label="Frame-difference threshold",
                                help="Grey-level change counted as motion by the frame difference")
    open_kernel: int = param(0, 0, 15, step=1, unit="px", label="Opening kernel",
                             help="Morphological opening removes specks smaller than this (0 = off)")
    dilate_iterations: int = param(1, 0, 5, step=1, label="Dilate iterations",
                                   help="Joins the broken pieces of a blurred shuttle")
    max_background: int = param(170, 0, 255, step=1, label="Ignore lights above",
                                help="Brighter-than-average method: pixels whose average is at least this bright "
                                     "(ceiling lights, windows) are never foreground (255 = off)")


@dataclass(frozen=True, slots=True)
class ContourLengthParams(ParamGroup):
    """Filter 1: contour length (perimeter)."""

    TITLE: ClassVar[str] = "Contour length"
    min_length: float = param(20.0, 0.0, 2000.0, step=1.0, unit="px", label="Minimum length")
    max_length: float = param(250.0, 1.0, 5000.0, step=5.0, unit="px", label="Maximum length")
    # A shuttle far from the camera, or edge-on, makes a blob of 3 × 3 mask pixels (16 px long at
    # the demo court's half-scale model) in a frame or two of its flight: too short for the
    # minimum, which keeps the noise out, but where the followed shuttle is predicted it is the
    # shuttle far more often than noise.
    guided_min_length: float = param(14.0, 0.0, 2000.0, step=1.0, unit="px", label="... near the followed shuttle",
                                     help="A blob at least this long (and below the minimum) still passes where "
                                          "the followed shuttle is predicted (within 'guided radius'); 0 = off")
    guided_radius: float = param(12.0, 0.0, 200.0, step=1.0, unit="px", label="... guided radius",
                                 help="Distance from the followed shuttle's predicted position (px at 1280 px "
                                      "width, scaled with the width) within which the shorter blobs pass")
    # A shuttle touching a racket, an arm or a lit line's ghost merges with it into one blob: the
    # shuttle is the part of it that brightened since the previous frame (it moves ≥ its own size
    # a frame; a ghost or a slow arm does not), split off as a candidate of its own.
    split_min_length: float = param(40.0, 0.0, 5000.0, step=5.0, unit="px", label="Split blobs from length",
                                    help="Blobs at least this long (px at 1280 px width, scaled) also give "
                                         "candidates from their compact parts that brightened since the previous "
                                         "frame (a shuttle merged with a racket or an arm); 0 = off")
    split_threshold: float = param(40.0, 1.0, 255.0, step=1.0, label="... brightened by",
                                   help="Grey levels (at the processing scale) a pixel must have brightened since "
                                        "the previous frame to belong to a split-off part")
    # On the demo court (seed 3) a shuttle hidden behind a player for a few frames left its track
    # coasting with a grown gate, in which brightening parts of the player were split off
    # in both cameras, paired with each other and reported (8 FP2 in 400 frames). Requiring a
    # split part to have a candidate of the other camera near its epipolar line instead does not
    # stop them (they are each other's partners: right precision stays 0.9785), and on top of
    # this rule it costs 18 / 30 -> 22 / 33 wrong frames L / R on the 3 × 1000-frame benchmark.
    split_max_misses: int = param(0, 0, 50, step=1, unit="frames", label="... while the track missed at most",
                                  help="Split only around a followed track that missed its blob in at most this "
                                       "many of the last frames (0: it was seen in the previous frame)")


@dataclass(frozen=True, slots=True)
class TiltedRectParams(ParamGroup):
    """Filter 2: shortest side of the minimum-area (tilted) bounding rectangle."""

    TITLE: ClassVar[str] = "Tilted rectangle"
    min_short_side: float = param(1.0, 0.0, 200.0, step=0.5, unit="px", label="Shortest side ≥")
    max_short_side: float = param(30.0, 0.5, 500.0, step=0.5, unit="px", label="Shortest side ≤")


@dataclass(frozen=True, slots=True)
class ColourParams(ParamGroup):
    """Filter 3: whiteness of the pixels inside the contour."""

    TITLE: ClassVar[str] = "Colour"
    min_whiteness: float = param(0.0, 0.0, 255.0, step=1.0, label="Whiteness ≥",
                                 help="Mean of min(B, G, R) inside the contour")
    max_saturation: float = param(255.0, 0.0, 255.0, step=1.0, label="Saturation ≤",
                                  help="Mean of max(B,G,R) − min(B,G,R) inside the contour")
    min_contrast: float = param(10.0, 0.0, 255.0, step=1.0, label="Contrast ≥",
                                help="Brightest pixel of the blob above its surroundings (grey levels)")
    contrast_reference: float = param(40.0, 1.0, 255.0, step=1.0, label="Contrast for full score",
                                      help="Contrast at which a candidate's colour score saturates")
    head_fraction: float = param(0.5, 0.0, 0.95, step=0.05, label="Head: part of the peak",
                                 help="The position is the intensity centroid of the blob's pixels brighter than "
                                      "this fraction of its peak (0.5: the white cork, not the middle of the "
                                      "skirt; 0: the whole blob)")
    # Measured on the NYCU tuned-on rallies against the labels (the cork): the bright centroid
    # of a shuttle moving ≥ 4 px a frame lies 0.25–0.5 blob widths behind the label, ~6 px at
    # 2048×1536; moved by half a width, the median distance of moving detections to the label
    # went 6.0 → 2.5 px (held-out rally: 7.3 → 2.0 px).
    head_lead: float = param(0.5, 0.0, 2.0, step=0.05, label="Head: lead when moving",
                             help="A moving shuttle's cork is ahead of its bright centroid (the skirt trails "
                                  "and blurs behind it): the detection moves forward along its image path by "
                                  "this × the blob's width (0 = off)")
    head_lead_min_speed: float = param(400.0, 0.0, 20000.0, step=50.0, unit="px/s", label="... from image speed",
                                       help="Below this image speed the path's direction is too uncertain: no lead")
    # On the demo court a shuttle crossing a racket head or an arm merges with it into a blob
    # 20–28 px wide (the shuttle alone: 4–8 px); the blob's brightest part is still the shuttle,
    # but half that width led the report 9–13 px past the cork (8 of the 179 errors of
    # 3 × 1000 frames). The shuttle's apparent size changes slowly: its tracklet remembers it.
    head_lead_width_frames: int = param(5, 1, 60, step=1, unit="frames", label="... width over",
                                        help="The width that sets the lead is the smallest of the blob's widths on "
                                             "its tracklet over this many frames (a shuttle merged with a racket "
                                             "or an arm is wider than itself); 1 = this frame's only")
    # A shuttle leaving the image is clipped by the edge: its visible part's bright centroid stays
    # 0.3–2.2 px inside while the cork is already 1–5 px outside (demo court: 6 of the 87 online
    # errors of 3 × 1000 frames were such reports, counted FP2 as the cork is not in the image).
    # Since main's own border rules (stereo.exit_margin, exit_by_path) landed, 4 px cost more than
    # it gave there (split on, wrong frames L / R of 3 × 1000: 4 px 18 / 33 — in the right camera
    # 4 corks still 0–4.4 px inside dropped, 1 FP2 avoided —, 2 px and 0 both 18 / 30).
    edge_exit: float = param(2.0, 0.0, 20.0, step=0.5, unit="px", label="Head: gone at the edge within",
                             help="A detection whose track moves towards an image edge and which lies within "
                                  "this distance of it (px at 1280 px width, scaled with the width) is a clipped "
                                  "shuttle whose cork has left: nothing is reported (0 = off)")
    edge_exit_area: float = param(0.6, 0.0, 1.0, step=0.05, label="... when its area is below",
                                  help="... and its blob's area is below this fraction of the median of its "
                                       "tracklet's previous blobs' areas (the cork leads: it leaves first)")


@dataclass(frozen=True, slots=True)
class MotionParams(ParamGroup):
    """Filter 4: distance moved since the previous frame, speed-aware, and track keeping."""

    TITLE: ClassVar[str] = "Motion"
    base_radius: float = param(40.0, 0.0, 2000.0, step=1.0, unit="px", label="Base radius",
                               help="Allowed distance from the predicted position at zero speed")
    max_image_speed: float = param(15000.0, 0.0, 100000.0, step=100.0, unit="px/s",
                                   label="Maximum image speed",
                                   help="Fastest shuttle in the image; the gate grows with the time step")
    lost_after: float = param(0.15, 0.0, 5.0, step=0.01, unit="s", label="Lost after",
                              help="Without a hit for this long the track is dropped and any candidate may start a new one")
    coast_blind: int = param(10, 0, 60, step=1, unit="frames", label="Coast through glare",
                             help="The followed shuttle is carried on its image path for up to this many frames "
                                  "while it crosses a spot where the detector is blind (background brighter "
                                  "than 'Ignore lights above': lights, white lines, the net tape); 0 = off")
    min_displacement: float = param(0.0, 0.0, 50.0, step=0.5, unit="px", label="Stationary below",
                                    help="Candidates that moved less than this since the last frame are rejected (shuttles lying on the floor)")


@dataclass(frozen=True, slots=True)
class AssociationParams(ParamGroup):
    """Filter 4, multi-frame: candidates joined into smooth image paths (core/association.py)."""

    TITLE: ClassVar[str] = "Association"
    min_hits: int = param(3, 1, 50, step=1, unit="frames", label="Confirm after",
                          help="Frames a tracklet must be seen before it may supply the detection")
    early_confirm_quality: float = param(0.7, 0.0, 1.0, step=0.01, label="Confirm early at quality",
                                         help="A tracklet whose candidates' mean quality is at least this is "
                                              "confirmed one frame before 'Confirm after' (1 = never)")
    min_travel: float = param(12.0, 0.0, 500.0, step=1.0, unit="px", label="Minimum travel",
                              help="A tracklet must have moved this far over the travel window (lights, a shuttle on the floor do not)")
    travel_window: int = param(12, 1, 60, step=1, unit="frames", label="Travel window",
                               help="Minimum travel is measured as the net displacement over this many hits")
    flight_travel: float = param(100.0, 0.0, 5000.0, step=5.0, unit="px", label="Flight travel",
                                 help="A tracklet that has travelled this far may pause (apex, far court)")
    # Two allowances: the shuttle being followed slows at an apex or lies where it landed for
    # long, while another tracklet that travelled and stopped is mostly clutter that moved (a
    # shoe that stepped, a hand that came to rest): after rally_11-48-00 (left 733–744, labels:
    # nothing visible) a tracklet resting at a player's hand held the readout for 12 frames
    # under the shared 40-frame allowance.
    pause_frames: int = param(10, 0, 1000, step=1, unit="frames", label="Pause allowance",
                              help="How long such a tracklet may stay below the minimum travel")
    followed_pause_frames: int = param(40, 0, 100000, step=1, unit="frames", label="Pause allowance, followed",
                                       help="The pause allowance of the tracklet being followed, when larger "
                                            "(0 = the same as the others)")
    min_track_quality: float = param(0.15, 0.0, 1.0, step=0.01, label="Tracklet quality ≥",
                                     help="Running mean of the candidates' quality a tracklet needs to be the shuttle")
    quality_weight: float = param(2.0, 0.0, 10.0, step=0.1, label="Quality weight",
                                  help="Weight of the tracklet's quality in its merit (history counts 1)")
    candidate_weight: float = param(2.0, 0.0, 10.0, step=0.1, label="This frame's quality weight",
                                    help="Weight of the candidate's own quality this frame in its merit, on top "
                                         "of its tracklet's running quality (0 = off): a tracklet that slid onto "
                                         "a racket or a hand loses the choice the frame it stops looking like a shuttle")
    # Broadcast (bwf_00001 94, bwf_00025 51–53): a shuttle passing a still shoe or a dark patch
    # of the crowd was claimed by that clutter's long-lived tracklet (its history bonus beat the
    # shuttle's younger tracklet at equal distance), and the readout lost the shuttle. On the
    # two-camera rig the still tracklets that claim by history are mostly the shuttle itself,
    # held or lying (rally_11-47-02: the default at True cost 16 frames of its right camera).
    history_needs_motion: bool = flag(False, label="Only moving tracklets claim by history",
                                      help="A tracklet's age gives it first claim on nearby candidates only while "
                                           "it moves (travels 'Minimum travel' over the window) or is the one "
                                           "followed; still clutter claims by distance alone")
    rebirth_radius: float = param(60.0, 0.0, 2000.0, step=1.0, unit="px", label="Hit continuity",
                                  help="When the followed tracklet misses (a racket hit), a new blob this close "
                                       "to its last position inherits its history (0 = off)")
    max_misses: int = param(3, 0, 50, step=1, unit="frames", label="Coast for",
                            help="Frames a tracklet survives without a candidate")
    max_tracklets: int = param(80, 1, 500, step=1, label="Tracklets kept",
                               help="Upper bound on simultaneous hypotheses per camera")
    speed_gate_gain: float = param(0.6, 0.0, 5.0, step=0.05, label="Gate per speed",
                                   help="Gate radius grows by this fraction of the tracklet's own image step")
    acceleration_px: float = param(10.0, 0.0, 500.0, step=1.0, unit="px", label="Gate slack",
                                   help="Extra gate radius per frame for changes of velocity")
    velocity_smoothing: float = param(0.6, 0.05, 1.0, step=0.05, label="Velocity update",
                                      help="Weight of the newest velocity measurement")
    residual_scale: float = param(5.0, 0.1, 500.0, step=1.0, unit="px", label="Residual scale",
                                  help="Prediction residual that costs one unit of merit (smooth paths win)")
    jump_residual: float = param(30.0, 0.0, 2000.0, step=1.0, unit="px", label="Path break at",
                                 help="A step this far from the tracklet's prediction breaks its path: travel and "
                                      "pause allowance count again from there (a clutter hop cannot inherit a "
                                      "flight's travel; 0 = off)")
    jump_resets_residual: bool = flag(True, label="... and its residual",
                                      help="A path break also forgets the tracklet's prediction residual: a "
                                           "shuttle leaving the racket on a clutter tracklet (a racket head, a "
                                           "hand) is not held back for ~10 frames by that tracklet's old misses")
    jump_anchor_quality: float = param(0.8, 0.0, 1.0, step=0.01, label="... keeps its start from quality",
                                       help="A path break of the followed tracklet onto a candidate at least this "
                                            "shuttle-like (a shuttle leaving the racket) keeps the point before the "
                                            "break as the start of its travel, so the new flight counts as moving "
                                            "from its first frame (1 = never)")
    followed_swap_margin: float = param(0.6, 0.0, 1.0, step=0.05, label="Followed swaps at quality margin",
                                        help="Inside its gate the followed tracklet takes the most shuttle-like blob "
                                             "instead of the nearest when it scores this much higher (after a hit the "
                                             "nearest is often the racket or the hand; 1 = never)")
    followed_swap_track_quality: float = param(0.5, 0.0, 1.0, step=0.05, label="... while its quality ≥",
                                               help="The swap only while the followed tracklet's running quality is at "
                                                    "least this (it was on the shuttle until the hit, not sliding over "
                                                    "clutter after the shuttle left the view)")
    # Broadcast labels mark the shuttle held for the serve and lying after the rally; no
    # tracklet there travels, so the association refuses it and the readout stays empty. On the
    # tuned-on TV clips, in the frames with no report, the best refused blob scoring ≥ 0.75
    # was the labelled shuttle 11 times of 14 (the others: twice nothing labelled, once 32 px
    # off; benchmarks/broadcast_census.py --lone 0.75): a frame with nothing to report gains more from it than it risks. Not on the
    # two-camera rig, whose labels leave most still shuttles unmarked (tuned-on rallies at 0.75:
    # 98.00 → 96.48 %, 217 more FP2).
    lone_quality: float = param(1.0, 0.0, 1.0, step=0.01, label="Report a still blob from quality",
                                help="When no blob lies on a confirmed, travelling tracklet, the one the "
                                     "association refused whose own quality (the classifier's probability) is "
                                     "at least this is reported anyway: a shuttle held for the serve, or lying "
                                     "(1 = never)")
    hits_saturation: int = param(10, 1, 500, step=1, unit="frames", label="History counts up to",
                                 help="A tracklet's length adds to its merit up to this many frames")
    hysteresis: float = param(1.0, 0.0, 10.0, step=0.1, label="Hysteresis",
                              help="Merit bonus of the tracklet already followed")
    hysteresis_min_quality: float = param(0.1, 0.0, 1.0, step=0.01, label="... while quality ≥",
                                          help="The followed tracklet keeps its hysteresis only while this frame's "
                                               "candidate on it scores at least this (after a hit it goes on with the "
                                               "racket or a hand); 0 = always")
    blind_gate: float = param(30.0, 0.0, 2000.0, step=1.0, unit="px", label="Gate in a blind spot",
                              help="While the followed track is predicted where the detector is blind (a light, "
                                   "a white line), it takes only a candidate this close to its prediction and "
                                   "coasts otherwise (a hand or a racket nearby would take it over; 0 = off)")
    # 64, not 32: at a rally's start dozens of clutter tracklets are live and more blobs lie near
    # one of them than 32, so the serve's faint streak went unmeasured and the shuttle's new
    # track could not be born for 5–8 frames (rally_11-48-00 left 64–71: 62 blobs, 38 near a
    # tracklet). Costs ≈ 0.3 ms a pair of CPU, 10 % of the default's rate at 2048 px from a
    # rally's start (speed.py --long 0: 215.6 → 189–191 pairs/s, p99 8.2 → 10.5 ms); coarse keeps
    # 16. Measuring 64 only after a frame in which the followed tracklet found nothing fixed none
    # of the serves (the followed tracklet goes on with the racket instead of missing).
    max_measured: int = param(64, 1, 500, step=1, label="Blobs measured",
                              help="At most this many blobs per frame get the full-resolution measurement: "
                                   "those near a live tracklet first, then the strongest differences")
    min_quality: float = param(0.0, 0.0, 1.0, step=0.01, label="Minimum candidate quality",
                               help="Candidates below this shape/contrast score are not associated")
    exit_margin: float = param(0.0, 0.0, 200.0, step=1.0, unit="px", label="Left the image within",
                               help="A shuttle-like track last seen rising this close to the top edge, and then "
                                    "gone, has left the picture (a clear above a TV camera's top edge): until a "
                                    "new track comes in from an edge ('... back in within'), "
                                    "or '... for at most' has passed, nothing is reported (px at 1280 wide; 0 = off)")
    entry_margin: float = param(120.0, 0.0, 1000.0, step=5.0, unit="px", label="... back in within",
                                help="After the shuttle left the picture, a new track may be reported once its "
                                     "first point lies this close to an edge (its first frames back may be missed; "
                                     "px at 1280 wide, at least 'Left the image within')")
    exit_timeout: float = param(3.0, 0.0, 30.0, step=0.1, unit="s", label="... for at most",
                                help="How long the shuttle may stay out of the picture before any track may be "
                                     "reported again")


@dataclass(frozen=True, slots=True)
class ClassifierParams(ParamGroup):
    """The learned candidate classifier (core/classifier.py) that scores a blob by its looks."""

    TITLE: ClassVar[str] = "Candidate classifier"
    enabled: bool = flag(True, label="Use the classifier",
                         help="Score candidates with the learned classifier instead of contrast + size")
    model: str = choice("candidate_classifier", ("candidate_classifier",
                                                 "candidate_classifier_broadcast",
                                                 "candidate_classifier_coarse"),
                        label="Model", help="Classifier file in resources/ (_coarse: trained with "
                                            "background.coarse_from_width on, for the coarse preset)")
    # Recorded files only (core/adaptation.py): a first pass over the recording labels its own
    # candidates on long runs of detections and a classifier trained on them scores a second.
    adapt_min_run: int = param(0, 0, 200, step=1, unit="frames", label="Adapt to a file: runs of",
                               help="`badminton-track detect` on a file only (not live, not the "
                                    "two-camera track): a first pass takes every run of at least this "
                                    "many consecutive detections as the shuttle, trains a classifier for "
                                    "this recording on its candidates, and a second pass uses it (0: off)")


@dataclass(frozen=True, slots=True)
class StereoParams(ParamGroup):
    """Consistency of the two cameras' detections."""

    TITLE: ClassVar[str] = "Stereo"
    max_epipolar_error: float = param(6.0, 0.1, 500.0, step=0.5, unit="px",
                                      label="Epipolar tolerance",
                                      help="Largest distance of the right detection from the left one's epipolar line")
    min_distance: float = param(0.3, 0.0, 100.0, step=0.1, unit="m", label="Nearest",
                                help="Triangulated points closer to the left camera are rejected")
    max_distance: float = param(40.0, 0.5, 500.0, step=0.5, unit="m", label="Farthest")
    max_candidates: int = param(6, 1, 50, step=1, label="Candidates per camera",
                                help="How many best candidates per camera are tried for a stereo pair")
    adaptive_epipolar: bool = flag(True, label="Learn the epipolar tolerance",
                                   help="Widen the tolerance to what the rig really achieves, measured online on "
                                        "long, confident tracklets seen by both cameras (a rig calibrated by "
                                        "clicking court points is off by tens of pixels)")
    adaptive_factor: float = param(2.5, 1.0, 10.0, step=0.1, label="Learnt tolerance × median",
                                   help="The learnt tolerance is this multiple of the running median error")
    max_learnt_tolerance: float = param(250.0, 1.0, 2000.0, step=5.0, unit="px",
                                        label="Learnt tolerance ≤")
    cold_epipolar_error: float = param(30.0, 0.0, 500.0, step=1.0, unit="px",
                                       label="Tolerance until learnt",
                                       help="The epipolar tolerance from the start until the rig's error has been "
                                            "learnt (20 sure pairs): a rig imported from rough calibration files "
                                            "misses by tens of pixels, and a 6 px gate at a rally's first serve "
                                            "leaves both cameras' reports without a 3D point (0: the fixed "
                                            "tolerance from the start)")
    own_choice_bonus: float = param(1.0, 0.0, 10.0, step=0.1, label="Own-choice bonus",
                                    help="Merit bonus of each camera's own best candidate when pairing")
    confident_hits: int = param(15, 2, 500, step=1, unit="frames", label="Confident after",
                                help="Tracklets followed this long in both cameras feed the learnt tolerance")
    head_offset: float = param(0.022, 0.0, 0.1, step=0.001, unit="m", label="Cork ahead of the blob",
                               help="The blob's bright centroid lies this far behind the cork along the flight "
                                    "(the skirt trails); the 3D point is moved forward by it (0 = off)")
    head_min_speed: float = param(1.0, 0.0, 50.0, step=0.5, unit="m/s", label="Cork correction from",
                                  help="The cork correction needs a flight direction: below this speed the "
                                       "point is left as measured")
    guided_search: bool = flag(True, label="Look where the flight says",
                               help="When a camera has no detection near the 3D flight's projection, look "
                                    "there for a small white spot (a shuttle merged with a player or a line)")
    guided_min_contrast: float = param(25.0, 1.0, 255.0, step=1.0, unit="grey levels", label="Spot contrast ≥",
                                       help="The spot's whiteness (min of B, G, R) above its window's median")
    guided_coast: bool = flag(True, label="... and coast on it where blind",
                              help="A camera coasting through a blind spot (a light, a white line) reports "
                                   "the 3D flight's projection instead of a straight image path; with no "
                                   "detection, the projection is reported when it lies in a blind spot")
    guided_merged: bool = flag(True, label="... and where merged",
                               help="With no detection, the 3D flight's projection is also reported where it "
                                    "falls on a blob too large for a shuttle (merged with a player, a racket)")
    guided_other: bool = flag(True, label="... and where the other camera follows it",
                              help="With no detection, the 3D flight's projection (moved by where this camera's "
                                   "last pairs lay from their points) is reported when the other camera's "
                                   "sight has just moved that flight (the shuttle lost against a player's shirt "
                                   "or in the detector's mask)")
    guided_override: bool = flag(False, label="... also against a detection",
                                 help="Also replace a detection that is off the flight's projection")
    stereo_vouch: bool = flag(True, label="Stereo confirms a young track",
                              help="A candidate held back by the association (its track not confirmed yet, "
                                   "or not travelling far enough) passes when the other camera has a partner "
                                   "on its epipolar line and the two tracks' image velocities triangulate to a "
                                   "moving 3D point: the first frames of a serve or after a hit, a shuttle "
                                   "coming back slowly into view")
    vouch_max_epipolar: float = param(3.0, 0.1, 100.0, step=0.1, unit="px", label="... within epipolar",
                                      help="Largest epipolar error of such a pair, now and one velocity step back "
                                           "(not the learnt pairing tolerance, so a rig calibrated roughly does "
                                           "not vouch for chance alignments; see the next setting)")
    vouch_rig_factor: float = param(1.5, 0.0, 10.0, step=0.1, label="... or × the rig's error",
                                    help="Widen that gate to this many times the median epipolar error of "
                                         "sure pairs measured on this rig, for two tracks both moving ≥ 2 px a "
                                         "frame; also the stereo look's gate (0 = the fixed gate only)")
    vouch_min_quality: float = param(0.1, 0.0, 1.0, step=0.01, label="... track quality ≥",
                                     help="Running quality the held-back candidate's track needs")
    vouch_first_quality: float = param(0.4, 0.0, 1.0, step=0.01, label="... first sighting from quality",
                                       help="A candidate seen for the first time (its track has no velocity yet) may "
                                            "be vouched for by position alone when it scores at least this (1 = never)")
    vouch_first_partner_quality: float = param(0.1, 0.0, 1.0, step=0.01, label="... or with a sure partner from",
                                               help="A first sighting scoring less than that may still be vouched for "
                                                    "when it scores at least this and its partner is sure (a first "
                                                    "sighting scoring enough, or the other camera's own choice; 1 = never)")
    vouch_min_speed: float = param(2.0, 0.0, 100.0, step=0.5, unit="m/s", label="... 3D speed ≥",
                                   help="The pair's 3D velocity (from the two tracks' image velocities) must be "
                                        "at least this (lights and a shuttle at rest do not vouch)")
    vouch_lone: bool = flag(True, label="... also against a lone survivor",
                            help="A camera whose surviving candidates have no stereo partner among the other "
                                 "camera's is helped too, with the other camera's own choice as the partner "
                                 "(the shuttle's track held back at a racket contact while clutter passes)")
    vouch_position_quality: float = param(0.7, 0.0, 1.0, step=0.01, label="... by position from quality",
                                          help="A held-back candidate scoring at least this is vouched for by "
                                               "position alone when the two tracks' smoothed velocities disagree "
                                               "(just after a hit they mix the old and the new flight; 1 = never)")
    guided_weak_score: float = param(2.0, 0.0, 100.0, step=0.1, label="... against a weak lone detection",
                                     help="Without a stereo pair, a detection scoring below this (a track that slid "
                                          "onto a player after the shuttle's own was lost) is replaced by a spot "
                                          "found at the flight's projection when it lies off it (0 = off)")
    stereo_look: bool = flag(True, label="Look on the epipolar line",
                             help="Without a stereo pair, a camera with no detection looks for a white spot "
                                  "where its own image path continues, on the epipolar line of the other "
                                  "camera's sure detection (a small shuttle after a hit, before the 3D flight "
                                  "is known)")
    stereo_look_min_score: float = param(1.0, 0.0, 100.0, step=0.1, label="... from the other's score",
                                         help="The other camera's detection must score at least this")
    stereo_look_radius: float = param(8.0, 1.0, 100.0, step=0.5, unit="px", label="... within",
                                      help="How far from where the camera's image path continues (px at "
                                           "1280 px width)")
    flight_vouch: bool = flag(True, label="Pair where the flight says",
                              help="Two reports up to 1.5 × the epipolar tolerance off their line are still a "
                                   "pair when the followed 3D flight puts the shuttle where they triangulate "
                                   "(a rough rig's miss varies over the image)")
    pair_continuity: bool = flag(True, label="... or where the last pair continues",
                                 help="... or when the same two tracks were the last step's pair and their "
                                      "epipolar miss moved by at most 0.5 % of the image width since, up to 2 × "
                                      "the tolerance (rally_11-47-02: a flight whose miss went 6 → 151 → 7 px)")
    exit_margin: float = param(2.0, 0.0, 100.0, step=0.5, unit="px", label="Leaving the image within",
                               help="A detection this near the image's border is not reported when the 3D "
                                    "flight puts the shuttle just outside the image next to it (the clipped "
                                    "skirt of a shuttle leaving the view; an unpaired one only, unless 'by its "
                                    "image path' is on; 0 = off)")
    exit_by_path: bool = flag(True, label="... or by its image path",
                              help="... or when the camera's own image path (its last report moved on by its "
                                   "track's velocity) has left the image; paired detections too (the pair "
                                   "with a clipped skirt is biased)")
    out_of_view_weak: bool = flag(True, label="Nothing weak while out of view",
                                  help="Without a stereo pair, a detection scoring below the weak score is not "
                                       "reported while the 3D flight puts the shuttle outside this camera's image")
    alone_limit: bool = flag(True, label="Limit one-camera reports",
                             help="A detection the other camera does not see (no report there, no 3D point) "
                                  "is reported for at most 'for' frames in a row, unless this camera's readout "
                                  "has run on without a break since a frame with a 3D point (a flight the other "
                                  "camera lost: out of its view, behind a player)")
    alone_max_frames: int = param(0, 0, 1000, step=1, label="... for",
                                  help="How many frames in a row such a one-camera report is kept (0 = none: a "
                                       "camera reports alone only what continues a stereo-confirmed readout)")
    alone_anchor_gap: int = param(3, 0, 100, step=1, label="... anchored across",
                                  help="How many frames without a report this camera's readout may skip and still "
                                       "continue the stereo-confirmed readout before it")
    landed_frames: int = param(40, 0, 10000, step=1, unit="frames", label="Keep a landed shuttle",
                               help="When a camera's followed track stops being reported (its pause allowance "
                                    "ran out) soon after the 3D flight's last point near the floor, its candidate "
                                    "there is still reported for this many frames while it stays put (0 = off)")
    landed_max_height: float = param(0.3, 0.0, 5.0, step=0.05, unit="m", label="... landed below",
                                     help="The flight's last 3D point must be this low above the court")
    # A shuttle cannot stop in mid-air: a flight whose 3D points stop dead above the floor was
    # caught (by a hand, or on a racket's strings) and is out of play until it is hit again.
    caught_frames: int = param(10, 0, 1000, step=1, unit="frames", label="Caught after",
                               help="When a flight's 3D points stop dead above the floor (the flight refuses "
                                    "them and they stay within the caught radius) for this many frames, the "
                                    "shuttle was caught: it is not reported, in either camera, while it stays "
                                    "near the hand, until a new flight starts (0 = off)")
    caught_radius: float = param(0.10, 0.01, 2.0, step=0.01, unit="m", label="... within",
                                 help="How far the stopped 3D points may spread")
    caught_release_speed: float = param(4.0, 0.0, 100.0, step=0.5, unit="m/s", label="... until a flight of",
                                        help="A caught shuttle is reported again when the 3D flight follows it "
                                             "at this speed (a serve, a throw back to the server)")
    caught_hold: float = param(0.5, 0.0, 60.0, step=0.1, unit="s", label="... or for at most",
                               help="... or when this long has passed since the catch (the shuttle dropped "
                                    "from the hand for the next serve is reported)")
    align_pairs: bool = flag(True, label="Pair at one moment",
                             help="Cameras without a common trigger: the right camera's detection is moved along "
                                  "its track to the left image's time before the two are paired (images 4 ms apart "
                                  "put the demo court's shuttle 29 cm off in 3D, 2.5 cm once moved)")
    one_camera_rays: bool = flag(True, label="Follow on one camera",
                                 help="Cameras without a common trigger: a step that brings one camera's image only "
                                      "moves the 3D flight along that camera's ray to the shuttle, and the robot gets "
                                      "the flight's position there (else nothing until the next pair)")
    # A lying shuttle touches the floor with its cork (radius 1.3 cm) and its skirt's rim (radius
    # 3.2 cm, 6 cm behind the cork centre): the axis rises ~18° backwards, and the centroid of
    # the visible shuttle (skirt-heavy, ~55 % of the way along the axis) lies ~3.1 cm behind and
    # ~1.0 cm above the cork centre. It lies along its flight: cork ahead.
    rest_cork_ahead: float = param(0.031, 0.0, 0.1, step=0.001, unit="m", label="Lying: cork ahead",
                                   help="A shuttle lying where the last flight landed: its cork is this far "
                                        "ahead of the blob's 3D point along the landing direction (0 = off)")
    rest_cork_below: float = param(0.010, 0.0, 0.1, step=0.001, unit="m", label="Lying: cork below",
                                   help="... and this much lower (the skirt's rim holds the tail up)")


@dataclass(frozen=True, slots=True)
class TrajectoryParams(ParamGroup):
    """3D track keeping, shot segmentation and landing prediction (core/flight/trajectory.py)."""

    TITLE: ClassVar[str] = "Trajectory"
    doubles: bool = flag(True, label="Doubles court", help="In/out call against the doubles lines (else singles)")
    max_gap: float = param(0.25, 0.01, 5.0, step=0.01, unit="s", label="Longest gap",
                           help="A flight without a 3D point for longer than this has ended")
    measurement_noise: float = param(0.02, 0.001, 0.5, step=0.005, unit="m", label="3D point noise σ",
                                     help="Least σ of a 3D point given without its stereo noise shape (per axis; "
                                          "points from the stereo tracker use the image point noise instead)")
    pixel_noise: float = param(0.2, 0.01, 10.0, step=0.01, unit="px", label="Image point noise σ",
                               help="Least noise assumed per image coordinate of a stereo pair: the 3D "
                                    "point's noise follows from it and the rig's geometry (more in depth, "
                                    "more far away); the tracker measures the real value and uses the larger")
    outlier_sigma: float = param(5.0, 2.0, 50.0, step=0.5, unit="σ", label="Outlier gate",
                                 help="3D points farther than this many standard deviations from the flight's prediction are ignored")
    outlier_distance: float = param(0.5, 0.01, 10.0, step=0.01, unit="m", label="Outlier distance",
                                    help="3D points this far from the flight's prediction are ignored")
    robust_sigma: float = param(2.0, 0.0, 20.0, step=0.5, unit="σ", label="Down-weigh beyond",
                                help="A point farther than this many standard deviations from the flight's "
                                     "prediction (but inside the outlier gate) has its noise scaled by (distance / this)², "
                                     "so the farther it lies the less it moves the flight (0 = off)")
    hit_acceleration: float = param(150.0, 10.0, 5000.0, step=5.0, unit="m/s²",
                                    label="Hit acceleration",
                                    help="A velocity change this abrupt starts a new shot")
    model_noise: float = param(0.5, 0.0, 100.0, step=0.1, unit="m/s²", label="Model noise",
                               help="Random acceleration the drag model does not explain (spin, flipping, air)")
    aero_length_sigma: float = param(0.4, 0.01, 3.0, step=0.01, unit="m", label="Prior σ of L",
                                     help="Uncertainty of the aerodynamic length L before the session's first shot")
    aero_length_floor: float = param(0.1, 0.0, 3.0, step=0.01, unit="m", label="Session σ of L ≥",
                                     help="The session estimate of L never gets surer than this (feathers wear)")
    guide_tentative_points: int = param(4, 0, 100, step=1, label="Guide from a new shot after",
                                        help="While a new shot is being confirmed (after a hit), the cameras' guided "
                                             "search follows it once it has this many agreeing points (0 = no guide "
                                             "until it is confirmed)")
    starved_takeover: int = param(2, 0, 100, step=1, unit="points", label="New shot after a hidden hit",
                                  help="A new track that lies on one flight path but does not meet the followed "
                                       "flight's path replaces it after this many more agreeing points while the "
                                       "followed flight takes none (0 = only once that flight is lost: 'Longest gap')")
    min_points: int = param(6, 3, 100, step=1, label="Points before predicting",
                            help="3D points of a shot needed before a landing is predicted")


@dataclass(frozen=True, slots=True)
class LookaheadParams(ParamGroup):
    """The readout held back K frames and re-decided from the tracklets' futures (core/lookahead.py).

    Read by the file commands (`detect`, `track --lookahead N`), the benchmarks and the GUI's
    look-ahead view (these rules, with the file commands' 4 frames: Playback ▸ Look-ahead view);
    the robot stream stays frame by frame whatever is set here.
    """

    TITLE: ClassVar[str] = "Look-ahead"
    LIVE: ClassVar[bool] = False
    frames: int = param(0, 0, 120, step=1, unit="frames", label="Look-ahead",
                        help="The 2D readout is delayed by this many frames and re-decided once they are "
                             "known (0 = off: the live readout; latency = frames / fps)")
    min_support: int = param(2, 1, 120, step=1, unit="frames", label="Followed at least",
                             help="A tracklet's earlier candidates are taken only when the readout follows it "
                                  "this many frames of the look-ahead")
    backfill: bool = flag(True, label="Back-fill",
                          help="A frame with no detection takes the candidate of the tracklet the readout "
                               "follows next (a flight's unconfirmed first frames)")
    switch: bool = flag(True, label="Switch earlier",
                        help="A frame whose tracklet the readout leaves for good takes the candidate of the "
                             "tracklet it hands over to (the racket kept after a hit)")
    max_switch_delay: int = param(120, 1, 120, step=1, unit="frames", label="Switch within",
                                  help="The handover must come at most this many frames later")
    switch_needs_alive: bool = flag(True, label="... from a tracklet still seen",
                                    help="Switch only when the tracklet left is still seen at the handover (a "
                                         "racket, a hand), not when it was lost")
    min_speed: float = param(400.0, 0.0, 20000.0, step=50.0, unit="px/s", label="Taken from image speed",
                             help="A candidate is taken only when its tracklet moves at least this fast from it "
                                  "(a shuttle held still before the serve is not yet in play)")
    lead_in_run: int = param(0, 0, 200, step=1, unit="frames", label="Lead-in after a run of",
                             help="A run of this many detections on one tracklet is followed back, frame by "
                                  "frame, through the blobs next to its first one (the shuttle held before the "
                                  "serve, labelled visible on TV), in place of shorter reports elsewhere "
                                  "(0 = off; never with look-ahead 0)")
    lead_in_through: bool = flag(True, label="... through shorter reports",
                                 help="The lead-in replaces a shorter track's report on its way to the held "
                                      "shuttle and goes on through the held shuttle reported already (runs "
                                      "counted per tracklet); off: it stops at any report. The adaptation's "
                                      "first pass turns it off")
    lead_in_max_replaced: int = param(10, 0, 600, step=1, unit="frames", label="... replacing at most",
                                      help="A lead-in that would replace more reports than this is dropped "
                                           "whole: it ran beside a flight (reported on short tracklets), "
                                           "not through a hand's few frames")
    lead_in_radius: float = param(12.0, 1.0, 100.0, step=1.0, unit="px", label="Lead-in step",
                                  help="How far the blob of the frame before may lie, in pixels of a "
                                       "1280-wide picture (scaled to the video's width)")
    lead_in_frames: int = param(60, 1, 600, step=1, unit="frames", label="Lead-in at most",
                                help="How many frames a lead-in may go back (adds this many frames and the "
                                     "run's to the file commands' delay)")
    gap_fill_frames: int = param(0, 0, 60, step=1, unit="frames", label="Fill gaps of at most",
                                 help="A gap of at most this many frames between two detections takes, in each "
                                      "frame, the blob nearest the straight line between them (0 = off; only "
                                      "with the lead-in, whose delay it shares)")
    gap_fill_radius: float = param(10.0, 1.0, 100.0, step=1.0, unit="px", label="... within",
                                   help="How far from that line the blob may lie, in pixels of a 1280-wide "
                                        "picture (scaled to the video's width)")


@dataclass(frozen=True, slots=True)
class WindowParams(ParamGroup):
    """While the followed shuttle is confirmed, most frames are processed only in a window
    around its predicted position (core/window.py; faster at 2048 px, issue #7)."""

    TITLE: ClassVar[str] = "Windowed tracking"
    enabled: bool = flag(False, label="Track in a window",
                         help="While this camera follows a confirmed, travelling shuttle, process only a "
                              "window around its predicted position (grey image, background model, mask, "
                              "contours, measures); the whole frame every 'Whole frame every' frames")
    full_every: int = param(8, 1, 240, step=1, unit="frames", label="Whole frame every",
                            help="A whole frame at least this often: what the window leaves out (a new "
                                 "serve, a second shuttle) is seen at most this − 1 frames late (1 = always)")
    max_fraction: float = param(0.125, 0.01, 1.0, step=0.005, label="Window ≤ part of the frame",
                                help="Largest window area as a part of the frame's; a larger gate is clipped "
                                     "to it around the prediction")
    margin: float = param(48.0, 0.0, 1000.0, step=4.0, unit="px", label="Window margin",
                          help="Added on each side to the tracklet's motion gate (the blob's own size, a "
                               "racket hit's change of direction)")
    catch_up: bool = flag(False, label="Catch up outside the window",
                          help="On a whole frame, the background pixels no window covered since the last "
                               "whole frame learn as much as the frames they missed would have taught "
                               "them (1 − (1 − α)^k), instead of learning k× slower")
    stagger: bool = flag(False, label="Stagger the cameras' whole frames",
                         help="The cameras take their scheduled whole frames half a period apart, on a "
                              "fixed clock (the left camera at frames 0, 8, 16 …, the right at 4, 12 …), "
                              "so a pair never waits for two whole frames on schedule (latency)")
    watch_quality: float = param(0.5, 0.0, 1.0, step=0.01, label="Stay whole for a rival of quality",
                                 help="After a whole frame, the next one is whole too while a tracklet outside "
                                      "the window was seen with at least this running quality and is not "
                                      "confirmed yet (a new serve gets its confirming frames; 1 = never)")
    min_quality: float = param(0.0, 0.0, 1.0, step=0.01, label="Window a track of quality",
                               help="Track in a window only while the followed tracklet's running quality "
                                    "(the classifier's mean score of its candidates) is at least this: a "
                                    "clutter track followed before the serve keeps the frames whole")


@dataclass(frozen=True, slots=True)
class TrackerParams:
    """Every parameter of the pipeline, one group per box of the tuning dialog."""

    background: BackgroundParams = field(default_factory=BackgroundParams)
    binarize: BinarizeParams = field(default_factory=BinarizeParams)
    contour_length: ContourLengthParams = field(default_factory=ContourLengthParams)
    tilted_rect: TiltedRectParams = field(default_factory=TiltedRectParams)
    colour: ColourParams = field(default_factory=ColourParams)
    motion: MotionParams = field(default_factory=MotionParams)
    association: AssociationParams = field(default_factory=AssociationParams)
    classifier: ClassifierParams = field(default_factory=ClassifierParams)
    stereo: StereoParams = field(default_factory=StereoParams)
    trajectory: TrajectoryParams = field(default_factory=TrajectoryParams)
    lookahead: LookaheadParams = field(default_factory=LookaheadParams)
    window: WindowParams = field(default_factory=WindowParams)

    # ---- generic access, used by presets, the tuning dialog and the CLI -------------------
    def groups(self) -> Iterator[tuple[str, ParamGroup]]:
        """(attribute name, group) in dialog order."""
        for f in fields(self):
            yield f.name, getattr(self, f.name)

    def get(self, path: str) -> Any:
        """Value at ``"group.name"``."""
        group, name = self._split(path)
        return getattr(getattr(self, group), name)

    def with_value(self, path: str, value: Any) -> "TrackerParams":
        """A copy with one value replaced (validated)."""
        group, name = self._split(path)
        g = getattr(self, group)
        value = _coerce(type(g), name, value)
        return dataclasses.replace(self, **{group: dataclasses.replace(g, **{name: value})})

    def to_dict(self) -> dict[str, dict[str, Any]]:
        return {name: dataclasses.asdict(g) for name, g in self.groups()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "TrackerParams":
        """Build from a (possibly partial) nested dict; unknown keys are an error."""
        out = cls()
        for group, values in data.items():
            if group.startswith("_"):
                continue  # comments / metadata in preset files
            if not isinstance(values, dict) or group not in {f.name for f in fields(cls)}:
                raise ParamError(f"unknown parameter group {group!r}")
            for name, value in values.items():
                out = out.with_value(f"{group}.{name}", value)
        return out

    def save(self, path: str | Path, description: str = "") -> None:
        data: dict[str, Any] = {}
        if description:
            data["_description"] = description
        data.update(self.to_dict())
        Path(path).write_text(json.dumps(data, indent=2, ensure_ascii=False) + "\n", encoding="utf-8")

    @classmethod
    def load(cls, path: str | Path) -> "TrackerParams":
        try:
            data = json.loads(Path(path).read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise ParamError(f"preset file not found: {path}") from None
        except json.JSONDecodeError as exc:
            raise ParamError(f"preset file {path} is not valid JSON: {exc}") from None
        return cls.from_dict(data)

    def _split(self, path: str) -> tuple[str, str]:
        group, _, name = path.partition(".")
        g = getattr(self, group, None)
        if not isinstance(g, ParamGroup) or name not in {f.name for f in fields(g)}:
            raise ParamError(f"unknown parameter {path!r}")
        return group, name


def _coerce(group_type: type, name: str, value: Any) -> Any:
    """Convert a value (from JSON, a slider, the command line) to the field's declared type."""
    f = {f.name: f for f in fields(group_type)}[name]
    default = f.default
    if isinstance(default, bool):
        if isinstance(value, str):
            return value.strip().lower() in {"1", "true", "yes", "on"}
        return bool(value)
    if isinstance(default, int):
        return int(round(float(value)))
    if isinstance(default, float):
        return float(value)
    return str(value)


def field_info(group: ParamGroup) -> list[tuple[str, dataclasses.Field]]:
    """(name, field) of a group in declaration order; the tuning dialog renders these."""
    return [(f.name, f) for f in fields(group)]

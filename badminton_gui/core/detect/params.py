"""The parameters of one camera's detection stages, grouped as the tuning dialog shows them.

Why this file exists: the stages of ``core/detect/`` (segmentation, the paper's four filters,
scoring, tracklets, the coarse preset's window) read these groups; they are declared beside
those stages. All pixel quantities are in full-resolution pixels of the camera image.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ..param_fields import ParamGroup, choice, flag, param

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
    protect_radius: float = param(8.0, 0.0, 100.0, step=0.5, unit="px", label="Held shuttle kept within",
                                  help="Half-size of the box around a held landed shuttle that the next frame's "
                                       "mask keeps from a lower threshold (px at 1280 px width; a shuttle lying on "
                                       "the floor is ≈ 6–10 px long there; 0: its own pixel and the shake tolerance)")
    processing_scale: float = param(0.5, 0.125, 1.0, step=0.125, label="Processing scale",
                                    help="Background model runs on the image scaled by this factor")
    coarse_from_width: int = param(0, 0, 8192, step=64, unit="px", label="Coarser from width",
                                   help="Frames at least this wide run the background model at half the "
                                        "processing scale (2048 px cameras: a 512 px model, ~45 % less CPU) "
                                        "at some accuracy (NYCU F1 −1.4 to −1.8 points with the shipped "
                                        "classifier); positions and features still come from the full-resolution "
                                        "windows. 0: never, unless 'Coarser when the far shuttle spans' says so")
    coarse_shuttle_px: float = param(0.0, 0.0, 10.0, step=0.1, unit="px", label="Coarser when the far shuttle spans",
                                     help="The background model runs at half the processing scale when the "
                                          "farthest shuttle (its length, the median over the image, from the "
                                          "camera's view of the court or an assumed lens) still spans at least "
                                          "this many model pixels there (2: a far shuttle of 8 px or more at "
                                          "full resolution, as behind the court at 2048 px). Faster, but on "
                                          "courts it was not trained on it costs 3D coverage, so 0 (never) by "
                                          "default. Positions and features still come from the full-resolution "
                                          "windows; 'Model at the coarser scale' scores them")


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
class ShuttleScaleParams(ParamGroup):
    """The shuttle in the world's units, and the image gates of filters 1, 2 and 4 derived from
    them at each image position (core/detect/shuttle_scale.py)."""

    TITLE: ClassVar[str] = "Shuttle in the world"
    enabled: bool = flag(False, label="Gates from geometry",
                         help="Filters 1, 2 and 4 take their pixel limits at each image position from the "
                              "shuttle's size and speed below and the camera's geometry (the rig's court "
                              "pose; one camera alone: the field of view and distances below); off: the "
                              "pixel values of 'Contour length', 'Tilted rectangle' and 'Motion' hold "
                              "everywhere")
    length: float = param(0.065, 0.02, 0.2, step=0.005, unit="m", label="Shuttle length",
                          help="Cork tip to the skirt's rim: the largest extent of the shuttle")
    cork_diameter: float = param(0.025, 0.005, 0.1, step=0.001, unit="m", label="Cork diameter",
                                 help="The smallest part of the shuttle that still shows when far")
    max_speed: float = param(110.0, 1.0, 150.0, step=1.0, unit="m/s", label="Top speed",
                             help="Fastest shuttle (a smash leaves the racket at up to ~110 m/s)")
    court_margin: float = param(2.0, 0.0, 20.0, step=0.5, unit="m", label="Play volume: margin",
                                help="The shuttle flies over the court and this far around it")
    ceiling: float = param(10.0, 1.0, 30.0, step=0.5, unit="m", label="... up to height",
                           help="Highest shuttle above the floor")
    nearest: float = param(1.5, 0.1, 50.0, step=0.1, unit="m", label="Nearest shuttle",
                           help="The shuttle comes no closer to a camera than this")
    farthest: float = param(20.0, 1.0, 200.0, step=1.0, unit="m", label="One camera: farthest shuttle",
                            help="Without calibration: the farthest the shuttle gets from the camera")
    fov: float = param(60.0, 10.0, 170.0, step=1.0, unit="°", label="One camera: field of view",
                       help="Without calibration: the lens's horizontal field of view")
    # The pixel values of filters 1, 2 and 4 were tuned on the demo court at 1280×720, whose
    # cameras see a shuttle at ~185 px/m (the median over the image of the geometric middle of
    # the nearest and the farthest shuttle's scale), and on the NYCU rig at 2048×1536 (~239
    # px/m); a rig that sees the shuttle at half the scale gets half the pixel gates.
    reference_scale: float = param(200.0, 1.0, 10000.0, step=5.0, unit="px/m", label="Pixel values hold at",
                                   help="The image scale of the shuttle at which the pixel values of 'Contour "
                                        "length' (not its guided radius and split length: px at 1280 px width), "
                                        "'Tilted rectangle', 'Motion' and 'Association' (not its travel) hold; "
                                        "where the "
                                        "camera sees the shuttle at another scale they grow or shrink with it")
    per_position: bool = flag(True, label="Scale at each image position",
                              help="The gates follow the shuttle's scale at the candidate's image position (a "
                                   "near and a far part of the court differ); off: one factor per camera, the "
                                   "median over its image")


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
    edge_exit_frames: int = param(8, 1, 120, step=1, unit="frames", label="... over",
                                  help="How many of the tracklet's previous blobs that median is taken over")


@dataclass(frozen=True, slots=True)
class MotionParams(ParamGroup):
    """Filter 4: distance moved since the previous frame, speed-aware, and track keeping."""

    TITLE: ClassVar[str] = "Motion"
    base_radius: float = param(40.0, 0.0, 2000.0, step=1.0, unit="px", label="Base radius",
                               help="Allowed distance from the predicted position at zero speed")
    max_image_speed: float = param(15000.0, 0.0, 100000.0, step=100.0, unit="px/s",
                                   label="Maximum image speed",
                                   help="Fastest shuttle in the image; the gate grows with the time step "
                                        "(with 'Gates from geometry': the top speed in m/s seen from the camera)")
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
                              help="At most this many blobs per frame get the (more expensive) full-resolution "
                                   "measurement: those near a live tracklet first, then the strongest differences")
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
    coarse_model: str = choice("candidate_classifier", ("candidate_classifier",
                                                        "candidate_classifier_coarse",
                                                        "candidate_classifier_broadcast"),
                               label="Model at the coarser scale",
                               help="Classifier used while the background model runs at half the "
                                    "processing scale ('Coarser when the far shuttle spans', 'Coarser "
                                    "from width'): its mask-based features differ from the full scale's")
    # Recorded files only (core/adaptation.py): a first pass over the recording labels its own
    # candidates on long runs of detections and a classifier trained on them scores a second.
    adapt_min_run: int = param(0, 0, 200, step=1, unit="frames", label="Adapt to a file: runs of",
                               help="`badminton-track detect` on a file only (not live, not the "
                                    "two-camera track): a first pass takes every run of at least this "
                                    "many consecutive detections as the shuttle, trains a classifier for "
                                    "this recording on its candidates, and a second pass uses it (0: off)")


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
                               "them (1 − (1 − α)^k), instead of learning k× slower; the background-like "
                               "ones only where the grey value stayed within the threshold of the "
                               "last whole frame's")
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
    near_large: float = param(0.0, 0.0, 1000.0, step=4.0, unit="px", label="Whole near a player within",
                              help="No window while the followed shuttle is predicted within this of a blob "
                                   "too large for a shuttle on the last whole frame (a player, a racket: "
                                   "where it may be struck and leave the old path at once; 0 = off)")

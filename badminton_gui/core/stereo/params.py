"""The parameters of stereo pairing and of the per-camera readout rules.

Why this file exists: the stages of ``core/stereo/`` and ``core/flight/camera_rules.py`` read
the ``stereo`` group; it is declared beside them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ..param_fields import ParamGroup, flag, param

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
    play_volume: bool = flag(True, label="Pairs inside the play volume",
                             help="With a court pose, two detections whose 3D point lies outside the play "
                                  "volume (the court plus 'Play volume: margin' around it, up to its height; "
                                  "Shuttle scale group) are not a pair, and both are rejected when they pair "
                                  "nowhere else: an LED board's moving dot beside the court, which both cameras "
                                  "see where it is. Without a court pose it does nothing")
    off_volume_radius: float = param(0.0, 0.0, 5.0, step=0.05, unit="m", label="... nor alone where pairs were refused",
                                     help="A camera's candidate with no partner inside the play volume whose line of "
                                          "sight passes this near a place where a pair was refused as off the play "
                                          "volume is rejected: the board's dot that camera keeps while the other "
                                          "camera's dot is no candidate that step (0 = off)")
    off_volume_memory: float = param(60.0, 0.0, 3600.0, step=5.0, unit="s", label="... refused within",
                                     help="How long a place where a pair was refused as off the play volume is "
                                          "remembered (a board stands where it stands; its dot comes back)")
    serve_start: bool = flag(False, label="Before the serve, pairs that start like one",
                             help="With a court pose, while no flight is followed (no 3D point for the "
                                  "trajectory's 'Longest gap'), two detections are a pair only once their "
                                  "tracks' 3D points start like a serve (the next settings); both are rejected "
                                  "until then: a shuttle held before the serve is at rest, and an LED board's "
                                  "dot inside the play volume's margin slides along its board")
    serve_points: int = param(3, 2, 20, step=1, unit="pairs", label="... over",
                              help="At least this many pairs of the same two tracks, one after the other "
                                   "(within the trajectory's 'Longest gap' of each other and in all), make the start")
    serve_min_speed: float = param(5.0, 0.0, 100.0, step=0.5, unit="m/s", label="... moving at least",
                                   help="Their average speed from the first to the last of those pairs")
    serve_min_climb: float = param(2.0, -50.0, 50.0, step=0.5, unit="m/s", label="... climbing at least",
                                   help="Their average upward speed (a serve must clear the net), and they move "
                                        "towards the net")
    serve_min_rise: float = param(0.15, 0.0, 5.0, step=0.01, unit="m", label="... rising at least",
                                  help="How much higher the last of those pairs lies than the first (two frames' "
                                       "triangulation noise does not rise this much)")
    serve_max_height: float = param(4.0, 0.0, 20.0, step=0.1, unit="m", label="... from at most",
                                    help="The first of those pairs no higher than this above the court (a "
                                         "player's hand or racket, and the first frames a far camera may miss)")
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
    vouch_min_step: float = param(1.0, 0.0, 50.0, step=0.1, unit="px", label="... track's last step ≥",
                                  help="The held-back candidate's track must have moved at least this in its last "
                                       "frame (its smoothed velocity remembers older motion: a track that stopped)")
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
    flight_reach: float = param(160.0, 0.0, 1000.0, step=5.0, unit="m/s", label="Pair within the flight's reach",
                                help="While a 3D flight is followed, a pair that triangulates farther from where "
                                     "the flight puts the shuttle than a shuttle hit since the flight's last point "
                                     "could have gone at this speed (plus 1 m and the flight's spread) is another "
                                     "object (an LED board's moving dot): it is not paired, a camera's choice whose "
                                     "line of sight misses that reach gives way, and pairs where the flight puts the "
                                     "shuttle come first (160 = the fastest smash, the default; 0 = off)")
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
    landed_recent: float = param(1.0, 0.0, 60.0, step=0.1, unit="s", label="... within",
                                 help="... and at most this old: a shuttle lands and comes to rest in a fraction "
                                      "of a second")
    landed_step: float = param(4.0, 0.0, 100.0, step=0.5, unit="px", label="... moving at most",
                               help="How far a held landed shuttle's candidate may move from one frame to the next, "
                                    "in pixels of a 1280-wide picture (it slides a little; a hand picking it up "
                                    "moves more)")
    flown_memory: float = param(5.0, 0.0, 600.0, step=0.5, unit="s", label="... its track flown within",
                                help="Only a track reported with a 3D point above the floor this recently is held "
                                     "(a landed shuttle slides and lies still for up to ~1.5 s first; a shoe walked "
                                     "along the floor was never seen in the air)")
    landed_shoe_past: bool = flag(True, label="... through a shoe walking past",
                                  help="A new track never seen in the air, with no stereo partner above the floor, "
                                       "does not take the report from the landed shuttle while the hold lasts (a "
                                       "player's white shoe walking past after the rally)")
    landed_other_anchor: bool = flag(True, label="... anchored by the other camera's hold",
                                     help="A camera's report keeps its right to a hold while the other camera holds "
                                          "its landed shuttle (that hold leaves the frame without a 3D point)")
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
    caught_step: float = param(12.0, 0.0, 200.0, step=1.0, unit="px", label="... withheld moving at most",
                               help="How far a caught shuttle's report may move from one frame to the next and still "
                                    "be withheld as the one in the hand, in pixels of a 1280-wide picture (a hand "
                                    "carrying it walks, it does not fly)")
    caught_min_flight_speed: float = param(3.0, 0.0, 100.0, step=0.5, unit="m/s", label="... after a flight of",
                                           help="How fast the flight must have been followed just before its points "
                                                "stopped (a shuttle held before the serve had no flight)")
    caught_flight_gap: float = param(0.05, 0.0, 5.0, step=0.01, unit="s", label="... ending at most",
                                     help="How long before the first stopped point the flight's last accepted point "
                                          "may lie")
    caught_net_exception: bool = flag(True, label="... not at the net",
                                      help="A stop at the net (near its plane, not above its top) is no catch: the "
                                           "shuttle hangs in the mesh or falls off the tape in full view")
    caught_net_margin: float = param(0.3, 0.0, 3.0, step=0.05, unit="m", label="... the net within",
                                     help="How near the net's plane and above its top a stop counts as the net's")
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
class CourtAdaptParams(ParamGroup):
    """Adapting the candidate classifier to the court in front of the cameras, from flights both
    cameras agree on (``core/court_adaptation.py``)."""

    TITLE: ClassVar[str] = "Adapt to the court"
    enabled: bool = flag(False, label="Adapt to the court",
                         help="Flights both cameras agree on and the 3D flight filter follows label each "
                              "camera's candidates (the pair: the shuttle; blobs far from it: not); once "
                              "enough are collected, each camera's classifier is retrained on them and "
                              "swapped in between two steps (`track --adapt`: from a first pass)")
    min_flight_points: int = param(20, 3, 1000, step=1, unit="pairs", label="From flights of at least",
                                   help="A flight labels its frames only when the flight filter took at "
                                        "least this many of its pairs (a short one may be a wrong pair)")
    target_flights: int = param(6, 1, 500, step=1, unit="flights", label="Adapt after",
                                help="Live: the classifiers are retrained once this many flights ...")
    target_positives: int = param(400, 10, 100000, step=10, unit="frames", label="... and shuttle frames",
                                  help="... and this many labelled shuttle candidates per camera are collected")
    radius: float = param(8.0, 1.0, 100.0, step=0.5, unit="px", label="The shuttle within",
                          help="A candidate this close to the camera's report on a flight's pair is the "
                               "shuttle (px at 1280 wide)")
    far_radius: float = param(40.0, 5.0, 2000.0, step=5.0, unit="px", label="Not the shuttle beyond",
                              help="A candidate this far from that report is not the shuttle; those in "
                                   "between are not used (px at 1280 wide)")
    still_frames: int = param(120, 0, 10000, step=10, unit="frames", label="Still blobs after",
                              help="A candidate that stays within 3 px (at 1280 wide) for this many frames, "
                                   "far from every flight both cameras agreed on, is not the shuttle "
                                   "(lights, boards, lines, a shuttle at rest; 0: not used)")

"""The parameters of the 3D flight filter and of the look-ahead readout.

Why this file exists: ``core/flight/trajectory.py`` (the drag-model flight filter, landing
prediction) and ``core/lookahead.py`` (the readout decided a few frames later) read these groups.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ..param_fields import ParamGroup, flag, param

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
                                       "followed flight takes none, if it passes within 1 m of that path (0 = only "
                                       "once that flight is lost: 'Longest gap')")
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

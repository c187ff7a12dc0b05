"""`badminton-track track --left L --right R --calib RIG -o OUT.csv`: stereo tracking of a file pair."""

from __future__ import annotations

import argparse
import logging
import sys

from ..core.tracker import configure_opencv_threads
from ..io.track_file import TrackFileError, adapt_to_pair, track_to_csv
from .common import (Progress, UserError, add_json_argument, add_lookahead_argument, add_preset_argument,
                     add_video_pair_arguments, open_stereo_videos, outcomes_json, params_from_args,
                     baud_rate, frame_count, preset_file, print_json, refuse_output_over_inputs)
from .csv_columns import COURT_FRAME, LEFT_CAMERA_FRAME, TRACK_COLUMNS, columns_epilog

_log = logging.getLogger(__name__)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("track", help="track the shuttle in a stereo video pair",
                       description="Track the shuttle in two synchronised videos; one CSV row per "
                                   "left frame with both 2D detections, the 3D point (court frame "
                                   "when the rig has a court pose, else left-camera frame), "
                                   "distance, speed and the predicted landing point.",
                       epilog=columns_epilog("Columns of OUTPUT (an empty cell: no value):", TRACK_COLUMNS)
                       + f"\n\nThe {COURT_FRAME}. The {LEFT_CAMERA_FRAME}.")
    add_video_pair_arguments(p, "rig file (OpenCV FileStorage YAML)")
    p.add_argument("-o", "--output", required=True, help="output CSV")
    add_preset_argument(p)
    add_lookahead_argument(p)
    p.add_argument("--robot", metavar="PORT", help="also stream results to the robot on this "
                   "serial port / Bluetooth port / pyserial URL")
    p.add_argument("--baud", type=baud_rate, default=115200, help="robot link baud rate (default 115200)")
    p.add_argument("--robot-required", action="store_true",
                   help="stop with exit status 2 when the --robot port cannot be opened at the start, "
                        "and end with exit status 2 (the output still written in full) when the link "
                        "was lost during the run (default: say so on stderr, track anyway and keep "
                        "retrying the port)")
    p.add_argument("--max-frames", type=frame_count, default=None, help="stop after this many frames")
    add_json_argument(p, "output, pairs, points_3d, points_3d_percent, pairs_per_second, frame "
                         "('court' or 'left-camera'), rig_epipolar_px (null: not measured), rig_swapped_px "
                         "(the same pairs with the cameras exchanged), rig_note ('' when the rig "
                         "held), score (null without labels, else left/right with "
                         "tp, tn, fp1, fp2, fn and accuracy, precision, recall, f1 as fractions)")
    p.add_argument("--adapt", action=argparse.BooleanOptionalAction, default=None,
                   help="first adapt each camera's classifier to this court from the flights both "
                        "cameras agree on (two passes; default: the preset's adapt.enabled)")
    p.add_argument("--trace", action="store_true", help="a last CSV column, Trace, naming the tracker's "
                   "rules that fired on each row's step")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    refuse_output_over_inputs(args.output, args.left, args.right, args.calib, args.left_times,
                              args.right_times, preset_file(args))
    params = params_from_args(args)
    adapt = params.adapt.enabled if args.adapt is None else args.adapt
    # The file has its future: the classifiers come from a whole first pass, not live.
    params = params.with_value("adapt.enabled", False)
    classifiers = _adapted_classifiers(args, params) if adapt else None
    link = _robot_link(args)     # before the videos' reader thread: a refused port starts nothing
    source = None
    link_status = None
    try:
        rig, source, total = open_stereo_videos(args)
        configure_opencv_threads()
        truth = _labels_in_times(args)
        progress = Progress(total, "track")
        try:
            summary = track_to_csv(source, rig, params, args.output, max_frames=args.max_frames,
                                   link=link, progress=None if args.quiet else progress.update,
                                   truth=truth, trace=args.trace, classifiers=classifiers)
        except TrackFileError as exc:
            raise UserError(str(exc)) from None
        finally:
            if not args.quiet:
                progress.close()
    finally:
        if source is not None:
            source.close()
        if link is not None:
            link.close()
            link_status = _report_link(link, args.quiet)
    n, hits3d = summary.pairs, summary.points_3d
    if n == 0:
        raise UserError("the videos hold no frames")
    frame_name = "court" if rig.has_court_pose else "left-camera"
    if summary.rig_note:
        note = summary.rig_note
        _log.warning("%s%s", note[:1].lower(), note[1:])
    if summary.warning:
        _log.warning("%s", summary.warning)
    if args.json:
        score = None
        if summary.score_left is not None and summary.score_right is not None:
            score = {"left": outcomes_json(summary.score_left), "right": outcomes_json(summary.score_right)}
        print_json({"output": str(args.output), "pairs": n, "points_3d": hits3d,
                    "points_3d_percent": round(100 * hits3d / n, 3),
                    "pairs_per_second": round(summary.pairs_per_second, 3), "frame": frame_name,
                    "rig_epipolar_px": summary.rig_epipolar_px, "rig_swapped_px": summary.rig_swapped_px,
                    "rig_note": summary.rig_note,
                    "warning": summary.warning, "score": score})
    elif not args.quiet:
        print(f"{n} frame pairs, 3D point in {hits3d} ({100 * hits3d / n:.1f} %), "
              f"{summary.pairs_per_second:.1f} pairs/s (decoding included), {frame_name} frame -> {args.output}")
        if summary.score_text:
            print(summary.score_text + " (the timestamp files' labels)")
    if args.robot_required and link_status is not None and link_status.outages:
        raise UserError(f"robot link: lost {_times(link_status.outages)} during the run, "
                        f"{link_status.seconds_down:.1f} s without a link (--robot-required); "
                        f"{args.output} is complete")
    return 0


def _times(n: int) -> str:
    return "once" if n == 1 else f"{n} times"


def _adapted_classifiers(args, params):
    """The first pass of ``--adapt``: each camera's classifier adapted to this court, or None
    (said on stderr) when no flight both cameras agreed on was long enough."""
    rig, source, total = open_stereo_videos(args)
    configure_opencv_threads()
    progress = Progress(total, "adapt")
    judged: list = []
    try:
        classifiers, harvest = adapt_to_pair(source, rig, params, max_frames=args.max_frames,
                                             progress=None if args.quiet else progress.update, judged=judged)
    finally:
        source.close()
        if not args.quiet:
            progress.close()
    said = (f"{harvest.flights} flights, shuttle candidates {harvest.positives[0]} / {harvest.positives[1]}, "
            f"others {harvest.negatives[0]} / {harvest.negatives[1]} (left / right)")
    if classifiers is None:
        _log.warning("adaptation: nothing to learn from (%s); the preset's classifiers are kept", said)
    elif not args.quiet:
        print(f"adapted to the court: {said}", file=sys.stderr)
        for side, h in zip(("left", "right"), judged):
            print(f"  {side}: {'kept the preset' if h.kept else 'fine-tuned'}; held-back {h.rows} rows, "
                  f"loss {h.loss_before:.4f} -> {h.loss_after:.4f}, shuttle first {100 * h.top_before:.1f} -> "
                  f"{100 * h.top_after:.1f} %", file=sys.stderr)
    return classifiers


def _robot_link(args):
    """The link to ``--robot``, or None. A port that cannot be opened is said at once, on one
    line: tracking goes on and the link keeps retrying, or, with ``--robot-required``, exit 2."""
    if not args.robot:
        return None
    from ..io.robot_link import RobotLink
    link = RobotLink(args.robot, args.baud)
    # A Bluetooth port may take seconds to connect: a run that cannot go without it waits longer.
    status = link.wait_first_attempt(10.0 if args.robot_required else 2.0)
    if status.connected:
        return link
    reason = status.last_error or f"{args.robot} did not open in time"
    if args.robot_required:
        link.close()
        raise UserError(f"robot link: {reason} (--robot-required)")
    _log.error("robot link: %s; tracking anyway, retrying the port every %g s", reason,
               RobotLink.RETRY_MAX_S)
    return link


def _report_link(link, quiet: bool):
    """What the robot got, on stderr: always when nothing was sent or the link was lost on the
    way (the robot went without results then). Returns the link's last status."""
    s = link.status()
    if not s.messages_sent:
        _log.error("robot link: nothing was sent to %s%s", s.port,
                   f" (last error: {s.last_error})" if s.last_error else "")
    elif not quiet:
        print(f"robot link: {s.messages_sent} messages sent to {s.port}, {s.messages_dropped} "
              f"replaced by newer ones, {s.errors} errors", file=sys.stderr)
    if s.outages:
        _log.error("robot link: lost %s during the run, %.1f s without a link in all (last error: %s)",
                   _times(s.outages), s.seconds_down, s.last_error or "none")
    return s


def _labels_in_times(args):
    """The labels the timestamp files carry (the NYCU recordings' CSVs do): the summary then
    scores the rows against them; None for plain timestamp files."""
    from ..io.truth import LabelTruth, has_label_columns
    if args.left_times and args.right_times and has_label_columns(args.left_times) \
            and has_label_columns(args.right_times):
        return LabelTruth.read(args.left_times, args.right_times)
    return None

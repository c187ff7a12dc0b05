"""`badminton-track track --left L --right R --calib RIG -o OUT.csv`: stereo tracking of a file pair."""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

from ..core.lookahead import StereoLookahead
from ..core.tracker import StereoTracker, configure_opencv_threads
from ..io.labels import TRACK_COLUMNS, track_row
from .common import (Progress, UserError, add_lookahead_argument, add_preset_argument,
                     add_video_pair_arguments, open_stereo_videos, params_from_args)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("track", help="track the shuttle in a stereo video pair",
                       description="Track the shuttle in two synchronised videos; one CSV row per "
                                   "left frame with both 2D detections, the 3D point (court frame "
                                   "when the rig has a court pose, else left-camera frame), "
                                   "distance, speed and the predicted landing point.")
    add_video_pair_arguments(p, "rig file (OpenCV FileStorage YAML)")
    p.add_argument("-o", "--output", required=True, help="output CSV")
    add_preset_argument(p)
    add_lookahead_argument(p)
    p.add_argument("--robot", metavar="PORT", help="also stream results to the robot on this "
                   "serial port / Bluetooth port / pyserial URL")
    p.add_argument("--baud", type=int, default=115200, help="robot link baud rate")
    p.add_argument("--max-frames", type=int, default=None, help="stop after this many frames")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    params = params_from_args(args)
    rig, source, total = open_stereo_videos(args)
    link = None
    if args.robot:
        from ..io.robot_link import RobotLink
        link = RobotLink(args.robot, args.baud)
    configure_opencv_threads()
    tracker = StereoTracker(rig, params)
    # The CSV gets the re-decided readout; the robot keeps the live one (no latency).
    lookahead = StereoLookahead(rig, params, tracker.epipolar_tolerance)
    progress = Progress(total, "track")
    n = hits3d = 0
    start = time.perf_counter()
    out_path = Path(args.output)
    try:
        out_path.parent.mkdir(parents=True, exist_ok=True)
        with out_path.open("w", newline="") as fh:
            writer = csv.writer(fh)
            writer.writerow(TRACK_COLUMNS)
            while args.max_frames is None or n < args.max_frames:
                frame = source.read()
                if frame is None:
                    break
                result = tracker.process(frame.left, frame.right, frame.t_left, frame.index,
                                         frame.index_right, keep_masks=False)
                for decided in lookahead.push(result):
                    writer.writerow(track_row(decided))
                    hits3d += decided.point is not None
                if link is not None:
                    link.send_result(result)
                n += 1
                if not args.quiet:
                    progress.update(n)
            for decided in lookahead.flush():
                writer.writerow(track_row(decided))
                hits3d += decided.point is not None
    except OSError as exc:
        raise UserError(f"cannot write {args.output}: {exc.strerror or exc}") from None
    finally:
        source.close()
        tracker.close()
        if link is not None:
            link.close()
        if not args.quiet:
            progress.close()
    if n == 0:
        raise UserError("the videos hold no frames")
    elapsed = time.perf_counter() - start
    if not args.quiet:
        frame_name = "court" if rig.has_court_pose else "left-camera"
        print(f"{n} frame pairs, 3D point in {hits3d} ({100 * hits3d / n:.1f} %), "
              f"{n / elapsed:.1f} pairs/s (decoding included), {frame_name} frame → {args.output}")
    return 0

"""`badminton-track refine-calib --left L.mp4 --right R.mp4 --calib RIG.yaml -o REFINED.yaml`.

Why this file exists: a rig whose two cameras were calibrated separately (the NYCU ``.cfg``
pair) can be degrees off in their relative pose, which no chessboard session fixes after the
fact. This command tracks a recorded rally with that rig, keeps the pairs of detections that
are the followed shuttle in both cameras (labels are never read), refits the relative pose to
them (core/calibrate/refine.py) and writes the refined rig — or, when the rally cannot support a
refit (too few flights, too little of the image covered), says why and exits non-zero.
"""

from __future__ import annotations

import argparse

from ..core.errors import TrackerInputError
from ..core.calibrate.refine import PairCollector, refine_relative_pose
from ..core.tracker import StereoTracker, configure_opencv_threads
from .common import (INPUT_ERRORS, Progress, UserError, add_json_argument, add_preset_argument,
                     add_video_pair_arguments, open_stereo_videos, params_from_args, preset_file,
                     frame_count, print_json, refuse_output_over_inputs)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("refine-calib", help="refine a rig's relative pose from a tracked rally",
                       description="Track a recorded rally, keep the shuttle's pairs of detections "
                                   "and refit the cameras' relative pose to them (self-calibration; "
                                   "intrinsics, baseline length and the court pose are kept).")
    add_video_pair_arguments(p, "rig file to start from (.yaml)")
    p.add_argument("-o", "--output", required=True, help="refined rig file to write (.yaml)")
    p.add_argument("--max-frames", type=frame_count, default=None, help="stop after this many frames")
    add_preset_argument(p)
    add_json_argument(p, "frames, pairs, inliers, before_median_px, after_median_px, "
                         "before_p90_px, after_p90_px, held_back_before_px, held_back_after_px, "
                         "rotation_change_deg, baseline_turn_deg, accepted, reason, output (null "
                         "when not refined; the exit status is then 2)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    refuse_output_over_inputs(args.output, args.left, args.right, args.calib, args.left_times,
                              args.right_times, preset_file(args))
    params = params_from_args(args)
    rig, source, total = open_stereo_videos(args)
    configure_opencv_threads()
    tracker = StereoTracker(rig, params)
    collector = PairCollector()
    progress = Progress(total, "refine-calib")
    n = 0
    try:
        while args.max_frames is None or n < args.max_frames:
            frame = source.read()
            if frame is None:
                break
            try:
                collector.add(tracker.process_frame(frame, keep_masks=False))
            except TrackerInputError:
                pass                # a pair the tracker refuses (a stalled clock) gives no sample
            n += 1
            if not args.quiet:
                progress.update(n)
    finally:
        source.close()
        tracker.close()
        if not args.quiet:
            progress.close()
    if n == 0:
        raise UserError("the videos hold no frames")
    refined, report = refine_relative_pose(rig, *collector.points())
    if args.json:
        print_json(_summary_json(n, report, args.output if report.accepted else None))
    else:
        print(f"{n} frame pairs: {report.summary()}")
    if not report.accepted:
        raise UserError(f"not refined: {report.reason}; {args.output} not written")
    try:
        refined.save(args.output)
    except INPUT_ERRORS as exc:
        raise UserError(str(exc)) from None
    except OSError as exc:
        raise UserError(f"cannot write {args.output}: {exc.strerror or exc}") from None
    if not args.json:
        print(f"refined rig -> {args.output}")
    return 0


def _summary_json(frames: int, report, output) -> dict:
    r = report
    return {"frames": frames, "pairs": r.pairs, "inliers": r.inliers,
            "before_median_px": r.before_median_px, "after_median_px": r.after_median_px,
            "before_p90_px": r.before_p90_px, "after_p90_px": r.after_p90_px,
            "held_back_before_px": r.held_back_before_px, "held_back_after_px": r.held_back_after_px,
            "rotation_change_deg": r.rotation_change_deg, "baseline_turn_deg": r.baseline_turn_deg,
            "accepted": r.accepted, "reason": r.reason,
            "output": str(output) if output is not None else None}

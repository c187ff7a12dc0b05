"""`badminton-track detect VIDEO -o OUT.csv`: one camera alone, TrackNet label format out."""

from __future__ import annotations

import argparse
import logging

from ..io.detect_file import ADAPTING, DetectFileError, detect_to_csv
from .common import (INPUT_ERRORS, Progress, UserError, add_json_argument, add_lookahead_argument,
                     add_preset_argument, params_from_args, preset_file, print_json,
                     refuse_output_over_inputs)
from .csv_columns import LABEL_COLUMNS, columns_epilog

_log = logging.getLogger(__name__)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("detect", help="detect the shuttle in one camera's video",
                       description="Detect the shuttle in one video and write Frame,Visibility,X,Y (pixels).",
                       epilog=columns_epilog("Columns of OUTPUT:", LABEL_COLUMNS))
    p.add_argument("video", help="input video file")
    p.add_argument("-o", "--output", required=True, help="output CSV (TrackNet label format)")
    add_preset_argument(p)
    add_lookahead_argument(p)
    p.add_argument("--adapt", action=argparse.BooleanOptionalAction, default=None,
                   help="first adapt the classifier to this recording from its own long runs of "
                        "detections (two passes; default: the preset's classifier.adapt_min_run, off in "
                        "every shipped preset, and never with --lookahead 0, the live readout)")
    add_json_argument(p, "video, output, frames, found, found_percent, frames_per_second, "
                         "frame_count (announced by the video; 0 unknown), truncated, adapted, "
                         "adapted_runs, adapted_frames, lead_in_frames, gap_fill_frames")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    refuse_output_over_inputs(args.output, args.video, preset_file(args))
    params = params_from_args(args)
    bars: dict[str, Progress] = {}     # the pass shown now (the adaptation's, then the detection's)

    def progress(stage: str, done: int, total: int) -> None:
        if stage not in bars:
            for bar in bars.values():
                bar.close()
            bars.clear()
            bars[stage] = Progress(total or None, "adapt" if stage == ADAPTING else "detect", force=False)
        bars[stage].update(done)

    try:
        summary = detect_to_csv(args.video, params, args.output, adapt=args.adapt,
                                progress=None if args.quiet else progress)
    except DetectFileError as exc:
        raise UserError(str(exc)) from None
    except INPUT_ERRORS as exc:
        raise UserError(str(exc)) from None
    finally:
        for bar in bars.values():
            bar.close()
    if summary.truncated:
        _log.warning("%s ended after %d of %d frames (truncated?)", args.video, summary.frames,
                     summary.frame_count)
    if args.json:
        print_json({"video": str(args.video), "output": str(args.output), "frames": summary.frames,
                    "found": summary.found, "found_percent": round(summary.found_share, 3),
                    "frames_per_second": round(summary.frames_per_second, 3),
                    "frame_count": summary.frame_count, "truncated": summary.truncated,
                    "adapted": summary.adapted, "adapted_runs": summary.adapted_runs,
                    "adapted_frames": summary.adapted_frames, "lead_in_frames": summary.lead_in,
                    "gap_fill_frames": summary.gap_fill})
    elif not args.quiet:
        for line in (summary.adaptation_text,
                     f"{summary.frames} frames, shuttle found in {summary.found} ({summary.found_share:.1f} %), "
                     f"{summary.frames_per_second:.1f} frames/s -> {args.output}",
                     summary.lead_in_text):
            if line:
                print(line)
    return 0

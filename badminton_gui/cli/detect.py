"""`badminton-track detect VIDEO -o OUT.csv`: one camera alone, TrackNet label format out."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from ..core.adaptation import DEFAULT_MIN_RUN, adapt_to_recording
from ..core.detector import CameraDetector
from ..core.lookahead import CameraLookahead
from ..io.labels import write_point_labels
from ..io.prefetch import PrefetchingReader
from ..io.video import VideoFile
from .common import (INPUT_ERRORS, Progress, UserError, add_lookahead_argument, add_preset_argument,
                     params_from_args)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("detect", help="detect the shuttle in one camera's video",
                       description="Detect the shuttle in one video and write Frame,Visibility,X,Y (pixels).")
    p.add_argument("video", help="input video file")
    p.add_argument("-o", "--output", required=True, help="output CSV (TrackNet label format)")
    add_preset_argument(p)
    add_lookahead_argument(p)
    p.add_argument("--adapt", action=argparse.BooleanOptionalAction, default=None,
                   help="first adapt the classifier to this recording from its own long runs of "
                        "detections (two passes; default: the preset's classifier.adapt_min_run, on "
                        "for --preset broadcast, and never with --lookahead 0, the live readout)")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    p.set_defaults(func=run)


def _frames(path: str, label: str, quiet: bool):
    """The video's (image, time) from its start, decoded ahead on a reader thread."""
    video = PrefetchingReader(VideoFile(path))
    progress = Progress(video.frame_count or None, label, force=False)
    try:
        i = 0
        while (frame := video.read()) is not None:
            yield frame, i / video.fps
            i += 1
            if not quiet:
                progress.update(i)
    finally:
        video.close()
        if not quiet:
            progress.close()


def _adapted_classifier(args: argparse.Namespace, params):
    """The classifier adapted to this recording (core/adaptation.py), or None to keep the preset's."""
    if args.adapt is False or (args.adapt is None and (params.classifier.adapt_min_run <= 0
                                                       or params.lookahead.frames == 0)):
        # --lookahead 0 is the live readout, which the GUI gives: it keeps the shipped classifier.
        return None
    if params.classifier.adapt_min_run <= 0:   # --adapt with a preset that has it off
        params = params.with_value("classifier.adapt_min_run", DEFAULT_MIN_RUN)
    start = time.perf_counter()
    try:
        classifier, harvest = adapt_to_recording(params, lambda: _frames(args.video, "adapt", args.quiet))
    except INPUT_ERRORS as exc:
        raise UserError(str(exc)) from None
    if not args.quiet:
        if classifier is None:
            print("adaptation: no run of detections long enough; the preset's classifier is kept")
        else:
            print(f"adapted to the recording: {harvest.runs} runs, {harvest.frames} frames "
                  f"({time.perf_counter() - start:.1f} s)")
    return classifier


def run(args: argparse.Namespace) -> int:
    params = params_from_args(args)
    try:
        # Decoded ahead on a reader thread while this one detects (io/prefetch.py).
        video = PrefetchingReader(VideoFile(args.video))
    except INPUT_ERRORS as exc:
        raise UserError(str(exc)) from None
    start = time.perf_counter()
    try:
        adapted = _adapted_classifier(args, params)
    except BaseException:
        video.close()
        raise
    detector = CameraDetector(params)
    if adapted is not None:
        detector.use_classifier(adapted)
    lookahead = CameraLookahead(params)
    frames, visible, xy = [], [], []

    def emit(results) -> None:
        for res in results:
            d = res.detection
            frames.append(len(frames))
            visible.append(d is not None)
            xy.append((d.x, d.y) if d else (0.0, 0.0))

    progress = Progress(video.frame_count or None, "detect", force=False)
    i = 0
    try:
        while True:
            frame = video.read()
            if frame is None:
                break
            res = detector.process(frame, i / video.fps, keep_mask=False)
            emit(lookahead.push(res, i / video.fps))
            i += 1
            if not args.quiet:
                progress.update(i)
        emit(lookahead.flush())
    finally:
        video.close()
        if not args.quiet:
            progress.close()
    if i == 0:
        raise UserError(f"{args.video} holds no frames")
    try:
        Path(args.output).parent.mkdir(parents=True, exist_ok=True)
        write_point_labels(args.output, frames, visible, xy)
    except OSError as exc:
        raise UserError(f"cannot write {args.output}: {exc.strerror or exc}") from None
    elapsed = time.perf_counter() - start
    if not args.quiet:
        print(f"{i} frames, shuttle found in {sum(visible)} ({100 * sum(visible) / i:.1f} %), "
              f"{i / elapsed:.1f} frames/s → {args.output}")
        if lookahead.changes["lead_in"]:
            over = lookahead.changes["lead_in_over"]
            print(f"lead-in: {lookahead.changes['lead_in']} frames taken before runs of "
                  f"{params.lookahead.lead_in_run} detections (the shuttle held before a serve)"
                  + (f", {over} of them in place of a shorter track's report" if over else ""))
    if video.frame_count and i < video.frame_count - 1:
        print(f"warning: {args.video} ended after {i} of {video.frame_count} frames (truncated?)")
    return 0

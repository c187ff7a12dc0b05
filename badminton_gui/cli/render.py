"""`badminton-track render --left L [--right R] (--csv TRACK.csv | --calib RIG) -o OUT.mp4`: a clip
with the red circle, its trail, the readouts and the court plan drawn on one camera or both.

The track comes from a CSV that `track` (two cameras) or `detect` (one) wrote earlier, or is made
now with the options of those commands (rig, pairing, preset, look-ahead) by their own loops.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..core.tracker import configure_opencv_threads
from ..io.detect_file import ADAPTING
from ..io.render_video import (RENDERING, TRACKING, check_output_path, detect_for_render,
                               read_render_csv, render_video, track_for_render)
from ..io.track_file import TrackFileError
from .common import (INPUT_ERRORS, Progress, UserError, add_lookahead_argument, add_preset_argument,
                     frame_count, open_stereo_videos, params_from_args)

_BAR_LABELS = {ADAPTING: "adapt", TRACKING: "track", RENDERING: "render"}


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "render", help="write an MP4 with the tracking drawn on the video(s)",
        description="Draw the shuttle's red circle, its trail and the frame/time on one camera's "
                    "video or both side by side, with the distance, speed, landing point and a court "
                    "plan under them when the track has 3D. The track is a CSV written by `track` or "
                    "`detect` (--csv), or is tracked now (--calib for a pair, nothing more for one video).")
    p.add_argument("--left", help="left camera's video (or the one video)")
    p.add_argument("--right", help="right camera's video")
    p.add_argument("--csv", help="track from `badminton-track track` or `detect`; without it the "
                                 "videos are tracked now")
    p.add_argument("--calib", help="rig file: needed to track a pair now; with --csv it says whether "
                                   "the 3D is in court coordinates, for the court plan (without it: "
                                   "when the CSV predicts a landing, which only court coordinates do)")
    p.add_argument("--left-times", help="tracking now: CSV with Frame,Timestamp for the left video")
    p.add_argument("--right-times", help="tracking now: CSV with Frame,Timestamp for the right video")
    p.add_argument("--video-times", action="store_true",
                   help="tracking now: pair the cameras by the videos' own frame timestamps")
    add_preset_argument(p)
    add_lookahead_argument(p)
    p.add_argument("-o", "--output", required=True, help="output clip (.mp4)")
    p.add_argument("--camera", choices=("left", "right", "both"), default=None,
                   help="camera(s) to show (default: both when two videos are given)")
    p.add_argument("--fps", type=float, default=None, help="clip frame rate (default: the video's)")
    size = p.add_mutually_exclusive_group()
    size.add_argument("--scale", type=float, default=None, help="size of each camera's picture, "
                                                                "as a share of the video's (e.g. 0.5)")
    size.add_argument("--width", type=int, default=None, help="width of each camera's picture (px)")
    p.add_argument("--max-frames", type=frame_count, default=None, help="stop after this many frames")
    p.set_defaults(func=run)


def _cameras(args) -> tuple[int, ...]:
    given = tuple(cam for cam, path in ((0, args.left), (1, args.right)) if path)
    if not given:
        raise UserError("give the video(s): --left and/or --right")
    choice = args.camera or ("both" if len(given) == 2 else "left" if given == (0,) else "right")
    cameras = {"left": (0,), "right": (1,), "both": (0, 1)}[choice]
    missing = [("--left", "--right")[c] for c in cameras if c not in given]
    if missing:
        raise UserError(f"--camera {choice} needs {' and '.join(missing)}")
    return cameras


def run(args: argparse.Namespace) -> int:
    cameras = _cameras(args)
    inputs = [args.left, args.right, args.csv, args.calib, args.left_times, args.right_times]
    try:
        check_output_path(args.output, inputs)
    except INPUT_ERRORS as exc:
        raise UserError(str(exc)) from None
    bars: dict[str, Progress] = {}

    def progress(stage: str, done: int, total: int) -> None:
        if args.quiet:
            return
        if stage not in bars:
            for bar in bars.values():
                bar.close()
            bars.clear()
            bars[stage] = Progress(total or None, _BAR_LABELS.get(stage, "detect"))
        bars[stage].update(done)

    try:
        track, court_frame = _track(args, cameras, progress)
        videos = {0: args.left, 1: args.right}
        if not track.stereo:                     # one camera's detections: on that camera's video
            if len(cameras) == 2:
                raise UserError(f"{track.source} is one camera's detections: render one camera "
                                f"(--camera left or right)")
            videos, cameras = {0: videos[cameras[0]]}, (0,)
        summary = render_video(track, videos, args.output, cameras=cameras, fps=args.fps,
                               scale=args.scale, width=args.width, court_frame=court_frame,
                               max_frames=args.max_frames, progress=progress)
    except TrackFileError as exc:
        raise UserError(str(exc)) from None
    except INPUT_ERRORS as exc:
        raise UserError(str(exc)) from None
    finally:
        for bar in bars.values():
            bar.close()
    if not args.quiet:
        w, h = summary.size
        print(f"{summary.frames} frames ({w}x{h}, {summary.fps:g} fps), "
              f"{summary.frames_per_second:.1f} frames/s → {summary.output}")
    return 0


def _track(args, cameras, progress):
    """(RenderTrack, whether its 3D is in court coordinates): read from --csv, or tracked now."""
    from ..core.rig import StereoRig
    from ..io.video import VideoFile
    if args.csv:
        if args.left_times or args.right_times or args.video_times:
            raise UserError("--left-times/--right-times/--video-times are for tracking now: a CSV "
                            "already pairs the frames")
        video = VideoFile(args.left or args.right)
        fps = video.fps
        video.close()
        track = read_render_csv(args.csv, fps)
        court_frame = StereoRig.load(args.calib).has_court_pose if args.calib else track.has_landing
        return track, court_frame
    params = params_from_args(args)
    configure_opencv_threads()
    if args.left and args.right:
        if not args.calib:
            raise UserError("tracking a pair now needs its rig (--calib), or give a --csv from `track`")
        rig, source, total = open_stereo_videos(args)
        try:
            track = track_for_render(source, rig, params, max_frames=args.max_frames,
                                     progress=progress, total=total or 0)
        finally:
            source.close()
        return track, rig.has_court_pose
    video_path = Path(args.left or args.right)
    video = VideoFile(video_path)
    fps = video.fps
    video.close()
    return detect_for_render(video_path, params, fps=fps, progress=progress), False

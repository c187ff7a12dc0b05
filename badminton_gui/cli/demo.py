"""``badminton-track demo``: write a synthetic stereo recording with exact ground truth.

Why this file exists: it turns the demo court (``io/demo_scene.py``) into files that every other
command and outside tools can read: two videos, the rig file and the truth, so detection,
tracking and evaluation can be tried without cameras.

Writes into DIR: ``left.mp4``, ``right.mp4`` (mp4v), ``rig.yaml`` (StereoRig.save),
``truth.csv`` (court-frame positions, velocities, per-camera pixels and visibility) and
``left_labels.csv`` / ``right_labels.csv`` (TrackNet ``Frame,Visibility,X,Y``).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import cv2

from ..io.safe_write import replacing
from .common import Progress, UserError
from .csv_columns import COURT_FRAME, LABEL_COLUMNS, TRUTH_COLUMNS, columns_epilog

# The ranges the demo's arguments are checked against when parsed: what the renderer and the
# mp4v writer handle (a 0×0 frame cannot be drawn; beyond 4096 px a side or 1000 fps the writer
# fails or, at an infinite rate, never returns).
MIN_SIDE, MAX_SIDE = 64, 4096
MIN_FPS, MAX_FPS = 1.0, 1000.0
MAX_SEED = 2**32 - 1
MAX_FRAMES = 1_000_000


def demo_size(text: str) -> tuple[int, int]:
    """--size WxH, each side MIN_SIDE … MAX_SIDE px."""
    try:
        w, h = text.strip().lower().split("x")
        size = (int(w), int(h))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not WIDTHxHEIGHT, e.g. 1280x720") from None
    if not all(MIN_SIDE <= side <= MAX_SIDE for side in size):
        raise argparse.ArgumentTypeError(
            f"{text!r}: each side must be {MIN_SIDE} to {MAX_SIDE} px")
    return size


def demo_fps(text: str) -> float:
    """--fps: a finite frame rate, MIN_FPS … MAX_FPS."""
    try:
        fps = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of frames per second") from None
    if not (math.isfinite(fps) and MIN_FPS <= fps <= MAX_FPS):
        raise argparse.ArgumentTypeError(f"{text!r}: the frame rate must be {MIN_FPS:g} to {MAX_FPS:g} fps")
    return fps


def demo_seed(text: str) -> int:
    """--seed: a whole number, 0 … MAX_SEED."""
    try:
        seed = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if not 0 <= seed <= MAX_SEED:
        raise argparse.ArgumentTypeError(f"{text!r}: the seed must be 0 to {MAX_SEED}")
    return seed


def demo_frames(text: str) -> int:
    """--frames: a whole number, 1 … MAX_FRAMES."""
    try:
        frames = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number of frame pairs") from None
    if not 1 <= frames <= MAX_FRAMES:
        raise argparse.ArgumentTypeError(f"{text!r}: the number of frame pairs must be 1 to {MAX_FRAMES}")
    return frames


def register(sub) -> None:
    p = sub.add_parser(
        "demo", help="write a synthetic stereo rally (videos, rig, ground truth)",
        description="Render the synthetic demo court: two videos, the exact rig file and the "
                    "ground truth of every frame.",
        epilog=columns_epilog("Columns of DIR/truth.csv (empty: no shuttle in play):", TRUTH_COLUMNS)
        + "\n\n" + columns_epilog("Columns of DIR/left_labels.csv and DIR/right_labels.csv:",
                                    LABEL_COLUMNS) + f"\n\nThe {COURT_FRAME}.")
    p.add_argument("--frames", type=demo_frames, required=True, metavar="N", help="number of frame pairs")
    output = p.add_mutually_exclusive_group(required=True)
    output.add_argument("-o", "--output", type=Path, metavar="DIR",
                        help="output folder (created if missing)")
    output.add_argument("--out", type=Path, dest="output", help=argparse.SUPPRESS)  # the old spelling
    p.add_argument("--seed", type=demo_seed, default=0, help="rally seed (default 0)")
    p.add_argument("--size", type=demo_size, default=(1280, 720), metavar="WxH",
                   help="image size of each camera (default 1280x720)")
    p.add_argument("--rig", choices=("binocular", "ends"), default="binocular",
                   help="binocular: two cameras 0.6 m apart at the court side (default); "
                        "ends: one camera behind each baseline")
    p.add_argument("--fps", type=demo_fps, default=120.0, help="frame rate (default 120)")
    p.add_argument("--no-noise", action="store_true", help="no sensor noise")
    p.add_argument("--no-flicker", action="store_true", help="no lighting flicker")
    p.set_defaults(func=run)


def _open_writer(path: Path, fps: float, size: tuple[int, int], shown: Path) -> cv2.VideoWriter:
    """A writer into ``path`` (the temporary file that becomes ``shown``)."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), fps, size)
    if not writer.isOpened():
        raise UserError(f"cannot write the video {shown} (mp4v encoder unavailable or folder "
                        f"not writable)")
    return writer


def run(args: argparse.Namespace) -> int:
    from ..io.demo_scene import DemoScene, write_label_csv, write_truth_csv

    if args.frames < 1:
        raise UserError(f"--frames must be at least 1, got {args.frames}")
    if not args.fps > 0:
        raise UserError(f"--fps must be positive, got {args.fps}")
    out: Path = args.output
    if out.exists() and not out.is_dir():
        raise UserError(f"the output path {out} exists and is not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserError(f"cannot create the output folder {out}: {exc.strerror or exc}") from None

    scene = DemoScene(seed=args.seed, size=args.size, rig=args.rig, fps=args.fps,
                      n_frames=args.frames, noise=not args.no_noise,
                      flicker=not args.no_flicker)
    try:
        scene.rig.save(out / "rig.yaml")
    except OSError as exc:
        raise UserError(f"cannot write {out / 'rig.yaml'}: {exc.strerror or exc}") from None
    truths = []
    progress = Progress(args.frames, "demo")
    # Each file is written beside its name and renamed when whole: an interrupted run leaves the
    # previous demo (or nothing), never a cut-off video.
    try:
        with (replacing(out / "left.mp4", suffix=".mp4") as left_tmp,
              replacing(out / "right.mp4", suffix=".mp4") as right_tmp):
            writers = [_open_writer(left_tmp, args.fps, scene.image_size, out / "left.mp4"),
                       _open_writer(right_tmp, args.fps, scene.image_size, out / "right.mp4")]
            try:
                while (frame := scene.read()) is not None:
                    writers[0].write(frame.left)
                    writers[1].write(frame.right)
                    truths.append(scene.truth(frame.index))
                    progress.update(len(truths))
            finally:
                for w in writers:
                    w.release()
                progress.close()
                scene.close()
        with replacing(out / "truth.csv") as tmp:
            write_truth_csv(tmp, truths)
        for camera, name in ((0, "left_labels.csv"), (1, "right_labels.csv")):
            with replacing(out / name) as tmp:
                write_label_csv(tmp, truths, camera)
    except OSError as exc:
        raise UserError(f"cannot write the demo in {out}: {exc.strerror or exc}") from None
    visible = sum(t.visible_left for t in truths), sum(t.visible_right for t in truths)
    print(f"wrote {len(truths)} frame pairs ({scene.image_size[0]}x{scene.image_size[1]}, "
          f"{args.fps:g} fps, {args.rig} rig, seed {args.seed}) to {out}; shuttle visible in "
          f"{visible[0]} left / {visible[1]} right frames")
    return 0

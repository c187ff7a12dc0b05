"""``badminton-track calibrate``: stereo calibration from two folders of chessboard images.

Why this file exists: calibrating without a screen (or re-running a calibration on stored
images) must give the same rig and the same figures as the wizard; both call the core
(``core.calib_folders`` + ``core.calibration.solve_stereo``). Images are paired by sorted file
name (one folder holding both cameras' images is split by "left"/"right" in the names). The
rig file is written with ``StereoRig.save`` (GUIDE §8).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..core.calib_board import BoardError, BoardSpec
from ..core.calib_folders import pair_image_files, views_from_pairs
from ..core.calibration import CalibrationError, SolveOptions, solve_stereo
from ..core.rig import RigError
from .common import Progress, UserError, refuse_output_over_inputs


def register(sub) -> None:
    p = sub.add_parser(
        "calibrate", help="stereo calibration from left/right chessboard image folders",
        description="Calibrate a stereo rig from chessboard images: LEFT-DIR and RIGHT-DIR hold "
                    "the two cameras' images of the same board poses, paired by sorted file "
                    "name. One folder holding both (left01.jpg, right01.jpg, … as in OpenCV's "
                    "sample) may be given as both: its images are split by 'left'/'right' in "
                    "the name, or use --left-glob/--right-glob. Prints RMS and epipolar errors, "
                    "baseline, focal lengths, per-view errors and the rejected views, and "
                    "writes the rig YAML.")
    p.add_argument("--left-dir", type=Path, required=True, help="folder of left-camera images")
    p.add_argument("--right-dir", type=Path, required=True, help="folder of right-camera images")
    p.add_argument("--left-glob", default="*",
                   help="file-name pattern inside LEFT-DIR (default: every image), e.g. 'left*'")
    p.add_argument("--right-glob", default="*",
                   help="file-name pattern inside RIGHT-DIR (default: every image)")
    p.add_argument("--board", default="9x6",
                   help="inner corners COLSxROWS (a board of 10×7 squares is 9x6; default 9x6)")
    p.add_argument("--square", type=float, required=True,
                   help="side of one square in metres (sets the unit of the baseline)")
    p.add_argument("--charuco", action="store_true", help="the board is a ChArUco board")
    p.add_argument("--intrinsics", choices=("auto", "fix", "refine"), default="auto",
                   help="stereo step: keep per-camera intrinsics, refine them jointly, or decide "
                        "(default)")
    p.add_argument("--outlier-px", type=float, default=1.0,
                   help="reject views whose error exceeds max(2×median, this) (default 1.0 px)")
    p.add_argument("--subpix-window", type=int, default=None, metavar="PX",
                   help="cornerSubPix half-window in px (default: a third of a square, at most "
                        "11; OpenCV's stereo sample uses 11)")
    p.add_argument("-o", "--output", type=Path, required=True, help="rig file to write (.yaml)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    try:
        spec = BoardSpec.parse(args.board, args.square,
                               kind="charuco" if args.charuco else "chessboard")
    except BoardError as exc:
        raise UserError(str(exc)) from None
    try:
        pairs = pair_image_files(args.left_dir, args.right_dir, args.left_glob, args.right_glob)
        refuse_output_over_inputs(args.output, *(image for pair in pairs for image in pair))
        bar = Progress(len(pairs), "finding the board")
        if args.subpix_window is not None and not 1 <= args.subpix_window <= 50:
            raise UserError("--subpix-window must be 1..50 px")
        found = views_from_pairs(pairs, spec, progress=lambda f, _t: bar.update(round(
            f * len(pairs))), subpix_half_window=args.subpix_window)
        bar.close()
        options = SolveOptions(intrinsics=args.intrinsics, outlier_min_px=args.outlier_px)
        result = solve_stereo(found.views, found.image_size, spec, options)
    except CalibrationError as exc:
        raise UserError(str(exc)) from None

    print(f"{len(pairs)} image pairs, board found in both images of {len(found.views)}")
    for line in result.summary_lines():
        print(line)
    print("per-view reprojection error (px) and epipolar error (px):")
    for v in result.view_errors:
        print(f"  {v.view_id:<24} left {v.left_px:6.3f}  right {v.right_px:6.3f}  "
              f"epipolar {v.epipolar_px:6.3f}")
    for w in found.warnings:
        print(f"warning, {w.view_id} (kept; judged by its error): {w.reason}")
    if found.skipped or result.rejected:
        print("rejected views:")
        for r in found.skipped + result.rejected:
            print(f"  {r.view_id}: {r.reason}")
    else:
        print("rejected views: none")
    try:
        result.to_rig().save(args.output)
    except (OSError, RigError) as exc:
        raise UserError(f"cannot write {args.output}: {exc}") from None
    print(f"rig written to {args.output.resolve()}")
    return 0

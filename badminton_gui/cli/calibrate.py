"""``badminton-track calibrate``: stereo calibration from two folders of chessboard images.

Why this file exists: calibrating without a screen (or re-running a calibration on stored
images) must give the same rig and the same figures as the wizard; both call the core
(``core.calibrate.folders`` + ``core.calibrate.stereo.solve_stereo``). Images are paired by sorted file
name (one folder holding both cameras' images is split by "left"/"right" in the names). The
rig file is written with ``StereoRig.save``.
"""

from __future__ import annotations

import argparse
import logging
from pathlib import Path

from ..core.calibrate.board import BoardError, BoardSpec
from ..core.calibrate.folders import pair_image_files, views_from_pairs
from ..core.calibrate.stereo import CalibrationError, SolveOptions, solve_stereo
from ..core.rig import RigError
from .common import Progress, UserError, add_json_argument, print_json, refuse_output_over_inputs

_log = logging.getLogger(__name__)


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
    add_json_argument(p, "pairs, views_used, image_size [w, h], rms_left_px, rms_right_px, "
                         "rms_stereo_px, epipolar_px, epipolar_grade, baseline_m, baseline_std_m, "
                         "T_m [x, y, z], left and right {fx, fy, cx, cy} in px, intrinsics_mode, "
                         "views [{view, left_px, right_px, epipolar_px}], warnings and rejected "
                         "[{view, reason}], output (lengths in the unit of --square)")
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

    for w in found.warnings:
        _log.warning("%s (kept; judged by its error): %s", w.view_id, w.reason)
    rejected = found.skipped + result.rejected
    if not args.json:
        print(f"{len(pairs)} image pairs, board found in both images of {len(found.views)}")
        for line in result.summary_lines():
            print(line)
        print("per-view reprojection error (px) and epipolar error (px):")
        for v in result.view_errors:
            print(f"  {v.view_id:<24} left {v.left_px:6.3f}  right {v.right_px:6.3f}  "
                  f"epipolar {v.epipolar_px:6.3f}")
        if rejected:
            print("rejected views:")
            for r in rejected:
                print(f"  {r.view_id}: {r.reason}")
        else:
            print("rejected views: none")
    try:
        result.to_rig().save(args.output)
    except (OSError, RigError) as exc:
        raise UserError(f"cannot write {args.output}: {exc}") from None
    if args.json:
        print_json(_summary_json(len(pairs), result, found.warnings, rejected, args.output.resolve()))
    else:
        print(f"rig written to {args.output.resolve()}")
    return 0


def _summary_json(pairs: int, result, warnings, rejected, output: Path) -> dict:
    def intrinsics(m) -> dict:
        return {"fx": m[0, 0], "fy": m[1, 1], "cx": m[0, 2], "cy": m[1, 2]}

    return {"pairs": pairs, "views_used": len(result.view_errors),
            "image_size": list(result.image_size), "rms_left_px": result.rms_left,
            "rms_right_px": result.rms_right, "rms_stereo_px": result.rms_stereo,
            "epipolar_px": result.epipolar_px, "epipolar_grade": result.epipolar_grade,
            "baseline_m": result.baseline, "baseline_std_m": result.baseline_std,
            "T_m": [float(v) for v in result.T.ravel()], "left": intrinsics(result.M1),
            "right": intrinsics(result.M2), "intrinsics_mode": result.intrinsics_mode,
            "views": [{"view": v.view_id, "left_px": v.left_px, "right_px": v.right_px,
                       "epipolar_px": v.epipolar_px} for v in result.view_errors],
            "warnings": [{"view": w.view_id, "reason": w.reason} for w in warnings],
            "rejected": [{"view": r.view_id, "reason": r.reason} for r in rejected],
            "output": str(output)}

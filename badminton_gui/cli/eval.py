"""`badminton-track eval PRED.csv LABELS.csv`: TrackNet's five-outcome protocol."""

from __future__ import annotations

import argparse
import logging
import math

import numpy as np

from ..core.evaluation import DEFAULT_TOLERANCE, evaluate, tolerance_px
from ..io.labels import CsvFormatError, read_point_labels
from ..io.video import VideoFile
from .common import INPUT_ERRORS, UserError, add_json_argument, outcomes_json, print_json

_log = logging.getLogger(__name__)

STANDARD_WIDTHS = (512, 640, 1280, 1920, 2048, 2560, 3840)
MAX_WIDTH = 100_000     # px: a wider "image" is a typo


def positive_tolerance(text: str) -> float:
    """--tolerance: a finite number of pixels above 0 (argparse says it as a usage error)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of pixels") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text!r}: the tolerance must be a finite number of pixels above 0")
    return value


def image_width(text: str) -> int:
    """--width: a whole number of pixels, 1 to MAX_WIDTH."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number of pixels") from None
    if not 1 <= value <= MAX_WIDTH:
        raise argparse.ArgumentTypeError(f"{text!r}: the image width must be 1 to {MAX_WIDTH} px")
    return value


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("eval", help="score predictions against labels (TrackNet protocol)",
                       description="Count TP/TN/FP1/FP2/FN and print accuracy, precision, recall, F1. "
                                   "PRED may be `detect` output or `track` output (--camera).")
    p.add_argument("pred", help="predictions CSV")
    p.add_argument("labels", help="labels CSV (Frame,Visibility,X,Y)")
    p.add_argument("--tolerance", type=positive_tolerance, default=DEFAULT_TOLERANCE,
                   help="pixels at 512 px image width, scaled to the video width (default 4)")
    p.add_argument("--width", type=image_width, default=None, help="image width in pixels")
    p.add_argument("--video", default=None, help="read the image width from this video")
    p.add_argument("--camera", choices=("left", "right"), default=None,
                   help="for `track` output: which camera's columns to score")
    add_json_argument(p, "frames, tolerance_px, width, width_assumed (true: guessed from the "
                         "labels), tp, tn, fp1, fp2, fn, and accuracy, precision, recall, f1 as "
                         "fractions (null when undefined)")
    p.set_defaults(func=run)


def read_predictions(path: str, camera: str | None):
    """Predictions as {frame: (visible, x, y)} from `detect` or `track` output."""
    if camera is None:
        try:
            return read_point_labels(path).as_dict()
        except CsvFormatError as exc:
            if "VisL" in str(exc):
                raise UserError(f"{path} is `track` output: add --camera left or --camera right") from None
            raise
    # `track` output repeats a camera's frame on the steps only the other camera brought.
    if camera == "left":
        return read_point_labels(path, "Frame", "VisL", "XL", "YL", unique=False).as_dict()
    pred = read_point_labels(path, "FrameR", "VisR", "XR", "YR", unique=False)
    out: dict[int, tuple[bool, float, float]] = {}
    for f, v, (x, y) in zip(pred.frames, pred.visible, pred.xy):
        # A right frame paired with two left frames counts once, with its first result.
        out.setdefault(int(f), (bool(v), float(x), float(y)))
    return out


def run(args: argparse.Namespace) -> int:
    try:
        labels = read_point_labels(args.labels)
        pred = read_predictions(args.pred, args.camera)
        width = args.width
        if width is None and args.video:
            width = VideoFile(args.video).width
    except INPUT_ERRORS as exc:
        raise UserError(str(exc)) from None
    width_assumed = width is None
    if width_assumed:
        largest = np.nanmax(labels.xy[:, 0]) if labels.visible.any() else 0.0
        width = next((w for w in STANDARD_WIDTHS if w > largest), STANDARD_WIDTHS[-1])
        _log.warning("image width assumed %d px (largest label X is %.0f); pass --width or --video "
                     "to set it", width, largest)
    tol = tolerance_px(width, args.tolerance)
    label_dict = labels.as_dict()
    result = evaluate(pred, label_dict, tol)
    unpredicted = sum(f not in pred for f in label_dict)
    if unpredicted:
        _log.warning("%d of the %d labelled frames have no prediction in %s; they are scored as "
                     "not detected (FN where the shuttle is visible)", unpredicted, len(label_dict),
                     args.pred)
    if args.json:
        print_json({"frames": result.total, "tolerance_px": tol, "width": int(width),
                    "width_assumed": width_assumed, "unpredicted_frames": unpredicted,
                    **outcomes_json(result)})
    else:
        print(f"frames {result.total}  tolerance {tol:.1f} px at width {width}")
        print(result.summary())
    if math.isnan(result.accuracy):
        raise UserError("no labelled frames to score")
    return 0

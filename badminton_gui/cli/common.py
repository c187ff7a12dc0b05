"""Helpers shared by the CLI commands: user errors, progress bar, argument parsing, output."""

from __future__ import annotations

import argparse
import json
import math
import sys
import textwrap
import time
from pathlib import Path

from ..core.params import ParamError
from ..core.rig import RigError
from ..io.sources import SourceError
from ..io.track_file import FILE_LOOKAHEAD


class UserError(Exception):
    """Something the user can fix; printed as one line, exit status 2."""


# Errors from the layers below that are the user's input, not our bug.
INPUT_ERRORS = (ParamError, RigError, SourceError, FileNotFoundError, IsADirectoryError,
                PermissionError, ValueError)


def refuse_output_over_inputs(output, *inputs, what: str = "output") -> None:
    """Stop (UserError, exit 2) when ``output`` would overwrite one of ``inputs``: the same path,
    a symlink to it or a hard link of it. Every command that writes a file calls this before it
    reads anything; None inputs (options not given) are skipped, so pass the options as they are:
    ``refuse_output_over_inputs(args.output, args.left, args.right, args.calib)``."""
    from ..io.safe_write import clashing_input
    if output is None:
        return
    clash = clashing_input(output, inputs)
    if clash is not None:
        same = "" if str(output) == clash else f" ({clash}, the same file)"
        raise UserError(f"the {what} {output} is also an input{same}: writing it would destroy "
                        "the input; choose another output path")


def preset_file(args):
    """``--preset`` when it names a file (an input that an output must not overwrite), else None."""
    preset = getattr(args, "preset", None)
    return preset if preset and Path(preset).is_file() else None


BAUD_RANGE = (50, 4_000_000)     # what serial adapters offer; Bluetooth SPP ignores the rate


def baud_rate(text: str) -> int:
    """argparse type of ``--baud``: a whole number of bits per second within BAUD_RANGE (USB
    adapters accept non-standard rates such as 250000, so any rate in the range is taken)."""
    try:
        baud = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number of bits per second") from None
    if not BAUD_RANGE[0] <= baud <= BAUD_RANGE[1]:
        raise argparse.ArgumentTypeError(f"{baud} is outside {BAUD_RANGE[0]} … {BAUD_RANGE[1]} "
                                         "(common rates: 9600, 57600, 115200, 921600)")
    return baud


def seconds_or_zero(text: str) -> float:
    """argparse type of a time limit: finite seconds ≥ 0 (0: no limit); nan, inf and negative
    values are refused."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"{text} must be finite seconds ≥ 0 (0: no limit)")
    return value


def count_or_zero(text: str) -> int:
    """argparse type of a count: a whole number ≥ 0 (0: no limit)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"{value} must be ≥ 0 (0: no limit)")
    return value


def frame_count(text: str) -> int:
    """argparse type of ``--max-frames``: a whole number of frames, at least 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number of frames") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value}: give at least 1 frame (leave the option out for all)")
    return value


def parse_size(text: str) -> tuple[int, int]:
    try:
        w, h = text.lower().split("x")
        size = (int(w), int(h))
    except ValueError:
        raise UserError(f"size {text!r} is not WIDTHxHEIGHT, e.g. 1280x720") from None
    if size[0] < 64 or size[1] < 64 or size[0] > 8192 or size[1] > 8192:
        raise UserError(f"size {text!r} is outside 64x64 … 8192x8192")
    return size


class Progress:
    """A one-line progress bar on stderr, redrawn at most 10 times a second.

    Silent when stderr is not a terminal unless ``force`` is set, so logs stay clean.
    """

    def __init__(self, total: int | None, label: str, force: bool = False) -> None:
        self.total = total
        self.label = label
        self.enabled = force or sys.stderr.isatty()
        self.start = time.perf_counter()
        self._last_draw = 0.0
        self.count = 0

    def update(self, count: int) -> None:
        self.count = count
        now = time.perf_counter()
        if not self.enabled or now - self._last_draw < 0.1:
            return
        self._last_draw = now
        self._draw(now)

    def _draw(self, now: float) -> None:
        rate = self.count / max(now - self.start, 1e-9)
        if self.total:
            frac = min(self.count / self.total, 1.0)
            bar = "#" * int(frac * 30)
            eta = (self.total - self.count) / rate if rate > 0 else 0.0
            text = (f"\r{self.label} [{bar:<30}] {self.count}/{self.total} "
                    f"{rate:6.1f}/s eta {eta:5.1f}s")
        else:
            text = f"\r{self.label} {self.count} {rate:6.1f}/s"
        sys.stderr.write(text)
        sys.stderr.flush()

    def close(self) -> None:
        if self.enabled:
            self._draw(time.perf_counter())
            sys.stderr.write("\n")
            sys.stderr.flush()


class CliHelpFormatter(argparse.HelpFormatter):
    """argparse's help, except that a paragraph of the description or epilog whose lines are
    indented (a table of CSV columns or JSON keys) is printed as written, not re-wrapped."""

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        out = []
        for para in textwrap.dedent(text).strip("\n").split("\n\n"):
            if any(line.startswith(" ") for line in para.splitlines()):
                out.append("\n".join(indent + line for line in para.splitlines()))
            else:
                out.append(textwrap.fill(" ".join(para.split()), width, initial_indent=indent,
                                         subsequent_indent=indent))
        return "\n\n".join(out)


def add_logging_arguments(parser: argparse.ArgumentParser, top_level: bool = False) -> None:
    """-v/--verbose, -q/--quiet and --log-file, on the program and on every command (so both
    `badminton-track -v detect ...` and `badminton-track detect -v ...` work). The command's copy
    sets nothing unless given, so it does not undo the program's."""
    def default(value):
        return value if top_level else argparse.SUPPRESS

    # A command that already defines one of these options keeps its own (no clash at start-up).
    taken = set(parser._option_string_actions)
    group = parser.add_mutually_exclusive_group()
    if not {"-v", "--verbose"} & taken:
        group.add_argument("-v", "--verbose", action="count", default=default(0),
                           help="more detail on stderr (-vv: debugging detail); the log file gets "
                                "debugging detail too")
    if not {"-q", "--quiet"} & taken:
        group.add_argument("-q", "--quiet", action="store_true", default=default(False),
                           help="print nothing but results and errors: no progress bar, no warnings "
                                "(detect and track then print no summary either)")
    if "--log-file" not in taken:
        parser.add_argument("--log-file", metavar="PATH", default=default(None),
                            help=f"log to this file (default: {log_file_for_help()}, shared with "
                                 f"the GUI)")


def log_file_for_help() -> str:
    """The default log file's path, escaped for an argparse help string."""
    from ..io.logging_setup import default_log_file
    return str(default_log_file()).replace("%", "%%")


def add_json_argument(parser: argparse.ArgumentParser, keys: str) -> None:
    """--json: the summary as one JSON object on stdout instead of text. ``keys`` documents them."""
    parser.add_argument("--json", action="store_true",
                        help="print the summary as one JSON object on stdout instead of text: " + keys)


def _json_value(value):
    """JSON has no NaN or infinity: those become null, as do numpy scalars their Python value."""
    if isinstance(value, dict):
        return {str(k): _json_value(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_value(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):
        value = value.item()      # numpy scalar
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def print_json(summary: dict) -> None:
    """The one JSON object a command prints with --json (ASCII only: any console prints it)."""
    print(json.dumps(_json_value(summary), indent=2, allow_nan=False))


def outcomes_json(outcomes) -> dict:
    """A score (core.evaluation.Outcomes) for --json: the five counts and the four figures as
    fractions (0..1; null when undefined, e.g. precision with nothing detected)."""
    o = outcomes
    return {"tp": o.tp, "tn": o.tn, "fp1": o.fp1, "fp2": o.fp2, "fn": o.fn, "accuracy": o.accuracy,
            "precision": o.precision, "recall": o.recall, "f1": o.f1}


def add_preset_argument(parser) -> None:
    parser.add_argument("--preset", default=None,
                        help="parameter preset name (see `badminton-track presets`) or a .json file")




def add_lookahead_argument(parser) -> None:
    parser.add_argument("--lookahead", type=int, default=FILE_LOOKAHEAD, metavar="N",
                        help="re-decide each frame's detection once the next N frames are known "
                             f"(default {FILE_LOOKAHEAD}; 0 = the live, frame-by-frame readout)")


def params_from_args(args):
    """The TrackerParams chosen by --preset (default preset otherwise) and --lookahead."""
    from ..io.presets import load_preset
    try:
        params = load_preset(getattr(args, "preset", None))
        if getattr(args, "lookahead", None) is not None:
            params = params.with_value("lookahead.frames", args.lookahead)
        return params
    except INPUT_ERRORS as exc:
        raise UserError(str(exc)) from None


def add_video_pair_arguments(parser, calib_help: str) -> None:
    """The recorded video pair's options, read back by :func:`open_stereo_videos`: the two videos,
    their rig, and how their frames pair (timestamp files, the videos' own times, or index)."""
    parser.add_argument("--left", required=True, help="left camera video")
    parser.add_argument("--right", required=True, help="right camera video")
    parser.add_argument("--calib", required=True, help=calib_help)
    parser.add_argument("--left-times", help="CSV with Frame,Timestamp for the left video")
    parser.add_argument("--right-times", help="CSV with Frame,Timestamp for the right video")
    parser.add_argument("--video-times", action="store_true",
                        help="pair the cameras by the videos' own frame timestamps (recordings whose "
                             "cameras dropped frames; without this and without timestamp files, "
                             "frame i pairs with frame i)")


def open_stereo_videos(args):
    """(rig, source, pair count or None) for the commands that read a recorded video pair
    (`track`, `refine-calib`): ``--left --right --calib [--left-times --right-times |
    --video-times] [--max-frames]``; the pairs are decoded on a reader thread (io/prefetch.py)."""
    from ..core.rig import StereoRig
    from ..io.labels import read_timestamps
    from ..io.prefetch import PrefetchingReader
    from ..io.video import VideoPair, frame_times
    if (args.left_times is None) != (args.right_times is None):
        raise UserError("give --left-times and --right-times together")
    video_times = args.video_times
    if video_times and args.left_times:
        raise UserError("give either --left-times/--right-times or --video-times, not both")
    try:
        rig = StereoRig.load(args.calib)
        lt = rt = None
        if args.left_times:
            lt = read_timestamps(args.left_times)[1]
            rt = read_timestamps(args.right_times)[1]
        elif video_times:
            # One decoding pass per video (seconds at 2048 px): shown as its own progress line.
            scans = []
            for path in (args.left, args.right):
                scan = Progress(100, f"frame times of {Path(path).name} (%)")
                try:
                    scans.append(frame_times(path, progress=lambda f, s=scan: s.update(round(100 * f))))
                finally:
                    if scan.count:
                        scan.close()
            lt, rt = scans
        source = VideoPair(args.left, args.right, lt, rt)
        rig.check_image_size(*source.image_size, what="the videos")
    except INPUT_ERRORS as exc:
        raise UserError(str(exc)) from None
    total = source.frame_count if lt is None else source.step_count
    if args.max_frames:
        total = min(total, args.max_frames) if total else args.max_frames
    return rig, PrefetchingReader(source), total or None

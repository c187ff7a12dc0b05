"""``badminton-track``: the headless command line over the same core as the GUI.

Why this file exists: it only assembles the sub-commands; each lives in its own module of this
package with a ``register(subparsers)`` function, so commands can be added without touching the
others. Errors that a user can fix (missing file, wrong resolution, bad CSV) are caught here
and printed as one line on stderr with exit status 2; nothing else is swallowed.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from .common import UserError

# Module names in this package, in the order `--help` lists them.
COMMAND_MODULES = ("demo", "detect", "track", "eval", "import_calib", "refine_calib", "calibrate", "presets", "render",
                   "robot_listen")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="badminton-track",
        description="Headless shuttlecock tracking: demo court, detection, stereo tracking, "
                    "evaluation and calibration.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(f"{__name__}.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"{__name__}.{name}":
                continue  # command not built yet in this checkout
            raise
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except UserError as exc:
        print(f"badminton-track {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"badminton-track {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())

"""``badminton-track``: the headless command line over the same core as the GUI.

Why this file exists: it only assembles the sub-commands; each lives in its own module of this
package with a ``register(subparsers)`` function, so commands can be added without touching the
others. Errors that a user can fix (missing file, wrong resolution, bad CSV) are caught here
and printed as one line on stderr with exit status 2; nothing else is swallowed: a bug's
traceback goes to the log file (io/logging_setup.py) and to stderr, and the exit status is 1.
Results go to stdout, everything else (progress, warnings, errors) to stderr.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys

from .. import __version__
from ..io.logging_setup import (FILE_ONLY, configure_logging, describe_environment, log_uncaught,
                                make_console_safe)
from .common import CliHelpFormatter, UserError, add_logging_arguments

PROG = "badminton-track"
_log = logging.getLogger(__name__)

# Module names in this package, in the order `--help` lists them.
COMMAND_MODULES = ("demo", "detect", "track", "eval", "import_calib", "refine_calib", "calibrate", "presets", "render",
                   "robot_listen")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Headless shuttlecock tracking: demo court, detection, stereo tracking, "
                    "evaluation and calibration.",
        epilog="Every command also takes -v/-q/--log-file after its name. Results go to stdout; "
               "progress, warnings and errors to stderr. Exit status: 0 done, 2 a problem with "
               "the input (one line on stderr), 1 a bug (its traceback is also in the log file).")
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    add_logging_arguments(parser, top_level=True)
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
    for command in {id(p): p for p in sub.choices.values()}.values():
        add_logging_arguments(command)
        command.formatter_class = CliHelpFormatter   # keeps the epilogs' column tables as written
    return parser


def main(argv: list[str] | None = None) -> int:
    make_console_safe()
    parser = build_parser()
    args = parser.parse_args(argv)
    log_file = configure_logging(PROG, verbose=args.verbose, quiet=args.quiet, log_file=args.log_file)
    _log.info("%s started: %s %s (%s)", args.command, PROG, __version__, describe_environment())
    _log.debug("arguments: %s", sys.argv[1:] if argv is None else argv)
    try:
        code = int(args.func(args) or 0)
    except UserError as exc:
        print(f"{PROG} {args.command}: error: {exc}", file=sys.stderr)
        _log.error("%s: %s", args.command, exc, extra=FILE_ONLY)
        return 2
    except KeyboardInterrupt:
        print(f"{PROG} {args.command}: interrupted", file=sys.stderr)
        _log.info("%s: interrupted", args.command, extra=FILE_ONLY)
        return 130
    except Exception:
        # A bug: its traceback into the log (the operator sends that file), then Python's usual
        # report on stderr and exit status 1.
        log_uncaught(*sys.exc_info(), where=args.command)
        where = f"; the traceback is also in {log_file}" if log_file else ""
        print(f"{PROG} {args.command}: internal error{where}", file=sys.stderr)
        raise
    _log.info("%s: exit status %d", args.command, code)
    return code


if __name__ == "__main__":
    sys.exit(main())

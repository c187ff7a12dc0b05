"""`badminton-gui`: the operator's application, and its unattended screenshot mode.

Why this file exists: the entry point declared in pyproject. Without arguments it reopens the
last source (the demo court the first time). ``--source demo|video|cameras`` overrides it, and
``--screenshot PATH --quit-after SECONDS`` tracks for that long, saves the window and exits 0
(used under Xvfb to check the product end to end).

Everything the program says goes to the log file of io/logging_setup.py as well as to stderr,
Qt's own messages included: started from a desktop launcher it has no terminal, and the file is
what an operator can send.
"""

from __future__ import annotations

import argparse
import logging
import os
import signal
import sys

from .. import __version__
from ..core.params import ParamError
from ..io.logging_setup import configure_logging, default_log_file, describe_environment, make_console_safe

PROG = "badminton-gui"
_log = logging.getLogger(__name__)
# --quit-after: how much longer to wait for the first result when none arrived in time.
FIRST_RESULT_GRACE_MS = 60_000


# The tracker's Python parts hold the GIL; a 1 ms switch interval (default 5 ms) lets the
# 30 Hz display timer run on time (measured: ~20 % more display refreshes, no tracking loss).
GIL_SWITCH_INTERVAL = 0.001


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog=PROG, description="Courtside stereo shuttlecock tracker.")
    p.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    p.add_argument("--source", choices=("demo", "video", "single", "cameras"),
                   help="what to track (default: the last source, else the demo court); 'single': one "
                        "camera's video given as --left (a TV clip: add --preset broadcast)")
    p.add_argument("--left", help="left video file / camera index")
    p.add_argument("--right", help="right video file / camera index")
    p.add_argument("--calib", help="rig file (OpenCV FileStorage YAML)")
    p.add_argument("--left-times", help="CSV with Frame,Timestamp for the left video")
    p.add_argument("--right-times", help="CSV with Frame,Timestamp for the right video")
    p.add_argument("--video-times", action="store_true",
                   help="pair a video pair by the files' own frame timestamps (cameras that dropped frames)")
    p.add_argument("--left-labels", help="CSV with Frame,Visibility,X,Y for the left video: the readouts "
                                         "score the tracking against it live (timestamp files that carry "
                                         "these columns are used without this)")
    p.add_argument("--right-labels", help="the same for the right video")
    p.add_argument("--preset", help="parameter preset name or .json file")
    p.add_argument("--fast", action="store_true", help="process files as fast as possible (no real-time pacing)")
    p.add_argument("--screenshot", metavar="PATH", help="save a screenshot of the window before quitting")
    p.add_argument("--quit-after", type=float, metavar="SECONDS",
                   help="quit after this many seconds (or at the first result, if none arrived by then)")
    verbosity = p.add_mutually_exclusive_group()
    verbosity.add_argument("-v", "--verbose", action="count", default=0,
                           help="more detail on stderr (-vv: debugging detail); the log file gets "
                                "debugging detail too")
    verbosity.add_argument("-q", "--quiet", action="store_true", help="only errors on stderr")
    p.add_argument("--log-file", metavar="PATH",
                   help="log to this file (default: %s)"
                        % str(default_log_file()).replace("%", "%%"))
    return p


def main(argv: list[str] | None = None) -> int:
    make_console_safe()
    args = build_parser().parse_args(argv)
    configure_logging(PROG, verbose=args.verbose, quiet=args.quiet, log_file=args.log_file)
    _log.info("%s %s started (%s)", PROG, __version__, describe_environment())
    _log.debug("arguments: %s", sys.argv[1:] if argv is None else argv)
    # Ctrl+C while Qt and the tracker are still loading (seconds on a busy machine) is
    # remembered and honoured once the window exists, rather than ending in a traceback.
    early_interrupt: list[bool] = []
    signal.signal(signal.SIGINT, lambda *_: early_interrupt.append(True))
    sys.setswitchinterval(GIL_SWITCH_INTERVAL)
    from ..core.tracker import configure_opencv_threads
    configure_opencv_threads()
    # Scanning for cameras makes OpenCV warn once per absent device; the dialog says it better.
    os.environ.setdefault("OPENCV_LOG_LEVEL", "ERROR")
    if args.source in ("video", "cameras") and not (args.left and args.right):
        _log.error("--source %s needs --left and --right", args.source)
        return 2

    from PySide6.QtCore import QCoreApplication, Qt, qInstallMessageHandler
    from PySide6.QtWidgets import QApplication

    from . import settings as st
    from .main_window import MainWindow

    qInstallMessageHandler(_qt_message_to_log)
    # Shared GL contexts: pyqtgraph's shaders stay valid if a GL view is ever re-created.
    QCoreApplication.setAttribute(Qt.ApplicationAttribute.AA_ShareOpenGLContexts)
    app = QApplication.instance() or QApplication(sys.argv[:1])
    app.setOrganizationName(st.ORGANISATION)
    app.setApplicationName(st.APPLICATION)
    params = None
    if args.preset:
        from ..io.presets import load_preset
        try:
            params = load_preset(args.preset)
        except ParamError as exc:
            _log.error("%s", exc)
            return 2
    spec = None
    if args.source:
        spec = st.SourceSpec(args.source, args.left or "", args.right or "", args.calib or "",
                             args.left_times or "", args.right_times or "", not args.fast,
                             video_times=args.video_times, left_labels=args.left_labels or "",
                             right_labels=args.right_labels or "")
    elif args.fast:
        spec = st.SourceSpec(realtime=False)
    window = MainWindow(params=params, spec=spec)
    if args.preset:
        window.remember_preset(args.preset)   # the tuning dialog's Reset returns to it
    if args.fast:
        window.realtime_action.setChecked(False)
        window._realtime_changed()
    window.show()
    # Ctrl+C in the terminal closes the window cleanly instead of being ignored by Qt. The
    # close is queued: a Python signal handler runs between any two bytecodes, e.g. inside the
    # 3D view's paintGL, and closing the window there crashed (segfault in 2 of 4 tries).
    from PySide6.QtCore import QTimer
    signal.signal(signal.SIGINT, lambda *_: QTimer.singleShot(0, window.close))
    if early_interrupt:
        QTimer.singleShot(0, window.close)

    status = {"code": 0}
    if args.quit_after is not None:

        waited = {"extra_ms": 0}

        def finish() -> None:
            if window.results_seen == 0 and waited["extra_ms"] < FIRST_RESULT_GRACE_MS \
                    and not (window.banner.text and window.banner.kind == "error"):
                # A loaded machine can take longer than SECONDS to open the source and load the
                # classifier: wait for the first result (not for ever) rather than fail a run
                # that would have tracked. A banner means the source failed: no use waiting.
                waited["extra_ms"] += 500
                QTimer.singleShot(500, finish)
                return
            if window.results_seen == 0:
                # Unattended runs must fail loudly when nothing was tracked.
                reason = window.banner.text or "no result arrived in time"
                _log.error("nothing tracked: %s", reason)
                status["code"] = 1
            if args.screenshot:
                path = os.path.abspath(args.screenshot)
                if not window.grab_window().save(path):
                    _log.error("cannot write the screenshot %s", path)
                    status["code"] = 1
                else:
                    print(f"screenshot: {path}; results shown {window.results_seen}, "
                          f"display {window.display_rate:.1f} Hz, processing "
                          f"{_processing_fps(window):.1f} fps")
            window.close()
            app.quit()

        QTimer.singleShot(int(args.quit_after * 1000), finish)
    app.exec()
    _log.info("exit status %d", status["code"])
    return status["code"]


def _qt_message_to_log(kind, context, message: str) -> None:
    """Qt's warnings (a missing platform plugin, a GL context that failed) into the log file,
    at the matching level, instead of only to a terminal the operator may not have."""
    from PySide6.QtCore import QtMsgType
    level = {QtMsgType.QtDebugMsg: logging.DEBUG, QtMsgType.QtInfoMsg: logging.INFO,
             QtMsgType.QtWarningMsg: logging.WARNING, QtMsgType.QtCriticalMsg: logging.ERROR,
             QtMsgType.QtFatalMsg: logging.CRITICAL}.get(kind, logging.WARNING)
    logging.getLogger("qt").log(level, "%s", message)


def _processing_fps(window) -> float:
    p = window.latest_packet
    return p.stats.processing_fps if p is not None else 0.0


if __name__ == "__main__":
    sys.exit(main())

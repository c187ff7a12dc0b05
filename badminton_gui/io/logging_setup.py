"""One logging set-up for ``badminton-track`` and ``badminton-gui``: a log an operator can hand over.

Why this file exists: a window started from a desktop launcher has no terminal, so whatever the
program says (its warnings, a traceback, a crash inside Qt or OpenCV) is lost unless it lands in
a file. Both programs call :func:`configure_logging` first thing; it sends

- every record of INFO and above (DEBUG too with ``-v``) to a rotating file,
  ``badminton-gui.log`` in :func:`badminton_gui.io.app_dirs.log_dir` (or ``--log-file``),
- records at the console's level (WARNING; INFO/DEBUG with ``-v``/``-vv``; ERROR with ``-q``)
  to stderr, one plain line each,
- uncaught exceptions, in the main thread and in any other thread, to the file with their
  traceback before Python's usual report on stderr,
- a hard crash (segmentation fault in a C extension) to the same file, through ``faulthandler``.

When the log file cannot be opened (read-only home, a full disk) the program runs on with the
console only and says so once. Stdlib only: the CLI and the GUI both use it.
"""

from __future__ import annotations

import faulthandler
import logging
import logging.handlers
import os
import platform
import sys
import threading
from pathlib import Path

from .app_dirs import log_dir

try:
    import fcntl
except ImportError:      # Windows
    fcntl = None

LOG_FILE_NAME = "badminton-gui.log"
# Five old files of 2 MB: weeks of normal use, and small enough to attach to a message.
MAX_LOG_BYTES = 2 * 1024 * 1024
LOG_BACKUPS = 5

# A record carrying ``extra=FILE_ONLY`` goes to the log file but not to the console: for what
# the console already shows in its own words (a traceback printed by Python, a one-line error).
FILE_ONLY = {"file_only": True}

_log = logging.getLogger("badminton_gui")


class _State:
    """What :func:`configure_logging` installed, so a second call (tests, the GUI after a CLI
    call in one process) replaces it instead of stacking handlers and hooks."""

    handlers: list[logging.Handler] = []
    log_file: Path | None = None
    program = ""
    hooks_installed = False
    previous_excepthook = None
    previous_threading_excepthook = None
    faulthandler_was_enabled = False
    previous_root_level: int | None = None


def current_log_file() -> Path | None:
    """The file this process logs to, or None (logging not configured, or the file could not
    be opened). The GUI's About box and error banners name it."""
    return _State.log_file


def default_log_file() -> Path:
    """Where the log goes without ``--log-file``."""
    return log_dir() / LOG_FILE_NAME


class _RotatingLog(logging.handlers.RotatingFileHandler):
    """A rotating file that several processes can share (the GUI and a ``track`` run write the
    same log), and that keeps ``faulthandler`` pointed at the file it writes now.

    The stdlib handler assumes it is the file's only writer: when another process rotates the
    file, this one goes on writing into the renamed backup, and once that backup ages out of
    ``LOG_BACKUPS`` into a deleted file, so its records are lost. Here every record first checks
    that the path still names the file this handler writes (device and inode, as
    ``WatchedFileHandler`` does) and reopens it when not; a rollover is made under an advisory
    lock beside the log (POSIX), and only when no other process rotated meanwhile.

    faulthandler holds a file descriptor; rotation closes that descriptor and opens a new file,
    so it is re-pointed around every reopening (a stale descriptor could be reused by an
    unrelated file, which a crash report would then overwrite)."""

    def emit(self, record: logging.LogRecord) -> None:
        try:
            if self._rotated_elsewhere():
                self._reopen()
        except OSError:
            pass         # the directory went away or is unreadable: the stdlib's emit reports it
        super().emit(record)

    def doRollover(self) -> None:  # noqa: N802 - the stdlib's name
        with _RolloverLock(self.baseFilename):
            if self._rotated_elsewhere():
                self._reopen()     # another process rotated it first: the new file is short
                return
            _point_faulthandler(None)
            try:
                super().doRollover()
            finally:
                _point_faulthandler(self.stream)

    def _rotated_elsewhere(self) -> bool:
        """True when the path no longer names the open file (renamed or deleted by another
        process)."""
        if self.stream is None:
            return False
        try:
            on_disk = os.stat(self.baseFilename)
        except FileNotFoundError:
            return True
        own = os.fstat(self.stream.fileno())
        return (on_disk.st_dev, on_disk.st_ino) != (own.st_dev, own.st_ino)

    def _reopen(self) -> None:
        _point_faulthandler(None)
        try:
            old, self.stream = self.stream, None
            if old is not None:
                old.close()
            self.stream = self._open()
        finally:
            _point_faulthandler(self.stream)


class _RolloverLock:
    """An exclusive advisory lock on ``<log>.lock`` while a process rotates the log (POSIX
    ``flock``; elsewhere, and when the lock file cannot be made, no lock: Windows cannot rename
    a file another process holds open anyway, so there the first writer keeps rotating)."""

    def __init__(self, log_path: str) -> None:
        self.path = log_path + ".lock"
        self.fd: int | None = None

    def __enter__(self) -> "_RolloverLock":
        if fcntl is None:
            return self
        try:
            self.fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            fcntl.flock(self.fd, fcntl.LOCK_EX)
        except OSError:
            if self.fd is not None:
                os.close(self.fd)
            self.fd = None
        return self

    def __exit__(self, *exc) -> None:
        if self.fd is not None:
            fcntl.flock(self.fd, fcntl.LOCK_UN)
            os.close(self.fd)
            self.fd = None


def _point_faulthandler(stream) -> None:
    """Crash reports into ``stream``; None: back to stderr (or off when there is none)."""
    target = stream if stream is not None else sys.__stderr__
    try:
        if target is None:
            faulthandler.disable()
        else:
            faulthandler.enable(file=target, all_threads=True)
    except (ValueError, OSError, AttributeError):
        faulthandler.disable()   # a stream without a file descriptor (pythonw, a test double)


class _ConsoleFilter(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        return not getattr(record, "file_only", False)


def console_level(verbose: int = 0, quiet: bool = False) -> int:
    """WARNING by default, INFO with ``-v``, DEBUG with ``-vv``, ERROR with ``-q`` (which wins)."""
    if quiet:
        return logging.ERROR
    if verbose >= 2:
        return logging.DEBUG
    return logging.INFO if verbose == 1 else logging.WARNING


def configure_logging(program: str, *, verbose: int = 0, quiet: bool = False,
                      log_file: str | Path | None = None) -> Path | None:
    """Set up the log file, the console, the exception hooks and faulthandler; return the log
    file's path (None when it could not be opened: the console alone is used, with a warning).

    ``program`` names the process in the file's lines and in the console's (``badminton-track``,
    ``badminton-gui``); the two programs share the file. Calling it again replaces the set-up.
    """
    reset_logging()
    _State.program = program
    root = logging.getLogger()
    file_level = logging.DEBUG if verbose >= 1 else logging.INFO
    level_console = console_level(verbose, quiet)

    path = Path(log_file).expanduser() if log_file else default_log_file()
    file_handler: _RotatingLog | None = None
    failure = ""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        # Not delayed: faulthandler needs an open stream from the start.
        file_handler = _RotatingLog(path, maxBytes=MAX_LOG_BYTES, backupCount=LOG_BACKUPS,
                                    encoding="utf-8")
    except OSError as exc:
        failure = f"cannot write the log file {path} ({exc.strerror or exc}); logging to the console only"
    if file_handler is not None:
        file_handler.setLevel(file_level)
        file_handler.setFormatter(logging.Formatter(
            f"%(asctime)s {program}[%(process)d] %(threadName)s %(levelname)s %(name)s: %(message)s"))
        root.addHandler(file_handler)
        _State.handlers.append(file_handler)
        _State.log_file = path.resolve()

    stderr = sys.stderr
    if stderr is not None:       # pythonw on Windows has no console at all
        console = logging.StreamHandler(stderr)
        console.setLevel(level_console)
        console.setFormatter(logging.Formatter(f"{program}: %(levelname_lower)s: %(message)s"))
        console.addFilter(_ConsoleFilter())
        console.addFilter(_lower_level_name)
        root.addHandler(console)
        _State.handlers.append(console)

    _State.previous_root_level = root.level
    root.setLevel(min(file_level if file_handler is not None else level_console, level_console))
    _install_hooks()
    _point_faulthandler(file_handler.stream if file_handler is not None else None)
    if failure:
        _log.warning(failure)
    return _State.log_file


def _lower_level_name(record: logging.LogRecord) -> bool:
    record.levelname_lower = record.levelname.lower()
    return True


def reset_logging() -> None:
    """Remove what :func:`configure_logging` installed: handlers closed, hooks and faulthandler
    as they were before. Tests call it so one test's log file is not written by the next."""
    root = logging.getLogger()
    # faulthandler first: it must not keep the descriptor of a file about to be closed.
    if _State.hooks_installed:
        if _State.faulthandler_was_enabled:
            _point_faulthandler(None)
        else:
            faulthandler.disable()
    for handler in _State.handlers:
        root.removeHandler(handler)
        handler.close()
    _State.handlers = []
    _State.log_file = None
    if _State.previous_root_level is not None:
        root.setLevel(_State.previous_root_level)
        _State.previous_root_level = None
    if _State.hooks_installed:
        sys.excepthook = _State.previous_excepthook
        threading.excepthook = _State.previous_threading_excepthook
        _State.hooks_installed = False


def _install_hooks() -> None:
    _State.previous_excepthook = sys.excepthook
    _State.previous_threading_excepthook = threading.excepthook
    _State.faulthandler_was_enabled = faulthandler.is_enabled()
    sys.excepthook = _excepthook
    threading.excepthook = _threading_excepthook
    _State.hooks_installed = True


def log_uncaught(exc_type, exc, tb, where: str = "") -> None:
    """Write an exception that nobody handled, with its traceback, to the log file (once: the
    exception is marked, so a hook further up does not write it again)."""
    if exc is not None and getattr(exc, "_badminton_logged", False):
        return
    if exc_type is not None and issubclass(exc_type, KeyboardInterrupt):
        _log.info("interrupted%s", f" ({where})" if where else "", extra=FILE_ONLY)
    else:
        _log.critical("uncaught exception%s", f" in {where}" if where else "",
                      exc_info=(exc_type, exc, tb), extra=FILE_ONLY)
    if exc is not None:
        try:
            exc._badminton_logged = True
        except AttributeError:
            pass


def _excepthook(exc_type, exc, tb) -> None:
    log_uncaught(exc_type, exc, tb)
    previous = _State.previous_excepthook or sys.__excepthook__
    previous(exc_type, exc, tb)


def _threading_excepthook(args) -> None:
    if args.exc_type is not SystemExit:
        name = args.thread.name if args.thread is not None else "a thread"
        log_uncaught(args.exc_type, args.exc_value, args.exc_traceback, where=f"thread {name}")
    previous = _State.previous_threading_excepthook or threading.__excepthook__
    previous(args)


def describe_environment() -> str:
    """Python, the system and the versions of the big native libraries already loaded: the
    first question about any crash report."""
    parts = [f"Python {platform.python_version()}", platform.platform(terse=True)]
    for module, name in (("cv2", "OpenCV"), ("numpy", "numpy"), ("PySide6", "PySide6")):
        version = getattr(sys.modules.get(module), "__version__", None)
        if version:
            parts.append(f"{name} {version}")
    return ", ".join(parts)


def make_console_safe() -> None:
    """Let stdout and stderr print any character on any console: one the console's encoding
    lacks (an arrow on a Windows cp1252 console, a redirected stream) is written escaped instead
    of ending the program with UnicodeEncodeError after its work is done."""
    for stream in (sys.stdout, sys.stderr):
        reconfigure = getattr(stream, "reconfigure", None)
        if reconfigure is None:
            continue
        try:
            reconfigure(errors="backslashreplace")
        except (ValueError, OSError, TypeError):
            pass   # a stream that cannot change (already closed, a test double): leave it

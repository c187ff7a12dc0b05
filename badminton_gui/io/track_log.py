"""Recording a tracking session to a CSV file while the tracker runs (the GUI's *Record*).

Why this file exists: the operator wants the session afterwards — where the shuttle flew, what
the robot was told — in the same columns `badminton-track track` writes, so a recorded session
can be read by the same tools (`badminton-track eval`, a spreadsheet). Rows come from the
tracking thread at the tracking rate (up to 240 a second), so writing must be cheap and must
never stop the tracker: a full disk, a vanished USB stick or a folder made read-only ends the
*recording* with a one-sentence reason, keeps every whole row written until then (never a torn
last row), and leaves tracking alone. No Qt here: the GUI polls ``rows`` and ``error``.
"""

from __future__ import annotations

import errno
import threading
import time
from pathlib import Path

from .labels import TRACK_COLUMNS, track_row
from .safe_write import RowFile

# Rows reach the disk at least this often (s): a crash or a pulled cable loses at most this much.
FLUSH_EVERY_S = 0.5


class RecordingError(OSError):
    """The recording file cannot be started; the message is one sentence for the user."""


def describe_os_error(exc: OSError, path: Path) -> str:
    """One sentence for a failed write: what happened and what the user can do."""
    if exc.errno == errno.ENOSPC:
        return f"the disk is full writing {path}"
    if exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        return f"{path} cannot be written (no permission, or a read-only disk)"
    if exc.errno in (errno.ENOENT, errno.ENODEV, errno.EIO, errno.ENXIO):
        return f"the folder of {path} is gone (a removed disk?)"
    return f"writing {path} failed: {exc.strerror or exc}"


class TrackRecorder:
    """Appends one row per ``TrackResult`` to a CSV file; ``add`` is a worker result tap.

    The rows are the live readout, as the robot got it (no look-ahead), in ``TRACK_COLUMNS``.
    ``add`` is called on the tracking thread and ``close`` / the properties on the GUI thread,
    hence the lock. After a write error ``add`` does nothing, ``error`` says why and the file
    keeps what reached the disk.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self._lock = threading.Lock()
        self._rows = 0
        self._saved = 0          # rows known to be on the disk (at the last successful flush)
        self._error = ""
        self._last_flush = time.monotonic()
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            # The file itself, not a temporary one: a crash of the program keeps the session.
            self._fh = RowFile(self.path, TRACK_COLUMNS, replace_at_close=False)
            self._fh.flush()
        except OSError as exc:
            raise RecordingError(f"cannot record: {describe_os_error(exc, self.path)}") from None

    @property
    def rows(self) -> int:
        """Rows handed to the file so far (those before an error)."""
        with self._lock:
            return self._rows

    @property
    def rows_saved(self) -> int:
        """Rows known to have reached the disk (all of them after a normal ``close``)."""
        with self._lock:
            return self._saved

    @property
    def error(self) -> str:
        """Why the recording stopped by itself ('' while it runs or after a normal close)."""
        with self._lock:
            return self._error

    @property
    def closed(self) -> bool:
        with self._lock:
            return self._fh is None

    def add(self, result) -> None:
        """Write ``result``'s row (the tracking thread; ≈ 10 µs, a disk write every 0.5 s)."""
        with self._lock:
            if self._fh is None:
                return
            try:
                self._fh.write_row(track_row(result))
                self._rows += 1
                now = time.monotonic()
                if now - self._last_flush >= FLUSH_EVERY_S:
                    self._last_flush = now
                    self._fh.flush()
                    self._saved = self._fh.rows_saved
            except OSError as exc:
                self._fail(exc)

    def close(self) -> None:
        """Flush and close (the GUI thread; idempotent). A failing flush is reported in ``error``."""
        with self._lock:
            if self._fh is None:
                return
            try:
                self._fh.close()
            except OSError as exc:
                self._fail(exc)
                return
            self._saved = self._fh.rows_saved
            self._fh = None

    def _fail(self, exc: OSError) -> None:
        # The RowFile has cut the file back to its last whole row and closed it.
        self._error = describe_os_error(exc, self.path)
        fh, self._fh = self._fh, None
        self._saved = fh.rows_saved
        fh.abort()

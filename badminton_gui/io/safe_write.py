"""Writing output files so that nothing the user had is lost: the one place every writer goes through.

Why this file exists: an output path that names an input (``track … -o LEFT.mp4``) used to
overwrite the recording and report success; a full disk left a torn last row that the readers
then took for data; a crash halfway through replaced a good file with half a file. Three rules
hold for every file the program writes, and they live here so each writer does not reinvent them:

* **An output never resolves to an input** (:func:`clashing_input`): compared by real path, so
  through symlinks, and by ``os.path.samefile`` when the output exists, so through hard links.
* **A whole file appears at once** (:func:`replacing`): it is written to a uniquely named
  temporary file in the target's own folder and renamed over the target (``os.replace``, atomic
  on POSIX and Windows) only when complete; on any failure the temporary file is removed. A
  symlink is written *through*: the link stays and the file it points to is replaced. A target
  that exists and is not a regular file (``/dev/stdout``, a FIFO, ``/dev/full``) is written
  directly, since it cannot be replaced by a rename.
* **A file written row by row ends at a whole row** (:class:`RowFile`): rows are buffered whole
  and written whole; when a write fails part-way (ENOSPC: the disk is full) the file is cut back
  to the end of the last complete row before the error is raised, so what is kept can be read.
"""

from __future__ import annotations

import csv
import errno
import io
import os
import stat
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Iterable, Iterator

# Rows are handed to the OS in blocks of about this size (whole rows only).
ROW_BUFFER_BYTES = 64 * 1024


def _real(path: str | os.PathLike) -> str:
    return os.path.realpath(os.path.abspath(os.fspath(path)))


def same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether two paths name the same file: the same real path (symlinks followed), or, when both
    exist, the same inode (hard links)."""
    if _real(a) == _real(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:   # one of them does not exist (yet): then only the real paths can tell
        return False


def clashing_input(output: str | os.PathLike,
                   inputs: Iterable[str | os.PathLike | None]) -> str | None:
    """The first of ``inputs`` that ``output`` would overwrite, or None (None inputs are skipped)."""
    for path in inputs:
        if path is not None and same_file(output, path):
            return os.fspath(path)
    return None


def write_target(path: str | os.PathLike) -> Path:
    """The file a write to ``path`` really replaces: a symlink's final target (the link is kept),
    else ``path`` itself."""
    return Path(_real(path)) if os.path.islink(path) else Path(path)


def _is_special(path: Path) -> bool:
    """An existing target that is not a regular file (a device, a FIFO): written in place."""
    try:
        return not stat.S_ISREG(os.stat(path).st_mode)
    except OSError:
        return False


def _umask() -> int:
    """The process's umask, read without changing it (``os.umask`` would, racing other threads)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    return 0o022


def _temporary_beside(target: Path, suffix: str = ".tmp") -> Path:
    # A rename would replace a file its owner made read-only: refuse it as opening it would.
    if target.exists() and not os.access(target, os.W_OK):
        raise PermissionError(errno.EACCES, "Permission denied", str(target))
    fd, name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=suffix, dir=target.parent)
    os.close(fd)
    return Path(name)


def _publish(temporary: Path, target: Path) -> None:
    """Rename ``temporary`` over ``target`` with the mode the target had (or a new file's mode:
    mkstemp creates files readable by their owner only)."""
    try:
        mode = stat.S_IMODE(os.stat(target).st_mode)
    except OSError:
        mode = 0o666 & ~_umask()
    os.chmod(temporary, mode)
    os.replace(temporary, target)


@contextmanager
def replacing(path: str | os.PathLike, suffix: str = ".tmp") -> Iterator[Path]:
    """``with replacing(out) as tmp: write(tmp)``: ``out`` gets the whole of ``tmp`` when the block
    ends without an exception, and is left as it was otherwise (no temporary file remains).
    The folder of ``out`` is created if missing. ``suffix``: the temporary file's ending (a video
    writer picks its container from it: ``.mp4``)."""
    target = write_target(path)
    if _is_special(target):
        yield target
        return
    target.parent.mkdir(parents=True, exist_ok=True)
    temporary = _temporary_beside(target, suffix)
    try:
        yield temporary
        _publish(temporary, target)
    finally:
        if temporary.exists():
            temporary.unlink()


class RowFile:
    """A CSV file written row by row that always ends at a whole row.

    ``replace_at_close=True`` (files made in one go: ``track``'s output): the rows go to a
    temporary file beside the target, renamed over it by :meth:`close`. ``False`` (a live
    recording that must survive a crash of the program): the target itself is written.
    A failing write (a full disk, a removed stick) cuts the file back to its last whole row,
    puts it in place (the rows before the failure are kept; nothing is replaced when not even
    the header was written whole), closes it and raises the ``OSError``; :attr:`rows_saved`
    says how many rows the file holds. Not thread-safe: one writer, or the caller's lock.
    """

    def __init__(self, path: str | os.PathLike, header: Iterable[str] | None = None, *,
                 replace_at_close: bool = True) -> None:
        self.path = Path(path)
        self._target = write_target(path)
        self._temporary: Path | None = None
        if replace_at_close and not _is_special(self._target):
            self._target.parent.mkdir(parents=True, exist_ok=True)
            self._temporary = _temporary_beside(self._target)
        try:
            # Unbuffered: this class buffers whole rows itself, so it knows what reached the file.
            self._fh = open(self._temporary or self._target, "wb", buffering=0)
        except BaseException:
            self._discard()
            raise
        self._text = io.StringIO()
        self._csv = csv.writer(self._text)
        self._pending = bytearray()
        self._row_ends: list[int] = []     # end offsets of the pending rows, in ``_pending``
        self._size = 0                     # bytes in the file, whole rows only
        self._lines = 0                    # lines in the file, the header included
        self._has_header = header is not None
        self.rows = 0                      # rows handed to write_row
        self.rows_saved = 0                # rows known to be in the file
        if header is not None:
            self._append(header)

    @property
    def closed(self) -> bool:
        return self._fh is None

    def write_row(self, row: Iterable) -> None:
        if self._fh is None:
            raise ValueError(f"{self.path} is closed")
        self._append(row)
        self.rows += 1
        if len(self._pending) >= ROW_BUFFER_BYTES:
            self.flush()

    def _append(self, row: Iterable) -> None:
        self._text.seek(0)
        self._text.truncate()
        self._csv.writerow(row)
        self._pending += self._text.getvalue().encode("utf-8")
        self._row_ends.append(len(self._pending))

    def flush(self) -> None:
        """Hand the pending rows to the OS (whole rows; on failure see the class docstring)."""
        if self._fh is None or not self._pending:
            return
        data = memoryview(bytes(self._pending))
        done = 0
        try:
            while done < len(data):
                written = self._fh.write(data[done:])
                if not written:
                    raise OSError(f"no progress writing {self._target}")
                done += written
        except OSError:
            self._fail(done)
            raise
        self._size += done
        self._saved(len(self._row_ends))
        self._pending.clear()
        self._row_ends.clear()

    def _saved(self, lines: int) -> None:
        """``lines`` more whole lines are in the file (the header is a line, not a row)."""
        self._lines += lines
        self.rows_saved = max(0, self._lines - (1 if self._has_header else 0))

    def _fail(self, written: int) -> None:
        """Cut the file back to the last row that was written whole, keep it, and close it."""
        whole = sum(1 for end in self._row_ends if end <= written)
        keep = self._row_ends[whole - 1] if whole else 0
        self._saved(whole)
        fh, self._fh = self._fh, None
        try:
            fh.truncate(self._size + keep)
        except OSError:
            pass   # the size cannot be set: nothing better to do than keep what is there
        try:
            fh.close()
        except OSError:
            pass
        self._pending.clear()
        self._row_ends.clear()
        if self._temporary is not None:
            if self._lines:   # (without a whole line, the target stays as it was)
                try:
                    _publish(self._temporary, self._target)
                except OSError:
                    pass
            self._discard()

    def close(self) -> None:
        """Write what is pending, close, and put the file in place (idempotent)."""
        if self._fh is None:
            return
        self.flush()
        fh, self._fh = self._fh, None
        try:
            if self._temporary is not None:
                os.fsync(fh.fileno())   # the rename must not publish a file still in the cache
            fh.close()
            if self._temporary is not None:
                _publish(self._temporary, self._target)
        finally:
            self._discard()

    def abort(self) -> None:
        """Close without putting a temporary file in place (the target stays as it was)."""
        fh, self._fh = self._fh, None
        if fh is not None:
            try:
                fh.close()
            except OSError:
                pass
        self._discard()

    def _discard(self) -> None:
        if self._temporary is not None:
            try:
                self._temporary.unlink()
            except FileNotFoundError:
                pass
            self._temporary = None

    def __enter__(self) -> "RowFile":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        # Also when the loop writing the rows failed (a decoding error, Ctrl-C): the rows written
        # so far are whole and are kept, as they were before this class existed.
        try:
            self.close()
        except OSError:
            if exc_type is None:
                raise

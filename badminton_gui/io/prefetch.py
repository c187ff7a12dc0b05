"""Decode ahead: a source read on a background thread into a short queue, order kept.

Why this file exists: processing a recorded rally (`badminton-track track`) decoded each pair
of 2048×1536 frames on the same thread that then tracked them, so a third of the wall time was
decoding with the tracker idle. FFmpeg's decoding releases the GIL, so a reader thread that
stays a few pairs ahead overlaps decoding with tracking. Every frame is delivered, in order
(this is for files, where nothing may be skipped; live cameras use the GUI worker's
newest-frame-wins instead), and a failure of the reader is raised from ``read()`` in the
caller's thread, where it would have been raised without the prefetch.
"""

from __future__ import annotations

import queue
import threading
from typing import Any

# Enough to ride out a slow frame (a key frame, a seek) without holding many large frames:
# 4 pairs of 2048×1536 BGR frames are 75 MB.
DEFAULT_DEPTH = 4
_END = object()


class PrefetchingReader:
    """Wraps anything with ``read()`` (None at the end) and ``close()``; reads it ahead.

    Attributes other than ``read`` / ``close`` (``image_size``, ``fps``, ``frame_count``, ``name``)
    are the wrapped source's.
    """

    def __init__(self, source: Any, depth: int = DEFAULT_DEPTH) -> None:
        self._source = source
        self._queue: queue.Queue = queue.Queue(maxsize=max(1, int(depth)))
        self._stop = threading.Event()
        self._finished = False
        self._thread = threading.Thread(target=self._run, name="prefetch", daemon=True)
        self._thread.start()

    def __getattr__(self, name: str) -> Any:
        # Only called for attributes this object lacks: the wrapped source answers.
        return getattr(self._source, name)

    def _put(self, item: Any) -> bool:
        """Queue an item unless asked to stop (never blocks for ever on a full queue)."""
        while not self._stop.is_set():
            try:
                self._queue.put(item, timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                item = self._source.read()
                if item is None:
                    break
                if not self._put(item):
                    return
        except BaseException as exc:   # handed to the reader's caller, raised there
            self._put(exc)
            return
        self._put(_END)

    def read(self) -> Any:
        """The next item, None at the end; re-raises the reader thread's error."""
        if self._finished:
            return None
        item = self._queue.get()
        if item is _END:
            self._finished = True
            return None
        if isinstance(item, BaseException):
            self._finished = True
            raise item
        return item

    def close(self) -> None:
        """Stop the reader thread, then close the wrapped source (from this thread)."""
        self._stop.set()
        try:
            while True:
                self._queue.get_nowait()
        except queue.Empty:
            pass
        self._thread.join()
        self._source.close()

"""Frame sources: one protocol for live cameras, video files and the synthetic demo court.

Why this file exists: the tracker, the GUI worker and the CLI never care where frames come from.
Every source delivers :class:`~badminton_gui.core.types.StereoFrame` from ``read()``
and returns None at the end; failures raise :class:`SourceError` with one clear sentence.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from ..core.types import StereoFrame


class SourceError(RuntimeError):
    """A source that cannot open or stopped delivering; the message is shown to the user."""


class OpeningCancelled(SourceError):
    """Opening a source was given up because the user asked for something else meanwhile."""


@runtime_checkable
class FrameSource(Protocol):
    """What the tracker worker reads from."""

    name: str                       # human-readable, for the status bar

    @property
    def image_size(self) -> tuple[int, int]:
        """(width, height) of each camera's frames."""
        ...

    @property
    def fps(self) -> float | None:
        """Nominal frame rate, or None when unknown (live cameras)."""
        ...

    def read(self) -> StereoFrame | None:
        """The next frame pair, or None when the source has ended."""
        ...

    def close(self) -> None:
        ...

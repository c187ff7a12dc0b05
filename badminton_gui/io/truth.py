"""Where a source's truth comes from, frame by frame: the demo court's geometry or label files.

Why this file exists: the GUI scores its live readout against the truth when the source has one
(core/evaluation.py ``LiveScore``), so an operator who moves a slider on a labelled recording
sees the accuracy that setting gives. A source that knows its truth carries a ``frame_truth``
attribute (an object of this module); the worker asks it for each frame pair it tracked. The
demo court knows the exact projection of its shuttle; a recorded pair may come with one
TrackNet-style label file per camera (``Frame,Visibility,X,Y``, as the NYCU recordings'
``CameraReader_*.csv``, which are their timestamp files too).
"""

from __future__ import annotations

from pathlib import Path

from ..core.evaluation import Label
from ..core.types import StereoFrame
from .labels import CsvFormatError, read_point_labels


class DemoTruth:
    """The demo court's exact truth: the shuttle's projection where it is visible."""

    name = "demo truth"

    def __init__(self, scene) -> None:
        self._scene = scene

    def for_frame(self, frame: StereoFrame) -> tuple[Label, Label]:
        truth = self._scene.truth(frame.index)
        out = []
        for visible, uv in ((truth.visible_left, truth.uv_left), (truth.visible_right, truth.uv_right)):
            out.append((True, float(uv[0]), float(uv[1])) if visible and uv is not None
                       else (False, 0.0, 0.0))
        return out[0], out[1]


class LabelTruth:
    """Each camera's label file, looked up by that camera's frame index."""

    name = "labels"

    def __init__(self, left: dict[int, Label], right: dict[int, Label]) -> None:
        self._left = left
        self._right = right

    @classmethod
    def read(cls, left_path: str | Path, right_path: str | Path) -> "LabelTruth":
        """Both cameras' label files; CsvFormatError names the file and what is wrong with it."""
        return cls(read_point_labels(left_path).as_dict(), read_point_labels(right_path).as_dict())

    def for_frame(self, frame: StereoFrame) -> tuple[Label | None, Label | None]:
        return self.for_indices(frame.index, frame.index_right)

    def mismatch(self, frame_count: int) -> str:
        """A sentence when the left labels' rows do not fit a video of ``frame_count`` frames
        (label files of another recording score garbage), else ''."""
        if frame_count <= 0 or not self._left:
            return ""
        rows = max(self._left) + 1
        if abs(rows - frame_count) <= max(10, 0.05 * frame_count):
            return ""
        return (f"the left labels have {rows:,} frames and the video {frame_count:,}: they may "
                f"belong to another recording, and the score against them would mean nothing")

    def for_indices(self, index: int, index_right: int = -1) -> tuple[Label | None, Label | None]:
        """The labels of left frame ``index`` and right frame ``index_right`` (-1: the same)."""
        return self._left.get(index), self._right.get(index_right if index_right >= 0 else index)


def has_label_columns(path: str | Path) -> bool:
    """Whether a CSV (a timestamp file, say) also carries per-frame labels."""
    try:
        read_point_labels(path)
    except (CsvFormatError, OSError, ValueError):
        return False
    return True

"""CSV formats: TrackNet labels (``Frame,Visibility,X,Y``), timestamp files, tracker output.

Why this file exists: labels, timestamps and predictions cross the boundary between our program
and other tools (TrackNet's evaluation, the NYCU recordings, a spreadsheet). Reading is strict
and every error names the file, the line and the column, so a malformed CSV is a clear message
rather than a traceback.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np


class CsvFormatError(ValueError):
    """A CSV file that does not have the expected columns or values."""


@dataclass(frozen=True, slots=True)
class PointLabels:
    """Per-frame 2D points of one camera: arrays indexed by position, with the frame numbers."""

    frames: np.ndarray      # (N,) int
    visible: np.ndarray     # (N,) bool
    xy: np.ndarray          # (N, 2) float, pixels (nan where not visible)

    def as_dict(self) -> dict[int, tuple[bool, float, float]]:
        return {int(f): (bool(v), float(x), float(y))
                for f, v, (x, y) in zip(self.frames, self.visible, self.xy)}


def _open_rows(path: str | Path, required: tuple[str, ...]) -> tuple[list[dict[str, str]], Path]:
    path = Path(path)
    if not path.is_file():
        raise CsvFormatError(f"CSV file not found: {path}")
    try:
        with path.open(newline="", encoding="utf-8-sig") as fh:
            reader = csv.DictReader(fh)
            if reader.fieldnames is None:
                raise CsvFormatError(f"{path} is empty: expected a header with {', '.join(required)}")
            names = [n.strip() for n in reader.fieldnames]
            missing = [c for c in required if c not in names]
            if missing:
                raise CsvFormatError(f"{path} lacks the column(s) {', '.join(missing)} "
                                     f"(header is: {','.join(names)})")
            rows = []
            for row in reader:
                rows.append({(k or "").strip(): (v or "").strip() for k, v in row.items()})
    except UnicodeDecodeError:
        raise CsvFormatError(f"{path} is not a text CSV file") from None
    return rows, path


def _number(path: Path, line: int, column: str, text: str, kind=float):
    try:
        value = kind(float(text)) if kind is int else kind(text)
    except (TypeError, ValueError):
        raise CsvFormatError(f"{path} line {line}: {column} is {text!r}, not a number") from None
    if isinstance(value, float) and math.isinf(value):
        raise CsvFormatError(f"{path} line {line}: {column} is infinite")
    return value


def read_point_labels(path: str | Path, frame_col: str = "Frame", vis_col: str = "Visibility",
                      x_col: str = "X", y_col: str = "Y") -> PointLabels:
    """TrackNet-style labels or predictions. Extra columns are ignored."""
    rows, path = _open_rows(path, (frame_col, vis_col, x_col, y_col))
    frames, vis, xy = [], [], []
    for n, row in enumerate(rows, start=2):
        f = _number(path, n, frame_col, row[frame_col], int)
        v_text = row[vis_col]
        v = _number(path, n, vis_col, v_text, int) if v_text != "" else 0
        if v and (row[x_col] == "" or row[y_col] == ""):
            raise CsvFormatError(f"{path} line {n}: visible but X or Y is empty")
        x = _number(path, n, x_col, row[x_col]) if row[x_col] != "" else math.nan
        y = _number(path, n, y_col, row[y_col]) if row[y_col] != "" else math.nan
        frames.append(f)
        vis.append(bool(v))
        xy.append((x, y) if v else (math.nan, math.nan))
    return PointLabels(np.asarray(frames, dtype=int), np.asarray(vis, dtype=bool),
                       np.asarray(xy, dtype=float).reshape(-1, 2))


def read_timestamps(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """(frames, timestamps) from any CSV with ``Frame`` and ``Timestamp`` columns (sorted by frame)."""
    rows, path = _open_rows(path, ("Frame", "Timestamp"))
    frames = np.array([_number(path, n, "Frame", r["Frame"], int) for n, r in enumerate(rows, 2)],
                      dtype=int)
    times = np.array([_number(path, n, "Timestamp", r["Timestamp"]) for n, r in enumerate(rows, 2)],
                     dtype=float)
    if len(frames) == 0:
        raise CsvFormatError(f"{path} has no rows")
    order = np.argsort(frames, kind="stable")
    frames, times = frames[order], times[order]
    if np.any(np.diff(frames) != 1) or frames[0] != 0:
        raise CsvFormatError(f"{path}: frames must run 0, 1, 2, … without gaps")
    if np.any(np.diff(times) < 0):
        raise CsvFormatError(f"{path}: timestamps go backwards")
    return frames, times


def write_point_labels(path: str | Path, frames, visible, xy) -> None:
    """Write ``Frame,Visibility,X,Y`` (pixels; 0,0 where not visible, as TrackNet does)."""
    with Path(path).open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["Frame", "Visibility", "X", "Y"])
        for f, v, (x, y) in zip(frames, visible, xy):
            if v:
                w.writerow([int(f), 1, f"{x:.2f}", f"{y:.2f}"])
            else:
                w.writerow([int(f), 0, "0.00", "0.00"])


TRACK_COLUMNS = ("Frame", "FrameR", "Timestamp", "VisL", "XL", "YL", "VisR", "XR", "YR",
                 "Vis3D", "X", "Y", "Z", "Distance", "Speed", "LandX", "LandY", "LandT")


def track_row(result) -> list[str]:
    """One row of `track` output for a TrackResult (empty cells where there is no value)."""
    def fmt(v, nd=4):
        return "" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.{nd}f}"

    dl, dr = result.left.detection, result.right.detection
    p = result.point
    pred = result.flight.prediction if result.flight is not None else None
    return [
        str(result.index), str(result.index_right), f"{result.timestamp:.6f}",
        "1" if dl else "0", fmt(dl.x if dl else None, 2), fmt(dl.y if dl else None, 2),
        "1" if dr else "0", fmt(dr.x if dr else None, 2), fmt(dr.y if dr else None, 2),
        "1" if p else "0", fmt(p[0] if p else None), fmt(p[1] if p else None),
        fmt(p[2] if p else None), fmt(result.distance), fmt(result.speed, 3),
        fmt(pred.x if pred else None), fmt(pred.y if pred else None),
        fmt(pred.t if pred else None),
    ]

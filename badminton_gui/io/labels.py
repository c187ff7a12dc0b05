"""CSV formats: TrackNet labels (``Frame,Visibility,X,Y``), timestamp files, tracker output.

Why this file exists: labels, timestamps and predictions cross the boundary between our program
and other tools (TrackNet's evaluation, the NYCU recordings, a spreadsheet). Reading is strict
and every error names the file, the line and the column, so a malformed CSV is a clear message
rather than a traceback.
"""

from __future__ import annotations

import csv
import io
import logging
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..core.frame_checks import MAX_TIMESTAMP

_log = logging.getLogger(__name__)


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


# The largest frame number a label or timestamp file may give: a day at 10 000 fps. A larger one
# is a corrupt or mistyped cell (a 20-digit number does not even fit the arrays it is read into).
MAX_FRAME = 10**9


def read_csv_rows(path: str | Path, required: tuple[str, ...]) -> tuple[list[tuple[int, dict[str, str]]], Path]:
    """The rows as (line number, {column: text}), after the checks every CSV here needs: the
    header has the ``required`` columns and no row has fewer cells than the header. A last row
    without a line break may have been cut off in the middle of a number: it is read, with a
    warning that says so."""
    path = Path(path)
    if not path.is_file():
        raise CsvFormatError(f"CSV file not found: {path}")
    try:
        with path.open(newline="", encoding="utf-8-sig") as fh:
            text = fh.read()
    except UnicodeDecodeError:
        raise CsvFormatError(f"{path} is not a text CSV file") from None
    reader = csv.reader(io.StringIO(text, newline=""))
    try:
        header = next(reader, None)
        if header is None or not any(h.strip() for h in header):
            raise CsvFormatError(f"{path} is empty: expected a header with {', '.join(required)}")
        names = [n.strip() for n in header]
        missing = [c for c in required if c not in names]
        if missing:
            shown = " ".join(",".join(names).split())
            shown = shown if len(shown) <= 80 else shown[:77] + "..."
            raise CsvFormatError(f"{path} lacks the column(s) {', '.join(missing)} "
                                 f"(header is: {shown})")
        rows = []
        for cells in reader:
            if not any(c.strip() for c in cells):
                continue                       # a blank line
            if len(cells) < len(names):
                raise CsvFormatError(
                    f"{path} line {reader.line_num} has {len(cells)} fields, the header {len(names)}: "
                    f"a torn row (was the file cut off?)")
            rows.append((reader.line_num, {n: c.strip() for n, c in zip(names, cells)}))
    except csv.Error as exc:
        raise CsvFormatError(f"{path} line {reader.line_num}: {exc}") from None
    if rows and not text.endswith(("\n", "\r")):
        _log.warning("%s line %d, the last, does not end with a line break: if the file was cut off "
                     "there, that row's last value may be incomplete", path, rows[-1][0])
    return rows, path


def parse_number(path: Path, line: int, column: str, text: str, kind=float):
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise CsvFormatError(f"{path} line {line}: {column} is {text!r}, not a number") from None
    if not math.isfinite(value):
        raise CsvFormatError(f"{path} line {line}: {column} is {text!r}, not a finite number")
    if kind is int:
        if value != int(value):
            raise CsvFormatError(f"{path} line {line}: {column} is {text!r}, not a whole number")
        return int(value)
    return value


def _frame_number(path: Path, line: int, column: str, text: str) -> int:
    frame = parse_number(path, line, column, text, int)
    if not 0 <= frame <= MAX_FRAME:
        raise CsvFormatError(f"{path} line {line}: {column} is {text!r}, not a frame number "
                             f"(0 to {MAX_FRAME})")
    return frame


def read_point_labels(path: str | Path, frame_col: str = "Frame", vis_col: str = "Visibility",
                      x_col: str = "X", y_col: str = "Y", unique: bool = True) -> PointLabels:
    """TrackNet-style labels or predictions. Extra columns are ignored.

    ``unique``: a frame number given twice is refused, with the numbers (which row would be
    meant?); `track` output, whose steps may repeat a camera's frame, is read with False."""
    rows, path = read_csv_rows(path, (frame_col, vis_col, x_col, y_col))
    frames, vis, xy = [], [], []
    for n, row in rows:
        f = _frame_number(path, n, frame_col, row[frame_col])
        v_text = row[vis_col]
        v = parse_number(path, n, vis_col, v_text, int) if v_text != "" else 0
        if v and (row[x_col] == "" or row[y_col] == ""):
            raise CsvFormatError(f"{path} line {n}: visible but X or Y is empty")
        x = parse_number(path, n, x_col, row[x_col]) if row[x_col] != "" else math.nan
        y = parse_number(path, n, y_col, row[y_col]) if row[y_col] != "" else math.nan
        frames.append(f)
        vis.append(bool(v))
        xy.append((x, y) if v else (math.nan, math.nan))
    frames_arr = np.asarray(frames, dtype=np.int64)
    if unique and len(frames_arr):
        values, counts = np.unique(frames_arr, return_counts=True)
        repeated = values[counts > 1]
        if len(repeated):
            shown = ", ".join(map(str, repeated[:10].tolist())) + (", …" if len(repeated) > 10 else "")
            raise CsvFormatError(f"{path} gives {len(repeated)} frame number(s) more than once "
                                 f"({shown}): which row is meant?")
    return PointLabels(frames_arr, np.asarray(vis, dtype=bool),
                       np.asarray(xy, dtype=float).reshape(-1, 2))


def read_timestamps(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """(frames, timestamps) from any CSV with ``Frame`` and ``Timestamp`` columns (sorted by frame).

    The timestamps are seconds, finite, and never go back. Equal neighbours (a clock that
    stalled) are allowed here; ``VideoPair`` marks the frames they time. A file whose every
    timestamp is the same times nothing and is refused."""
    rows, path = read_csv_rows(path, ("Frame", "Timestamp"))
    frames = np.array([_frame_number(path, n, "Frame", r["Frame"]) for n, r in rows], dtype=np.int64)
    times = np.array([parse_number(path, n, "Timestamp", r["Timestamp"]) for n, r in rows], dtype=float)
    if len(frames) == 0:
        raise CsvFormatError(f"{path} has no rows")
    big = np.flatnonzero(np.abs(times) > MAX_TIMESTAMP)
    if len(big):
        raise CsvFormatError(f"{path} line {rows[big[0]][0]}: Timestamp is {times[big[0]]:g}, beyond "
                             f"±{MAX_TIMESTAMP:g} s: timestamps must be seconds")
    order = np.argsort(frames, kind="stable")
    frames, times = frames[order], times[order]
    lines = np.asarray([n for n, _ in rows])[order]
    if np.any(np.diff(frames) != 1) or frames[0] != 0:
        raise CsvFormatError(f"{path}: frames must run 0, 1, 2, … without gaps")
    back = np.flatnonzero(np.diff(times) < 0)
    if len(back):
        k = back[0] + 1
        raise CsvFormatError(f"{path} line {lines[k]}: timestamps go backwards "
                             f"({float(times[k - 1])!r} then {float(times[k])!r} s)")
    if len(times) > 1 and times[0] == times[-1]:
        raise CsvFormatError(f"{path}: all {len(times)} timestamps are {float(times[0])!r} s: the file does "
                             f"not time its frames")
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


# ``withheld_reason`` is last so readers of the earlier columns keep working: why the row's 3D
# cells are empty although both cameras may have a detection ('' when nothing was withheld).
TRACK_COLUMNS = ("Frame", "FrameR", "Timestamp", "VisL", "XL", "YL", "VisR", "XR", "YR",
                 "Vis3D", "X", "Y", "Z", "Distance", "Speed", "LandX", "LandY", "LandT",
                 "withheld_reason")


def track_row(result, withheld: str = "") -> list[str]:
    """One row of `track` output for a TrackResult (empty cells where there is no value).
    ``withheld``: the reason its 3D point, distance, speed and landing are not to be trusted
    (a stalled clock, a pair with no partner frame): those cells stay empty."""
    def fmt(v, nd=4):
        return "" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.{nd}f}"

    dl, dr = result.left.detection, result.right.detection
    p = None if withheld else result.point
    pred = result.flight.prediction if result.flight is not None and not withheld else None
    return [
        str(result.index), str(result.index_right), f"{result.timestamp:.6f}",
        "1" if dl else "0", fmt(dl.x if dl else None, 2), fmt(dl.y if dl else None, 2),
        "1" if dr else "0", fmt(dr.x if dr else None, 2), fmt(dr.y if dr else None, 2),
        "1" if p else "0", fmt(p[0] if p else None), fmt(p[1] if p else None),
        fmt(p[2] if p else None), fmt(None if withheld else result.distance),
        fmt(None if withheld else result.speed, 3),
        fmt(pred.x if pred else None), fmt(pred.y if pred else None),
        fmt(pred.t if pred else None), withheld,
    ]

"""Writing a clip with the tracking drawn on it: one camera, or both side by side, with the
readouts and the court plan under them when the track has 3D.

Why this file exists: users of TrackNet-style tools check a track by watching it, and share it
as a video. `badminton-track render` and the GUI's *Export video…* both call
:func:`render_video` (drawing in core/overlay_draw.py, no Qt), from a CSV that `track` or
`detect` wrote earlier, or from one they write now (:func:`track_for_render`,
:func:`detect_for_render`: the very loops of those commands, so the clip shows the rows the
commands give). The frames to show come from the CSV's own ``Frame``/``FrameR`` columns, so a
pair tracked by timestamps is shown paired the same way without the timestamp files.

The clip is written to a hidden temporary file beside the output and renamed when complete:
nothing half-written ever carries the output's name, and a failure, a Cancel or Ctrl-C removes
the temporary file. OpenCV's wheels encode MPEG-4 Part 2 (``mp4v``) into MP4; H.264 is not
in them.
"""

from __future__ import annotations

import math
import os
import secrets
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

import cv2
import numpy as np

from ..core.overlay_draw import (OverlayHistory, ShuttleStep, draw_feed, draw_plan, draw_readouts,
                                 feed_caption, plan_size)
from .safe_write import clashing_input
from .labels import TRACK_COLUMNS, CsvFormatError, parse_number, read_csv_rows, read_point_labels
from .prefetch import PrefetchingReader
from .sources import SourceError
from .track_log import describe_os_error
from .video import VideoFile

# The stages ``progress(stage, done, total)`` reports besides those of io/detect_file.py.
TRACKING, RENDERING = "tracking", "rendering"
CAMERA_NAMES = ("Left", "Right")
# How far outside the picture a CSV's point may lie before the CSV is taken for another
# video's (a share of the width / height): coasted positions may leave the frame a little.
_OUTSIDE_TOLERANCE = 0.1


class RenderError(ValueError):
    """Input that cannot be rendered or an output that cannot be written; one sentence."""


@dataclass(frozen=True)
class RenderTrack:
    """A track to draw: its steps, whether it has a second camera and 3D, and from where."""

    steps: tuple[ShuttleStep, ...]
    stereo: bool             # a `track` CSV (both cameras' columns); else `detect`'s, one camera
    source: str              # the CSV's name, for messages

    @property
    def has_3d(self) -> bool:
        return any(s.point is not None for s in self.steps)

    @property
    def has_landing(self) -> bool:
        return any(s.landing is not None for s in self.steps)


@dataclass(frozen=True)
class RenderSummary:
    frames: int              # frames written
    seconds: float           # wall time of the rendering pass
    output: Path
    cancelled: bool          # stopped by ``should_stop``: nothing was written
    size: tuple[int, int]    # the clip's width, height
    fps: float
    video_frames: int = 0    # frames of the (first) video, 0 when unknown

    @property
    def frames_per_second(self) -> float:
        return self.frames / self.seconds if self.seconds > 0 else 0.0


# ---- reading a track --------------------------------------------------------------------------

def read_render_csv(path: str | Path, fps: float) -> RenderTrack:
    """A `track` CSV (``Frame,FrameR,Timestamp,VisL,…``) or a `detect` CSV
    (``Frame,Visibility,X,Y``, timed at ``fps``), told apart by their header."""
    path = Path(path)
    if not path.is_file():
        raise RenderError(f"CSV file not found: {path}")
    with path.open(newline="", encoding="utf-8-sig", errors="replace") as fh:
        header = {name.strip() for name in fh.readline().split(",")}
    if "VisL" in header:
        return _read_track_csv(path)
    labels = read_point_labels(path)
    steps = tuple(ShuttleStep(int(f), -1, int(f) / fps, (float(x), float(y)) if v else None)
                  for f, v, (x, y) in zip(labels.frames, labels.visible, labels.xy))
    if not steps:
        raise RenderError(f"{path} has no rows")
    return RenderTrack(steps, False, path.name)


def _read_track_csv(path: Path) -> RenderTrack:
    # withheld_reason is optional: tracks written before it existed render as they are.
    rows, path = read_csv_rows(path, tuple(c for c in TRACK_COLUMNS if c != "withheld_reason"))

    def value(line: int, row: dict, column: str, kind=float):
        text = row[column]
        return None if text == "" else parse_number(path, line, column, text, kind)

    steps = []
    for line, row in rows:
        xy = {}
        for side in ("L", "R"):
            seen = value(line, row, f"Vis{side}", int)
            x, y = value(line, row, f"X{side}"), value(line, row, f"Y{side}")
            if seen and (x is None or y is None):
                raise CsvFormatError(f"{path} line {line}: Vis{side} is 1 but X{side} or Y{side} is empty")
            xy[side] = (x, y) if seen else None
        point = None
        if value(line, row, "Vis3D", int):
            point = tuple(value(line, row, c) for c in ("X", "Y", "Z"))
            if None in point:
                raise CsvFormatError(f"{path} line {line}: Vis3D is 1 but X, Y or Z is empty")
        land = tuple(value(line, row, c) for c in ("LandX", "LandY", "LandT"))
        steps.append(ShuttleStep(
            value(line, row, "Frame", int), value(line, row, "FrameR", int),
            value(line, row, "Timestamp") or 0.0, xy["L"], xy["R"], point,
            value(line, row, "Distance"), value(line, row, "Speed"),
            None if None in land else land))
    if not steps:
        raise RenderError(f"{path} has no rows")
    return RenderTrack(tuple(steps), True, path.name)


def track_for_render(source, rig, params, *, max_frames: int | None = None,
                     progress: Callable[[str, int, int], None] | None = None,
                     should_stop: Callable[[], bool] | None = None, total: int = 0) -> RenderTrack | None:
    """Track a video pair now (io/track_file.py, `track`'s loop) into a temporary CSV and read it
    back; None when ``should_stop`` stopped it. The source is not closed here."""
    from .track_file import track_to_csv
    with _temporary_csv() as csv_path:
        summary = track_to_csv(source, rig, params, csv_path, max_frames=max_frames,
                               progress=None if progress is None else (lambda n: progress(TRACKING, n, total)),
                               should_stop=should_stop)
        if summary.cancelled or (should_stop is not None and should_stop()):
            return None
        if summary.pairs == 0:
            raise RenderError("the videos hold no frames")
        return _read_track_csv(Path(csv_path))


def detect_for_render(video: str | Path, params, *, fps: float,
                      progress: Callable[[str, int, int], None] | None = None,
                      should_stop: Callable[[], bool] | None = None) -> RenderTrack | None:
    """Detect in one video now (io/detect_file.py, `detect`'s loop, with its adaptation pass when
    the parameters ask for one) and read the rows back; None when ``should_stop`` stopped it."""
    from .detect_file import detect_to_csv
    with _temporary_csv() as csv_path:
        summary = detect_to_csv(video, params, csv_path, progress=progress, should_stop=should_stop)
        if summary.cancelled or (should_stop is not None and should_stop()):
            return None
        return read_render_csv(csv_path, fps)


class _temporary_csv:
    """A temporary CSV path, removed on exit whatever happened."""

    def __enter__(self) -> str:
        fd, self.path = tempfile.mkstemp(prefix="badminton-render-", suffix=".csv")
        os.close(fd)
        return self.path

    def __exit__(self, *exc) -> None:
        try:
            os.unlink(self.path)
        except FileNotFoundError:
            pass


# ---- checking the inputs ------------------------------------------------------------------------

def check_output_path(output: str | Path, inputs: Sequence[str | Path | None]) -> Path:
    """The output as a Path, or a RenderError: it must be an .mp4 that is none of the inputs (its
    folder is made when the clip is written, as `track` makes its CSV's)."""
    out = Path(output)
    if out.suffix.lower() != ".mp4":
        raise RenderError(f"the output {out} must end in .mp4 (the clip is an MP4 file)")
    if out.is_dir():
        raise RenderError(f"the output {out} is a folder")
    clash = clashing_input(out, [given or None for given in inputs])
    if clash is not None:
        raise RenderError(f"the output {out} is one of the inputs ({clash}): choose another file name")
    return out


def _check_matches(track: RenderTrack, camera: int, video: VideoFile) -> None:
    """A RenderError when the CSV cannot be this video's: frames past its end, or points far
    outside its picture."""
    name = CAMERA_NAMES[camera].lower()
    indices = [s.index if camera == 0 else s.index_right for s in track.steps]
    last = max(indices)
    if video.frame_count > 0 and last >= video.frame_count:
        raise RenderError(f"{track.source} goes to frame {last} of the {name} camera but "
                          f"{video.path.name} has {video.frame_count} frames: the CSV is of another video")
    if min(indices) < 0:
        raise RenderError(f"{track.source} has no {name}-camera frames (FrameR is -1): "
                          f"render the other camera")
    w, h = video.width, video.height
    tol_w, tol_h = _OUTSIDE_TOLERANCE * w, _OUTSIDE_TOLERANCE * h
    for s in track.steps:
        xy = s.left if camera == 0 else s.right
        if xy is not None and not (-tol_w <= xy[0] <= w + tol_w and -tol_h <= xy[1] <= h + tol_h):
            raise RenderError(f"{track.source} puts the shuttle at ({xy[0]:.0f}, {xy[1]:.0f}) px in "
                              f"{name} frame {s.index if camera == 0 else s.index_right} but "
                              f"{video.path.name} is {w}×{h}: the CSV is of another video")


# ---- the layout -------------------------------------------------------------------------------

def _even(v: float) -> int:
    return max(2, int(round(v / 2.0)) * 2)


@dataclass(frozen=True)
class RenderLayout:
    """Where everything goes in a clip's frame: the feeds side by side, the strip of readouts
    (and the court plan at its right when the 3D is in court coordinates) under them."""

    feed_size: tuple[int, int]      # one camera's picture in the clip
    cameras: tuple[int, ...]        # (0,), (1,) or (0, 1): left / right / both
    strip_height: int               # 0: no readouts (no 3D)
    plan: bool                      # the court plan in the strip

    @property
    def size(self) -> tuple[int, int]:
        w, h = self.feed_size
        return w * len(self.cameras), h + self.strip_height

    @staticmethod
    def make(video_size: tuple[int, int], cameras: tuple[int, ...], has_3d: bool, court_frame: bool,
             scale: float | None = None, width: int | None = None) -> "RenderLayout":
        """``scale`` (of the video's size) or ``width`` (of one feed, px) sizes the feeds;
        sizes are rounded to even pixels (what MPEG-4 needs)."""
        vw, vh = video_size
        k = width / vw if width else (scale or 1.0)
        feed = (_even(vw * k), _even(vh * k))
        strip = _even(max(120.0, 0.28 * feed[1])) if has_3d else 0
        return RenderLayout(feed, cameras, strip, has_3d and court_frame)


def compose_frame(layout: RenderLayout, frames: dict[int, np.ndarray], step: ShuttleStep,
                  history: OverlayHistory, doubles: bool = True) -> np.ndarray:
    """One frame of the clip: each camera's picture (full resolution, BGR) shrunk to the layout
    with its overlays, and the strip under them. ``history`` has seen ``step`` already."""
    w, h = layout.feed_size
    out = np.empty((layout.size[1], layout.size[0], 3), np.uint8)
    for slot, cam in enumerate(layout.cameras):
        frame = frames[cam]
        fh, fw = frame.shape[:2]
        feed = cv2.resize(frame, (w, h), interpolation=cv2.INTER_AREA if w < fw else cv2.INTER_LINEAR)
        shuttle = step.left if cam == 0 else step.right
        index = step.index if cam == 0 else step.index_right
        name = CAMERA_NAMES[cam] if step.index_right >= 0 else "Video"    # -1: one camera's track
        draw_feed(feed, w / fw, shuttle, history.trail(cam), feed_caption(name, step, index, shuttle is not None))
        out[:h, slot * w:(slot + 1) * w] = feed
    if layout.strip_height:
        sh = layout.strip_height
        total_w = layout.size[0]
        plan_w = min(plan_size(sh)[0], total_w // 2) if layout.plan else 0
        out[h:, :total_w - plan_w] = draw_readouts(total_w - plan_w, sh, step, doubles)
        if plan_w:
            plan = draw_plan(sh, step, history.flight(), doubles)
            out[h:, total_w - plan_w:] = plan[:, :plan_w]
    return out


# ---- writing ------------------------------------------------------------------------------------

class AtomicVideoWriter:
    """An mp4v writer into a hidden temporary file beside ``output``, renamed onto it by
    :meth:`commit`; :meth:`discard` (or any exception inside a ``with``) removes it."""

    def __init__(self, output: Path, fps: float, size: tuple[int, int]) -> None:
        self.output = output
        try:
            output.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise RenderError(f"cannot write the clip: {describe_os_error(exc, output)}") from None
        # Named here, created by the encoder: a file made by mkstemp would keep mode 0600.
        self.temporary = output.with_name(f".{output.stem}.{secrets.token_hex(4)}.partial.mp4")
        self._writer = cv2.VideoWriter(str(self.temporary), cv2.VideoWriter_fourcc(*"mp4v"), fps, size)
        if not self._writer.isOpened():
            self.discard()
            raise RenderError(f"cannot write the clip {output}: OpenCV's mp4v encoder did not open "
                              f"({size[0]}×{size[1]} at {fps:g} fps; is the folder writable?)")

    def write(self, frame: np.ndarray) -> None:
        self._writer.write(frame)

    def commit(self) -> None:
        self._writer.release()
        try:
            if self.temporary.stat().st_size == 0:
                raise RenderError(f"cannot write the clip {self.output}: the encoder wrote nothing "
                                  f"(disk full?)")
            os.replace(self.temporary, self.output)
        except OSError as exc:
            self.discard()
            raise RenderError(f"cannot write the clip: {describe_os_error(exc, self.output)}") from None
        except RenderError:
            self.discard()
            raise

    def discard(self) -> None:
        self._writer.release()
        try:
            self.temporary.unlink()
        except FileNotFoundError:
            pass

    def __enter__(self) -> "AtomicVideoWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is not None:
            self.discard()


class _FrameCursor:
    """One video read forward to the frame indices a track asks for (they never go back),
    decoded ahead on a reader thread (io/prefetch.py): FFmpeg releases the GIL, so decoding
    overlaps the drawing and the encoding instead of taking turns with them."""

    def __init__(self, video: VideoFile, name: str) -> None:
        self.name, self.file_name = name, video.path.name
        self.reader = PrefetchingReader(video)
        self.index, self.frame = -1, None

    def at(self, index: int) -> np.ndarray:
        if index < self.index:
            raise RenderError(f"the CSV's {self.name} frames go back from {self.index} to {index}: "
                              f"it is not one track in time order")
        while self.index < index:
            frame = self.reader.read()
            if frame is None:
                raise RenderError(f"{self.file_name} ended before frame {index}, which the CSV "
                                  f"shows: the CSV is of another video (or the video is truncated)")
            self.index, self.frame = self.index + 1, frame
        return self.frame

    def close(self) -> None:
        self.reader.close()


def shown_steps(track: RenderTrack, cameras: tuple[int, ...]) -> list[int]:
    """The positions of the steps that become frames of the clip: every step for both cameras
    (a pair, or a right frame no left frame was paired with); for one camera, the first step of
    each of its frames."""
    if len(cameras) == 2:
        return list(range(len(track.steps)))
    cam = cameras[0]
    keep, last = [], None
    for k, s in enumerate(track.steps):
        index = s.index if cam == 0 else s.index_right
        if index != last:
            keep.append(k)
            last = index
    return keep


def render_video(track: RenderTrack, videos: dict[int, str | Path], output: str | Path, *,
                 cameras: tuple[int, ...], fps: float | None = None, scale: float | None = None,
                 width: int | None = None, court_frame: bool = True, doubles: bool = True,
                 max_frames: int | None = None,
                 progress: Callable[[str, int, int], None] | None = None,
                 should_stop: Callable[[], bool] | None = None) -> RenderSummary:
    """Write the clip of ``track`` on ``videos`` (camera 0 / 1 → file) showing ``cameras``.

    ``fps``: the clip's rate (default: the first video's); ``scale`` or ``width`` (one feed's
    width, px) keep the file small; ``court_frame``: the track's 3D is in court coordinates, so
    the court plan is drawn. ``progress(RENDERING, frames written, frames in all)`` after each
    frame; ``should_stop()`` before each: then nothing is left on disk and the summary says
    ``cancelled``. Raises RenderError / SourceError / CsvFormatError with one sentence."""
    if not cameras or any(c not in videos for c in cameras):
        raise RenderError("no video for the camera to render")
    if len(cameras) == 2 and not track.stereo:
        raise RenderError(f"{track.source} is one camera's detections: render one camera")
    if scale is not None and not 0.05 <= scale <= 4.0:
        raise RenderError(f"the scale must be between 0.05 and 4, got {scale:g}")
    if width is not None and not 64 <= width <= 8192:
        raise RenderError(f"the width must be between 64 and 8192 px, got {width}")
    if fps is not None and not (math.isfinite(fps) and 0 < fps <= 1000):
        raise RenderError(f"the frame rate must be between 0 and 1000 fps, got {fps:g}")
    out = check_output_path(output, list(videos.values()))
    opened: dict[int, VideoFile] = {}
    try:
        for cam in cameras:
            opened[cam] = VideoFile(videos[cam])
        sizes = {(v.width, v.height) for v in opened.values()}
        if len(sizes) > 1:
            raise RenderError("the two videos differ in size: they are not a stereo pair")
        for cam, video in opened.items():
            _check_matches(track, cam, video)
        first = opened[cameras[0]]
        clip_fps = fps or first.fps
        layout = RenderLayout.make((first.width, first.height), cameras, track.stereo and track.has_3d,
                                   court_frame, scale, width)
        return _write(track, opened, out, layout, clip_fps, doubles, max_frames, progress, should_stop,
                      first.frame_count)
    finally:
        for video in opened.values():
            video.close()


def _write(track, opened, out, layout, fps, doubles, max_frames, progress, should_stop,
           video_frames) -> RenderSummary:
    cursors = {cam: _FrameCursor(v, CAMERA_NAMES[cam].lower()) for cam, v in opened.items()}
    try:
        return _write_frames(track, cursors, out, layout, fps, doubles, max_frames, progress,
                             should_stop, video_frames)
    finally:
        for cursor in cursors.values():
            cursor.close()


def _write_frames(track, cursors, out, layout, fps, doubles, max_frames, progress, should_stop,
                  video_frames) -> RenderSummary:
    shown = shown_steps(track, layout.cameras)
    if max_frames:
        shown = shown[:max_frames]
    total = len(shown)
    history = OverlayHistory()
    start = time.perf_counter()
    written = 0
    with AtomicVideoWriter(out, fps, layout.size) as writer:
        k_next = 0
        for pos in shown:
            if should_stop is not None and should_stop():
                writer.discard()
                return RenderSummary(written, time.perf_counter() - start, out, True, layout.size, fps,
                                     video_frames)
            # Every step up to this one feeds the trails, shown or not (the window's trail has
            # the right camera's detections of the steps a left-only clip skips).
            while k_next <= pos:
                history.push(track.steps[k_next])
                k_next += 1
            step = track.steps[pos]
            frames = {cam: cursors[cam].at(step.index if cam == 0 else step.index_right)
                      for cam in layout.cameras}
            writer.write(compose_frame(layout, frames, step, history, doubles))
            written += 1
            if progress is not None:
                progress(RENDERING, written, total)
        writer.commit()
    return RenderSummary(written, time.perf_counter() - start, out, False, layout.size, fps, video_frames)

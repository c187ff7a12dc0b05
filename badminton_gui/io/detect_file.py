"""Detecting the shuttle in one camera's recorded video into a CSV file: the one loop behind
`badminton-track detect` and the GUI's *Tools ▸ Process a recording…* for a single video.

Why this file exists: a TV clip gets its best readout only from a file — the look-ahead with the
lead-in from the held shuttle (core/lookahead.py), and when asked the classifier adapted to the
recording in a first pass (core/adaptation.py) — and the operator in the desktop tool must get the same
rows as the command line. So both call :func:`detect_to_csv`, which adds what a long job needs in
either: progress per pass, cancellation between two frames (the rows decided so far are written
and the file stays a valid CSV), the score against labels when there are any, and one-sentence
errors for a file that cannot be written (a full disk). No Qt here.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ..core.adaptation import DEFAULT_MIN_RUN, adapt_to_recording
from ..core.detector import CameraDetector
from ..core.evaluation import LiveScore, Outcomes
from ..core.lookahead import CameraLookahead
from ..core.params import TrackerParams
from .labels import write_point_labels
from .prefetch import PrefetchingReader
from .safe_write import replacing
from .sources import SourceError
from .track_log import describe_os_error
from .video import VideoFile

# The passes ``progress`` reports: the adaptation's first pass, then the detection.
ADAPTING, DETECTING = "adapting", "detecting"


class DetectFileError(OSError):
    """The output cannot be written; the message is one sentence for the user."""


@dataclass(frozen=True)
class DetectFileSummary:
    frames: int             # frames detected (rows written)
    found: int              # rows with the shuttle
    seconds: float          # wall time of both passes, decoding included
    output: Path
    cancelled: bool         # stopped by ``should_stop`` (the rows so far are in the file)
    adapt_asked: bool = False   # a first pass was to adapt the classifier (``adaptation_asked``)
    adapted: bool = False   # ... and did (a run of detections was long enough)
    adapted_runs: int = 0   # the runs of detections it learnt from, and their frames
    adapted_frames: int = 0
    adapt_seconds: float = 0.0
    lead_in: int = 0        # frames the lead-in took (core/lookahead.py), and of them those
    lead_in_over: int = 0   # that replaced a shorter track's report
    lead_in_run: int = 0
    gap_fill: int = 0       # frames the gap fill took (core/lookahead.py)
    frame_count: int = 0    # the frames the video's header announced (0: unknown)
    score: Outcomes | None = None   # against the labels given, None without

    @property
    def frames_per_second(self) -> float:
        return self.frames / self.seconds if self.seconds > 0 else 0.0

    @property
    def found_share(self) -> float:
        return 100.0 * self.found / self.frames if self.frames else 0.0

    @property
    def truncated(self) -> bool:
        """The video ended well before its announced frame count (a cut-off file)."""
        return not self.cancelled and bool(self.frame_count) and self.frames < self.frame_count - 1

    @property
    def adaptation_text(self) -> str:
        """What the first pass did, one sentence ('' when adaptation was not asked for)."""
        if self.adapted:
            return (f"adapted to the recording: {self.adapted_runs} runs, {self.adapted_frames} frames "
                    f"({self.adapt_seconds:.1f} s)")
        return ("adaptation: no run of detections long enough; the preset's classifier is kept"
                if self.adapt_asked else "")

    @property
    def lead_in_text(self) -> str:
        if not self.lead_in and not self.gap_fill:
            return ""
        over = f", {self.lead_in_over} of them in place of a shorter track's report" if self.lead_in_over else ""
        gaps = f"; {self.gap_fill} frames taken in short gaps between detections" if self.gap_fill else ""
        return (f"lead-in: {self.lead_in} frames taken before runs of {self.lead_in_run} detections "
                f"(the shuttle held before a serve){over}{gaps}")

    @property
    def score_text(self) -> str:
        """'against the labels: 92.43 % (F1 95.12)' or '' without labels."""
        if self.score is None or not self.score.total:
            return ""
        return f"against the labels: {100 * self.score.accuracy:.2f} % (F1 {100 * self.score.f1:.2f})"


def adaptation_asked(params: TrackerParams, adapt: bool | None) -> bool:
    """Whether the classifier is adapted first: ``adapt`` when given, else the preset's
    ``classifier.adapt_min_run`` — never for the live readout (look-ahead 0), which the GUI's
    live view gives and which keeps the shipped classifier."""
    if adapt is not None:
        return adapt
    return params.classifier.adapt_min_run > 0 and params.lookahead.frames > 0


def detect_to_csv(video: str | Path, params: TrackerParams, output: str | Path, *,
                  adapt: bool | None = None, labels: dict | None = None,
                  progress: Callable[[str, int, int], None] | None = None,
                  should_stop: Callable[[], bool] | None = None) -> DetectFileSummary:
    """Detect the shuttle in every frame of ``video`` and write ``Frame,Visibility,X,Y`` rows.

    ``adapt`` (see :func:`adaptation_asked`): a first pass over the video adapts the classifier
    to it. ``labels``: frame → (visible, x, y), to score the rows (core/evaluation.py). ``progress(pass,
    frames done, frames in all or 0)`` is called per frame; ``should_stop()`` is asked before
    each: in the first pass it abandons the adaptation and writes nothing, in the second the
    look-ahead's pending rows are decided and written and the summary says ``cancelled``.
    Raises the sources' errors for an unreadable video, :class:`DetectFileError` for the output.
    """
    stop = should_stop or (lambda: False)
    out_path = Path(output)
    start = time.perf_counter()
    classifier, harvest, adapt_seconds = None, None, 0.0
    asked = adaptation_asked(params, adapt)
    if asked:
        if params.classifier.adapt_min_run <= 0:   # asked for under a preset that has it off
            params = params.with_value("classifier.adapt_min_run", DEFAULT_MIN_RUN)
        classifier, harvest = adapt_to_recording(params, lambda: _frames(video, ADAPTING, progress),
                                                 should_stop=stop)
        adapt_seconds = time.perf_counter() - start
        if stop():
            return DetectFileSummary(0, 0, time.perf_counter() - start, out_path, True, adapt_asked=True)
    source = PrefetchingReader(VideoFile(video))   # decoded ahead on a reader thread
    detector = CameraDetector(params)
    if classifier is not None:
        detector.use_classifier(classifier)
    lookahead = CameraLookahead(params)
    score = LiveScore(source.width) if labels is not None else None
    visible: list[bool] = []
    xy: list[tuple[float, float]] = []

    def emit(results) -> None:
        for res in results:
            d = res.detection
            if score is not None:
                score.add(0, d, labels.get(len(visible)))
            visible.append(d is not None)
            xy.append((d.x, d.y) if d is not None else (0.0, 0.0))

    total = int(source.frame_count or 0)
    cancelled = False
    n = 0
    try:
        while True:
            if stop():
                cancelled = True
                break
            frame = source.read()
            if frame is None:
                break
            emit(lookahead.push(detector.process(frame, n / source.fps, keep_mask=False), n / source.fps))
            n += 1
            if progress is not None:
                progress(DETECTING, n, total)
        emit(lookahead.flush())
    finally:
        source.close()
    if n == 0 and not cancelled:
        raise SourceError(f"{video} holds no frames")
    try:
        with replacing(out_path) as whole_file:   # the file appears whole, or not at all
            write_point_labels(whole_file, range(len(visible)), visible, xy)
    except OSError as exc:
        raise DetectFileError(f"cannot write the detections: {describe_os_error(exc, out_path)}") from None
    return DetectFileSummary(
        n, sum(visible), time.perf_counter() - start, out_path, cancelled,
        adapt_asked=asked, adapted=classifier is not None,
        adapted_runs=harvest.runs if classifier is not None else 0,
        adapted_frames=harvest.frames if classifier is not None else 0,
        adapt_seconds=adapt_seconds,
        lead_in=lookahead.changes["lead_in"], lead_in_over=lookahead.changes["lead_in_over"],
        lead_in_run=params.lookahead.lead_in_run, gap_fill=lookahead.changes["gap_fill"], frame_count=total,
        score=score.outcomes(0) if score is not None else None)


def _frames(video: str | Path, stage: str, progress):
    """The video's (image, time) from its start, decoded ahead on a reader thread."""
    return recording_frames(video, None if progress is None else
                            (lambda done, total: progress(stage, done, total)))


def recording_frames(video: str | Path, progress: Callable[[int, int], None] | None = None):
    """The video's (image, time) from its start, decoded ahead on a reader thread: what the
    classifier's adaptation pass reads (``detect`` and the GUI's look-ahead view of a TV clip).
    ``progress(frames done, frames in all or 0)`` after each."""
    source = PrefetchingReader(VideoFile(video))
    total = int(source.frame_count or 0)
    try:
        i = 0
        while (frame := source.read()) is not None:
            yield frame, i / source.fps
            i += 1
            if progress is not None:
                progress(i, total)
    finally:
        source.close()

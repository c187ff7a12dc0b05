"""Tracking a recorded video pair into a CSV file: the one loop behind `badminton-track track`
and the GUI's *Tools ▸ Process a recording…*.

Why this file exists: the command line and the desktop tool must give the same rows for the
same recording, so they share this loop (the GUI and the CLI drive the same core).
It adds what a long job needs in either: progress (pairs done, of how many), cancellation
between two pairs — the rows decided so far are written and the file stays a valid CSV —, and
one-sentence errors for a file that cannot be written (a full disk). No Qt here.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ..core.evaluation import LiveScore, Outcomes
from ..core.params import TrackerParams
from ..core.rig import StereoRig, inputs_look_swapped, refine_threshold, swapped_sentence
from ..core.court_adaptation import StereoHarvest, adapt_to_stereo_recording
from ..core.errors import TrackerInputError
from ..core.track_lookahead import StereoLookahead
from ..core.tracker import StereoTracker
from ..core.types import CameraResult, TrackResult
from .labels import TRACK_COLUMNS, track_row
from .safe_write import RowFile
from .track_log import describe_os_error


# Frames of look-ahead of the file commands (`detect`, `track`, the GUI's Process a recording): a
# file has its future, so the readout is re-decided 4 frames later (core/lookahead.py). Chosen on
# the tuned-on clips: 4 frames beat 8 and 15, whose earlier back-fills and later handovers take
# more wrong candidates than right ones.
FILE_LOOKAHEAD = 4


# The withheld_reason of a row whose pair the tracker refused for a reason the source did not
# foresee (``TrackerInputError``): the row is empty.
WITHHELD_REFUSED = "input_refused"


class TrackFileError(OSError):
    """The output cannot be written; the message is one sentence for the user."""


@dataclass(frozen=True)
class TrackFileSummary:
    pairs: int              # frame pairs tracked
    points_3d: int          # rows with a 3D point
    seconds: float          # wall time, decoding included
    output: Path
    cancelled: bool         # stopped by ``should_stop`` (the rows so far are in the file)
    rig_epipolar_px: float | None = None   # how far the rig missed (StereoTracker.rig_epipolar_px)
    image_width: int = 0
    # The written rows scored against the pair's labels (``truth``), per camera; None without.
    score_left: Outcomes | None = None
    score_right: Outcomes | None = None
    # Rows whose 3D cells were withheld, by reason (the CSV's ``withheld_reason``), and the
    # source's sentences on what the output lacks (a file cut short, a stalled clock).
    withheld: tuple[tuple[str, int], ...] = ()
    source_notes: tuple[str, ...] = ()
    # Why the tracker refused pairs (``TrackerInputError``'s sentence, how many pairs), first first.
    refusals: tuple[tuple[str, int], ...] = ()
    rig_swapped_px: float | None = None    # the same pairs with the cameras exchanged (StereoTracker)

    @property
    def warning(self) -> str:
        """One sentence on what in the output may be wrong or missing; '' when nothing is."""
        parts = list(self.source_notes)
        parts += [f"{n} pair{'s' if n != 1 else ''} refused: {reason}" for reason, n in self.refusals]
        if self.withheld:
            counts = ", ".join(f"{n} {reason}" for reason, n in self.withheld)
            total = sum(n for _, n in self.withheld)
            parts.append(f"3D withheld in {total} row{'s' if total != 1 else ''} ({counts}; "
                         f"column withheld_reason)")
        return "; ".join(parts)

    @property
    def score_text(self) -> str:
        """'against the labels: left 98.56 %, right 98.77 % (F1 …)' or '' without labels."""
        if self.score_left is None or self.score_right is None:
            return ""
        parts = [f"{side} {100 * o.accuracy:.2f} % (F1 {100 * o.f1:.2f})"
                 for side, o in (("left", self.score_left), ("right", self.score_right)) if o.total]
        return "against the labels: " + ", ".join(parts) if parts else ""

    @property
    def pairs_per_second(self) -> float:
        return self.pairs / self.seconds if self.seconds > 0 else 0.0

    @property
    def rig_note(self) -> str:
        """A sentence for a rig whose sure pairs missed their epipolar lines by more than
        ``refine_threshold`` (median): its 3D points are off; '' for a rig that held."""
        px = self.rig_epipolar_px
        if px is None or px <= refine_threshold(self.image_width):
            return ""
        if inputs_look_swapped(px, self.rig_swapped_px, self.image_width):
            return (swapped_sentence(px, self.rig_swapped_px)
                    + " Give the left video as the right one and the right as the left (their "
                    "timestamp files too).")
        return (f"The shuttle's pairs missed their epipolar lines by {px:.0f} px (median; a good rig "
                f"stays under {refine_threshold(self.image_width):.0f} px here): the rig's relative pose "
                f"is off, and so are the 3D points. `badminton-track refine-calib` (or Calibration ▸ "
                f"Refine from tracked shuttle…) refits it from the play.")


def track_to_csv(source, rig: StereoRig, params: TrackerParams, output: str | Path, *,
                 max_frames: int | None = None, link=None,
                 progress: Callable[[int], None] | None = None,
                 should_stop: Callable[[], bool] | None = None, truth=None,
                 classifiers: tuple | None = None, trace: bool = False) -> TrackFileSummary:
    """Track every pair ``source.read()`` gives (a ``FrameSource``: a ``VideoPair``, possibly
    behind a ``PrefetchingReader``) and write one row per step to ``output``: per left frame, and
    per right frame no left frame was paired with (free-running cameras, ``VideoPair``).

    The rows are re-decided with ``params.lookahead.frames`` frames of look-ahead (the robot,
    when ``link`` is given, gets the live results at once). ``progress(pairs done)`` is called
    after every pair and ``should_stop()`` asked before each: when it says yes the look-ahead's
    pending rows are written and the summary says ``cancelled``. The source is not closed here.
    ``truth`` (io/truth.py ``LabelTruth``; default: the source's ``frame_truth``, as the GUI's
    sources carry): the written rows are scored against it (core/evaluation.py) in the summary.
    ``classifiers``: (left, right) candidate classifiers used instead of the preset's (one
    adapted to each camera's recording, or a leave-one-rally-out study's). ``trace``: a last
    column, ``Trace``, names the tracker's rules that fired on each row's step (space-separated,
    ``TrackResult.trace``; the look-ahead's re-decisions are not in it).
    """
    if truth is None:
        truth = getattr(source, "frame_truth", None)
    score = LiveScore(rig.image_size[0]) if truth is not None else None
    last_scored = [None, None]      # each camera's frame index scored last: a step repeats one

    def scored(decided):
        if score is not None:
            left, right = truth.for_indices(decided.index, decided.index_right)
            for cam, index, result, label in ((0, decided.index, decided.left, left),
                                              (1, decided.index_right, decided.right, right)):
                if index != last_scored[cam] or index < 0:
                    score.add(cam, result.detection, label)
                    last_scored[cam] = index
        return decided

    out_path = Path(output)
    tracker = StereoTracker(rig, params)
    tracker.trace = trace
    if classifiers is not None:
        tracker.left.use_classifier(classifiers[0])
        tracker.right.use_classifier(classifiers[1])
    lookahead = StereoLookahead(rig, params, tracker.epipolar_tolerance)
    n = hits3d = 0
    cancelled = False
    doubt = getattr(source, "doubt", None)     # VideoPair's: a step whose 3D would be made up
    withheld: dict[str, int] = {}
    refused: set[tuple[int, int]] = set()     # (index, index_right) of the pairs the tracker refused
    refusals: dict[str, int] = {}               # the tracker's reason -> pairs refused for it

    def row(decided) -> list[str]:
        nonlocal hits3d
        reason = doubt(decided.index, decided.index_right) if doubt is not None else ""
        if not reason and (decided.index, decided.index_right) in refused:
            reason = WITHHELD_REFUSED
        if reason:
            withheld[reason] = withheld.get(reason, 0) + 1
        hits3d += decided.point is not None and not reason
        return track_row(decided, reason) + ([" ".join(decided.trace)] if trace else [])

    start = time.perf_counter()
    rows = None
    try:
        # Written beside the output and renamed over it at the end: a run that fails keeps its
        # whole rows, and a previous output is never half overwritten.
        with RowFile(out_path, TRACK_COLUMNS + (("Trace",) if trace else ())) as rows:
            while max_frames is None or n < max_frames:
                if should_stop is not None and should_stop():
                    cancelled = True
                    break
                frame = source.read()
                if frame is None:
                    break
                try:
                    result = tracker.process_frame(frame, keep_masks=False)
                except TrackerInputError as exc:
                    # A pair the tracker refuses (a camera whose clock stalled): its row keeps
                    # its place in the file, empty and marked, and the run goes on.
                    refusals[str(exc)] = refusals.get(str(exc), 0) + 1
                    result = TrackResult(frame.index, frame.timestamp, CameraResult(None),
                                         CameraResult(None), index_right=frame.index_right)
                    refused.add((frame.index, frame.index_right))
                else:
                    if link is not None:
                        link.send_result(result)
                for decided in map(scored, lookahead.push(result)):
                    rows.write_row(row(decided))
                n += 1
                if progress is not None:
                    progress(n)
            for decided in map(scored, lookahead.flush()):
                rows.write_row(row(decided))
    except OSError as exc:
        kept = f"; its first {rows.rows_saved} rows are kept" if rows is not None and rows.rows_saved else ""
        raise TrackFileError(f"cannot write the track: {describe_os_error(exc, out_path)}{kept}") from None
    finally:
        tracker.close()
    return TrackFileSummary(n, hits3d, time.perf_counter() - start, out_path, cancelled,
                            tracker.rig_epipolar_px, rig.image_size[0],
                            None if score is None else score.outcomes(0),
                            None if score is None else score.outcomes(1),
                            tuple(sorted(withheld.items())), tuple(getattr(source, "notes", ())),
                            tuple(refusals.items()), tracker.rig_swapped_px)


def adapt_to_pair(source, rig: StereoRig, params: TrackerParams, *, max_frames: int | None = None,
                  progress: Callable[[int], None] | None = None,
                  should_stop: Callable[[], bool] | None = None,
                  judged: list | None = None) -> tuple[tuple | None, StereoHarvest]:
    """The first pass of `track --adapt`: the recording tracked once with the preset's classifiers,
    the candidates of every flight both cameras agree on labelled (core/court_adaptation.py), and
    each camera's classifier trained on them: ((left, right) or None when the pass found nothing
    to learn from or was stopped, the harvest). ``track_to_csv(classifiers=...)`` then tracks
    a second pass with them. ``judged`` receives each camera's held-back comparison
    (core/court_adaptation.py ``HeldBack``). The source is not closed here."""
    tracker = StereoTracker(rig, params.with_value("adapt.enabled", False))

    def frames():
        n = 0
        while max_frames is None or n < max_frames:
            frame = source.read()
            if frame is None:
                return
            yield frame
            n += 1
            if progress is not None:
                progress(n)

    try:
        return adapt_to_stereo_recording(tracker, frames(), should_stop or (lambda: False), params.adapt,
                                         judged)
    finally:
        tracker.close()

"""One tracker step's work in progress, handed from stage to stage.

Why this file exists: the stages of :class:`~badminton_gui.core.tracker.StereoTracker` (pairing,
the flight's look, the exits from view, the landed hold, the readout) each refine the same few
things — each camera's result and report, the pair's 3D point — and may name the rule that
fired; this is the one object they pass along, so a stage's signature says what it reads.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from .flight.guide import StepGuide
from .types import CameraResult, Candidate

SIDES = ("left", "right")


@dataclass(slots=True)
class Step:
    """Each camera's result and report, the pair's 3D point (left-camera frame) and epipolar
    error, the flight's guide at this time, and the rules that fired (None: not traced).
    ``frames``: each camera's image this step (a one-camera step: the other's last one)."""

    t: float
    t_right: float
    frames: tuple[np.ndarray | None, np.ndarray | None]
    guide: StepGuide
    results: list[CameraResult] = field(default_factory=list)
    dets: list[Candidate | None] = field(default_factory=lambda: [None, None])
    point: np.ndarray | None = None
    epi: float | None = None
    trace: list[str] | None = None
    # The pair's measured point extended the followed flight (``TrackResult.pair_in_flight``).
    in_flight: bool = False
    # No shuttle in play yet (``stereo.serve_start``): the pairing took only serve-like starts.
    before_serve: bool = False

    def fired(self, rule: str, cam: int | None = None) -> None:
        """The rule ``rule`` (of camera ``cam``) changed this step's readout."""
        if self.trace is not None:
            self.trace.append(rule if cam is None else f"{rule}:{SIDES[cam]}")

    def fired_all(self, fired: tuple[tuple[str, int | None], ...]) -> None:
        """Each (rule, camera) of ``fired`` changed this step's readout."""
        for rule, cam in fired:
            self.fired(rule, cam)

    def take(self, rule: str, results: tuple[CameraResult, CameraResult]) -> None:
        """The cameras' results become ``results``; ``rule`` fired on each whose result changed."""
        for cam in (0, 1):
            if results[cam] is not self.results[cam]:
                self.fired(rule, cam)
        self.results[0], self.results[1] = results

    def add(self, cam: int, found: Candidate) -> None:
        """``found`` becomes camera ``cam``'s report and joins its candidates."""
        self.dets[cam] = found
        self.results[cam] = dataclasses.replace(self.results[cam],
                                                candidates=self.results[cam].candidates + (found,))

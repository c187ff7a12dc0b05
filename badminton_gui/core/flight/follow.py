"""The 3D flight filter's step, and the 3D point the step reports.

Why this file exists: the stage between the stereo measurement and the shuttle's phase. The
flight (drag and gravity, ``Trajectory``) takes the step's measured point, or, with no pair, the
line of sight of the one camera that sees the shuttle (``flight/sight.py``); the point reported
is the flight's estimate when it took the point, the next shot's tentative one when it refused
it, or a shuttle lying where the last flight landed moved to its cork.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..params import TrackerParams
from ..rig import StereoRig
from ..step import Step
from ..stereo.cork import CorkCorrection
from ..stereo.measure import Measurement
from .trajectory import Trajectory
from ..types import Candidate, FlightInfo
from .sight import PAIRED_SIGHT_NOISE, SightOfCamera


class FlightFollower:
    """Feeds the flight filter a step's measurement or sight; says which point to report."""

    def __init__(self, rig: StereoRig, params: TrackerParams, trajectory: Trajectory, sight: SightOfCamera,
                 cork: CorkCorrection, right_xy: Callable[[Candidate], tuple[float, float]]) -> None:
        self.rig = rig
        self.params = params
        self.trajectory = trajectory
        self.sight = sight
        self.cork = cork
        self._right_xy = right_xy

    def follow(self, step: Step, m: Measurement) -> tuple[FlightInfo, int | None]:
        """The flight after this step, and the camera whose sight moved it (None: the measured
        point did, or nothing). With no pair, the one camera that sees the shuttle (the other's
        hidden, merged with a player, lost by its detector, or its readout on something else)
        moves the flight along its line of sight: the robot keeps a 3D point."""
        sight_cam = None
        if m.point is None and self.params.stereo.one_camera_rays and self.rig.has_court_pose:
            sight_cam = self.sight.camera(step.dets[0], step.dets[1], step.t)
        if sight_cam is None:
            head = np.eye(3) * m.head_variance if m.head_variance > 0 else None
            info = self.trajectory.update(step.t, m.point, m.noise_shape, head)
            step.in_flight = m.point is not None and self.trajectory.filtered_position() is not None
            if self.trajectory.point_elsewhere:
                step.fired("flight_kept_from_track_elsewhere")
            return info, None
        # The right image's own time when its clock lags (``align_pairs``), never earlier
        # than the last step (the trajectory would take that for a replay and reset).
        last = self.trajectory.last_time
        t_sight = step.t if sight_cam == 0 or (last is not None and step.t_right <= last) else step.t_right
        step.fired("one_camera_sight", sight_cam)
        return self.sight.feed(sight_cam, step.dets[sight_cam], t_sight, PAIRED_SIGHT_NOISE), sight_cam

    def point_to_report(self, step: Step, measured, sight_cam: int | None):
        """The 3D point to report (output frame) before the phase's rules; notes the pair's
        reprojection misses, and shows the flight's projection in the camera that lost it
        (``stereo.guided_other``)."""
        sp = self.params.stereo
        filtered = self.trajectory.filtered_position()
        left, right = step.dets
        if filtered is not None and step.point is not None and sp.one_camera_rays:
            self.sight.note_pair(step.t, self.rig.to_output(self.cork.last_blob_point()),
                                 ((left.x, left.y), self._right_xy(right)))
        if filtered is not None and sight_cam is not None and sp.guided_other:
            blind = 1 - sight_cam
            shown = self.sight.projected_readout(blind, filtered, step.t, step.results[blind], step.frames[blind])
            if shown is not None:
                step.results[blind] = shown
                step.fired("guided_other", blind)
        if filtered is not None:
            return filtered
        if self.trajectory.point_rejected:
            # An outlier to the followed flight: no point, unless it is the next shot's already.
            return self.trajectory.tentative_position()
        if measured is not None and self.rig.has_court_pose:
            return self.resting_cork(measured)
        return measured

    def resting_cork(self, point: tuple[float, float, float]) -> tuple[float, float, float]:
        """A shuttle lying where the last flight landed: move the blob's point to the cork."""
        direction = self.trajectory.resting_direction(point)
        if direction is None:
            return point
        sp = self.params.stereo
        return (point[0] + sp.rest_cork_ahead * direction[0], point[1] + sp.rest_cork_ahead * direction[1],
                point[2] - sp.rest_cork_below)

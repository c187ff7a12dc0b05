"""The flight stage of the tracker: what the 3D flight says about each camera's readout, and the
shuttle's phase (in play, landed, caught, seen by one camera only).

Why this package exists: after the stereo stage has measured (or not) a 3D point, the followed
flight looks where a camera lost the shuttle, says when the shuttle left a camera's view, moves
the flight along one camera's line of sight, and decides whether the shuttle is still in play;
those rules and their state live here, not in :class:`~badminton_gui.core.tracker.StereoTracker`.
"""

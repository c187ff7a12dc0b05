"""The stereo stage of the tracker: the two cameras' candidates made into one 3D measurement.

Why this package exists: pairing two cameras' detections (the epipolar gate learnt from the rig's
real error, the pair chosen, a young track vouched for by the other camera, each camera's image
path) is one stage of :class:`~badminton_gui.core.tracker.StereoTracker`, between the per-camera
detectors and the 3D flight filter; its rules and their state live here, not in the tracker.
"""

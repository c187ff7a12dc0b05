"""The one exception type the public API raises for input it cannot use.

Why this file exists: a caller of ``StereoTracker.process`` or ``StereoRig`` should catch one
documented type, whose message is a sentence naming what is wrong (the frame, the timestamp,
the rig key), and never a ``cv2.error`` or an ``OverflowError`` from deep inside the pipeline.
It subclasses ``ValueError`` so existing ``except ValueError`` handlers keep working.
"""

from __future__ import annotations


class TrackerInputError(ValueError):
    """Input the tracker cannot use (a frame, a timestamp, a rig); the message says why."""

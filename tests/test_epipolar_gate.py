"""The stereo pairing's epipolar gate from a fresh start (``stereo.cold_epipolar_error``,
``adaptive_epipolar``): a rough rig misses by tens of px, so the gate is wide until the rig's
real error has been learnt from sure pairs."""

import dataclasses

from badminton_gui.core.params import TrackerParams
from badminton_gui.core.tracker import StereoTracker
from badminton_gui.io.demo_scene import make_rig


def _tracker(**stereo) -> StereoTracker:
    p = TrackerParams()
    p = dataclasses.replace(p, stereo=dataclasses.replace(p.stereo, **stereo))
    return StereoTracker(make_rig("binocular", (1280, 720)), p, parallel=False)


def test_the_epipolar_gate_is_the_cold_one_until_the_rigs_error_is_learnt():
    """From a fresh start the pair gate is ``cold_epipolar_error`` (a rough rig misses by tens of
    px); after EPIPOLAR_LEARNT_SAMPLES sure pairs it is the learnt one, even when narrower; 0
    keeps the fixed tolerance; without learning there is no cold gate either."""
    from badminton_gui.core.stereo.epipolar import EPIPOLAR_LEARNT_SAMPLES

    t = _tracker(cold_epipolar_error=30.0, max_epipolar_error=6.0, adaptive_factor=2.5)
    assert t.epipolar_tolerance() == 30.0
    for _ in range(EPIPOLAR_LEARNT_SAMPLES - 1):
        t.gate.add_sample(4.0)
    assert t.epipolar_tolerance() == 30.0
    t.gate.add_sample(4.0)
    assert t.epipolar_tolerance() == 10.0          # 2.5 × the median 4 px
    t.reset()
    assert t.epipolar_tolerance() == 30.0
    t.close()
    for stereo in ({"cold_epipolar_error": 0.0}, {"adaptive_epipolar": False}):
        t = _tracker(max_epipolar_error=6.0, **stereo)
        assert t.epipolar_tolerance() == 6.0
        t.close()

"""The per-frame trace of the rules that fired (``StereoTracker.trace``, ``TrackResult.trace``,
``badminton-track track --trace``).

Off by default (a result stays cheap: an empty tuple); on, every step names its phase last and
the rules that changed its readout before it, and the trace changes nothing else.
"""

from __future__ import annotations

import csv

from badminton_gui.core.params import TrackerParams
from badminton_gui.core.tracker import StereoTracker
from badminton_gui.io.demo_scene import DemoScene
from badminton_gui.io.track_file import track_to_csv

FRAMES = 260
SIZE = (480, 270)


def _run(scene_frames, rig, trace: bool):
    tracker = StereoTracker(rig, TrackerParams(), parallel=False)
    tracker.trace = trace
    try:
        return [tracker.process_frame(frame, keep_masks=False) for frame in scene_frames]
    finally:
        tracker.close()


def _readout(r):
    # repr: a guided spot's NaN fields are equal only as text
    return repr((r.point, r.left.detection, r.right.detection, r.distance, r.speed, r.epipolar_error))


def test_the_trace_is_empty_unless_enabled_and_changes_nothing():
    scene = DemoScene(seed=0, size=SIZE, n_frames=FRAMES)
    try:
        frames = list(iter(scene.read, None))
    finally:
        scene.close()
    plain, traced = _run(frames, scene.rig, False), _run(frames, scene.rig, True)
    assert all(r.trace == () for r in plain)
    assert [_readout(r) for r in plain] == [_readout(r) for r in traced]
    assert all(r.trace and r.trace[-1].startswith("phase:") for r in traced)
    fired = {name for r in traced for name in r.trace}
    # the demo rally: the shuttle unseen, then in play, one camera losing it for a while
    assert {"phase:in_play", "phase:unseen"} <= fired
    assert any(name.startswith("one_camera_sight:") for name in fired)
    assert any(name.startswith(("guided_search:", "guided_coast:")) for name in fired)
    for r in traced:
        if r.point is not None and "phase:in_play" in r.trace:
            assert r.point[2] > TrackerParams().stereo.landed_max_height


def test_track_to_csv_writes_the_trace_as_a_last_column(tmp_path):
    scene = DemoScene(seed=0, size=SIZE, n_frames=60)
    try:
        track_to_csv(scene, scene.rig, TrackerParams(), tmp_path / "traced.csv", trace=True)
    finally:
        scene.close()
    rows = list(csv.reader((tmp_path / "traced.csv").open()))
    assert rows[0][-1] == "Trace" and len(rows) == 61
    assert all(row[-1].split()[-1].startswith("phase:") for row in rows[1:])

"""Each camera's detector in a process of its own (``StereoTracker(..., processes=True)``) gives
the very results of the detectors in the tracker's process, step by step: on the demo court
(default preset, and the coarse preset's windows) and on a stretch of a NYCU rally (skipped
without the data)."""

import contextlib
import dataclasses
import itertools
import math

import numpy as np
import pytest

from badminton_gui.core.camera_process import CameraProcessError, RemoteDetector
from badminton_gui.core.tracker import StereoTracker
from badminton_gui.io.demo_eval import dropped_frame_steps
from badminton_gui.io.demo_scene import DemoScene
from badminton_gui.io.presets import load_preset
from tests.conftest_data import NYCU_DIR, open_nycu_rally, requires_data


def _same(a, b, path="result") -> str | None:
    """Where ``a`` and ``b`` differ (None: nowhere): dataclasses field by field, arrays and
    floats exactly (NaN equal to NaN)."""
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        if type(a) is not type(b):
            return f"{path}: {type(a).__name__} against {type(b).__name__}"
        for f in dataclasses.fields(a):
            if f.name == "processing_ms":
                continue
            found = _same(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}")
            if found:
                return found
        return None
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        ok = (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.shape == b.shape
              and np.array_equal(a, b, equal_nan=a.dtype.kind == "f"))
        return None if ok else f"{path}: {a!r} against {b!r}"
    if isinstance(a, (tuple, list)):
        if not isinstance(b, (tuple, list)) or len(a) != len(b):
            return f"{path}: {a!r} against {b!r}"
        for k, (x, y) in enumerate(zip(a, b)):
            found = _same(x, y, f"{path}[{k}]")
            if found:
                return found
        return None
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return None
    return None if a == b and type(a) is type(b) else f"{path}: {a!r} against {b!r}"


def _compare(rig, frames, params=None, keep_masks=False) -> tuple[int, int]:
    """(steps compared, questions the stand-ins asked their workers); fails at the first step
    whose results differ."""
    ours = StereoTracker(rig, params)
    theirs = StereoTracker(rig, params, processes=True)
    steps = 0
    try:
        for frame in frames:
            a = ours.process_frame(frame, keep_masks=keep_masks)
            b = theirs.process_frame(frame, keep_masks=keep_masks)
            found = _same(a, b)
            assert found is None, f"step {steps} (frame {frame.index}): {found}"
            assert _same(ours.left.last_diagnostics, theirs.left.last_diagnostics) is None
            steps += 1
    finally:
        ours.close()
        theirs.close()
    return steps, theirs.left.questions + theirs.right.questions


def _demo(seed: int, frames: int, size=(640, 360)):
    scene = DemoScene(seed=seed, size=size, rig="binocular", n_frames=frames)
    out = []
    while (f := scene.read()) is not None:
        out.append(f)
    return scene.rig, out


def test_demo_court_same_results_in_processes():
    rig, frames = _demo(3, 240)
    steps, questions = _compare(rig, frames, keep_masks=True)
    assert steps == 240
    assert questions > 0        # the flight's coast asked a worker about its mask


def test_coarse_preset_windows_same_results_in_processes():
    rig, frames = _demo(0, 200)
    assert _compare(rig, frames, load_preset("coarse"))[0] == 200


def test_one_camera_steps_same_results_in_processes():
    """Free-running cameras: steps that bring one camera's image only (``_process_one``)."""
    scene = DemoScene(seed=3, size=(640, 360), rig="binocular", n_frames=150)
    steps = list(dropped_frame_steps(scene, 150))
    assert any(not (s.fresh_left and s.fresh_right) for s in steps)
    assert _compare(scene.rig, steps)[0] == len(steps)


def test_frames_put_in_the_workers_buffers_are_not_copied():
    """Frames written straight into the ring of shared buffers (as a decoder could) give the
    same results, with no copy."""
    rig, frames = _demo(2, 120)
    ours, theirs = StereoTracker(rig), StereoTracker(rig, processes=True)
    try:
        for k, frame in enumerate(frames):
            left, right = theirs.cameras.frame_buffers((frame.left.shape, frame.right.shape))
            left[:], right[:] = frame.left, frame.right
            shared = dataclasses.replace(frame, left=left, right=right)
            assert _same(ours.process_frame(frame, keep_masks=False),
                         theirs.process_frame(shared, keep_masks=False)) is None, k
        assert theirs.cameras.copy_cpu() == 0.0
    finally:
        ours.close()
        theirs.close()


@requires_data
def test_nycu_stretch_same_results_in_processes():
    rally = NYCU_DIR / "rally_11-46-04"
    if not rally.is_dir():
        pytest.skip("rally_11-46-04 is absent")
    rig, src = open_nycu_rally(rally)
    with contextlib.closing(src):
        frames = list(itertools.islice(iter(src.read, None), 150))
    assert _compare(rig, frames)[0] == 150


def test_parameters_and_reset_reach_the_worker():
    """A parameter snapshot and a reset mid-run are applied in the worker in their order."""
    rig, frames = _demo(1, 90)
    changed = load_preset(None).with_value("association.min_hits", 4)
    ours, theirs = StereoTracker(rig), StereoTracker(rig, processes=True)
    try:
        for k, frame in enumerate(frames):
            if k == 30:
                for tracker in (ours, theirs):
                    tracker.set_params(changed)
            if k == 60:
                for tracker in (ours, theirs):
                    tracker.reset()
            assert _same(ours.process_frame(frame, keep_masks=False),
                         theirs.process_frame(frame, keep_masks=False)) is None, k
    finally:
        ours.close()
        theirs.close()


def test_a_failure_in_the_worker_is_raised_here():
    detector = RemoteDetector()
    try:
        with pytest.raises(CameraProcessError, match="cv2.error"):
            detector.find_candidates(np.zeros((4, 4, 3), np.float32), 0.0)   # a float image
        # The worker goes on: the next frame is processed.
        result = detector.find_candidates(np.zeros((360, 640, 3), np.uint8), 0.01)
        assert result.image_size == (640, 360)
    finally:
        detector.close()
        detector.close()    # twice: nothing left to close

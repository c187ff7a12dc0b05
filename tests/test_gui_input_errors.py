"""Input the tracker refuses, seen from the window (pytest-qt, under Xvfb).

Why this file exists: a rig that cannot be right and a pair with a NaN timestamp used to stop the
worker with "internal error in the tracker"; the operator must instead read a sentence naming
what is wrong, and a bad pair must not end the run.
"""

from __future__ import annotations

import dataclasses
import os

import numpy as np
import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("PySide6")

pytestmark = [pytest.mark.gui,
              pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (run under Xvfb)")]

from badminton_gui.gui.settings import SourceSpec  # noqa: E402
from badminton_gui.io.demo_scene import DemoScene  # noqa: E402

WAIT_MS = 40_000


def write_rig_with_zero_m1(path) -> None:
    """The demo rig's file with M1 all zeros (written as text: StereoRig refuses to hold it)."""
    scene = DemoScene(seed=0)
    scene.rig.save(path)
    scene.close()
    text = path.read_text()
    start = text.index("M1:")
    data = text.index("data:", start)
    end = text.index("]", data)
    path.write_text(text[:data] + "data: [ 0., 0., 0., 0., 0., 0., 0., 0., 0. ]" + text[end + 1:])


class NanTimeScene:
    """The demo court whose pair ``bad_index`` carries a NaN timestamp, as a broken camera
    clock would give."""

    def __init__(self, bad_index: int) -> None:
        self.scene = DemoScene(seed=0)
        self.bad_index = bad_index
        self.name = "demo with a NaN timestamp"
        self.image_size = self.scene.image_size
        self.fps = self.scene.fps
        self.delivered = 0

    def read(self):
        frame = self.scene.read()
        if frame is None:
            return None
        self.delivered += 1
        if frame.index == self.bad_index:
            frame = dataclasses.replace(frame, t_left=float("nan"), t_right=float("nan"))
        return frame

    def close(self) -> None:
        self.scene.close()


def test_a_rig_that_cannot_be_right_is_named_in_the_banner(main_window, qtbot, tmp_path):
    rig = tmp_path / "zero_m1.yaml"
    write_rig_with_zero_m1(rig)
    window = main_window()
    window.start_spec(SourceSpec("demo", calib=str(rig), realtime=False))
    qtbot.waitUntil(lambda: window.banner.text != "", timeout=WAIT_MS)
    text = window.banner.text
    assert "M1" in text and "focal lengths" in text and str(rig) in text
    assert "internal error" not in text.lower() and "\n" not in text
    window.start_spec(SourceSpec("demo", realtime=False))       # the window goes on
    qtbot.waitUntil(lambda: window.latest_packet is not None, timeout=WAIT_MS)


def test_a_nan_timestamp_skips_that_pair_with_a_sentence_and_tracking_goes_on(main_window, qtbot):
    source = NanTimeScene(bad_index=5)
    window = main_window()
    window.start_opener(lambda: (source, source.scene.rig), source.name)
    qtbot.waitUntil(lambda: window.banner.text != "", timeout=WAIT_MS)
    text = window.banner.text
    assert text.startswith("Frame skipped: the left timestamp is nan")
    assert "internal error" not in text.lower()
    # The run goes on past the bad pair: later pairs are tracked and shown.
    qtbot.waitUntil(lambda: window.latest_packet is not None
                    and window.latest_packet.stats.frames >= 20, timeout=WAIT_MS)
    assert source.delivered > 20
    assert np.isfinite(window.latest_packet.result.timestamp)

"""The rejected-candidates overlay says why (pytest-qt, under Xvfb): each rejected candidate
near the shuttle carries its filter's word, and a panel names the rules that fired on the step
and what each detector stage rejected, from the worker's result; with the overlay off the
worker traces nothing.
"""

from __future__ import annotations

import os
import threading
import time

import numpy as np
import pytest

pytest.importorskip("pytestqt")
pytest.importorskip("PySide6")

pytestmark = [pytest.mark.gui,
              pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs a display (run under Xvfb)")]

SMALL = (480, 270)      # the demo court small: a rule fires within its first 30 pairs


def _small_demo():
    from badminton_gui.io.demo_scene import DemoScene
    scene = DemoScene(seed=0, size=SMALL, n_frames=400)
    return scene, scene.rig


def _diagnostics(**tracklets):
    from badminton_gui.core.detect.diagnostics import (DetectionDiagnostics, ScoreReport, ShapeReport,
                                                        TrackletReport)
    report = dict(linked=4, rejected_motion=3, passed=1, exit_hold=False, coasting=False,
                  lone_accepted=False)
    report.update(tracklets)
    return DetectionDiagnostics(windowed=False, shapes=ShapeReport(12, 5, 1, 0, 0),
                                scoring=ScoreReport(6, 1, 0, 1), tracklets=TrackletReport(**report))


def _rules(trace, side: str) -> list[str]:
    return [n for n in trace if not n.startswith("phase:") and (":" not in n or n.endswith(":" + side))]


def test_the_panel_names_the_phase_this_cameras_rules_and_the_stage_counts():
    from badminton_gui.gui.overlays import trace_lines

    trace = ("guided_search:left", "landed_hold:right", "caught", "phase:caught")
    left = trace_lines(trace, "left", _diagnostics(coasting=True))
    assert left[0] == "phase:caught · guided_search:left · caught"
    assert "landed_hold" not in "\n".join(left)            # the other camera's rule
    assert left[1] == "shapes 12: len 5 · side 1 · unmeasured 0"
    assert left[2] == "scoring 6: white 1 · still 0 · score 1"
    assert left[3] == "tracklets 4: motion 3 · passed 1 · coasting"
    right = trace_lines(trace, "right", _diagnostics())
    assert right[0] == "phase:caught · landed_hold:right · caught"
    assert trace_lines(("phase:in_play",), "left", _diagnostics())[0] == "phase:in_play · no rule fired"
    assert trace_lines((), "left", _diagnostics())[0] == "one camera: no stereo rules"
    assert trace_lines(("phase:in_play",), "left", None) == ["no trace: tracked before the overlay was on"]


def _run_worker(worker, until, timeout_s: float = 90.0) -> list:
    """Run a TrackingWorker headless, asking for the next display packet after each one taken,
    until ``until(packets)``; the packets."""
    packets = []
    worker.set_display_size(320, 180)
    thread = threading.Thread(target=worker.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + timeout_s
    try:
        while not until(packets) and time.monotonic() < deadline:
            packet = worker.output.take()
            if packet is None:
                time.sleep(0.005)
                continue
            packets.append(packet)
            worker.request_display()
    finally:
        worker.abort()
        thread.join(30)
    assert until(packets), "the worker did not get there in time"
    return packets


def test_the_worker_traces_only_while_asked_and_the_packet_carries_it(qapp):
    from badminton_gui.core.detect.diagnostics import DetectionDiagnostics
    from badminton_gui.core.params import TrackerParams
    from badminton_gui.gui.feed_view import FeedView
    from badminton_gui.gui.overlays import trace_lines
    from badminton_gui.gui.worker import TrackingWorker

    worker = TrackingWorker(_small_demo, TrackerParams(), realtime=False)
    asked = []

    def traced_rule(packets) -> bool:
        if len(packets) >= 5 and not asked:
            worker.set_trace(True)           # the overlay turned on while it plays
            asked.append(len(packets))
        return any(p.diagnostics is not None and _rules(p.result.trace, "right") + _rules(p.result.trace, "left")
                   for p in packets)

    packets = _run_worker(worker, traced_rule)
    untraced = packets[:asked[0]]
    assert all(p.result.trace == () and p.diagnostics is None for p in untraced)    # costs nothing off
    traced = [p for p in packets if p.diagnostics is not None]
    for p in traced:
        assert p.result.trace[-1].startswith("phase:")
        assert all(isinstance(d, DetectionDiagnostics) for d in p.diagnostics)
    # The pair where a rule fired (one camera's line of sight on the demo's first flight): its
    # camera's panel names the rule as `track --trace` does.
    fired = next(p for p in traced if _rules(p.result.trace, "left") + _rules(p.result.trace, "right"))
    side = "right" if _rules(fired.result.trace, "right") else "left"
    rule = _rules(fired.result.trace, side)[0]
    feed = FeedView(side.title())
    feed.set_trace(trace_lines(fired.result.trace, side, fired.diagnostics[side == "right"]))
    assert rule in feed.trace_text.splitlines()[0]
    assert fired.result.trace[-1] in feed.trace_text


def test_the_window_shows_the_rules_that_fired_with_the_overlay_on(main_window, qtbot):
    """Through the window: C (the rejected-candidates overlay) makes the worker trace, and a
    feed's panel names a rule of the demo court's first flight; off again, the panel goes."""
    window = main_window()
    window.realtime_action.setChecked(False)
    window.rejected_action.trigger()
    assert window.rejected_action.isChecked()
    window.start_opener(_small_demo, "small demo")

    def named_rule() -> bool:
        heads = [feed.trace_text.splitlines()[0] for feed in (window.left_feed, window.right_feed)
                 if feed.trace_text]
        return any(name.endswith((":left", ":right")) and not name.startswith("phase:")
                   for head in heads for name in head.split(" · "))

    qtbot.waitUntil(named_rule, timeout=90_000)
    window.rejected_action.trigger()
    assert window.left_feed.trace_text == "" and window.right_feed.trace_text == ""
    qtbot.waitUntil(lambda: window.latest_packet is not None and window.latest_packet.diagnostics is None
                    and window.latest_packet.result.trace == (), timeout=30_000)


def _colour_pixels(image, colour, rect=None, tol: int = 40) -> int:
    from PySide6.QtGui import QImage
    qimage = image.toImage().convertToFormat(QImage.Format.Format_RGB32)   # bytes B, G, R, A
    arr = np.frombuffer(qimage.constBits(), np.uint8).reshape(qimage.height(), qimage.bytesPerLine() // 4, 4)
    if rect is not None:
        arr = arr[int(rect.top()):int(rect.bottom()) + 1, int(rect.left()):int(rect.right()) + 1]
    b, g, r = (arr[..., i].astype(int) for i in range(3))
    near = (abs(r - colour.red()) < tol) & (abs(g - colour.green()) < tol) & (abs(b - colour.blue()) < tol)
    return int(near.sum())


def test_feed_labels_the_nearest_rejected_candidates_by_filter(qtbot):
    from badminton_gui.core.types import REJECT_REASONS, CameraResult, Candidate
    from badminton_gui.gui.feed_view import MAX_REJECT_LABELS, FeedView
    from badminton_gui.gui.overlays import REJECT_SHORT, reject_style

    feed = FeedView("Left")
    qtbot.addWidget(feed)
    feed.resize(640, 360)
    image = np.full((360, 640, 4), 40, np.uint8)          # a synthetic dark frame, 1280×720 shown at ½
    shuttle = Candidate(640, 360, 20, 3, 200, 12, 0, 1)

    def rejected(k: int, reason: str) -> Candidate:
        # Spread round the shuttle, farther for each k, apart enough for every label to fit.
        angle = 2.4 * k
        r = 60 + 35 * k
        return Candidate(640 + r * np.cos(angle), 360 + r * np.sin(angle), 10, 3, 50, 8, 0, 0,
                         rejected_by=reason)

    others = [rejected(k, REJECT_REASONS[k % len(REJECT_REASONS)]) for k in range(9)]
    camera = CameraResult(detection=shuttle, candidates=(shuttle, *others[::-1]), image_size=(1280, 720))
    feed.set_frame(image, 0.5, camera, np.zeros((0, 3)))

    labels = feed.reject_labels()
    assert len(labels) == MAX_REJECT_LABELS                       # capped
    # nearest to the shuttle first, each worded by its filter, beside its own ring
    assert [reason for _, reason, _ in labels] == [c.rejected_by for c in others[:MAX_REJECT_LABELS]]
    for (word, reason, rect), c in zip(labels, others):
        assert word == REJECT_SHORT[reason]
        ring = feed.image_to_widget(c.x, c.y)
        assert rect.adjusted(-12, -12, 12, 12).contains(ring)
    rects = [rect for _, _, rect in labels]
    assert not any(a.intersects(b) for i, a in enumerate(rects) for b in rects[i + 1:])

    # Drawn only with the overlay on: the label's word in its filter's colour inside its box.
    word, reason, rect = labels[0]
    colour = reject_style(reason)[0]
    assert _colour_pixels(feed.grab(), colour, rect) == 0
    feed.show_rejected = True
    assert _colour_pixels(feed.grab(), colour, rect) >= 5

    # A cluster (a player's limbs) and, farther, a ring of another filter: the cluster's first
    # ring is labelled, then the other filter's, then more of the cluster where they find room;
    # labels never cover one another.
    cluster = tuple(Candidate(900 + 6 * k, 300 + 4 * k, 10, 3, 50, 8, 0, 0, rejected_by="motion")
                    for k in range(8))
    far = Candidate(200, 600, 10, 3, 50, 8, 0, 0, rejected_by="short_side")
    feed.set_frame(image, 0.5, CameraResult(detection=shuttle, candidates=(shuttle, far) + cluster,
                                            image_size=(1280, 720)), np.zeros((0, 3)))
    labels = feed.reject_labels()
    assert [word for word, _, _ in labels[:2]] == ["motion", "side"]
    assert 2 <= len(labels) <= MAX_REJECT_LABELS
    rects = [rect for _, _, rect in labels]
    assert not any(a.intersects(b) for i, a in enumerate(rects) for b in rects[i + 1:])


def test_feed_draws_the_trace_panel_only_with_the_overlay(qtbot):
    from PySide6.QtGui import QColor

    from badminton_gui.core.types import CameraResult
    from badminton_gui.gui.feed_view import FeedView

    feed = FeedView("Left")
    qtbot.addWidget(feed)
    feed.resize(640, 360)
    feed.set_frame(np.full((360, 640, 4), 90, np.uint8), 0.5,
                   CameraResult(detection=None, image_size=(1280, 720)), np.zeros((0, 3)))
    feed.set_trace(["phase:in_play · guided_search:left", "shapes 3: len 1 · side 0 · unmeasured 0"])
    white = QColor(255, 255, 255)
    from PySide6.QtCore import QRectF
    corner = QRectF(0, 360 - 60, 320, 60)
    assert _colour_pixels(feed.grab(), white, corner, tol=30) == 0
    feed.show_rejected = True
    assert _colour_pixels(feed.grab(), white, corner, tol=30) > 20
    assert feed.trace_text.startswith("phase:in_play · guided_search:left")

"""The advice to use the faster preset when tracking falls behind its source (gui/keep_up.py).

The watch itself is plain Python (tested without Qt); the last test drives the window's banner
and its button under Xvfb.
"""

from __future__ import annotations

import os
from types import SimpleNamespace

import pytest

from badminton_gui.core.params import TrackerParams
from badminton_gui.gui.keep_up import KeepUpWatch, has_faster_preset
from badminton_gui.io.presets import load_preset

WIDE = (2048, 1536)


def stats(frames=0, dropped=0, fps=80.0, capture=119.0, playback=1.0):
    return SimpleNamespace(frames=frames, dropped=dropped, processing_fps=fps,
                           capture_fps_left=capture, playback_speed=playback)


def feed(watch, samples, *, live=False, paced=True, paused=False, params=None, size=WIDE, hz=15):
    """Feed ``samples`` (stats per tick, at ``hz``); the list of (time, advice) given."""
    params = params or TrackerParams()
    given = []
    for k, s in enumerate(samples):
        now = k / hz
        advice = watch.update(now, s, live=live, paced=paced, paused=paused, params=params, image_size=size)
        if advice is not None:
            given.append((now, advice))
    return given


def test_only_wide_frames_without_the_coarse_setup_have_a_faster_preset():
    assert has_faster_preset(TrackerParams(), 2048)
    assert not has_faster_preset(load_preset("coarse"), 2048)
    assert not has_faster_preset(TrackerParams(), 1280)
    assert not has_faster_preset(load_preset("broadcast"), 1280)


def test_a_recording_played_slowly_gets_the_advice_once_after_five_seconds():
    """Not judged in the first 2 s (cold rate meters: here 20 pairs/s), then 5 s behind; the
    figures are the period's medians."""
    watch = KeepUpWatch()
    cold = [stats(fps=20.0, playback=0.18)] * 30
    given = feed(watch, cold + [stats(fps=82.0, playback=0.69), stats(fps=84.0, playback=0.71),
                                stats(fps=83.0, playback=0.70)] * (5 * 20))
    assert len(given) == 1
    when, text = given[0]
    assert 7.0 <= when < 7.3
    assert text.startswith("Tracking keeps up with 83 of the 119 frame pairs a second")
    assert "2048×1536" in text and "0.70× real time" in text and "coarse preset" in text
    watch.reset()                                   # a new source: it may say it again
    assert len(feed(watch, [stats(playback=0.7)] * 120)) == 1


def test_short_slowdowns_pauses_and_fast_enough_tracking_give_no_advice():
    slow, fine = stats(playback=0.8), stats(playback=1.0)
    # slow for 4 s, caught up, slow for 4 s again: never 5 s in a row
    assert feed(KeepUpWatch(), ([slow] * 60 + [fine]) * 4) == []
    assert feed(KeepUpWatch(), [slow] * 200, paused=True) == []
    assert feed(KeepUpWatch(), [stats(playback=0.97)] * 200) == []
    assert feed(KeepUpWatch(), [slow] * 200, paced=False) == []          # flat out by choice
    assert feed(KeepUpWatch(), [slow] * 200, params=load_preset("coarse")) == []
    assert feed(KeepUpWatch(), [slow] * 200, size=(1280, 720)) == []


def test_live_cameras_advised_on_the_share_of_pairs_dropped():
    # 80 of 119 pairs a second tracked: 39 dropped a second, a third
    dropping = [stats(frames=int(80 * k / 15), dropped=int(39 * k / 15)) for k in range(200)]
    given = feed(KeepUpWatch(), dropping, live=True, paced=False)
    assert len(given) == 1 and "so pairs are being dropped" in given[0][1]
    # 2 % dropped (a hiccup now and then) is keeping up
    keeping = [stats(frames=int(117 * k / 15), dropped=int(2 * k / 15)) for k in range(200)]
    assert feed(KeepUpWatch(), keeping, live=True, paced=False) == []


@pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs Xvfb (QT_QPA_PLATFORM=xcb)")
def test_the_banner_offers_the_preset_and_its_button_applies_it(main_window, qtbot):
    from badminton_gui.gui.worker import WorkerStats

    window = main_window(params=TrackerParams())
    window._keep_up.sustained_s, window._keep_up.warm_up_s = 0.5, 0.0
    packet = SimpleNamespace(stats=WorkerStats(processing_fps=83.0, capture_fps_left=119.0,
                                               playback_speed=0.7, paced=True),
                             result=SimpleNamespace(left=SimpleNamespace(image_size=WIDE)))
    for k in range(10):
        window._check_keep_up(k * 0.1, packet)
    assert window.banner.isVisible() and window.banner.kind == "advice"
    assert "coarse preset" in window.banner.text
    assert window.banner.action_button.text() == "Use coarse"
    window.banner.action_button.click()
    assert not window.banner.isVisible()
    assert window.params == load_preset("coarse")
    assert not has_faster_preset(window.params, 2048)
    # An error shown later is red and has no button.
    window.banner.show_message("The left camera stopped delivering frames.")
    assert window.banner.kind == "error" and not window.banner.action_button.isVisible()


def _yield_run(watch, samples, *, live=True, paced=False, paused=False, hz=30):
    """Feed DisplayYield ``samples`` at ``hz``; the interval it returned after each."""
    return [watch.update(k / hz, s, live=live, paced=paced, paused=paused) for k, s in enumerate(samples)]


def test_the_court_views_slow_down_while_live_pairs_are_dropped_and_come_back_after_a_while():
    from badminton_gui.gui.keep_up import DisplayYield

    watch = DisplayYield(normal_s=1 / 15, slowed_s=0.25, hold_s=10.0)
    # 119 pairs a second, all tracked, for 3 s: normal rate throughout.
    keeping = [stats(frames=int(119 * k / 30), dropped=0) for k in range(90)]
    assert set(_yield_run(watch, keeping)) == {1 / 15} and not watch.slowed
    # Then 5 % dropped: slowed within half a second, once the last second's share passes 1 %.
    base = keeping[-1].frames
    dropping = [stats(frames=base + int(113 * k / 30), dropped=int(6 * k / 30)) for k in range(1, 61)]
    intervals = [watch.update(3 + k / 30, s, live=True, paced=False, paused=False)
                 for k, s in enumerate(dropping, start=1)]
    first = intervals.index(0.25)
    assert 5 <= first <= 15 and set(intervals[first:]) == {0.25} and watch.slowed
    # Caught up: still slowed for the hold, then normal again.
    frames, dropped = dropping[-1].frames, dropping[-1].dropped
    t0 = 5.0
    after = [(t0 + k / 30, watch.update(t0 + k / 30, stats(frames=frames + int(119 * k / 30), dropped=dropped),
                                        live=True, paced=False, paused=False)) for k in range(1, 400)]
    back = next(t for t, interval in after if interval == 1 / 15)
    assert 15.0 <= back <= 16.1
    # Less than 1 % dropped (one pair now and then) is no reason to slow the views.
    calm = DisplayYield(normal_s=1 / 15)
    trickle = [stats(frames=int(119 * k / 30), dropped=k // 90) for k in range(300)]
    assert set(_yield_run(calm, trickle)) == {1 / 15}


def test_a_slow_paced_playback_slows_the_views_but_a_flat_out_or_paused_one_does_not():
    from badminton_gui.gui.keep_up import DisplayYield

    watch = DisplayYield(normal_s=1 / 15)
    # a paced file slow for a second or more: slowed; a hiccup shorter than that: not
    assert _yield_run(watch, [stats(playback=0.9)] * 31, live=False, paced=True)[-1] == watch.slowed_s
    watch.reset()
    hiccup = [stats(playback=0.9)] * 20 + [stats(playback=1.0)] + [stats(playback=0.9)] * 20
    assert set(_yield_run(watch, hiccup, live=False, paced=True)) == {1 / 15}
    assert _yield_run(watch, [stats(playback=0.9)], live=False, paced=True, paused=True) == [1 / 15]
    assert not watch.slowed                                      # a pause starts afresh
    assert set(_yield_run(watch, [stats(playback=0.5)] * 30, live=False, paced=False)) == {1 / 15}
    assert set(_yield_run(watch, [stats(playback=0.99)] * 30, live=False, paced=True)) == {1 / 15}


@pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs Xvfb (QT_QPA_PLATFORM=xcb)")
def test_the_window_slows_its_court_views_and_says_so_while_the_cameras_drop_pairs(main_window, monkeypatch):
    """Live packets with 10 % dropped: the plan view and the readouts are redrawn at 4 Hz
    instead of 15, the readouts are told why, and the feeds still take every packet."""
    from badminton_gui.gui import main_window as mw
    from badminton_gui.gui.worker import LatestSlot, WorkerStats

    window = main_window(params=TrackerParams())
    window._timer.stop()                          # the test drives the ticks and the clock
    clock = [1000.0]
    monkeypatch.setattr(mw.time, "perf_counter", lambda: clock[0])

    class StandInWorker:
        output, link_error = LatestSlot(), ""

        def request_display(self, not_before=0.0):
            pass

        def set_display_size(self, width, height):
            pass

    plan_shown, readout_notes, feed_frames = [], [], []
    monkeypatch.setattr(window.plan, "show_packet", plan_shown.append)
    monkeypatch.setattr(window.side, "show_packet", lambda p: None)
    if window.gl_view is not None:
        monkeypatch.setattr(window.gl_view, "show_packet", lambda p: None)
    monkeypatch.setattr(window.readouts, "show_packet", lambda p, hz, slowed=None: readout_notes.append(slowed))
    monkeypatch.setattr(window.left_feed, "set_frame", lambda *a: feed_frames.append(a))
    monkeypatch.setattr(window.right_feed, "set_frame", lambda *a: None)
    monkeypatch.setattr(window, "_check_keep_up", lambda now, packet: None)
    window.worker = StandInWorker()
    try:
        for k in range(90):                                # 3 s of ticks at 30 Hz
            stats_now = WorkerStats(frames=int(107 * k / 30), dropped=int(12 * k / 30), live=True,
                                    processing_fps=107.0, capture_fps_left=119.0)
            window.worker.output.put(SimpleNamespace(stats=stats_now, result=SimpleNamespace(left=None, right=None),
                                                     left=None, right=None, display_scale=1.0,
                                                     trail_left=None, trail_right=None,
                                                     label_left=None, label_right=None))
            window._refresh_display()
            clock[0] += mw.DISPLAY_INTERVAL_MS / 1000.0
    finally:
        window.worker = None
    assert len(feed_frames) == 90
    # 15 Hz while the first half second is judged, 4 Hz after: 8 + 10, give or take a tick
    assert 15 <= len(plan_shown) <= 21 and len(readout_notes) == len(plan_shown)
    assert readout_notes[0] is None and readout_notes[-1] == pytest.approx(4.0)
    assert window._slowed_views_hz() == pytest.approx(4.0)

"""Measure the GUI's cost on its own thread and its effect on the tracking rate.

Why this file exists: the performance goal says the GUI shows both feeds at up to 30 Hz without
lowering the tracking rate, with frame-to-screen ≤ 2 ms per feed on the GUI thread. This runs
the real MainWindow on the demo court as fast as the tracker goes, times (perf_counter) the
feed update path of each feed (``FeedView.set_frame`` + the ``paintEvent`` that follows), the
whole display slot, the 3D view's ``paintGL`` and the 2D plots' paints, and compares the
worker's results per second with the same worker running with no window at all, in
alternating phases of the same run (shared machines drift by ±15–25 % between runs). It ends with the issue's
figures: display Hz per feed, frame-to-screen per feed (median / p95), tracking results/s with
and without the window and their ratio, and the GUI-thread slot times. Run under Xvfb:

    QT_QPA_PLATFORM=xcb xvfb-run -a -s "-screen 0 1600x900x24" \
        .venv/bin/python scripts/gui-timing.py --seconds 20 --rounds 2

``--nycu PAIRS --preset coarse`` replaces the demo court by the real rig at its real rate: a NYCU
rally's 2048×1536 pairs held in memory and delivered like live cameras at 119 fps, so the figure
is the one the operator meets — how many of the cameras' pairs are tracked (and how many dropped)
with the window showing them, against the same tracker with no window.
"""

from __future__ import annotations

import argparse
import functools
import os
import statistics
import sys
import tempfile
import threading
import time
from collections import defaultdict
from pathlib import Path

import numpy as np


def _pct(values: list[float], q: float) -> float:
    return float(np.percentile(values, q)) if values else float("nan")


def _cpu_by_thread() -> dict[tuple[int, str], float]:
    """CPU seconds so far per (thread id, name) of this process, and of the X server."""
    tick = os.sysconf("SC_CLK_TCK")
    out: dict[tuple[int, str], float] = {}
    main_tid = os.getpid()

    def add(stat_path: str, tid: int, name: str | None = None) -> None:
        try:
            text = Path(stat_path).read_text()
        except OSError:
            return
        comm = text[text.index("(") + 1:text.rindex(")")]
        if tid == main_tid:
            comm = "GUI thread"
        fields = text[text.rindex(")") + 2:].split()
        out[(tid, name or comm)] = (int(fields[11]) + int(fields[12])) / tick

    for task in Path("/proc/self/task").iterdir():
        add(str(task / "stat"), int(task.name))
    # Python does not give its threads OS names; name the alone-phase worker by its id.
    for t in threading.enumerate():
        if t.name == "tracking" and t.native_id is not None:
            for key in [k for k in out if k[0] == t.native_id]:
                out[(key[0], "tracking")] = out.pop(key)
    display = os.environ.get("DISPLAY", "")
    if display.startswith(":"):
        try:
            xpid = int(Path(f"/tmp/.X{display[1:].split('.')[0]}-lock").read_text().strip())
            add(f"/proc/{xpid}/stat", -xpid, "X server")
        except (OSError, ValueError):
            pass
    return out


def _gui_thread_sched() -> tuple[float, float]:
    """(on-CPU s, waiting-for-a-CPU s) of the GUI thread so far, from /proc schedstat."""
    try:
        run, wait, _ = Path(f"/proc/self/task/{os.getpid()}/schedstat").read_text().split()
        return int(run) / 1e9, int(wait) / 1e9
    except (OSError, ValueError):
        return float("nan"), float("nan")


def _cpu_delta(before: dict, after: dict, seconds: float) -> str:
    """Per thread name, CPU used between two snapshots (threads that ended are not counted)."""
    by_name: dict[str, float] = defaultdict(float)
    for key, value in after.items():
        by_name[key[1]] += value - before.get(key, 0.0)
    rows = sorted(((v / seconds, k) for k, v in by_name.items()), reverse=True)
    return ", ".join(f"{k} {v * 100:.0f}%" for v, k in rows if v >= 0.01)


def _display_side_cpu(before: dict, after: dict) -> float:
    """CPU seconds between two snapshots of the threads that only serve the display: the GUI
    thread, Mesa's llvmpipe rasterizer threads and the X server."""
    return sum(value - before.get(key, 0.0) for key, value in after.items()
               if key[1] in ("GUI thread", "X server") or key[1].startswith("llvmpipe"))


class _NycuReplay:
    """Live cameras stand-in: real 2048×1536 NYCU frames held in memory, delivered on the rig's
    119 fps clock (``fps`` None: the worker treats it as cameras, newest pair wins, drops
    counted). Decoding the rally's video would cost the tracker half its time (README Speed), a
    camera costs it none: this measures the GUI beside the tracker at the rig's real rate. The
    stretch plays forwards then backwards, so the background model never sees a cut."""

    FPS = 119.0

    def __init__(self, pairs, rig) -> None:
        self.pairs, self.rig = pairs, rig
        self.name = "NYCU rally (live replay)"
        self.image_size = (pairs[0][0].shape[1], pairs[0][0].shape[0])
        self.fps = None
        self._k = 0
        self._t0 = 0.0

    @classmethod
    def load(cls, n: int, skip: int) -> "_NycuReplay":
        sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
        import speed
        rally = speed.DATA / speed.RALLY
        rig = speed.rig_from_nycu(rally / "CameraReader_1.cfg", rally / "CameraReader_2.cfg")
        pairs = [(left, right) for left, right, _ in speed.load_pairs(n, None, skip)]
        print(f"{len(pairs)} pairs of {speed.RALLY} in memory (from pair {skip})")
        return cls(pairs, rig)

    def restart(self) -> "_NycuReplay":
        self._k, self._t0 = 0, time.perf_counter()
        return self

    def read(self):
        from badminton_gui.core.types import StereoFrame
        k = self._k
        self._k += 1
        due = self._t0 + k / self.FPS
        wait = due - time.perf_counter()
        if wait > 0:
            time.sleep(wait)
        n = len(self.pairs)
        i = k % (2 * n - 2)
        i = i if i < n else 2 * n - 2 - i
        left, right = self.pairs[i]
        t = k / self.FPS
        return StereoFrame(left, right, t, t, k, k)

    def close(self) -> None:
        pass


def _alternate(args, window, with_gui, latencies, worker_module, display_cpu_ms) -> int:
    """``--ab``: the display as it was (buffer 1, views never slowed) against as it is, phase by
    phase in one process, so the machine's drift (±20 % between runs here) hits both alike."""
    setups = {"before (buffer 1, no yield)": (1, window._display_yield.normal_s),
              f"now (buffer {worker_module.LIVE_BUFFER_PAIRS}, yield)": (worker_module.LIVE_BUFFER_PAIRS,
                                                                        window._display_yield.slowed_s)}
    totals = {name: {"results": 0.0, "dropped": 0, "latency": [], "cpu": []} for name in setups}
    names = list(setups)
    for r in range(args.ab):
        for name in (names if r % 2 == 0 else names[::-1]):
            worker_module.LIVE_BUFFER_PAIRS, window._display_yield.slowed_s = setups[name]
            rate, _, _, dropped, _ = with_gui(args.seconds)
            totals[name]["results"] += rate * args.seconds
            totals[name]["dropped"] += dropped
            totals[name]["latency"] += latencies
            totals[name]["cpu"].append(display_cpu_ms[-1])
            print(f"round {r + 1} {name:32s}: {rate:6.1f} results/s, dropped {dropped:4d}, "
                  f"latency p50 {_pct(latencies, 50):.1f} / p99 {_pct(latencies, 99):.1f} ms, "
                  f"display-side CPU {display_cpu_ms[-1]:.1f} ms a pair shown", flush=True)
    window.close()
    print("\nTotals")
    for name, t in totals.items():
        share = t["dropped"] / max(t["results"] + t["dropped"], 1.0)
        print(f"  {name:32s}: {100 * share:.2f} % of the camera pairs dropped ({t['dropped']}), latency p50 "
              f"{_pct(t['latency'], 50):.1f} / p99 {_pct(t['latency'], 99):.1f} ms, display-side CPU "
              f"{statistics.median(t['cpu']):.1f} ms a pair shown (median of the phases)")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=20.0, help="length of each phase")
    ap.add_argument("--rounds", type=int, default=2, help="alone/GUI phase pairs")
    ap.add_argument("--size", default="1280x720", help="demo frame size WxH")
    ap.add_argument("--realtime", action="store_true", help="pace the demo at its 120 fps instead of flat out")
    ap.add_argument("--hide", nargs="*", default=[], choices=["3D", "plan", "side"],
                    help="hide these court views during the GUI phases (each view's share of the cost)")
    ap.add_argument("--nycu", type=int, default=0, metavar="PAIRS",
                    help="instead of the demo court: PAIRS pairs of a NYCU rally (2048×1536) held in "
                         "memory and delivered as live cameras at the rig's 119 fps (forwards, then "
                         "backwards, so the tracker never sees a cut); the tracker keeps up or drops")
    ap.add_argument("--skip", type=int, default=200, help="--nycu: pairs of the rally skipped first")
    ap.add_argument("--preset", default=None, help="tracker preset (default: the default preset)")
    ap.add_argument("--live-buffer", type=int, default=None, metavar="PAIRS",
                    help="camera pairs the live grabber keeps (default: gui/worker.py LIVE_BUFFER_PAIRS; "
                         "1 = newest pair only)")
    ap.add_argument("--ab", type=int, default=0, metavar="ROUNDS",
                    help="only: ROUNDS rounds of two window phases, the live buffer at 1 pair with the "
                         "court views never slowed (the older display) against today's "
                         "defaults, in alternating order; totals of pairs tracked and dropped per set-up")
    ap.add_argument("--no-yield", action="store_true",
                    help="keep the court views at their normal rate while tracking is behind "
                         "(gui/keep_up.py DisplayYield off: what the yield saves)")
    ap.add_argument("--switch-interval", type=float, default=None,
                    help="GIL switch interval in s (default: what badminton-gui sets)")
    args = ap.parse_args()
    size = tuple(int(v) for v in args.size.lower().split("x"))
    os.environ.setdefault("BADMINTON_GUI_SETTINGS",
                          str(Path(tempfile.mkdtemp(prefix="gui-timing-")) / "settings.ini"))

    import pyqtgraph as pg
    from PySide6.QtCore import QCoreApplication, Qt
    from PySide6.QtWidgets import QApplication

    from badminton_gui.gui import feed_view
    from badminton_gui.gui.main_window import MainWindow
    from badminton_gui.gui import worker as worker_module
    from badminton_gui.gui.worker import TrackingWorker
    if args.live_buffer:
        worker_module.LIVE_BUFFER_PAIRS = args.live_buffer
    # Every result's latency (frame available → result; with a live source the wait in the
    # grabber's buffer included), recorded where the worker makes its statistics.
    latencies: list[float] = []
    real_stats = worker_module.WorkerStats

    def recording_stats(**fields):
        latencies.append(fields.get("latency_ms", float("nan")))
        return real_stats(**fields)
    worker_module.WorkerStats = recording_stats
    from badminton_gui.io.demo_scene import DemoScene

    from badminton_gui.io.presets import load_preset
    params = load_preset(args.preset)
    if args.nycu:
        replay = _NycuReplay.load(args.nycu, args.skip)

        def opener():
            return replay.restart(), replay.rig
    else:
        def opener():
            scene = DemoScene(seed=0, size=size)
            return scene, scene.rig

    QCoreApplication.setAttribute(Qt.ApplicationAttribute.AA_ShareOpenGLContexts)
    from badminton_gui.gui import app as gui_app
    sys.setswitchinterval(args.switch_interval if args.switch_interval is not None
                          else getattr(gui_app, "GIL_SWITCH_INTERVAL", 0.001))
    print(f"GIL switch interval {sys.getswitchinterval() * 1000:.2f} ms")
    app = QApplication(sys.argv[:1])

    # ---- instrumentation (class level, so every instance is timed) -------------------------
    times: dict[str, list[float]] = defaultdict(list)
    pending_set: dict[int, float] = {}     # feed id → set_frame ms waiting for its paint
    shown_at: dict[str, list[float]] = defaultdict(list)   # feed → times a new frame was painted
    feed_ids: dict[int, str] = {}

    def timed(cls, name, key, after=None):
        original = getattr(cls, name)

        @functools.wraps(original)
        def wrapper(self, *a, **k):
            t0 = time.perf_counter()
            out = original(self, *a, **k)
            ms = (time.perf_counter() - t0) * 1000.0
            if after is None:
                times[key].append(ms)
            else:
                after(self, ms)
            return out
        setattr(cls, name, wrapper)

    def after_set(feed, ms):
        if id(feed) in feed_ids:
            pending_set[id(feed)] = ms
            times[f"set_frame {feed_ids[id(feed)]}"].append(ms)

    def after_paint(feed, ms):
        if id(feed) not in feed_ids:
            return
        name = feed_ids[id(feed)]
        times[f"paintEvent {name}"].append(ms)
        if id(feed) in pending_set:
            times[f"frame-to-screen {name}"].append(pending_set.pop(id(feed)) + ms)
            shown_at[name].append(time.perf_counter())

    refresh_with_packet: list[float] = []
    refresh_all: list[float] = []
    original_refresh = MainWindow._refresh_display

    def refresh(self):
        before = self.results_seen
        t0 = time.perf_counter()
        original_refresh(self)
        ms = (time.perf_counter() - t0) * 1000.0
        refresh_all.append(ms)
        if self.results_seen != before:
            refresh_with_packet.append(ms)
    MainWindow._refresh_display = refresh
    if hasattr(MainWindow, "_late_poll"):
        timed(MainWindow, "_late_poll", "late-poll slot (a tick found no packet)")

    timed(feed_view.FeedView, "set_frame", None, after_set)
    timed(feed_view.FeedView, "paintEvent", None, after_paint)
    from badminton_gui.gui import court_views, main_window as mw
    if not court_views.gl_unavailable_reason():
        timed(court_views._gl_window_class(), "paintGL", "3D paintGL")
    timed(court_views.CourtGLView, "show_packet", "slot part: 3D show_packet")
    timed(court_views.CourtPlanView, "show_packet", "slot part: plan show_packet")
    timed(court_views.SideView, "show_packet", "slot part: side show_packet")
    timed(mw.Readouts, "show_packet", "slot part: readouts show_packet")
    timed(pg.GraphicsView, "paintEvent", "2D plots paintEvent")

    from PySide6.QtCore import QEventLoop, QTimer

    def pump(seconds: float) -> None:
        """Run the event loop like app.exec() for a while (no busy polling to skew the figures)."""
        loop = QEventLoop()
        QTimer.singleShot(int(seconds * 1000), loop.quit)
        loop.exec()

    # ---- phases ----------------------------------------------------------------------------
    def rate_of(sample_a, sample_b) -> float:
        (ta, fa), (tb, fb) = sample_a, sample_b
        return (fb - fa) / (tb - ta) if tb > ta else float("nan")

    def latency_text(values: list[float]) -> str:
        return f"latency p50 {_pct(values, 50):.1f} / p99 {_pct(values, 99):.1f} ms"

    def alone(seconds: float) -> tuple[float, float]:
        latencies.clear()
        cpu0, t0 = _cpu_by_thread(), time.perf_counter()
        # No window, nobody asks for display packets: the tracker as a headless user runs it.
        worker = TrackingWorker(opener, params, realtime=args.realtime)
        thread = threading.Thread(target=worker.run, daemon=True, name="tracking")
        thread.start()
        samples, ms = [], []
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            time.sleep(0.25)
            st = worker.latest_stats
            if st is not None:
                samples.append((time.perf_counter(), st.frames))
                ms.append(st.processing_ms)
        cpu_use = _cpu_delta(cpu0, _cpu_by_thread(), time.perf_counter() - t0)
        worker.abort()
        thread.join(10)
        warm = [s for s in samples if s[0] >= samples[0][0] + 2.0] if samples else []
        dropped = worker.latest_stats.dropped if worker.latest_stats is not None else 0
        if args.nycu:
            cpu_use += f"; dropped {dropped} camera pairs, {latency_text(latencies)}"
        return (rate_of(warm[0], warm[-1]) if len(warm) > 1 else float("nan"),
                statistics.median(ms) if ms else float("nan"), cpu_use)

    window = MainWindow(start=False)
    if args.preset:
        window.use_preset(args.preset)
    if args.no_yield:
        window._display_yield.slowed_s = window._display_yield.normal_s
    window.resize(1280, 720)
    window.show()
    window.realtime_action.setChecked(args.realtime)
    # A hidden view is skipped by the display (MainWindow._refresh_slow_views draws only views on
    # screen), so hiding one measures what it costs the tracking rate.
    hidden = {"3D": window.gl_view.widget if window.gl_view is not None else None,
              "plan": window.plan.widget, "side": window.side.widget}
    for name in args.hide:
        if hidden[name] is not None:
            hidden[name].hide()
    feed_ids[id(window.left_feed)] = "left"
    feed_ids[id(window.right_feed)] = "right"

    def with_gui(seconds: float) -> tuple[float, float, float, float]:
        latencies.clear()
        cpu0, t0 = _cpu_by_thread(), time.perf_counter()
        sched0 = _gui_thread_sched()
        ticks0 = len(refresh_all)
        window.start_opener(opener, "demo (timing)")
        samples, ms = [], []
        n_before = window.results_seen
        views0 = dict(window.slow_view_updates)
        end = time.monotonic() + seconds
        t_first = None
        slowed = []
        while time.monotonic() < end:
            pump(0.25)
            slowed.append(window._display_yield.slowed)
            p = window.latest_packet
            st = window.worker.latest_stats if window.worker is not None else None
            if st is not None:
                samples.append((time.perf_counter(), st.frames))
                ms.append(st.processing_ms)
            if p is not None and t_first is None:
                t_first, n_first = time.perf_counter(), window.results_seen
        built = window.worker.packets_built if window.worker is not None else 0
        shown = (window.results_seen - n_first) / (time.perf_counter() - t_first) if t_first else 0.0
        cpu1 = _cpu_by_thread()
        cpu_use = _cpu_delta(cpu0, cpu1, time.perf_counter() - t0)
        span = time.perf_counter() - t0
        sched1 = _gui_thread_sched()
        frames_shown = window.results_seen - n_before
        display_cpu_ms.append(_display_side_cpu(cpu0, cpu1) * 1000.0 / max(frames_shown, 1))
        cpu_use += (f"; {latency_text(latencies)}; display timer ran {(len(refresh_all) - ticks0) / span:.1f} ticks/s; GUI thread "
                    f"on a CPU {(sched1[0] - sched0[0]) / span * 100:.0f}% of the time, runnable but "
                    f"waiting for a CPU {(sched1[1] - sched0[1]) / span * 100:.0f}%, the rest idle or "
                    f"blocked (event loop, GIL); worker built {built / span:.1f} display packets/s; "
                    f"3D view {(window.slow_view_updates.get('3D', 0) - views0.get('3D', 0)) / span:.1f} "
                    f"updates/s, slowed for tracking {100.0 * sum(slowed) / max(len(slowed), 1):.0f}% of the time")
        window.stop_worker()
        warm = [s for s in samples if s[0] >= samples[0][0] + 2.0] if samples else []
        return (rate_of(warm[0], warm[-1]) if len(warm) > 1 else float("nan"),
                statistics.median(ms) if ms else float("nan"), shown,
                p.stats.dropped if p is not None else 0, cpu_use)

    pump(1.0)
    what = (f"NYCU rally as live cameras, 2048×1536 at {_NycuReplay.FPS:.0f} fps, {args.nycu} pairs in memory"
            if args.nycu else f"demo {size[0]}×{size[1]}, {'real-time' if args.realtime else 'as fast as possible'}")
    print(f"{what}, preset {args.preset or 'default'}, live buffer {worker_module.LIVE_BUFFER_PAIRS} pairs, "
          f"court views {'not ' if args.no_yield else ''}slowed while tracking is behind, "
          f"window {window.width()}×{window.height()}, feeds "
          f"{window.left_feed.width()}×{window.left_feed.height()}, "
          f"{'3D + 2D views' if window.gl_view is not None else '2D views only'}"
          + (f", hidden: {', '.join(args.hide)}" if args.hide else ""))
    alone_fps, gui_fps, feed_hz, display_cpu_ms = [], [], defaultdict(list), []
    if args.ab:
        return _alternate(args, window, with_gui, latencies, worker_module, display_cpu_ms)
    for r in range(args.rounds):
        fps_a, ms_a, cpu_a = alone(args.seconds)
        alone_fps.append(fps_a)
        print(f"round {r + 1} tracker alone : {fps_a:6.1f} results/s, tracker {ms_a:5.1f} ms/pair (median)")
        print(f"    CPU (% of one core): {cpu_a}")
        t_phase = time.perf_counter()
        fps_g, ms_g, shown, dropped, cpu_g = with_gui(args.seconds)
        gui_fps.append(fps_g)
        for name, stamps in shown_at.items():     # new frames painted per second, after 2 s warm-up
            warm = [t for t in stamps if t >= t_phase + 2.0]
            if len(warm) > 1:
                feed_hz[name].append((len(warm) - 1) / (warm[-1] - warm[0]))
        print(f"round {r + 1} with the GUI  : {fps_g:6.1f} results/s, tracker {ms_g:5.1f} ms/pair (median), "
              f"display {shown:5.1f} Hz, dropped {dropped}; with/alone {fps_g / fps_a:.2f}")
        print(f"    CPU (% of one core): {cpu_g}")
    window.close()

    print(f"\nGUI thread, ms (n, median, p95, p99, max) over all GUI phases:")
    rows = [("display slot (refreshes that took a packet)", refresh_with_packet),
            ("display slot (all timer ticks)", refresh_all)]
    rows += [(k, v) for k, v in sorted(times.items())]
    for name, values in rows:
        print(f"  {name:46s} n={len(values):5d}  median {_pct(values, 50):6.2f}  p95 {_pct(values, 95):6.2f}  "
              f"p99 {_pct(values, 99):6.2f}  max {max(values) if values else float('nan'):7.2f}")

    # The figures, in one place.
    print("\nSummary (goal: both feeds at 30 Hz, tracking rate unchanged, frame-to-screen <= 2 ms per feed)")
    print("  tracking results/s alone   : " + ", ".join(f"{v:.1f}" for v in alone_fps))
    print("  tracking results/s with GUI: " + ", ".join(f"{v:.1f}" for v in gui_fps))
    print("  ratio with/alone per round : " + ", ".join(f"{g / a:.2f}" for g, a in zip(gui_fps, alone_fps))
          + f"; all rounds {sum(gui_fps) / sum(alone_fps):.2f}")
    for name in ("left", "right"):
        f2s = times.get(f"frame-to-screen {name}", [])
        print(f"  {name:5s} feed: display " + "/".join(f"{v:.1f}" for v in feed_hz.get(name, [])) +
              f" Hz per round; frame-to-screen median {_pct(f2s, 50):.2f} ms, p95 {_pct(f2s, 95):.2f} ms")
    print("  display-side CPU (GUI thread + GL rasterizer + X server) per frame pair shown: "
          + ", ".join(f"{v:.1f}" for v in display_cpu_ms) + " ms per round")
    print(f"  display slot (ticks with a packet): median {_pct(refresh_with_packet, 50):.2f} ms, "
          f"p95 {_pct(refresh_with_packet, 95):.2f} ms, max {max(refresh_with_packet, default=float('nan')):.2f} ms")
    app.quit()
    return 0


if __name__ == "__main__":
    sys.exit(main())

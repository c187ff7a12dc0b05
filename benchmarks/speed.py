"""Speed of the tracker against the plain full-resolution chain, measured in the same run.

    .venv/bin/python benchmarks/speed.py [--pairs 300] [--long 10000] [--profile]

For each resolution (2048×1536 NYCU frames as recorded, and the same frames resized to 1280×720
and 640×480) it prints:
  - pairs/s of ``StereoTracker.process`` on frames already in memory, and the ratio to the
    *plain chain* — MOG2 + threshold + open + findContours + the four filters, per camera, one
    camera after the other, at full resolution (the paper written plainly) — timed on the same
    frames in the same run (absolute times drift ±15–25 % between runs on shared machines, ratios do not);
  - latency from a frame pair to its TrackResult, p50 / p99, and the process's voluntary context
    switches a pair (a thread waiting, mostly for the GIL);
  - peak RSS;
  - the F1 (TrackNet protocol, both cameras) of the tracker at that resolution on NYCU rallies
    (``--f1-rallies``; detections scaled back to the recorded 2048 px, so the tolerance is the
    same 16 px there), decoded once and fed to one tracker per resolution.
Then the file processing figures (`track` on a NYCU rally, decoding included: pairs/s and the
share of time spent decoding vs tracking), resident memory after 1000 and after ``--long`` pairs
of the NYCU rallies decoded at full resolution one after another into one tracker, as a camera
would deliver them (current RSS, and the peak since the long run began: the kernel's peak is
reset first, so the frames held in memory by the timing runs do not hide growth), and
with ``--profile`` a cProfile summary of where the tracker's time goes. The tracker runs with one
OpenCV thread, as ``track`` and the GUI run it (``--cv-threads 0``: OpenCV's own pool; the plain
chain always keeps OpenCV's default): the two camera threads already use both cores, and OpenCV's
pool on top of them costs CPU.

``--trees DIR [DIR ...]`` compares source trees (other commits, extracted with ``git archive``)
in this process, interleaved pair by pair: thread CPU a pair and its paired difference.

``--process-bound`` measures instead what the GIL costs at 2048 px: each camera's
``CameraDetector`` in its own process (one OpenCV thread each, its own frames in memory, both
started together) against ``StereoTracker`` with its two camera threads on the same frames, and
``StereoTracker`` one-threaded. The process figure is a bound (detector only: no stereo choice,
triangulation or trajectory, and no frame crossing a process boundary), for planning. Then,
alternating, the tracker's two threads against the two detector processes fed the way a tracker
would have to feed them (each frame copied into the process's shared memory, the
``CameraResult`` pickled back): pairs/s, p99, and the CPU a pair costs each way.

``--stages`` splits the CPU a pair (one thread) between each camera's candidate stage and the
stereo stage; ``--processes`` runs ``StereoTracker`` with its camera threads and with a process
per camera (``processes=True``; frames copied into the workers' shared memory, or found there
already) alternately on the same frames: pairs/s, latency, the CPU a pair including the
workers', and a digest of the outputs, which must match.

First of all it prints how fast the demo court renders at 1280×720 (the GUI's demo must render
faster than the cameras' rate it imitates); that part needs no data.

The rest needs ../shared/data/nycu-stereo (or $BADMINTON_DATA/nycu-stereo). Tests never assert on these figures.
"""

from __future__ import annotations

import argparse
import cProfile
import dataclasses
import importlib
import io
import math
import pstats
import resource
import sys
import time
from pathlib import Path

import cv2
import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from badminton_gui.core.params import TrackerParams  # noqa: E402
from badminton_gui.core.rig import StereoRig  # noqa: E402
from badminton_gui.core.tracker import StereoTracker  # noqa: E402
from badminton_gui.io.labels import read_timestamps  # noqa: E402
from badminton_gui.io.nycu import rig_from_nycu  # noqa: E402
from badminton_gui.io.presets import load_preset  # noqa: E402
from badminton_gui.io.video import VideoPair  # noqa: E402

sys.path.insert(0, str(REPO / "benchmarks"))
from clips import DATA_DIR  # noqa: E402  (../shared/data, or $BADMINTON_DATA as for accuracy.py)

DATA = DATA_DIR / "nycu-stereo"
RALLY = "rally_11-46-04"


def peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _status_mb(key: str) -> float:
    """A memory line of /proc/self/status (VmRSS: now, VmHWM: peak since the last reset), MB."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(key + ":"):
            return int(line.split()[1]) / 1024.0
    return float("nan")


def reset_peak_rss() -> bool:
    """Reset the kernel's peak-RSS mark (Linux: write 5 to clear_refs); False if refused."""
    try:
        Path("/proc/self/clear_refs").write_text("5")
        return True
    except OSError:
        return False


class PlainChain:
    """The paper's chain written plainly, one camera: the baseline every speed-up is measured against."""

    def __init__(self) -> None:
        self.mog = cv2.createBackgroundSubtractorMOG2(history=200, varThreshold=16, detectShadows=False)
        self.kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3))
        self.last: tuple[float, float] | None = None

    def process(self, frame: np.ndarray) -> tuple[float, float] | None:
        mask = self.mog.apply(frame, learningRate=0.03)
        _, mask = cv2.threshold(mask, 150, 255, cv2.THRESH_BINARY)
        mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, self.kernel)
        contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        best = None
        for c in contours:
            length = cv2.arcLength(c, True)
            if not 4 <= length <= 250:
                continue
            (cx, cy), (w, h), _ = cv2.minAreaRect(c)
            if not 1 <= min(w, h) <= 30:
                continue
            x, y, bw, bh = cv2.boundingRect(c)
            patch = frame[y:y + bh, x:x + bw]
            whiteness = float(patch.min(axis=2).mean())
            if whiteness < 100:
                continue
            dist = 0.0 if self.last is None else math.hypot(cx - self.last[0], cy - self.last[1])
            if self.last is not None and dist > 200:
                continue
            if best is None or dist < best[0]:
                best = (dist, (cx, cy))
        if best is not None:
            self.last = best[1]
        return None if best is None else best[1]


def load_pairs(n: int, size: tuple[int, int] | None, skip: int = 0
               ) -> list[tuple[np.ndarray, np.ndarray, float]]:
    d = DATA / RALLY
    lt = read_timestamps(d / "CameraReader_1.csv")[1]
    rt = read_timestamps(d / "CameraReader_2.csv")[1]
    src = VideoPair(d / "CameraReader_1.mp4", d / "CameraReader_2.mp4", lt, rt)
    pairs = []
    try:
        while len(pairs) < n:
            f = src.read()
            if f is None:
                break
            if skip > 0:
                skip -= 1
                continue
            left, right = f.left, f.right
            if size is not None:
                left = cv2.resize(left, size, interpolation=cv2.INTER_AREA)
                right = cv2.resize(right, size, interpolation=cv2.INTER_AREA)
            pairs.append((left, right, f.t_left))
    finally:
        src.close()
    return pairs


def scaled_rig(rig: StereoRig, size: tuple[int, int]) -> StereoRig:
    """The same rig for frames resized to ``size`` (intrinsics scaled)."""
    sx = size[0] / rig.image_size[0]
    sy = size[1] / rig.image_size[1]
    s = np.diag([sx, sy, 1.0])
    return StereoRig(s @ rig.M1, rig.D1, s @ rig.M2, rig.D2, rig.R, rig.T, size,
                     R_court=rig.R_court, T_court=rig.T_court)


class opencv_threads:
    """Context: OpenCV's own thread count set to ``n`` (None: leave it), restored on exit."""

    def __init__(self, n: int | None) -> None:
        self.n = n
        self.saved = cv2.getNumThreads()

    def __enter__(self):
        if self.n is not None:
            cv2.setNumThreads(self.n)

    def __exit__(self, *exc) -> None:
        cv2.setNumThreads(self.saved)


def time_plain(pairs) -> float:
    left, right = PlainChain(), PlainChain()
    start = time.perf_counter()
    for lf, rf, _ in pairs:
        left.process(lf)
        right.process(rf)
    return len(pairs) / (time.perf_counter() - start)


def time_tracker(pairs, rig: StereoRig, params: TrackerParams, repeat: int = 1, switches: list | None = None):
    """(pairs/s, latency p50, p99 ms). ``switches``, if given, gets the process's voluntary context
    switches a pair: how often a thread waited (for the GIL, mostly) — two camera threads that
    hand the GIL to each other at every small OpenCV call made ≈ 65 a pair (README Speed)."""
    tracker = StereoTracker(rig, params)
    lat = []
    before = resource.getrusage(resource.RUSAGE_SELF).ru_nvcsw
    start = time.perf_counter()
    for _ in range(repeat):
        for lf, rf, t in pairs:
            t0 = time.perf_counter()
            tracker.process(lf, rf, t, keep_masks=False)
            lat.append(time.perf_counter() - t0)
    rate = len(lat) / (time.perf_counter() - start)
    if switches is not None:
        switches.append((resource.getrusage(resource.RUSAGE_SELF).ru_nvcsw - before) / max(len(lat), 1))
    tracker.close()
    lat_ms = np.asarray(lat) * 1000
    return rate, float(np.percentile(lat_ms, 50)), float(np.percentile(lat_ms, 99))


def file_processing(rig: StereoRig, params: TrackerParams, n: int) -> tuple[float, float]:
    d = DATA / RALLY
    lt = read_timestamps(d / "CameraReader_1.csv")[1]
    rt = read_timestamps(d / "CameraReader_2.csv")[1]
    src = VideoPair(d / "CameraReader_1.mp4", d / "CameraReader_2.mp4", lt, rt)
    tracker = StereoTracker(rig, params)
    decode = track = 0.0
    count = 0
    try:
        while count < n:
            t0 = time.perf_counter()
            f = src.read()
            t1 = time.perf_counter()
            if f is None:
                break
            tracker.process(f.left, f.right, f.t_left, f.index, f.index_right, keep_masks=False)
            t2 = time.perf_counter()
            decode += t1 - t0
            track += t2 - t1
            count += 1
    finally:
        src.close()
        tracker.close()
    return count / (decode + track), decode / (decode + track)


def long_run(rig: StereoRig, params: TrackerParams, n: int) -> tuple[dict[int, tuple[float, float]], int, bool]:
    """Resident memory over a long run as the cameras would give it: the NYCU rallies at full
    resolution decoded one after another into one tracker (each rally's times shifted to start
    a second after the last one ended: a pause between rallies), again from the first when they
    run out, until ``n`` pairs. Returns {pairs: (RSS MB now, peak MB since the start)} after
    1 000 pairs and after ``n``, the number of rallies started, and whether the kernel's peak
    mark could be reset (else the peak is the process's, frames of earlier runs included)."""
    rallies = sorted(p for p in DATA.iterdir() if (p / "CameraReader_1.mp4").exists())
    tracker = StereoTracker(rig, params)
    reset = reset_peak_rss()
    rss: dict[int, tuple[float, float]] = {}
    count, offset, started = 0, 0.0, 0
    try:
        while count < n:
            d = rallies[started % len(rallies)]
            started += 1
            lt = read_timestamps(d / "CameraReader_1.csv")[1]
            rt = read_timestamps(d / "CameraReader_2.csv")[1]
            src = VideoPair(d / "CameraReader_1.mp4", d / "CameraReader_2.mp4", lt, rt)
            last = offset
            try:
                while count < n:
                    f = src.read()
                    if f is None:
                        break
                    last = offset + f.t_left
                    tracker.process(f.left, f.right, last, keep_masks=False)
                    count += 1
                    if count in (1000, n):
                        rss[count] = (_status_mb("VmRSS"), _status_mb("VmHWM"))
            finally:
                src.close()
            offset = last + 1.0
    finally:
        tracker.close()
    return rss, started, reset


F1_RALLIES = ("rally_11-46-04", "rally_11-49-21")   # one tuned-on, one held-out (benchmarks/clips.py)


def f1_by_resolution(full_rig: StereoRig, params: TrackerParams, sizes, rallies,
                     max_pairs: int) -> dict:
    """F1 of the tracker at each size on the rallies: one decode, one tracker per size."""
    from badminton_gui.core.evaluation import Outcomes, evaluate, tolerance_px
    from badminton_gui.io.labels import read_point_labels

    native = full_rig.image_size
    totals = {size: Outcomes() for size in sizes}
    for name in rallies:
        d = DATA / name
        lt = read_timestamps(d / "CameraReader_1.csv")[1]
        rt = read_timestamps(d / "CameraReader_2.csv")[1]
        src = VideoPair(d / "CameraReader_1.mp4", d / "CameraReader_2.mp4", lt, rt)
        trackers = {size: StereoTracker(full_rig if size is None else scaled_rig(full_rig, size), params)
                    for size in sizes}
        preds = {size: ({}, {}) for size in sizes}
        try:
            for _ in range(max_pairs):
                f = src.read()
                if f is None:
                    break
                for size, tracker in trackers.items():
                    if size is None:
                        lf, rf, sx, sy = f.left, f.right, 1.0, 1.0
                    else:
                        lf = cv2.resize(f.left, size, interpolation=cv2.INTER_AREA)
                        rf = cv2.resize(f.right, size, interpolation=cv2.INTER_AREA)
                        sx, sy = native[0] / size[0], native[1] / size[1]
                    r = tracker.process(lf, rf, f.t_left, f.index, f.index_right, keep_masks=False)
                    left, right = preds[size]
                    for out, det, idx in ((left, r.left.detection, f.index),
                                          (right, r.right.detection, f.index_right)):
                        entry = (True, det.x * sx, det.y * sy) if det else (False, 0.0, 0.0)
                        if idx not in out or not out[idx][0]:
                            out[idx] = entry
        finally:
            src.close()
            for tracker in trackers.values():
                tracker.close()
        for cam, labels_path in ((0, d / "CameraReader_1.csv"), (1, d / "CameraReader_2.csv")):
            labels = read_point_labels(labels_path).as_dict()
            for size in sizes:
                pred = preds[size][cam]
                last = max(pred) if pred else -1
                totals[size] = totals[size] + evaluate(
                    pred, {k: v for k, v in labels.items() if k <= last}, tolerance_px(native[0]))
    return totals


def demo_render_rate(n: int = 300, size: tuple[int, int] = (1280, 720)) -> tuple[float, float]:
    """Frame pairs per second the demo court renders at ``size``, and the demo's own frame rate."""
    from badminton_gui.io.demo_scene import DemoScene

    scene = DemoScene(seed=0, size=size, rig="binocular", n_frames=n + 10)
    try:
        for _ in range(10):      # warm-up: first shot generated, caches filled
            scene.read()
        start = time.perf_counter()
        count = 0
        while scene.read() is not None:
            count += 1
        return count / (time.perf_counter() - start), float(scene.fps)
    finally:
        scene.close()


def _detector_process(camera: int, n: int, preset: str | None, barrier, out) -> None:
    """One camera's detector alone in this process, over its own frames: (camera, frames/s, CPU ms)."""
    from badminton_gui.core.detector import CameraDetector
    cv2.setNumThreads(1)
    frames = [(pair[camera], pair[2]) for pair in load_pairs(n, None)]
    detector = CameraDetector(load_preset(preset))
    for frame, t in frames[:20]:                     # warm the background model up
        detector.process(frame, t, keep_mask=False)
    barrier.wait()
    cpu, wall = time.thread_time(), time.perf_counter()
    for frame, t in frames:
        detector.process(frame, t + 100.0, keep_mask=False)   # a later clock: no time reversal
    wall = time.perf_counter() - wall
    out.put((camera, len(frames) / wall, 1000 * (time.thread_time() - cpu) / len(frames)))


def _handover_worker(conn, shm_name: str, shape: tuple[int, ...], preset: str | None) -> None:
    """One camera's detector in this process, reading each frame from shared memory."""
    import pickle
    from multiprocessing import shared_memory

    from badminton_gui.core.detector import CameraDetector
    cv2.setNumThreads(1)
    shm = shared_memory.SharedMemory(name=shm_name)
    frame = np.ndarray(shape, np.uint8, buffer=shm.buf)
    detector = CameraDetector(load_preset(preset))
    cpu = 0.0
    try:
        while True:
            t = conn.recv()
            if t is None:
                break
            start = time.thread_time()
            result = detector.process(frame, t, keep_mask=False)
            conn.send_bytes(pickle.dumps(result, protocol=pickle.HIGHEST_PROTOCOL))
            cpu += time.thread_time() - start
        conn.send(cpu)
    finally:
        del frame
        shm.close()


def processes_with_handover(pairs, preset: str | None) -> tuple[float, float, float, float, list[float]]:
    """Each camera's detector in its own process, fed as a tracker would have to feed it.

    The parent copies each frame into that camera's shared memory, sends the timestamp, and
    unpickles the ``CameraResult`` that comes back (no stereo choice: a bound on what a
    process per camera could give when the frames arrive in the parent's memory).
    Returns (pairs/s, p99 latency ms, parent CPU ms a pair, of it copying, workers' CPU ms a frame).
    """
    import multiprocessing as mp
    import pickle
    from multiprocessing import shared_memory

    ctx = mp.get_context("fork")
    shape = pairs[0][0].shape
    shms = [shared_memory.SharedMemory(create=True, size=int(np.prod(shape))) for _ in range(2)]
    views = [np.ndarray(shape, np.uint8, buffer=shm.buf) for shm in shms]
    links, procs = [], []
    try:
        for shm in shms:
            ours, theirs = ctx.Pipe()
            proc = ctx.Process(target=_handover_worker, args=(theirs, shm.name, shape, preset), daemon=True)
            proc.start()
            links.append(ours)
            procs.append(proc)
        for view in views:
            view[:] = 0                                  # pages touched before timing
        latency, copying = [], 0.0
        cpu, wall = time.process_time(), time.perf_counter()
        for left, right, t in pairs:
            t0 = time.perf_counter()
            c0 = time.thread_time()
            for view, link, frame in ((views[0], links[0], left), (views[1], links[1], right)):
                np.copyto(view, frame)
                link.send(t)
            copying += time.thread_time() - c0
            for link in links:
                pickle.loads(link.recv_bytes())
            latency.append(time.perf_counter() - t0)
        wall = time.perf_counter() - wall
        parent = 1000 * (time.process_time() - cpu) / len(pairs)
        for link in links:
            link.send(None)
        workers = [1000 * link.recv() / len(pairs) for link in links]
    finally:
        for proc in procs:
            proc.join(timeout=10)
            if proc.is_alive():
                proc.terminate()
        del views
        for shm in shms:
            shm.close()
            shm.unlink()
    return (len(pairs) / wall, float(np.percentile(np.asarray(latency) * 1000, 99)), parent,
            1000 * copying / len(pairs), workers)


def process_bound(full_rig: StereoRig, preset: str | None, n: int) -> None:
    import multiprocessing as mp
    ctx = mp.get_context("fork")
    barrier, out = ctx.Barrier(2), ctx.Queue()
    procs = [ctx.Process(target=_detector_process, args=(c, n, preset, barrier, out)) for c in (0, 1)]
    for proc in procs:
        proc.start()
    per_camera = sorted(out.get() for _ in procs)
    for proc in procs:
        proc.join()
    print("two processes, detector only: " + "; ".join(
        f"camera {c + 1} {rate:.1f} frames/s ({cpu:.2f} ms CPU a frame)" for c, rate, cpu in per_camera)
        + f" -> at most {min(r for _, r, _ in per_camera):.1f} pairs/s")
    pairs = load_pairs(n, None)
    params = load_preset(preset)
    # Threads and handed-over processes alternate (the machine's load drifts between runs).
    for round_ in range(2):
        for mode in (("threads", "processes") if round_ == 0 else ("processes", "threads")):
            if mode == "threads":
                with opencv_threads(1):
                    tracker = StereoTracker(full_rig, params)
                    cpu, wall = time.process_time(), time.perf_counter()
                    latency = []
                    for lf, rf, t in pairs:
                        t0 = time.perf_counter()
                        tracker.process(lf, rf, t, keep_masks=False)
                        latency.append(time.perf_counter() - t0)
                    wall = time.perf_counter() - wall
                    tracker.close()
                print(f"round {round_ + 1}, StereoTracker, two camera threads: {len(pairs) / wall:6.1f} pairs/s, "
                      f"p99 {np.percentile(np.asarray(latency) * 1000, 99):5.1f} ms, "
                      f"{1000 * (time.process_time() - cpu) / len(pairs):5.2f} ms CPU a pair")
            else:
                rate, p99, parent, copying, workers = processes_with_handover(pairs, preset)
                print(f"round {round_ + 1}, two detector processes, frames handed over: {rate:6.1f} pairs/s, "
                      f"p99 {p99:5.1f} ms, parent {parent:5.2f} ms CPU a pair (copying the frames "
                      f"{copying:4.2f}), each worker " + " / ".join(f"{w:4.2f}" for w in workers)
                      + f" ms CPU a frame: {parent + sum(workers):5.2f} ms CPU a pair in all")
    for threads in (2, 1):
        with opencv_threads(threads):
            for parallel in (True, False):
                tracker = StereoTracker(full_rig, params, parallel=parallel)
                cpu, wall = time.process_time(), time.perf_counter()
                for lf, rf, t in pairs:
                    tracker.process(lf, rf, t, keep_masks=False)
                wall = time.perf_counter() - wall
                tracker.close()
                print(f"StereoTracker, {'two camera threads' if parallel else 'one thread':>18}, "
                      f"OpenCV threads {threads}: {len(pairs) / wall:6.1f} pairs/s, "
                      f"{1000 * (time.process_time() - cpu) / len(pairs):5.2f} ms CPU a pair")


def stage_cpu(full_rig: StereoRig, params: TrackerParams, n: int, skip: int, preset: str | None) -> tuple:
    """The thread CPU a pair spends in each camera's candidate stage (``plan_window`` and
    ``find_candidates``: stages 1–4) and in the rest of ``StereoTracker.process`` (the stereo
    stage: pairing, vouch, look, hold, 3D, flight, phase), one thread (``parallel=False``), 2048 px.
    CPU time, not wall: the machine's load stretches the wall clock but hardly the CPU a pair.
    Returns (left, right, stereo) ms a pair, means."""
    pairs = load_pairs(n, None, skip)
    tracker = StereoTracker(full_rig, params, parallel=False)
    spent = {"left": 0.0, "right": 0.0}
    for side, det in (("left", tracker.left), ("right", tracker.right)):
        for name in ("plan_window", "find_candidates"):
            def timed(*args, _run=getattr(det, name), _side=side, **kw):
                c0 = time.thread_time()
                out = _run(*args, **kw)
                spent[_side] += time.thread_time() - c0
                return out
            setattr(det, name, timed)
    rows = []
    for lf, rf, t in pairs:
        spent["left"] = spent["right"] = 0.0
        c0 = time.thread_time()
        tracker.process(lf, rf, t, keep_masks=False)
        total = time.thread_time() - c0
        rows.append((spent["left"], spent["right"], total - spent["left"] - spent["right"]))
    tracker.close()
    ms = 1000 * np.asarray(rows)
    mean, total = ms.mean(axis=0), ms.sum(axis=1).mean()
    print(f"CPU a pair by stage, {RALLY} pairs {skip}-{skip + len(pairs) - 1}, preset {preset or 'default'}, "
          f"one thread: total {total:.2f} ms; " + ", ".join(
              f"{name} {m:.2f} ms ({100 * m / total:.1f} %, p99 {np.percentile(ms[:, k], 99):.2f})"
              for k, (name, m) in enumerate(zip(("left camera's candidates", "right camera's candidates",
                                                  "stereo stage"), mean))))
    bound = max(mean[0], mean[1]) + mean[2]
    print(f"  a process per camera, the stereo stage after both: at best {bound:.2f} ms a pair on the "
          f"critical path ({1000 / bound:.0f} pairs/s on idle cores) against {total:.2f} ms in turn "
          f"({1000 / total:.0f} pairs/s), before the frames' hand-over")
    return tuple(float(m) for m in mean)


def processes_ab(full_rig: StereoRig, params: TrackerParams, n: int, skip: int, rounds: int,
                 preset: str | None) -> None:
    """``StereoTracker`` with its camera threads against ``StereoTracker(processes=True)`` (each
    camera's detector in a worker process), alternated in this run on the same frames held in
    memory, 2048 px. Two ways of handing the frames over: ``processes`` copies each frame into
    the worker's shared memory (``copying``: this process's CPU doing it), ``proc-shm`` finds each
    pair already in the workers' buffers (``ProcessCameras.frame_buffers``: where a decoder could
    write it; the benchmark's own copy there stands in for the decoding and is not timed).
    Per mode: pairs/s and latency p50 / p99 of ``process``, the CPU a pair (this process's and the
    workers'; of it the workers'), and a digest of the outputs (all must match). The first pair
    is not timed (it waits for the workers to start)."""
    import hashlib
    import os
    pairs = load_pairs(n, None, skip)
    print(f"threads against processes: {RALLY} pairs {skip}-{skip + len(pairs) - 1}, preset {preset or 'default'}")
    print(f"{'round':>5} {'mode':>9} {'pairs/s':>8} {'p50 ms':>7} {'p99 ms':>7} {'CPU/pair':>9} "
          f"{'of it workers':>13} {'copying':>11} {'outputs':>8} {'load':>5}")
    modes = ("threads", "processes", "proc-shm")
    for r in range(rounds):
        for mode in modes[r % 3:] + modes[:r % 3]:
            procs, shm = mode != "threads", mode == "proc-shm"
            tracker = StereoTracker(full_rig, params, processes=procs)

            def placed(lf, rf):
                if not shm:
                    return lf, rf, 0.0
                c = time.process_time()
                bl, br = tracker.cameras.frame_buffers((lf.shape, rf.shape))
                np.copyto(bl, lf)
                np.copyto(br, rf)
                return bl, br, time.process_time() - c

            # The first pair untimed, either way: it waits for the workers to start (imports).
            lf, rf, _ = placed(pairs[0][0], pairs[0][1])
            results = [tracker.process(lf, rf, pairs[0][2], keep_masks=False)]
            workers0 = tracker.cameras.worker_cpu() if procs else 0.0
            copy0 = tracker.cameras.copy_cpu() if procs else 0.0
            lat, untimed = [], 0.0
            c0 = time.process_time()
            for lf, rf, t in pairs[1:]:
                lf, rf, spent = placed(lf, rf)
                untimed += spent
                t0 = time.perf_counter()
                results.append(tracker.process(lf, rf, t, keep_masks=False))
                lat.append(time.perf_counter() - t0)
            cpu = time.process_time() - c0 - untimed
            workers = tracker.cameras.worker_cpu() - workers0 if procs else 0.0
            copying = tracker.cameras.copy_cpu() - copy0 if procs else 0.0
            tracker.close()
            digest = hashlib.sha1()
            for res in results:
                digest.update(repr(dataclasses.replace(res, processing_ms=0.0)).encode())
            lat_ms, timed = np.asarray(lat) * 1000, len(lat)
            print(f"{r + 1:>5} {mode:>9} {timed / sum(lat):8.1f} {np.percentile(lat_ms, 50):7.2f} "
                  f"{np.percentile(lat_ms, 99):7.2f} {1000 * (cpu + workers) / timed:6.2f} ms "
                  f"{1000 * workers / timed:10.2f} ms {1000 * copying / timed:8.2f} ms "
                  f"{digest.hexdigest()[:8]} {os.getloadavg()[0]:5.1f}",
                  flush=True)


def window_ab(full_rig: StereoRig, params: TrackerParams, n: int, skip: int, rounds: int,
              preset: str | None) -> None:
    """Windowed tracking (core/window.py) off and on, alternated in this process, 2048 px.

    Per round and setting: one thread (``parallel=False``), the thread CPU time a pair and a
    camera frame; then the tracker's two camera threads, pairs/s, latency p50 / p99 and the
    process CPU time a pair; the share of camera frames processed in a window, and how many
    pairs had a 3D point (the outputs are not identical: a different model outside the window).
    Last, from the one-thread run: the p99 of the CPU a pair, and a latency model that the
    machine's load does not set (a pair whose cameras both run windowed costs both cameras'
    CPU, in turn; any other pair the slower camera's plus the rest, side by side — a lower
    bound there, the GIL's queueing left out).
    """
    import os
    pairs = load_pairs(n, None, skip)
    on = params.with_value("window.enabled", True)
    off = params.with_value("window.enabled", False)
    print(f"window A/B: {RALLY} pairs {skip}-{skip + len(pairs) - 1}, preset {preset or 'default'}, "
          f"full_every {on.window.full_every}, max_fraction {on.window.max_fraction}, margin {on.window.margin}")
    print(f"{'round':>5} {'window':>6} {'1-thread CPU/pair':>17} {'CPU/frame':>9} {'windowed':>8} "
          f"{'2-thr pairs/s':>13} {'p50':>6} {'p99':>6} {'CPU/pair':>8} {'3D pts':>6} {'load':>5} "
          f"{'CPU p99':>7} {'model p50':>9} {'p99':>6}")
    for r in range(rounds):
        for name, p in (("off", off), ("on", on)):
            tracker = StereoTracker(full_rig, p, parallel=False)
            camera_cpu = {}
            for side, det in (("left", tracker.left), ("right", tracker.right)):
                def timed(frame, t, keep_mask=True, _run=det.find_candidates, _side=side):
                    c0 = time.thread_time()
                    result = _run(frame, t, keep_mask)
                    camera_cpu[_side] = time.thread_time() - c0
                    return result
                det.find_candidates = timed
            cpu = 0.0
            per_pair, model = [], []
            for lf, rf, t in pairs:
                c0 = time.thread_time()
                tracker.process(lf, rf, t, keep_masks=False)
                spent = time.thread_time() - c0
                cpu += spent
                both_windowed = all(w.last_window is not None
                                    for w in (tracker.left.window_tracker, tracker.right.window_tracker))
                per_pair.append(spent)
                model.append(spent if both_windowed else spent - min(camera_cpu.values()))
            win = tracker.left.window_tracker, tracker.right.window_tracker
            share = sum(w.windowed for w in win) / max(sum(w.frames for w in win), 1) if p.window.enabled else 0.0
            tracker.close()
            tracker = StereoTracker(full_rig, p, parallel=True)
            lat = []
            points = 0
            c0, w0 = time.process_time(), time.perf_counter()
            for lf, rf, t in pairs:
                t0 = time.perf_counter()
                res = tracker.process(lf, rf, t, keep_masks=False)
                lat.append(time.perf_counter() - t0)
                points += res.point is not None
            wall = time.perf_counter() - w0
            cpu2 = time.process_time() - c0
            tracker.close()
            lat_ms = np.asarray(lat) * 1000
            cpu_p99 = 1000 * np.percentile(per_pair, 99)
            model_ms = 1000 * np.asarray(model)
            per_pair = 1000 * cpu / len(pairs)
            print(f"{r:>5} {name:>6} {per_pair:14.2f} ms {per_pair / 2:6.2f} ms {100 * share:7.1f}% "
                  f"{len(pairs) / wall:13.1f} {np.percentile(lat_ms, 50):6.2f} {np.percentile(lat_ms, 99):6.2f} "
                  f"{1000 * cpu2 / len(pairs):5.2f} ms {points:6d} {os.getloadavg()[0]:5.1f} "
                  f"{cpu_p99:7.2f} {np.percentile(model_ms, 50):9.2f} {np.percentile(model_ms, 99):6.2f}",
                  flush=True)


def _tree_modules(tree: Path) -> dict:
    """The ``badminton_gui`` modules imported from another source tree (a directory holding
    ``badminton_gui/`` and ``resources/``), kept apart from this checkout's."""
    own = {k: m for k, m in sys.modules.items() if k == "badminton_gui" or k.startswith("badminton_gui.")}
    for k in own:
        del sys.modules[k]
    sys.path.insert(0, str(tree))
    try:
        for name in ("core.tracker", "io.presets", "io.nycu"):
            importlib.import_module("badminton_gui." + name)
        mods = {k: m for k, m in sys.modules.items() if k == "badminton_gui" or k.startswith("badminton_gui.")}
    finally:
        sys.path.remove(str(tree))
        for k in [k for k in sys.modules if k == "badminton_gui" or k.startswith("badminton_gui.")]:
            del sys.modules[k]
        sys.modules.update(own)
    return mods


def _use_modules(mods: dict) -> None:
    for k in [k for k in sys.modules if k == "badminton_gui" or k.startswith("badminton_gui.")]:
        del sys.modules[k]
    sys.modules.update(mods)


def trees_ab(trees: list[str], preset: str | None, n: int, skip: int, rounds: int) -> None:
    """Source trees against each other, interleaved pair by pair in this process (2048 px).

    Each tree (a directory with ``badminton_gui/`` and ``resources/``, e.g. ``git archive COMMIT
    badminton_gui resources | tar -x -C DIR``; ``.``: this checkout) gets its own one-thread
    tracker; every frame pair goes through all of them back to back, in an order that rotates
    from pair to pair, so the machine's load falls on all alike. Per round and tree: thread CPU
    a pair (mean, p50, p99), the per-pair difference to the first tree (mean, median, its
    standard error) and a hash of the outputs (same hash: the same points and detections).
    Runs of a few hundred pairs minutes apart differ by ±10 % on this shared machine; the
    paired differences resolve a few per cent.
    """
    import hashlib
    import os
    pairs = load_pairs(n, None, skip)
    own = {k: m for k, m in sys.modules.items() if k == "badminton_gui" or k.startswith("badminton_gui.")}
    paths = [REPO if t == "." else Path(t).resolve() for t in trees]
    modules = [own if p == REPO else _tree_modules(p) for p in paths]
    names = [p.name for p in paths]
    print(f"trees A/B: {RALLY} pairs {skip}-{skip + len(pairs) - 1}, preset {preset or 'default'}, "
          f"one thread each, interleaved pair by pair; first tree {names[0]}")
    try:
        for r in range(rounds):
            trackers, cpu, digests = [], [], []
            for mods in modules:
                _use_modules(mods)
                rig = mods["badminton_gui.io.nycu"].rig_from_nycu(DATA / RALLY / "CameraReader_1.cfg",
                                                                   DATA / RALLY / "CameraReader_2.cfg")
                params = mods["badminton_gui.io.presets"].load_preset(preset)
                trackers.append(mods["badminton_gui.core.tracker"].StereoTracker(rig, params, parallel=False))
                cpu.append([])
                digests.append(hashlib.sha1())
            for i, (lf, rf, t) in enumerate(pairs):
                for j in range(len(trees)):
                    k = (i + j) % len(trees)
                    _use_modules(modules[k])
                    c0 = time.thread_time()
                    res = trackers[k].process(lf, rf, t, keep_masks=False)
                    cpu[k].append(time.thread_time() - c0)
                    digests[k].update(repr((res.point, [(d.x, d.y) if d is not None else None
                                                        for d in (res.left.detection, res.right.detection)]
                                            )).encode())
            for tracker in trackers:
                tracker.close()
            first = 1000 * np.asarray(cpu[0])
            for name, spent, digest in zip(names, cpu, digests):
                ms = 1000 * np.asarray(spent)
                d = ms - first
                print(f"round {r} {name:>24}: CPU a pair {ms.mean():6.2f} ms, p50 {np.percentile(ms, 50):6.2f}, "
                      f"p99 {np.percentile(ms, 99):6.2f}; minus the first: mean {d.mean():+.3f} ms, "
                      f"median {np.median(d):+.3f}, s.e. {d.std() / math.sqrt(len(d)):.3f}; "
                      f"outputs {digest.hexdigest()[:8]}; load {os.getloadavg()[0]:.1f}", flush=True)
    finally:
        _use_modules(own)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pairs", type=int, default=300, help="frame pairs held in memory per resolution")
    ap.add_argument("--long", type=int, default=10000,
                    help="pairs for the memory run: the NYCU rallies at full resolution, decoded in turn (0: skip)")
    ap.add_argument("--preset", default=None)
    ap.add_argument("--profile", action="store_true")
    ap.add_argument("--cv-threads", type=int, default=1,
                    help="OpenCV's own thread count while the tracker runs (default 1: what "
                         "`track` and the GUI set, core.tracker.configure_opencv_threads; 0: "
                         "OpenCV's choice). The plain chain always runs with OpenCV's default")
    ap.add_argument("--f1-rallies", nargs="*", default=list(F1_RALLIES),
                    help="NYCU rallies scored at each resolution (none: skip the F1 column)")
    ap.add_argument("--f1-pairs", type=int, default=100000, help="at most this many pairs per rally for F1")
    ap.add_argument("--process-bound", action="store_true",
                    help="only: the detectors in two processes against the tracker's threads (2048 px)")
    ap.add_argument("--window", action="store_true",
                    help="only: the preset with window.enabled off and on, alternated (2048 px, "
                         "--pairs pairs from pair --skip on, --rounds rounds)")
    ap.add_argument("--stages", action="store_true",
                    help="only: the CPU a pair in each camera's candidate stage and in the stereo stage "
                         "(one thread, 2048 px, --pairs pairs from pair --skip on)")
    ap.add_argument("--processes", action="store_true",
                    help="only: StereoTracker's camera threads against a process per camera "
                         "(StereoTracker(processes=True)), alternated, --rounds rounds (2048 px)")
    ap.add_argument("--skip", type=int, default=0, help="--window, --stages, --processes: pairs skipped first")
    ap.add_argument("--rounds", type=int, default=3, help="--window, --trees: alternated rounds")
    ap.add_argument("--trees", nargs="+", default=None, metavar="DIR",
                    help="only: source trees (dirs with badminton_gui/ and resources/; '.': this "
                         "checkout) interleaved pair by pair, one thread each, thread CPU a pair "
                         "(2048 px, --pairs pairs from pair --skip on, --rounds rounds)")
    args = ap.parse_args()
    if args.trees:
        with opencv_threads(args.cv_threads or None):
            trees_ab(args.trees, args.preset, args.pairs, args.skip, args.rounds)
        return
    if args.stages or args.processes:
        params = load_preset(args.preset)
        full_rig = rig_from_nycu(DATA / RALLY / "CameraReader_1.cfg", DATA / RALLY / "CameraReader_2.cfg")
        with opencv_threads(args.cv_threads or None):
            if args.stages:
                stage_cpu(full_rig, params, args.pairs, args.skip, args.preset)
            if args.processes:
                processes_ab(full_rig, params, args.pairs, args.skip, args.rounds, args.preset)
        return
    if args.window:
        params = load_preset(args.preset)
        full_rig = rig_from_nycu(DATA / RALLY / "CameraReader_1.cfg", DATA / RALLY / "CameraReader_2.cfg")
        with opencv_threads(args.cv_threads or None):
            window_ab(full_rig, params, args.pairs, args.skip, args.rounds, args.preset)
        return
    render, demo_fps = demo_render_rate()
    print(f"demo court 1280x720: renders {render:.1f} pairs/s (it plays at {demo_fps:.0f} fps: "
          f"{render / demo_fps:.2f}x real time)")
    if not DATA.is_dir():
        sys.exit(f"needs {DATA}")
    params = load_preset(args.preset)
    full_rig = rig_from_nycu(DATA / RALLY / "CameraReader_1.cfg", DATA / RALLY / "CameraReader_2.cfg")
    print(f"cv2 {cv2.__version__}, {cv2.getNumberOfCPUs()} CPUs, preset {args.preset or 'default'}, "
          f"OpenCV threads in the tracker: {args.cv_threads or cv2.getNumThreads()}")
    if args.process_bound:
        process_bound(full_rig, args.preset, args.pairs)
        return
    tracker_threads = opencv_threads(args.cv_threads or None)
    sizes = (None, (1280, 720), (640, 480))
    f1 = {}
    if args.f1_rallies:
        with tracker_threads:
            f1 = f1_by_resolution(full_rig, params, sizes, args.f1_rallies, args.f1_pairs)
        print(f"F1 on {', '.join(args.f1_rallies)} (both cameras, first {args.f1_pairs} pairs at most)")
    print(f"{'resolution':>10} {'plain/s':>8} {'tracker/s':>9} {'ratio':>6} {'p50 ms':>7} {'p99 ms':>7} "
          f"{'RSS MB':>7} {'F1':>6} {'acc':>6} {'waits/pair':>10}")
    for size in sizes:
        pairs = load_pairs(args.pairs, size)
        rig = full_rig if size is None else scaled_rig(full_rig, size)
        plain = time_plain(pairs)
        waits: list[float] = []
        with tracker_threads:
            rate, p50, p99 = time_tracker(pairs, rig, params, switches=waits)
        w, h = pairs[0][0].shape[1], pairs[0][0].shape[0]
        score = f1.get(size)
        quality = f"{100 * score.f1:6.2f} {100 * score.accuracy:6.2f}" if score else f"{'-':>6} {'-':>6}"
        print(f"{w:>5}x{h:<4} {plain:8.1f} {rate:9.1f} {rate / plain:6.2f} {p50:7.2f} {p99:7.2f} "
              f"{peak_rss_mb():7.0f} {quality} {waits[0]:10.0f}")
        if args.profile and size is None:
            prof = cProfile.Profile()
            tracker = StereoTracker(rig, params, parallel=False)
            with tracker_threads:
                prof.enable()
                for lf, rf, t in pairs:
                    tracker.process(lf, rf, t, keep_masks=False)
                prof.disable()
            tracker.close()
            out = io.StringIO()
            pstats.Stats(prof, stream=out).sort_stats("tottime").print_stats(12)
            profile_text = out.getvalue()
        del pairs
    with tracker_threads:
        rate, decode_share = file_processing(full_rig, params, 600)
    print(f"file processing ({RALLY}, decoding included): {rate:.1f} pairs/s, "
          f"decoding {100 * decode_share:.0f} % / tracking {100 - 100 * decode_share:.0f} % of the time")
    if args.long:
        with tracker_threads:
            rss, started, reset = long_run(full_rig, params, args.long)
        peak = "peak since start" if reset else "process peak (reset refused)"
        print(f"memory (2048x1536, the NYCU rallies decoded in turn, {started} rallies): " + "; ".join(
            f"after {k} pairs RSS {now:.0f} MB, {peak} {hwm:.0f} MB" for k, (now, hwm) in rss.items()))
    if args.profile:
        print("\nprofile (2048x1536, one thread, top functions by own time):")
        print(profile_text)


if __name__ == "__main__":
    main()

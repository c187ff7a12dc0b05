"""Soak: does a tracker that runs for hours keep its memory flat?

    .venv/bin/python benchmarks/soak.py [--pairs 400000] [--size 320x180] [--every 1000]
                                        [--max-growth-mb 64]

A court-side tracker runs all day, so memory that grows a few bytes a pair is a crash hours
later, long after any test has finished. This drives ``StereoTracker.process`` (the API the CLI
and the GUI's worker call) with a few hundred demo-court pairs rendered once at a small size and
cycled with ever-increasing timestamps, so the tracker sees an endless session. Every
``--every`` pairs it samples the resident memory (VmRSS of /proc/self/status) and the total length
of every container (deque, list, dict, set) held by the tracker, its detectors and its trajectory:
a queue that never drops its oldest entry shows there before it shows in RSS.

It prints RSS and the container total at 1k, 10k, 100k and 400k pairs (those reached), the RSS
slope after the warm-up (KB per 1000 pairs, least squares over the samples past 10 % of the run),
and exits 1 if RSS grew by more than ``--max-growth-mb`` between the first sample past the
warm-up and the end, or if the container total kept growing (its last sample more than twice the
most of the run's first half, plus 100). Stopped early (Ctrl-C, SIGTERM), it prints and judges
the pairs done. Needs no data.
"""

from __future__ import annotations

import argparse
import signal
import sys
import time
from collections import deque
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from badminton_gui.core.tracker import StereoTracker  # noqa: E402
from badminton_gui.io.demo_scene import DemoScene  # noqa: E402

MILESTONES = (1_000, 10_000, 100_000, 400_000)
CONTAINERS = (deque, list, dict, set)


def rss_mb() -> float:
    """Resident memory now, MB (VmRSS of /proc/self/status)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    return float("nan")


def held_items(root: object, depth: int = 4) -> int:
    """Total length of the containers reachable from ``root``'s attributes (``depth`` levels):
    the tracker's queues, histories and caches together. numpy arrays are not containers here
    (their size is fixed by the frame); each object is counted once."""
    seen: set[int] = set()
    total = 0

    def attributes(obj: object) -> list:
        values = list(getattr(obj, "__dict__", {}).values())
        for name in getattr(type(obj), "__slots__", ()):
            if hasattr(obj, name):
                values.append(getattr(obj, name))
        return values

    def walk(obj: object, level: int) -> None:
        nonlocal total
        if id(obj) in seen or level > depth or isinstance(obj, (np.ndarray, str, bytes)):
            return
        seen.add(id(obj))
        if isinstance(obj, CONTAINERS):
            total += len(obj)
            items = obj.values() if isinstance(obj, dict) else obj
            for item in list(items)[:64]:       # nested containers (a tuple of deques, ...)
                walk(item, level + 1)
        elif isinstance(obj, tuple):
            for item in obj:
                walk(item, level + 1)
        elif hasattr(obj, "__dict__") or hasattr(type(obj), "__slots__"):
            if type(obj).__module__.startswith("badminton_gui"):
                for value in attributes(obj):
                    walk(value, level + 1)

    walk(root, 0)
    return total


def slope_kb_per_1000(samples: list[tuple[int, float, int]], start: int) -> float:
    points = [(n, mb) for n, mb, _ in samples if n >= start]
    if len(points) < 2:
        return float("nan")
    n, mb = np.array(points, dtype=float).T
    return float(np.polyfit(n / 1000.0, mb * 1024.0, 1)[0])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pairs", type=int, default=400_000)
    ap.add_argument("--size", default="320x180", help="demo frame size WxH (small: the soak is about memory)")
    ap.add_argument("--frames", type=int, default=600, help="demo pairs rendered once and cycled")
    ap.add_argument("--every", type=int, default=1000, help="sample memory every N pairs")
    ap.add_argument("--max-growth-mb", type=float, default=64.0,
                    help="fail if RSS grows more than this after the warm-up (10 %% of the run)")
    ap.add_argument("--print-every", type=int, default=10_000, help="print a progress line every N pairs")
    ap.add_argument("--seed", type=int, default=3)
    args = ap.parse_args(argv)
    if args.pairs < 1 or args.every < 1 or args.frames < 1:
        ap.error("--pairs, --every and --frames must be positive")
    w, h = (int(v) for v in args.size.lower().split("x"))

    scene = DemoScene(seed=args.seed, size=(w, h))
    frames = [scene.render(i) for i in range(args.frames)]
    period = 1.0 / scene.fps
    tracker = StereoTracker(scene.rig)
    warm_up = max(args.every, args.pairs // 10)
    samples: list[tuple[int, float, int]] = []
    start = time.perf_counter()
    print(f"soak: {args.pairs} pairs of {w}x{h} demo frames ({args.frames} cycled), "
          f"RSS {rss_mb():.1f} MB before the first pair", flush=True)
    # Stopped early (Ctrl-C, kill): the figures of the pairs done are still printed and judged.
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    try:
        for n in range(1, args.pairs + 1):
            left, right = frames[(n - 1) % args.frames]
            tracker.process(left, right, (n - 1) * period, n - 1, n - 1, keep_masks=False)
            if n % args.every == 0 or n == args.pairs:
                samples.append((n, rss_mb(), held_items(tracker)))
                if n in MILESTONES or n == args.pairs or n % args.print_every == 0:
                    rate = n / (time.perf_counter() - start)
                    print(f"  {n:>7} pairs: RSS {samples[-1][1]:7.1f} MB, held items "
                          f"{samples[-1][2]:6d}  ({rate:.0f} pairs/s)", flush=True)
    except KeyboardInterrupt:
        print(f"stopped after {samples[-1][0] if samples else 0} pairs", flush=True)
        if len(samples) < 2:
            return 1
    finally:
        tracker.close()

    warm_up = min(warm_up, max(args.every, samples[-1][0] // 10))   # a run stopped early
    base = next(s for s in samples if s[0] >= warm_up)
    last = samples[-1]
    growth = last[1] - base[1]
    slope = slope_kb_per_1000(samples, warm_up)
    print("\nmilestones:")
    for m in MILESTONES:
        hit = next((s for s in samples if s[0] == m), None)
        if hit is not None:
            print(f"  {m:>7} pairs: RSS {hit[1]:7.1f} MB, held items {hit[2]}")
    print(f"RSS after the warm-up ({base[0]} pairs) {base[1]:.1f} MB -> {last[1]:.1f} MB at {last[0]} "
          f"pairs: {growth:+.1f} MB, slope {slope:+.3f} KB / 1000 pairs "
          f"(bound {args.max_growth_mb:.0f} MB); held items {base[2]} -> {last[2]} "
          f"(max {max(s[2] for s in samples)})")
    failed = []
    if growth > args.max_growth_mb:
        failed.append(f"RSS grew {growth:.1f} MB > {args.max_growth_mb:.0f} MB")
    # Bounded queues fill up early and then stay; a leak keeps growing: the end is compared with
    # the most held in the first half of the run.
    first_half = max(s[2] for s in samples if s[0] <= max(samples[-1][0] // 2, samples[0][0]))
    if last[2] > 2 * first_half + 100:
        failed.append(f"held items grew from at most {first_half} in the first half to {last[2]}")
    if failed:
        print("FAIL: " + "; ".join(failed))
        return 1
    print("OK: memory flat within the bound")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Demo court errors per window of frames: one long run against runs started afresh before each window.

    .venv/bin/python benchmarks/demo_windows.py [--frames 2400] [--seeds 0] [--window 200] [--fresh 60] [--list]

For every window of ``--window`` frames, prints the wrong frames (FP1 + FP2 + FN) of the left
and right camera in one run from frame 0, then in brackets those of a tracker started afresh
``--fresh`` frames before the window (``--fresh 0``: no fresh runs). A window that does much
worse in the long run than afresh depends on what the tracker carried in (a flight filter, a
landed hold, a tracklet, the background model's memory); one that does as badly afresh is the
scene. A fresh start is no clean reference either: its background model learns the first frame
as the empty court, so a player standing there is background to it (fifteenth and sixteenth
rounds, benchmarks/README.md). ``--list`` also prints each run of wrong frames of the long run:
camera, outcome, first–last frame, what was reported (tracklet, predicted) and whether a landed
shuttle was held.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from badminton_gui.core.evaluation import classify, tolerance_px  # noqa: E402
from badminton_gui.core.params import TrackerParams  # noqa: E402
from badminton_gui.core.tracker import StereoTracker  # noqa: E402
from badminton_gui.io.demo_scene import DemoScene  # noqa: E402


def track(seed: int, start: int, end: int) -> dict[int, dict]:
    """Per frame of [start, end): {camera: (outcome, tracklet, predicted)} and the landed hold."""
    scene = DemoScene(seed=seed, n_frames=end)
    scene._next = start          # the scene renders any frame on its own: start there
    tracker = StereoTracker(scene.rig, TrackerParams())
    tol = tolerance_px(scene.rig.image_size[0])
    out = {}
    try:
        while (frame := scene.read()) is not None:
            result = tracker.process(frame.left, frame.right, frame.t_left, frame.index,
                                     frame.index_right, keep_masks=False)
            truth = scene.truth(frame.index)
            row = {"held": (tracker.rules.holding(0), tracker.rules.holding(1))}
            for cam, res, vis, uv in (("L", result.left, truth.visible_left, truth.uv_left),
                                      ("R", result.right, truth.visible_right, truth.uv_right)):
                d = res.detection
                code = classify(np.array([d is not None]),
                                np.array([[d.x, d.y] if d else [np.nan, np.nan]]),
                                np.array([bool(vis)]),
                                np.array([uv if (vis and uv) else [np.nan, np.nan]]), tol)[0]
                row[cam] = (str(code), None if d is None else d.tracklet, bool(d and d.predicted))
            out[frame.index] = row
    finally:
        tracker.close()
        scene.close()
    return out


def wrong(rows: dict[int, dict], cam: str, frames: range) -> int:
    return sum(rows[i][cam][0] not in ("TP", "TN") for i in frames if i in rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=2400)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--window", type=int, default=200)
    ap.add_argument("--fresh", type=int, default=60, help="frames tracked before each window afresh (0: none)")
    ap.add_argument("--list", action="store_true", help="list the long run's runs of wrong frames")
    args = ap.parse_args()
    for seed in args.seeds:
        long_run = track(seed, 0, args.frames)
        cells = []
        for w in range(0, args.frames, args.window):
            frames = range(w, min(w + args.window, args.frames))
            cell = f"{w}: {wrong(long_run, 'L', frames)}/{wrong(long_run, 'R', frames)}"
            if args.fresh > 0 and w > 0:
                fresh = track(seed, max(w - args.fresh, 0), frames.stop)
                cell += f" ({wrong(fresh, 'L', frames)}/{wrong(fresh, 'R', frames)})"
            cells.append(cell)
        fresh_note = f" (afresh from {args.fresh} before)" if args.fresh > 0 else ""
        print(f"seed {seed} wrong frames L/R per {args.window}{fresh_note}: " + " | ".join(cells), flush=True)
        if args.list:
            for cam in "LR":
                run = None
                for i in sorted(long_run):
                    code, ident, predicted = long_run[i][cam]
                    key = None if code in ("TP", "TN") else (code, ident, predicted, long_run[i]["held"][cam == "R"])
                    if run is not None and (key != run[0] or i != run[2] + 1):
                        print(f"  {cam} {run[0][0]:3s} {run[1]:5d}–{run[2]:5d} tracklet {run[0][1]}"
                              f"{' predicted' if run[0][2] else ''}{' held' if run[0][3] else ''}")
                        run = None
                    if key is not None:
                        run = (key, run[1] if run else i, i)
                if run is not None:
                    print(f"  {cam} {run[0][0]:3s} {run[1]:5d}–{run[2]:5d} tracklet {run[0][1]}"
                          f"{' predicted' if run[0][2] else ''}{' held' if run[0][3] else ''}")


if __name__ == "__main__":
    main()

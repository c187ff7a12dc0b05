"""Before → after of the court adaptation (core/court_adaptation.py) on demo courts it never saw.

Why this file exists: the adaptation must show what it gains, and what it costs, where nothing
was tuned. For each seed it tracks the demo court once with the preset's classifiers, labels the
candidates of the flights both cameras agreed on, fine-tunes each camera's classifier on them
(the offline form, as `track --adapt` does), and scores a second run with them against the
scene's truth, beside the first run's score. The real footage: `accuracy.py --adapt`.

    .venv/bin/python benchmarks/court_adaptation.py --size 640x360 --seeds 5 6 --frames 1000
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from badminton_gui.core.court_adaptation import adapt_to_stereo_recording  # noqa: E402
from badminton_gui.core.params import TrackerParams  # noqa: E402
from badminton_gui.core.tracker import StereoTracker  # noqa: E402
from badminton_gui.io.demo_eval import evaluate_demo  # noqa: E402
from badminton_gui.io.demo_scene import DemoScene  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=1000)
    ap.add_argument("--seeds", type=int, nargs="+", default=[5, 6])
    ap.add_argument("--size", default="640x360")
    ap.add_argument("--rig", default="binocular", choices=("binocular", "ends"))
    ap.add_argument("--lookahead", type=int, default=4, help="frames of look-ahead of the scored readout")
    args = ap.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    params = TrackerParams()
    for seed in args.seeds:
        start = time.perf_counter()
        scene = DemoScene(seed=seed, size=size, rig=args.rig, n_frames=args.frames)
        tracker = StereoTracker(scene.rig, params)
        judged: list = []
        try:
            classifiers, harvest = adapt_to_stereo_recording(tracker, iter(scene.read, None), judged=judged)
        finally:
            tracker.close()
            scene.close()
        before = evaluate_demo(seed, args.frames, size, args.rig, params, lookahead=args.lookahead)
        print(f"seed {seed} {args.size} {args.rig}: harvest {harvest.flights} flights, shuttle "
              f"{harvest.positives}, others {harvest.negatives}, still blobs "
              f"{[len(harvest.still_rows(cam)[0]) for cam in (0, 1)]}")
        for side, h in zip(("left", "right"), judged):
            print(f"  {side}: {'kept the preset' if h.kept else 'fine-tuned'}; held-back {h.rows} rows, loss "
                  f"{h.loss_before:.4f} -> {h.loss_after:.4f}, shuttle first {100 * h.top_before:.1f} -> "
                  f"{100 * h.top_after:.1f} %")
        print(f"  before  left {before.left.summary()}")
        print(f"          right {before.right.summary()}")
        if classifiers is None:
            print("  nothing to learn from")
            continue
        after = evaluate_demo(seed, args.frames, size, args.rig, params, lookahead=args.lookahead,
                              classifiers=classifiers)
        print(f"  after   left {after.left.summary()}")
        print(f"          right {after.right.summary()}")
        print(f"  3D median before {1000 * before.median_3d():.1f} mm ({len(before.errors_3d)} points), "
              f"after {1000 * after.median_3d():.1f} mm ({len(after.errors_3d)} points); "
              f"{time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

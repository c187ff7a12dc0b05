"""Tracker against the demo court's ground truth: 2D accuracy per camera and 3D error.

    .venv/bin/python benchmarks/demo_accuracy.py [--frames 1000] [--seeds 0 1 2] [--size 1280x720] [--rig binocular] [--errors] [--lookahead N] [--preset P]

Prints one line per seed and the totals: the figures of the tracking-engine issue
(2D accuracy ≥ 99 % per camera at the protocol's tolerance, 4 px at 512 px width; 3D RMS ≤ 1 cm within 6 m of the rig).
``--errors`` also lists every FP1 / FP2 / FN frame: the truth and the reported point, their
distance, the shot and how far into it, and the candidates near the truth with the filter that
rejected each (``-`` for the reported one) — where to look first when tuning.
``--lookahead N`` also scores, from the same tracking run, the readout re-decided N frames later
(core/lookahead.py: what `track --lookahead N` writes; latency N / fps online) and prints it
beside the online figure; ``--errors`` then lists the look-ahead readout's errors.
``--preset`` runs with a preset or a parameter file (e.g. ``{"shuttle_scale": {"enabled": true}}``)
instead of the built-in defaults.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from badminton_gui.io.demo_eval import evaluate_demo_lookaheads  # noqa: E402
from badminton_gui.io.presets import load_preset  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=1000)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--size", default="1280x720")
    ap.add_argument("--rig", default="binocular", choices=("binocular", "ends"))
    ap.add_argument("--range", type=float, default=6.0, help="3D error within this distance of the left camera")
    ap.add_argument("--errors", action="store_true", help="list every FP1 / FP2 / FN frame with its candidates")
    ap.add_argument("--lookahead", type=int, nargs="+", default=[], metavar="N",
                    help="also score the readout re-decided N frames later (core/lookahead.py); several N "
                         "are scored from the same tracking run")
    ap.add_argument("--preset", default=None, help="a preset name or a .json parameter file (default: the "
                                                   "built-in parameter defaults)")
    args = ap.parse_args()
    params = load_preset(args.preset) if args.preset else None
    ks = tuple(args.lookahead) + (0,)
    la_l, la_r = {}, {}
    la_errs, la_rngs = {k: [] for k in args.lookahead}, {k: [] for k in args.lookahead}
    size = tuple(int(v) for v in args.size.split("x"))
    total_l = total_r = None
    errs, rngs = [], []
    print(f"demo court {args.rig} {size[0]}x{size[1]}, {args.frames} frames per seed")
    print(f"{'seed':>4} {'acc L':>7} {'acc R':>7} {'F1 L':>7} {'F1 R':>7} {'3D pts':>6} "
          f"{'RMS≤' + str(args.range) + 'm':>9} {'med all':>8} {'pairs/s':>8}")
    for seed in args.seeds:
        listing: list[str] = []
        on_frame = None
        if args.errors:
            def on_frame(result, truth, codes, seed=seed, listing=listing):
                listing.extend(_error_lines(seed, result, truth, codes))
        scores = evaluate_demo_lookaheads(seed, args.frames, size, args.rig, params, on_frame=on_frame,
                                          lookaheads=ks)
        s = scores[0]
        if listing:
            print("\n".join(listing))
        total_l = s.left if total_l is None else total_l + s.left
        total_r = s.right if total_r is None else total_r + s.right
        errs.append(s.errors_3d)
        rngs.append(s.ranges)
        print(f"{seed:>4} {s.left.accuracy:7.4f} {s.right.accuracy:7.4f} {s.left.f1:7.4f} {s.right.f1:7.4f} "
              f"{len(s.errors_3d):>6} {100 * s.rms_3d(args.range):8.2f}cm {100 * s.median_3d():7.2f}cm "
              f"{s.pairs_per_s:8.1f}")
        print(f"     left  {s.left.summary()}\n     right {s.right.summary()}")
        for k in args.lookahead:
            la = scores[k]
            la_l[k] = la.left if k not in la_l else la_l[k] + la.left
            la_r[k] = la.right if k not in la_r else la_r[k] + la.right
            la_errs[k].append(la.errors_3d)
            la_rngs[k].append(la.ranges)
            print(f"     look-ahead {k}: accuracy L {la.left.accuracy:.4f} R {la.right.accuracy:.4f}, "
                  f"F1 L {la.left.f1:.4f} R {la.right.f1:.4f}, 3D RMS≤{args.range}m {100 * la.rms_3d(args.range):.2f}cm")
            print(f"     left  {la.left.summary()}\n     right {la.right.summary()}")
    e, r = np.concatenate(errs), np.concatenate(rngs)
    near = e[r <= args.range]
    print(f"total: accuracy left {total_l.accuracy:.4f} right {total_r.accuracy:.4f}; "
          f"3D RMS within {args.range} m: {100 * np.sqrt(np.mean(near ** 2)):.2f} cm over {len(near)} points; "
          f"all ranges: median {100 * np.median(e):.2f} cm, p95 {100 * np.percentile(e, 95):.2f} cm")
    for k in args.lookahead:
        e2, r2 = np.concatenate(la_errs[k]), np.concatenate(la_rngs[k])
        near2 = e2[r2 <= args.range]
        print(f"total with look-ahead {k} frames: accuracy left {la_l[k].accuracy:.4f} right "
              f"{la_r[k].accuracy:.4f}; 3D RMS within {args.range} m: {100 * np.sqrt(np.mean(near2 ** 2)):.2f} cm "
              f"over {len(near2)} points")
    # The RMS is ruled by a few gross errors (a wrong object in both cameras, a blob merged
    # with a line or a player): show the body of the distribution and how many are gross.
    if len(near):
        print(f"within {args.range} m: median {100 * np.median(near):.2f} cm, "
              f"p90 {100 * np.percentile(near, 90):.2f} cm, "
              f"{int((near > 0.05).sum())} points > 5 cm, {int((near > 0.5).sum())} > 50 cm; "
              f"RMS of the points ≤ 5 cm {100 * np.sqrt(np.mean(near[near <= 0.05] ** 2)):.2f} cm")


def _error_lines(seed: int, result, truth, codes, near: float = 40.0) -> list[str]:
    """One line per camera whose outcome is an error, then its candidates within ``near`` px."""
    lines = []
    for cam, res, vis, uv, code in (("L", result.left, truth.visible_left, truth.uv_left, codes[0]),
                                    ("R", result.right, truth.visible_right, truth.uv_right, codes[1])):
        if code in ("TP", "TN"):
            continue
        d = res.detection
        truth_s = f"({uv[0]:7.1f},{uv[1]:6.1f})" if uv else "(   none    )"
        det_s = (f"({d.x:7.1f},{d.y:6.1f}){' pred' if d.predicted else ''}" if d else "-")
        dist = f"{math.hypot(d.x - uv[0], d.y - uv[1]):6.1f}" if (d and uv) else "     -"
        lines.append(f"seed {seed} frame {truth.index:5d} {cam} {code:3s} visible {int(vis)} "
                     f"{truth.shot_kind or '-':5s} truth {truth_s} reported {det_s} distance {dist}")
        ref = uv or ((d.x, d.y) if d else None)
        if ref is None:
            continue
        for c in sorted(res.candidates, key=lambda c: math.hypot(c.x - ref[0], c.y - ref[1])):
            dc = math.hypot(c.x - ref[0], c.y - ref[1])
            if dc > near:
                break
            lines.append(f"      {dc:6.1f} px ({c.x:7.1f},{c.y:6.1f}) {c.rejected_by or '-':10s} "
                         f"score {c.score:5.2f} length {c.length:5.0f} short side {c.short_side:5.1f}"
                         f"{' predicted' if c.predicted else ''}")
    return lines


if __name__ == "__main__":
    main()

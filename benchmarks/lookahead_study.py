"""The look-ahead readout replayed on recorded online results: potential, and accuracy per K.

Why this file exists: `core/lookahead.py` only post-processes the online results, so replaying
it on results recorded once (``benchmarks/lookahead_record.py``) gives exactly what the CLI
would write, for many K and settings in seconds. Two reports:

* ``--potential``: every error frame of the online readout (GUIDE §6: FN, FP1, FP2), split by
  whether K frames of future could fix it — the label lies on a candidate whose tracklet the
  online readout follows within the next K frames (FN, FP1), or the reported tracklet is left
  for good within K frames (FP1, FP2);
* the outcomes and accuracy with the look-ahead at each K (``--frames 0 4 8 15``).

    .venv/bin/python benchmarks/lookahead_study.py [--cache DIR] [--potential] [--frames 0 4 8 15]
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from badminton_gui.core.evaluation import Outcomes, classify, evaluate, tolerance_px  # noqa: E402
from badminton_gui.core.lookahead import CameraLookahead  # noqa: E402
from badminton_gui.core.params import TrackerParams  # noqa: E402
from badminton_gui.io.labels import read_point_labels  # noqa: E402
from badminton_gui.io.presets import load_preset  # noqa: E402
from clips import broadcast_clips, cache_dir, stereo_clips  # noqa: E402
from result_cache import load_results  # noqa: E402


def _load(path: Path):
    try:
        return load_results(path)
    except (EOFError, OSError, json.JSONDecodeError):   # not a whole recording
        return []


def load_streams(cache: Path):
    """[(name, kind, camera, width, labels dict, [(frame index, t, CameraResult)], pairing)]."""
    out = []
    for c in stereo_clips():
        path = cache / f"{c.name}_track.json.gz"
        if path.exists():
            results = _load(path)
            for cam, labels in (("left", c.left_labels), ("right", c.right_labels)):
                stream = [(r.index if cam == "left" else r.index_right, r.timestamp,
                           r.left if cam == "left" else r.right) for r in results]
                out.append((c.name, "stereo-track", cam, 2048, read_point_labels(labels).as_dict(),
                            stream, c.held_out))
        for cam, labels in (("left", c.left_labels), ("right", c.right_labels)):
            path = cache / f"{c.name}_{cam}_detect.json.gz"
            if path.exists():
                results = _load(path)
                out.append((c.name, "stereo-detect", cam, 2048, read_point_labels(labels).as_dict(),
                            [(i, i / fps, r) for i, fps, r in results], c.held_out))
    for c in broadcast_clips():
        path = cache / f"{c.name}_-_detect.json.gz"
        if path.exists():
            results = _load(path)
            out.append((c.name, "broadcast", "-", 1280, read_point_labels(c.labels).as_dict(),
                        [(i, i / fps, r) for i, fps, r in results], c.held_out))
    return out


def readout(stream, params: TrackerParams):
    """{frame: (visible, x, y)} of the stream with the look-ahead of ``params`` (first row wins)."""
    la = CameraLookahead(params)
    decided = []
    for _, t, res in stream:
        decided += la.push(res, t)
    decided += la.flush()
    pred = {}
    for (index, _, _), res in zip(stream, decided):
        d = res.detection
        pred.setdefault(index, (d is not None, d.x if d else 0.0, d.y if d else 0.0))
    return pred, la.changes


def potential(stream, labels, width, ks):
    """Counts of error frames by what K frames of future could do about them."""
    tol = tolerance_px(width)
    followed = [(r.detection.tracklet if r.detection is not None else -1) for _, _, r in stream]
    seen = set()
    counts = Counter()
    for i, (index, _, res) in enumerate(stream):
        if index in seen or index not in labels:
            continue
        seen.add(index)
        lv, lx, ly = labels[index]
        d = res.detection
        code = classify(np.array([d is not None]), np.array([[d.x, d.y] if d else [np.nan, np.nan]]),
                        np.array([lv]), np.array([[lx, ly] if lv else [np.nan, np.nan]]), tol)[0]
        if code in ("TP", "TN"):
            continue
        counts[code] += 1
        on_label = None
        if lv:
            near = [c for c in res.candidates if c.tracklet >= 0 and not c.predicted
                    and np.hypot(c.x - lx, c.y - ly) <= tol]
            if d is not None and d.tracklet >= 0:
                near = [c for c in near if c.tracklet != d.tracklet] or near
            on_label = min(near, key=lambda c: np.hypot(c.x - lx, c.y - ly)).tracklet if near else None
            if on_label is None:
                counts[f"{code} label on no tracklet candidate"] += 1
        for k in ks:
            fut = followed[i + 1:i + 1 + k]
            if on_label is not None and on_label in fut:
                counts[f"{code} K={k}: label's tracklet followed within K"] += 1
            if d is not None and d.tracklet >= 0 and code in ("FP1", "FP2"):
                a = d.tracklet
                if a not in fut[-max(1, k // 2):]:
                    counts[f"{code} K={k}: reported tracklet left within K"] += 1
    return counts


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", default=None, help="folder of the recordings (default: the private cache folder)")
    ap.add_argument("--frames", type=int, nargs="+", default=[0, 4, 8, 15])
    ap.add_argument("--potential", action="store_true")
    ap.add_argument("--set", action="append", default=[], metavar="GROUP.NAME=VALUE",
                    help="look-ahead parameter overrides, e.g. lookahead.min_support=3")
    ap.add_argument("--per-clip", action="store_true")
    args = ap.parse_args()
    streams = load_streams(Path(args.cache) if args.cache else cache_dir("lookahead"))
    if args.potential:
        for kind in ("stereo-track", "stereo-detect", "broadcast"):
            for held in (False, True):
                sel = [s for s in streams if s[1] == kind and s[6] == held]
                if not sel:
                    continue
                tot = Counter()
                for s in sel:
                    tot += potential(s[5], s[4], s[3], [k for k in args.frames if k > 0])
                print(f"{kind} {'held-out' if held else 'tuned-on'} ({len(sel)} streams):")
                for key in sorted(tot):
                    print(f"   {key:55s} {tot[key]:6d}")
    for kind in ("stereo-track", "stereo-detect", "broadcast"):
        base = load_preset("broadcast") if kind == "broadcast" else TrackerParams()
        for held in (False, True):
            sel = [s for s in streams if s[1] == kind and s[6] == held]
            if not sel:
                continue
            for k in args.frames:
                params = base.with_value("lookahead.frames", k)
                for item in args.set:
                    name, _, value = item.partition("=")
                    params = params.with_value(name, value)
                tot, changes = Outcomes(), Counter()
                for name, _, cam, width, labels, stream, _ in sel:
                    pred, ch = readout(stream, params)
                    o = evaluate(pred, labels, tolerance_px(width))
                    if args.per_clip:
                        print(f"      {name:16s} {cam:5s} K={k:3d} {o.summary()}")
                    tot += o
                    changes.update(ch)
                print(f"{kind:13s} {'held-out' if held else 'tuned-on'} K={k:3d} {tot.summary()}  "
                      f"back-fills {changes['backfill']} switches {changes['switch']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Generalisation on real footage: each TV venue scored by a classifier that never saw it.

Why this file exists: the TV classifier is trained on three clips from two venues, and
leave-one-clip-out on those three says little about a hall it has never seen. Here the five venues
of the shared TV clips (``broadcast/venues.csv``) take turns: a classifier is trained on every clip
of the other four venues (tuned-on and held-out alike, as ``train_classifier.py --kind broadcast``
trains: ``train_classifier.dump``, ``train_broadcast``), and the left-out venue's clips go through
`detect --preset broadcast` with it (``broadcast_census.census``: the same chain and look-ahead,
adapted to each clip when the preset or ``--adapt`` says so). Each clip is scored by the protocol and by the in-play score, which
leaves out the labelled frames whose shuttle is at rest (core/evaluation.py ``at_rest_frames``).

    .venv/bin/python benchmarks/generalise.py --venues                  # five folds: three MLPs on ≈ 170,000 candidates each
    .venv/bin/python benchmarks/generalise.py --venues --only odense    # one fold
    .venv/bin/python benchmarks/generalise.py --venues --shipped        # the shipped classifier instead (no training)
    .venv/bin/python benchmarks/generalise.py --venues --adapt          # adapting each fold's classifier to each clip first
    .venv/bin/python benchmarks/generalise.py --venues --causes         # also why each venue's wrong frames are wrong
    .venv/bin/python benchmarks/generalise.py --rest                    # labelled frames at rest, per clip

The fold classifiers are written to the cache (``clips.cache_dir("venue-folds")``), never to
``resources/``, and reused while the pipeline and the training rows are unchanged.
"""

from __future__ import annotations

import argparse
import collections
import csv
import hashlib
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from badminton_gui.core.classifier import load_classifier  # noqa: E402
from badminton_gui.core.evaluation import Outcomes  # noqa: E402
from badminton_gui.io.labels import read_point_labels  # noqa: E402
from clips import DATA_DIR, broadcast_clips, cache_dir, rest_frames, stereo_clips  # noqa: E402

OUTCOMES = ("TP", "TN", "FP1", "FP2", "FN")


def venues() -> dict[str, str]:
    """clip -> venue, from the TV clips' ``venues.csv``."""
    with (DATA_DIR / "broadcast" / "venues.csv").open() as fh:
        return {row["clip"]: row["venue"] for row in csv.DictReader(fh)}


def outcomes(counts, prefix: str = "") -> Outcomes:
    """An Outcomes from census counts (``prefix`` "in-play ": the in-play ones)."""
    return Outcomes(*(counts[prefix + k] for k in OUTCOMES))


def fmt(o: Outcomes) -> str:
    return f"{o.accuracy:7.2%} {o.precision:7.2%} {o.recall:7.2%} {o.f1:7.2%}"


def counts_of(o: Outcomes) -> str:
    return f"TP {o.tp} TN {o.tn} FP1 {o.fp1} FP2 {o.fp2} FN {o.fn}"


def _score(task: tuple):
    """Census counts of one clip with one classifier (None: the preset's)."""
    from broadcast_census import census
    clip, classifier, rest, adapt = task
    cv2.setNumThreads(1)
    return census(clip, "broadcast", 4, None, classifier=classifier, adapt=adapt, at_rest=rest)


def fold_classifier(venue: str, jobs: list[tuple], parts: list, place: dict[str, str], seed: int):
    """The TV classifier trained on every clip not from ``venue`` (cached by the rows' digest)."""
    from train_classifier import train_broadcast
    rows = [p for p, job in zip(parts, jobs) if place.get(Path(job[0]).stem) != venue]
    x, y = np.vstack([p[0] for p in rows]), np.concatenate([p[1] for p in rows])
    digest = hashlib.sha1(x.tobytes() + y.tobytes()).hexdigest()[:12]
    path = cache_dir("venue-folds") / f"without-{venue}_seed{seed}_{digest}.json"
    if path.is_file():
        return load_classifier(str(path)), 0.0, len(y)
    started = time.perf_counter()
    model = train_broadcast(x, y, seed=seed)
    model.save(path)
    return model, time.perf_counter() - started, len(y)


def leave_venue_out(args) -> int:
    """Fold by fold (each fold's clips scored as soon as its classifier is trained, so an
    interrupted run still gives whole folds), then the totals per venue."""
    from train_classifier import dump
    place = venues()
    clips = [c for c in broadcast_clips() if c.name in place]
    missing = sorted(c.name for c in broadcast_clips() if c.name not in place)
    if missing:
        print(f"not in venues.csv (left out): {', '.join(missing)}")
    names = sorted(set(place[c.name] for c in clips))
    folds = [v for v in args.only if v in names] if args.only else names
    jobs = [(str(c.video), str(c.labels), "broadcast", 100000, True, "unchanged") for c in clips]
    if not args.shipped:
        with ProcessPoolExecutor(args.jobs) as pool:
            parts = list(pool.map(dump, jobs))
    who = "the shipped classifier" if args.shipped else "trained without its venue"
    from badminton_gui.io.presets import load_preset
    adapt = args.adapt if args.adapt is not None else load_preset("broadcast").classifier.adapt_min_run > 0
    who += ", adapted to each clip" if adapt else ", not adapted to each clip"
    print(f"TV clips, `detect --preset broadcast`, {who}; protocol, then in play "
          f"(frames at rest left out):", flush=True)
    per_venue: dict[str, tuple[Outcomes, Outcomes, int, int]] = {}
    for venue in folds:
        model = None
        if not args.shipped:
            model, seconds, rows = fold_classifier(venue, jobs, parts, place, args.seed)
            print(f"\nclassifier without {venue}: {rows} candidates, "
                  f"{'cached' if not seconds else f'trained in {seconds:.0f} s'}", flush=True)
        tasks = [(c, model, rest_frames(c.labels, 1280, c.video), adapt)
                 for c in clips if place[c.name] == venue]
        total, play, at_rest = Outcomes(), Outcomes(), 0
        causes: collections.Counter = collections.Counter()
        with ProcessPoolExecutor(args.jobs) as pool:
            for (clip, _m, rest, _a), counts in zip(tasks, pool.map(_score, tasks)):
                o, p = outcomes(counts), outcomes(counts, "in-play ")
                total, play, at_rest = total + o, play + p, at_rest + len(rest)
                print(f"  {clip.name:12s} {venue:13s} {'held-out' if clip.held_out else 'tuned-on':8s} "
                      f"{o.total:5d} frames {len(rest):4d} at rest  {fmt(o)}  | {fmt(p)}  ({counts_of(o)})",
                      flush=True)
                causes += counts
        per_venue[venue] = (total, play, at_rest, len(tasks))
        print(f"  {venue} total: {fmt(total)}  | in play {fmt(play)}  ({counts_of(total)}; in play "
              f"{counts_of(play)})", flush=True)
        if args.causes:
            _print_causes(causes)
    print(f"\nper venue ({who}): accuracy, precision, recall, F1 | the same in play")
    everything = [Outcomes(), Outcomes(), 0, 0]
    for venue, (o, p, rest, n) in per_venue.items():
        everything = [everything[0] + o, everything[1] + p, everything[2] + rest, everything[3] + n]
        print(f"  {venue:13s} {n:2d} clips {o.total:5d} frames {rest:4d} at rest  {fmt(o)}  | {fmt(p)}")
    o, p, rest, n = everything
    print(f"  {'all':13s} {n:2d} clips {o.total:5d} frames {rest:4d} at rest  {fmt(o)}  | {fmt(p)}")
    return 0


def _print_causes(counts: collections.Counter) -> None:
    """A venue's wrong frames by outcome and cause (broadcast_census.py's causes), most first."""
    rows = sorted(((k, v) for k, v in counts.items() if isinstance(k, tuple)), key=lambda kv: -kv[1])
    for (outcome, cause), n in rows:
        print(f"    {n:5d}  {outcome:3s}  {cause}")


def rest_census() -> int:
    """How many labelled-visible frames of each clip are at rest (the in-play score leaves them out)."""
    print(f"{'clip':26s} {'visible':>7s} {'at rest':>7s}  frames")
    for clip in stereo_clips():
        for camera, labels, video in (("left", clip.left_labels, clip.left),
                                      ("right", clip.right_labels, clip.right)):
            _line(f"{clip.name} {camera}", labels, rest_frames(labels, 2048, video))
    place = venues()
    for clip in broadcast_clips():
        _line(f"{clip.name} ({place.get(clip.name, '?')})", clip.labels, rest_frames(clip.labels, 1280, clip.video))
    return 0


def _line(name: str, labels: Path, rest: frozenset[int]) -> None:
    visible = int(read_point_labels(labels).visible.sum())
    print(f"{name:26s} {visible:7d} {len(rest):7d}  {_spans(sorted(rest))}")


def _spans(frames: list[int]) -> str:
    """1, 2, 3, 7 -> "1–3, 7"."""
    out, start = [], None
    for k, f in enumerate(frames):
        start = f if start is None else start
        if k + 1 == len(frames) or frames[k + 1] != f + 1:
            out.append(f"{start}–{f}" if f > start else str(f))
            start = None
    return ", ".join(out)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--venues", action="store_true", help="leave-one-venue-out on the TV clips")
    mode.add_argument("--rest", action="store_true", help="labelled frames at rest per clip")
    ap.add_argument("--only", nargs="*", default=None, metavar="VENUE", help="these folds only")
    ap.add_argument("--shipped", action="store_true",
                    help="--venues: score every venue with the shipped classifier (no training)")
    ap.add_argument("--adapt", action=argparse.BooleanOptionalAction, default=None,
                    help="--venues: adapt the classifier to each clip first, or not (default: as the "
                         "broadcast preset's classifier.adapt_min_run says; --adapt against --no-adapt "
                         "gives the adaptation's before -> after on unseen venues)")
    ap.add_argument("--causes", action="store_true",
                    help="--venues: also each venue's wrong frames by cause (broadcast_census.py)")
    ap.add_argument("--seed", type=int, default=0, help="the MLPs' random start")
    ap.add_argument("--jobs", type=int, default=1)
    args = ap.parse_args()
    return rest_census() if args.rest else leave_venue_out(args)


if __name__ == "__main__":
    raise SystemExit(main())

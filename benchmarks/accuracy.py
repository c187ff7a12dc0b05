"""Accuracy of `badminton-track track` and `detect` on the real clips.

Why this file exists: every figure about detection quality in the README must be regenerable
by one command. For each clip it runs the real CLI (`track` with both cameras of a stereo clip,
paired by the label files' timestamps, or by the videos' own times for a clip labelled through
seeks, whose labels it compares with the image each was drawn on: clips.LABELLED_BY_SEEK;
`detect` on each camera alone; `detect --preset
broadcast` on the TV clips), scores the output with the five-outcome protocol (TP, TN, FP1,
FP2, FN at 4 px @ 512 px width), and prints one row per clip and camera, marked tuned-on or
held-out, with the processing speed of the run. On the NYCU rallies it also triangulates the
labels (rig from the .cfg files) and reports the median / p90 distance of our 3D points.

    .venv/bin/python benchmarks/accuracy.py            # everything (~15–25 min on 2 cores)
    .venv/bin/python benchmarks/accuracy.py --quick    # 3 clips, first 900 frames

Two CLI runs go in parallel (one per core); each `track` run also uses two camera threads,
so the speeds printed are under full load (pessimistic), not isolated measurements.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import math
import re
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from badminton_gui.core.evaluation import Outcomes, evaluate, in_play, tolerance_px  # noqa: E402
from badminton_gui.core.rig import StereoRig  # noqa: E402
from badminton_gui.io.labels import read_point_labels  # noqa: E402
from clips import (LABELLED_BY_SEEK, broadcast_clips, nycu_cfgs, rest_frames,  # noqa: E402
                   seek_frame_map, stereo_clips)

CLI = [sys.executable, "-m", "badminton_gui.cli"]


@dataclass
class Row:
    clip: str
    camera: str
    mode: str
    held_out: bool
    kind: str
    outcomes: Outcomes
    rate: float          # frames (or pairs) per second of the CLI run, decoding included
    unit: str
    in_play: Outcomes    # the same without the labelled frames at rest (core/evaluation.py)
    rest: int            # how many labelled frames are at rest


def scored(clip: str, camera: str, mode: str, held_out: bool, kind: str, pred: dict, labels: Path,
           width: int, max_frames: int | None, video: Path, seek: bool, rate: float, unit: str) -> Row:
    """One row: ``pred`` scored by the protocol and in play (the label rows of ``labels`` whose
    shuttle is at rest left out, ``clips.rest_frames``)."""
    rest = rest_frames(labels, width, video)
    seek_video = video if seek else None
    return Row(clip, camera, mode, held_out, kind, score(pred, labels, width, max_frames, seek_video),
               rate, unit, score(pred, labels, width, max_frames, seek_video, rest), len(rest))


def run_cli(argv: list[str]) -> tuple[float, str]:
    start = time.perf_counter()
    proc = subprocess.run(CLI + argv, cwd=ROOT, capture_output=True, text=True)
    elapsed = time.perf_counter() - start
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(argv)} failed:\n{proc.stderr}")
    m = re.search(r"([\d.]+) (?:pairs|frames)/s", proc.stdout)
    return (float(m.group(1)) if m else float("nan")), proc.stdout


def score(pred: dict, labels_path: Path, width: int, max_frames: int | None,
          seek_video: Path | None = None, rest: frozenset[int] = frozenset()) -> Outcomes:
    """The five outcomes of ``pred`` (decoded frame -> detection) against a label file.
    ``seek_video``: the labels were drawn on the frames a seek to each index shows
    (clips.LABELLED_BY_SEEK): label row i is compared with the prediction for that image, and rows
    whose seek shows no image are left out. ``rest``: label rows left out (the in-play score)."""
    labels = in_play(read_point_labels(labels_path).as_dict(), rest)
    last = (max(pred) if pred else -1) if max_frames is not None else None
    if seek_video is not None:
        images = seek_frame_map(seek_video)
        labels = {i: v for i, v in labels.items()
                  if i < len(images) and images[i] >= 0 and (last is None or images[i] <= last)}
        pred = {i: pred[int(images[i])] for i in labels if int(images[i]) in pred}
    elif last is not None:
        labels = {f: v for f, v in labels.items() if f <= last}
    return evaluate(pred, labels, tolerance_px(width))


def read_track(path: Path):
    left, right, rows = {}, {}, []
    with path.open() as fh:
        for r in csv.DictReader(fh):
            f, fr = int(r["Frame"]), int(r["FrameR"])
            left[f] = (r["VisL"] == "1", float(r["XL"] or 0), float(r["YL"] or 0))
            right.setdefault(fr, (r["VisR"] == "1", float(r["XR"] or 0), float(r["YR"] or 0)))
            rows.append(r)
    return left, right, rows


def read_detect(path: Path) -> dict:
    return read_point_labels(path).as_dict()


def _lookahead_args(lookahead: int | None) -> list[str]:
    return [] if lookahead is None else ["--lookahead", str(lookahead)]


def stereo_jobs(clip, tmp: Path, max_frames: int | None, rig_path: Path, preset: str | None = None,
                lookahead: int | None = None, adapt: bool | None = None):
    """Jobs for one stereo clip: `track` first, then `detect` per camera. ``adapt``: `track
    --adapt` / `--no-adapt` (None: the preset's ``adapt.enabled``)."""
    out_track = tmp / f"{clip.name}_track.csv"
    extra = ["--max-frames", str(max_frames)] if max_frames else []
    preset_args = ["--preset", preset] if preset else []
    preset_args += _lookahead_args(lookahead)

    seek = clip.labelled_by_seek

    # Such a clip's label files time frame i at i / fps: its cameras pair by the videos' own
    # frame times instead (track --video-times).
    pairing = (["--video-times"] if seek else
               ["--left-times", str(clip.left_labels), "--right-times", str(clip.right_labels)])

    def track():
        rate, _ = run_cli(["track", "--left", str(clip.left), "--right", str(clip.right),
                           "--calib", str(rig_path), "-o", str(out_track)]
                          + pairing + extra + preset_args
                          + ([] if adapt is None else ["--adapt" if adapt else "--no-adapt"]))
        left, right, rows = read_track(out_track)
        rows_out = [scored(clip.name, "left", "track", clip.held_out, "stereo", left, clip.left_labels,
                           2048, max_frames, clip.left, seek, rate, "pairs/s"),
                    scored(clip.name, "right", "track", clip.held_out, "stereo", right, clip.right_labels,
                           2048, max_frames, clip.right, seek, rate, "pairs/s")]
        return rows_out, three_d_errors(rows, clip, rig_path)

    def detect(camera: str, video: Path, labels: Path):
        def job():
            out = tmp / f"{clip.name}_{camera}_detect.csv"
            if max_frames:
                rate = detect_in_process(video, out, max_frames, preset, lookahead)
            else:
                rate, _ = run_cli(["detect", str(video), "-o", str(out)] + preset_args)
                rate = rate if rate == rate else _rate_from_elapsed(video)
            return [scored(clip.name, camera, "detect", clip.held_out, "stereo", read_detect(out),
                           labels, 2048, max_frames, video, seek, rate, "frames/s")], None
        return job

    return [track, detect("left", clip.left, clip.left_labels),
            detect("right", clip.right, clip.right_labels)]


def _rate_from_elapsed(video: Path) -> float:
    return float("nan")


def detect_in_process(video: Path, out: Path, max_frames: int, preset: str | None,
                      lookahead: int | None = None) -> float:
    """`detect` limited to the first frames (the CLI has no --max-frames)."""
    import cv2

    from badminton_gui.cli.common import FILE_LOOKAHEAD
    from badminton_gui.core.detector import CameraDetector
    from badminton_gui.core.lookahead import CameraLookahead
    from badminton_gui.io.labels import write_point_labels
    from badminton_gui.io.presets import load_preset
    from badminton_gui.io.video import VideoFile
    v = VideoFile(video)
    params = load_preset(preset).with_value(
        "lookahead.frames", FILE_LOOKAHEAD if lookahead is None else lookahead)
    start = time.perf_counter()
    det = CameraDetector(params)
    if params.lookahead.frames > 0 and params.classifier.adapt_min_run > 0:
        # As `detect` does on a file (core/adaptation.py); the live readout (look-ahead 0) does not.
        from badminton_gui.core.adaptation import adapt_to_recording

        def first_frames():
            clip = VideoFile(video)
            try:
                for i in range(max_frames):
                    if (image := clip.read()) is None:
                        break
                    yield image, i / clip.fps
            finally:
                clip.close()
        adapted, _harvest = adapt_to_recording(params, first_frames)
        if adapted is not None:
            det.use_classifier(adapted)
    la = CameraLookahead(params)
    frames, vis, xy = [], [], []
    decided = []
    for i in range(max_frames):
        frame = v.read()
        if frame is None:
            break
        decided += la.push(det.process(frame, i / v.fps, keep_mask=False), i / v.fps)
    decided += la.flush()
    for i, res in enumerate(decided):
        d = res.detection
        frames.append(i)
        vis.append(d is not None)
        xy.append((d.x, d.y) if d else (0.0, 0.0))
    v.close()
    write_point_labels(out, frames, vis, xy)
    del cv2
    return len(frames) / (time.perf_counter() - start)


# A left label that moves more than this (px at 2048 px) between the frames 3 before and 3 after
# marks the shuttle in flight (``three_d_errors``' coverage count).
FLIGHT_MOVE_PX = 12.0


def three_d_errors(rows, clip, rig_path: Path) -> tuple[np.ndarray, int, int, int, int] | None:
    """NYCU rallies only: (distances (m) between our 3D points and the triangulated labels, frames
    in flight that both cameras report, how many of those have no 3D point for the robot, frames
    in flight that both cameras' labels mark whatever we report, how many of those have none)."""
    if not clip.name.startswith("rally_"):
        return None
    rig = StereoRig.load(rig_path)
    ll = read_point_labels(clip.left_labels).as_dict()
    rl = read_point_labels(clip.right_labels).as_dict()
    ours, pl, pr = [], [], []
    in_flight = without_point = labelled_flight = labelled_without = 0
    for r in rows:
        f = int(r["Frame"])
        a = ll.get(f)
        b = rl.get(int(r["FrameR"]))
        if not (a and b and a[0] and b[0]):
            continue
        before, after = ll.get(f - 3), ll.get(f + 3)
        if (before and after and before[0] and after[0]
                and math.hypot(after[1] - before[1], after[2] - before[2]) > FLIGHT_MOVE_PX):
            labelled_flight += 1
            labelled_without += r["Vis3D"] != "1"
            if r["VisL"] == "1" and r["VisR"] == "1":
                in_flight += 1
                without_point += r["Vis3D"] != "1"
        if r["Vis3D"] != "1":
            continue
        ours.append((float(r["X"]), float(r["Y"]), float(r["Z"])))
        pl.append(a[1:])
        pr.append(b[1:])
    counts = (in_flight, without_point, labelled_flight, labelled_without)
    if not ours:
        return (np.zeros(0), *counts)
    truth = rig.to_output(rig.triangulate(np.array(pl), np.array(pr)))
    return (np.linalg.norm(np.array(ours) - truth, axis=1), *counts)


def broadcast_job(clip, tmp: Path, max_frames: int | None, lookahead: int | None = None,
                  preset: str = "broadcast"):
    def job():
        out = tmp / f"{clip.name}_detect.csv"
        if max_frames:
            rate = detect_in_process(clip.video, out, max_frames, preset, lookahead)
        else:
            # The live readout (look-ahead 0) is what the GUI gets: it does not adapt the
            # classifier to the recording (core/adaptation.py), so neither does its figure.
            rate, _ = run_cli(["detect", str(clip.video), "-o", str(out), "--preset", preset]
                              + _lookahead_args(lookahead) + (["--no-adapt"] if lookahead == 0 else []))
        return [scored(clip.name, "-", "detect", clip.held_out, "broadcast", read_detect(out),
                       clip.labels, 1280, max_frames, clip.video, False, rate, "frames/s")], None
    return job


def fmt_row(r: Row) -> str:
    o = r.outcomes
    mark = "held-out" if r.held_out else "tuned-on"
    return (f"{r.clip:16s} {r.camera:5s} {r.mode:6s} {mark:8s} {o.tp:5d} {o.tn:5d} {o.fp1:5d} "
            f"{o.fp2:5d} {o.fn:5d}  {o.accuracy:6.3f} {o.precision:6.3f} {o.recall:6.3f} "
            f"{o.f1:6.3f}  {r.rest:4d} {r.in_play.accuracy:6.3f} {r.in_play.f1:6.3f}  {r.rate:6.1f} {r.unit}")


HEADER = (f"{'clip':16s} {'cam':5s} {'mode':6s} {'set':8s} {'TP':>5s} {'TN':>5s} {'FP1':>5s} "
          f"{'FP2':>5s} {'FN':>5s}  {'acc':>6s} {'prec':>6s} {'recall':>6s} {'F1':>6s}  "
          f"{'rest':>4s} {'playacc':>6s} {'playF1':>6s}  speed")


def main() -> int:
    ap = argparse.ArgumentParser(description="accuracy of track/detect on the real clips")
    ap.add_argument("--quick", action="store_true", help="3 clips, first 900 frames each")
    ap.add_argument("--jobs", type=int, default=2, help="CLI runs in parallel")
    ap.add_argument("--only", default=None, help="regex on clip names")
    ap.add_argument("--track-only", action="store_true",
                    help="stereo clips: `track` only (no one-camera `detect` rows, half the time)")
    ap.add_argument("--detect-only", action="store_true",
                    help="stereo clips: the one-camera `detect` rows only (no `track`)")
    ap.add_argument("--preset", default=None,
                    help="preset name or .json for the stereo clips (default: the default preset)")
    ap.add_argument("--rig", default=None, metavar="RIG.yaml",
                    help="rig file for the stereo clips (default: imported from the NYCU .cfg files); "
                         "the labels are triangulated with it too")
    ap.add_argument("--broadcast-preset", default="broadcast", metavar="NAME",
                    help="preset name or .json for the broadcast clips (default: broadcast)")
    ap.add_argument("--lookahead", type=int, default=None, metavar="N",
                    help="frames of look-ahead for every CLI run (default: the CLI's own default; 0 = live readout)")
    ap.add_argument("--adapt", action=argparse.BooleanOptionalAction, default=None,
                    help="stereo clips: `track --adapt` (each camera's classifier adapted to the clip "
                         "from a first pass's flights, core/court_adaptation.py) or --no-adapt "
                         "(default: the preset's adapt.enabled)")
    ap.add_argument("--keep", default=None, metavar="DIR",
                    help="write the CLI outputs (track/detect CSVs, rig) here and keep them for diagnosis")
    args = ap.parse_args()
    stereo = stereo_clips()
    broadcast = broadcast_clips()
    if not stereo and not broadcast:
        print("no data found under", ROOT.parent / "shared" / "data")
        return 1
    max_frames = None
    if args.quick:
        stereo = [c for c in stereo if c.name in ("rally_11-46-04", "rally_11-49-21")]
        broadcast = [c for c in broadcast if c.name == "bwf_00041"]
        max_frames = 900
    if args.only:
        stereo = [c for c in stereo if re.search(args.only, c.name)]
        broadcast = [c for c in broadcast if re.search(args.only, c.name)]
    with contextlib.ExitStack() as stack:
        if args.keep:
            tmp = Path(args.keep)
            tmp.mkdir(parents=True, exist_ok=True)
        else:
            tmp = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="accuracy_")))
        if args.rig:
            rig_path = Path(args.rig).resolve()
        else:
            rig_path = tmp / "nycu_rig.yaml"
            cfg1, cfg2 = nycu_cfgs()
            run_cli(["import-calib", "--nycu", str(cfg1), str(cfg2), "-o", str(rig_path)])
        jobs = []
        for c in stereo:
            clip_jobs = stereo_jobs(c, tmp, max_frames, rig_path, args.preset, args.lookahead, args.adapt)
            jobs += clip_jobs[:1] if args.track_only else clip_jobs[1:] if args.detect_only else clip_jobs
        jobs += [broadcast_job(c, tmp, max_frames, args.lookahead, args.broadcast_preset) for c in broadcast]
        start = time.perf_counter()
        with ThreadPoolExecutor(args.jobs) as pool:
            results = list(pool.map(lambda j: j(), jobs))
    rows = [r for rs, _ in results for r in rs]
    errs = [e for _, e in results if e is not None]
    print(HEADER)
    for r in rows:
        print(fmt_row(r))
    print()
    print("totals (summed outcomes):")
    for kind, mode in (("stereo", "track"), ("stereo", "detect"), ("broadcast", "detect")):
        for held in (False, True):
            sel = [r for r in rows if r.kind == kind and r.mode == mode and r.held_out == held]
            if not sel:
                continue
            tot = sum((r.outcomes for r in sel), Outcomes())
            rates = [r.rate for r in sel if r.rate == r.rate]
            print(f"  {kind:9s} {mode:6s} {'held-out' if held else 'tuned-on':8s} {tot.summary()}"
                  f"  median speed {np.median(rates) if rates else float('nan'):.1f} {sel[0].unit}")
            # Beside it, never instead: the in-play score (the frames at rest left out).
            play = sum((r.in_play for r in sel), Outcomes())
            print(f"  {'':9s} {'':6s} {'in play':8s} {play.summary()}  ({sum(r.rest for r in sel)} "
                  f"frames at rest left out)")
            # The totals without the clips labelled through seeks too: their score rests on
            # clips.seek_frame_map, the others' on the labels alone.
            sequential = [r for r in sel if r.clip not in LABELLED_BY_SEEK]
            if 0 < len(sequential) < len(sel):
                tot = sum((r.outcomes for r in sequential), Outcomes())
                print(f"  {'':9s} {'':6s} {'':8s} {tot.summary()}  without "
                      f"{', '.join(sorted({r.clip for r in sel} & LABELLED_BY_SEEK))} (labelled "
                      f"through seeks: benchmarks/clips.py)")
    if errs:
        d = np.concatenate([e[0] for e in errs])
        if len(d):
            print(f"3D vs triangulated labels (NYCU rallies, {len(d)} pairs): median "
                  f"{np.median(d):.3f} m, p90 {np.percentile(d, 90):.3f} m")
        flying, missing = sum(e[1] for e in errs), sum(e[2] for e in errs)
        if flying:
            # (the robot's live stream is the --lookahead 0 readout's: a flight's first points
            # reach only the file readout, core/lookahead.py)
            print(f"3D point on {100.0 * (flying - missing) / flying:.1f} % of the frames in "
                  f"flight that both cameras report ({missing} of {flying} without; flight: the left "
                  f"label moves > {FLIGHT_MOVE_PX:g} px over ±3 frames)")
        flying, missing = sum(e[3] for e in errs), sum(e[4] for e in errs)
        if flying:
            print(f"  ... on {100.0 * (flying - missing) / flying:.1f} % of the frames in flight that both "
                  f"cameras' labels mark, whatever the cameras report ({missing} of {flying} without)")
    print(f"wall time {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

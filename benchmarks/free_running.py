"""How the real two-camera clips' frames pair in time, and what pairing them at one time gives.

Why this file exists: the NYCU rallies' cameras pair within 0.1 ms, but launcher-stereo's are
free-running and drop frames (GUIDE §5): nearest-timestamp pairing there left right frames
unpaired (never tracked) and paired images milliseconds apart. This prints, per clip, what the
pairing schedule (``io/video.py`` ``pairing_schedule``) makes of the two clocks, and, for one
clip, how smooth the measured 3D points are with and without the right detection moved to the
left image's time (``StereoTracker._right_xy``): the leave-one-out residual of each measured
point about a quadratic through its six neighbours (a 7-point window ≤ 80 ms) — a shuttle's
flight is smooth on that scale, so the residual is measurement error, and a pair triangulated
from two moments shows up in it. No labels are read (the launcher clip has no 3D labels). Then
the demo court, whose truth is exact, with its right camera taken ``--demo-lag-ms`` before the
left (``io/demo_eval.py`` ``delayed_right_errors``): the 3D error with and without the move.
And the steps that bring one camera's image only (``stereo.one_camera_rays``): how many of the
clip's carry a reported point and how smooth those are, and the demo court with its cameras
dropping frames (``dropped_frame_errors``) against its truth, with and without the rays.

    .venv/bin/python benchmarks/free_running.py            # every clip's pairing, launcher 3D, demo (≈ 1.5 min)
    .venv/bin/python benchmarks/free_running.py --clip rally_11-46-04 --demo-lag-ms 2
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from clips import nycu_cfgs, stereo_clips  # noqa: E402

from badminton_gui.core.tracker import StereoTracker  # noqa: E402
from badminton_gui.io.demo_eval import delayed_right_errors, dropped_frame_errors  # noqa: E402
from badminton_gui.io.labels import read_timestamps  # noqa: E402
from badminton_gui.io.nycu import rig_from_nycu  # noqa: E402
from badminton_gui.io.presets import load_preset  # noqa: E402
from badminton_gui.io.video import VideoPair, frame_times, pairing_schedule  # noqa: E402

WINDOW = 7            # points in the local fit (the middle one left out)
WINDOW_SPAN = 0.08    # s: a window longer than this spans a gap or a hit and is skipped


def clip_times(clip) -> tuple[np.ndarray, np.ndarray]:
    """Each camera's frame times as the accuracy benchmark pairs them: the launcher clip by its
    videos' own times (its label files' Timestamp is i / fps), the rallies by their label CSVs."""
    if clip.labelled_by_seek:
        return frame_times(clip.left), frame_times(clip.right)
    return read_timestamps(clip.left_labels)[1], read_timestamps(clip.right_labels)[1]


def pairing_row(clip, left_times, right_times) -> str:
    steps = pairing_schedule(left_times, right_times)
    pairs = [(i, j) for i, j, fl, fr in steps if fl and fr]
    apart = np.array([abs(left_times[i] - right_times[j]) for i, j in pairs]) * 1000.0
    right_only = sum(1 for _, _, fl, _ in steps if not fl)
    left_only = sum(1 for _, _, _, fr in steps if not fr)
    return (f"{clip.name:16s} {len(left_times):5d} {len(right_times):5d} {len(pairs):6d} {right_only:10d} "
            f"{left_only:9d}   {np.median(apart):6.2f} {np.percentile(apart, 90):6.2f} {apart.max():6.2f}")


def tracked_points(clip, left_times, right_times, **values) -> tuple[np.ndarray, np.ndarray]:
    """Track the clip with the default preset (``values``: "group.name" overrides): (measured
    points, reported points), each row t, x, y, z, the pair's right − left time (s), and 1 for
    a step that brought one camera's image only."""
    rig = rig_from_nycu(*nycu_cfgs())
    source = VideoPair(clip.left, clip.right, left_times, right_times)
    params = load_preset("default")
    for key, value in values.items():
        params = params.with_value(key, value)
    tracker = StereoTracker(rig, params)
    measured, reported = [], []
    try:
        while (frame := source.read()) is not None:
            result = tracker.process_frame(frame, keep_masks=False)
            extra = (frame.t_right - frame.t_left, float(not (frame.fresh_left and frame.fresh_right)))
            if result.measured_point is not None:
                measured.append((result.timestamp, *result.measured_point, *extra))
            if result.point is not None:
                reported.append((result.timestamp, *result.point, *extra))
    finally:
        tracker.close()
        source.close()
    return np.array(measured).reshape(-1, 6), np.array(reported).reshape(-1, 6)


def residuals(clip, left_times, right_times, align: bool) -> tuple[np.ndarray, np.ndarray]:
    """(leave-one-out residual, m; the pair's time apart, s) of each measured 3D point."""
    return loo_residuals(tracked_points(clip, left_times, right_times, **{"stereo.align_pairs": align})[0])[:2]


def loo_residuals(pts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(leave-one-out residual about a quadratic through its neighbours, m; the pair's time
    apart, s; one-camera step) of each point of ``tracked_points`` whose window is short enough."""
    half = WINDOW // 2
    out, apart, alone = [], [], []
    for k in range(half, len(pts) - half):
        w = pts[k - half:k + half + 1]
        if w[-1, 0] - w[0, 0] > WINDOW_SPAN:
            continue
        t = w[:, 0] - w[half, 0]
        basis = np.stack([np.ones_like(t), t, t * t], axis=1)
        others = np.arange(WINDOW) != half
        coef, *_ = np.linalg.lstsq(basis[others], w[others, 1:4], rcond=None)
        out.append(float(np.linalg.norm(basis[half] @ coef - w[half, 1:4])))
        apart.append(abs(w[half, 4]))
        alone.append(bool(w[half, 5]))
    return np.array(out), np.array(apart), np.array(alone, dtype=bool)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--clip", default="launcher-stereo",
                        help="the clip whose 3D points are compared with and without alignment")
    parser.add_argument("--demo-lag-ms", type=float, default=4.0,
                        help="how long before the left image the demo's right one is taken (0: skip)")
    parser.add_argument("--demo-frames", type=int, default=400)
    parser.add_argument("--demo-seed", type=int, default=3)
    args = parser.parse_args()
    clips = stereo_clips()
    if not clips:
        print("no two-camera clips under ../shared/data", file=sys.stderr)
        return 1
    print("clip             left right  pairs right-only left-only   time apart in pairs, ms: median p90 max")
    times = {}
    for clip in clips:
        times[clip.name] = clip_times(clip)
        print(pairing_row(clip, *times[clip.name]))
    chosen = next((c for c in clips if c.name == args.clip), None)
    if chosen is None:
        print(f"no clip named {args.clip}", file=sys.stderr)
        return 1
    print(f"\n{chosen.name}: measured 3D points, leave-one-out residual about a quadratic "
          f"({WINDOW} points ≤ {WINDOW_SPAN * 1000:.0f} ms), cm")
    print("right detection        points  median    p90   pairs < 2 ms apart   pairs ≥ 4 ms apart")
    for align, label in ((False, "as seen"), (True, "at the left's time")):
        res, apart = residuals(chosen, *times[chosen.name], align)
        near, far = res[apart < 0.002], res[apart >= 0.004]

        def med(a):
            return f"{np.median(a) * 100:6.2f} (n={len(a)})" if len(a) else "     - (n=0)"
        print(f"{label:20s} {len(res):8d} {np.median(res) * 100:7.2f} {np.percentile(res, 90) * 100:6.2f}"
              f"   {med(near):>18s}   {med(far):>18s}")
    print(f"\n{chosen.name}: reported 3D points (what the robot gets), leave-one-out residual as above, cm")
    print("one-camera steps       steps  with a point   residual median p90 (n)   all points: n median p90")
    for rays, label in ((False, "give nothing"), (True, "follow the ray")):
        _, reported = tracked_points(chosen, *times[chosen.name], **{"stereo.one_camera_rays": rays})
        res, _, alone = loo_residuals(reported)
        steps = sum(1 for _, _, fl, fr in pairing_schedule(*times[chosen.name]) if not (fl and fr))
        one = res[alone]
        one_txt = (f"{np.median(one) * 100:6.2f} {np.percentile(one, 90) * 100:6.2f} ({len(one)})"
                   if len(one) else "     -      - (0)")
        print(f"{label:20s} {steps:7d} {int(reported[:, 5].sum()):13d}   {one_txt:>24s}   {len(res):6d} "
              f"{np.median(res) * 100:6.2f} {np.percentile(res, 90) * 100:6.2f}")
    print("\ndemo court (binocular rig, seed 3, 300 frames), cameras dropping frames (every 7th left, "
          "4 right): reported 3D points against the truth, cm")
    print("one-camera steps       pairs: n median    p90   one-camera steps: in play  n median    p90")
    for rays, label in ((False, "give nothing"), (True, "follow the ray")):
        pairs, alone, in_play = dropped_frame_errors(load_preset("default").with_value("stereo.one_camera_rays", rays))
        alone_txt = (f"{len(alone):4d} {np.median(alone) * 100:6.2f} {np.percentile(alone, 90) * 100:6.2f}"
                     if len(alone) else f"{0:4d}      -      -")
        print(f"{label:20s} {len(pairs):9d} {np.median(pairs) * 100:6.2f} {np.percentile(pairs, 90) * 100:6.2f}"
              f"   {in_play:24d} {alone_txt}")
    if args.demo_lag_ms > 0:
        print(f"\ndemo court (binocular rig, seed {args.demo_seed}, {args.demo_frames} frames), right image "
              f"{args.demo_lag_ms:g} ms before the left: 3D error against the truth, cm")
        print("right detection        measured: n median    p90   reported: n median    p90")
        params = load_preset("default")
        for lag, align, label in ((0.0, True, "taken together"), (args.demo_lag_ms / 1000.0, False, "as seen"),
                                  (args.demo_lag_ms / 1000.0, True, "at the left's time")):
            measured, reported = delayed_right_errors(lag, args.demo_frames, args.demo_seed,
                                                      params.with_value("stereo.align_pairs", align))
            print(f"{label:20s} {len(measured):12d} {np.median(measured) * 100:6.2f} "
                  f"{np.percentile(measured, 90) * 100:6.2f} {len(reported):12d} "
                  f"{np.median(reported) * 100:6.2f} {np.percentile(reported, 90) * 100:6.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

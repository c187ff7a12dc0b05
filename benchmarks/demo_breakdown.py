"""Per-point 3D error breakdown on the demo court (what carries the sum of squares).

    .venv/bin/python benchmarks/demo_breakdown.py [--frames 1000] [--seeds 0 1 2] [--out points.npz]

Runs the loop of ``io/demo_eval.py`` and keeps, for every frame with a reported 3D point and a
truth position: seed, frame, range from the left camera, the error vector (court frame and left
camera frame), the flight age (points of the flight so far), whether the shuttle is lying, the
epipolar error, and the error of the raw triangulation. Prints the sum of squares by category.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from badminton_gui.core.params import TrackerParams  # noqa: E402
from badminton_gui.core.tracker import StereoTracker  # noqa: E402
from badminton_gui.io.demo_scene import DemoScene  # noqa: E402


def with_settings(settings: list[str]) -> TrackerParams:
    """TrackerParams with ``group.name=value`` overrides."""
    params = TrackerParams()
    for item in settings:
        key, value = item.split("=", 1)
        group, name = key.split(".")
        sub = getattr(params, group)
        kind = type(getattr(sub, name))
        value = (value.lower() in ("1", "true", "yes")) if kind is bool else kind(value)
        params = dataclasses.replace(params, **{group: dataclasses.replace(sub, **{name: value})})
    return params


def collect(seed: int, frames: int, size=(1280, 720), rig="binocular",
            params: TrackerParams | None = None) -> list[dict]:
    scene = DemoScene(seed=seed, size=size, rig=rig, n_frames=frames)
    tracker = StereoTracker(scene.rig, params)
    centre = scene.rig.camera_centres()[0]
    rows = []
    try:
        while True:
            frame = scene.read()
            if frame is None:
                break
            res = tracker.process(frame.left, frame.right, frame.t_left, frame.index,
                                  frame.index_right, keep_masks=False)
            truth = scene.truth(frame.index)
            if res.point is None or truth.position is None:
                continue
            traj = tracker.trajectory
            f = traj._flight
            filtered = traj.filtered_position() is not None
            age = len(f.points) if (filtered and f is not None) else 0
            truth_p = np.asarray(truth.position)
            err = np.subtract(res.point, truth_p)
            err_cam = scene.rig.to_left([res.point])[0] - scene.rig.to_left([truth_p])[0]
            meas_err = (np.subtract(res.measured_point, truth_p) if res.measured_point is not None
                        else np.full(3, np.nan))
            speed = float(np.linalg.norm(truth.velocity)) if truth.velocity is not None else 0.0
            rows.append(dict(seed=seed, frame=frame.index, range=float(np.linalg.norm(truth_p - centre)),
                             err=err, err_cam=err_cam, meas_err=meas_err, age=age, filtered=filtered,
                             lying=speed < 0.3, speed=speed, z=float(truth_p[2]),
                             epi=res.epipolar_error if res.epipolar_error is not None else np.nan,
                             shot=truth.shot_index))
    finally:
        tracker.close()
        scene.close()
    return rows


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=1000)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--range", type=float, default=6.0)
    ap.add_argument("--out", default="")
    ap.add_argument("--set", nargs="*", default=[], help="parameter overrides: group.name=value")
    args = ap.parse_args()
    rows = []
    for seed in args.seeds:
        rows += collect(seed, args.frames, params=with_settings(args.set))
    keys = ("seed", "frame", "range", "age", "filtered", "lying", "speed", "z", "epi", "shot")
    data = {k: np.array([r[k] for r in rows]) for k in keys}
    for k in ("err", "err_cam", "meas_err"):
        data[k] = np.array([r[k] for r in rows])
    if args.out:
        np.savez(args.out, **data)
    near = data["range"] <= args.range
    e2 = np.sum(data["err"] ** 2, axis=1)
    total = e2[near].sum()
    n = int(near.sum())
    print(f"{n} points within {args.range} m, RMS {100 * np.sqrt(total / n):.2f} cm")

    def line(name, sel):
        sel = sel & near
        k = int(sel.sum())
        if not k:
            return
        print(f"  {name:<28} n={k:4d}  share of Σe² {100 * e2[sel].sum() / total:5.1f} %  "
              f"RMS {100 * np.sqrt(e2[sel].mean()):5.2f} cm  mean err court "
              f"{np.array2string(100 * data['err'][sel].mean(0), precision=2)} cm  cam "
              f"{np.array2string(100 * data['err_cam'][sel].mean(0), precision=2)} cm")

    gross = np.sqrt(e2) > 0.05
    age = data["age"]
    line("lying", data["lying"])
    line("not filtered, flying", ~data["filtered"] & ~data["lying"])
    line("gross > 5 cm (flying)", gross & ~data["lying"])
    for lo, hi in ((1, 5), (5, 10), (10, 20), (20, 40), (40, 10000)):
        line(f"flying age {lo}-{hi - 1}, ≤ 5 cm", (age >= lo) & (age < hi) & ~gross & ~data["lying"])
    for s in args.seeds:
        line(f"seed {s}", data["seed"] == s)
    for lo, hi in ((0, 3), (3, 4.5), (4.5, 6)):
        line(f"range {lo}-{hi} m", (data["range"] > lo) & (data["range"] <= hi))


if __name__ == "__main__":
    main()

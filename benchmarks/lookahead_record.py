"""Record the online per-frame results of `track` / `detect` on real clips, for the look-ahead study.

Why this file exists: the look-ahead readout (core/lookahead.py) only reads what the online
pipeline produced (candidates with their tracklet ids, the online choice), never feeds back into
it. So the online results of a clip can be recorded once (TrackResults / CameraResults without
masks, benchmarks/result_cache.py) and the look-ahead replayed on them for any K in seconds,
giving exactly the output the CLI would give. ``benchmarks/lookahead_study.py`` reads these
recordings, by default in the user's private cache folder (clips.py ``cache_dir``).

    .venv/bin/python benchmarks/lookahead_record.py [--out DIR] [--only REGEX] [--held-out]
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from clips import broadcast_clips, cache_dir, nycu_cfgs, stereo_clips  # noqa: E402
from result_cache import save_results  # noqa: E402


def _rig(tmp: Path):
    import subprocess
    rig_path = tmp / "nycu_rig.yaml"
    if not rig_path.exists():
        cfg1, cfg2 = nycu_cfgs()
        subprocess.run([sys.executable, "-m", "badminton_gui.cli", "import-calib", "--nycu", str(cfg1),
                        str(cfg2), "-o", str(rig_path)], cwd=ROOT, check=True, capture_output=True)
    return rig_path


def _save(path: Path, results) -> None:
    save_results(path, results)


def _strip(res):
    import dataclasses
    return dataclasses.replace(res, mask=None)


def job_track(name: str, out_dir: str) -> str:
    import dataclasses

    from badminton_gui.core.rig import StereoRig
    from badminton_gui.core.tracker import StereoTracker, configure_opencv_threads
    from badminton_gui.io.labels import read_timestamps
    from badminton_gui.io.video import VideoPair
    clip = next(c for c in stereo_clips() if c.name == name)
    configure_opencv_threads()
    rig = StereoRig.load(_rig(Path(out_dir)))
    source = VideoPair(clip.left, clip.right, read_timestamps(clip.left_labels)[1],
                       read_timestamps(clip.right_labels)[1])
    tracker = StereoTracker(rig)
    results = []
    start = time.perf_counter()
    while True:
        frame = source.read()
        if frame is None:
            break
        r = tracker.process(frame.left, frame.right, frame.t_left, frame.index, frame.index_right,
                            keep_masks=False)
        results.append(dataclasses.replace(r, left=_strip(r.left), right=_strip(r.right)))
    source.close()
    tracker.close()
    _save(Path(out_dir) / f"{name}_track.json.gz", results)
    return f"{name} track {len(results)} pairs {time.perf_counter() - start:.0f} s"


def job_detect(name: str, camera: str, out_dir: str, preset: str | None) -> str:
    from badminton_gui.core.detector import CameraDetector
    from badminton_gui.io.presets import load_preset
    from badminton_gui.io.video import VideoFile
    if camera == "-":
        clip = next(c for c in broadcast_clips() if c.name == name)
        video = clip.video
    else:
        clip = next(c for c in stereo_clips() if c.name == name)
        video = clip.left if camera == "left" else clip.right
    v = VideoFile(video)
    det = CameraDetector(load_preset(preset))
    results = []
    start = time.perf_counter()
    i = 0
    while True:
        frame = v.read()
        if frame is None:
            break
        results.append((i, v.fps, _strip(det.process(frame, i / v.fps, keep_mask=False))))
        i += 1
    v.close()
    _save(Path(out_dir) / f"{name}_{camera}_detect.json.gz", results)
    return f"{name} {camera} detect {i} frames {time.perf_counter() - start:.0f} s"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=None, help="folder of the recordings (default: the private cache folder)")
    ap.add_argument("--only", default=None, help="regex on clip names")
    ap.add_argument("--held-out", action="store_true", help="the held-out clips instead of the tuned-on ones")
    ap.add_argument("--modes", default="track,broadcast", help="track, detect, broadcast (comma-separated)")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    out = Path(args.out) if args.out else cache_dir("lookahead")
    out.mkdir(parents=True, exist_ok=True)
    _rig(out)
    modes = set(args.modes.split(","))
    stereo = [c for c in stereo_clips() if c.held_out == args.held_out]
    broadcast = [c for c in broadcast_clips() if c.held_out == args.held_out]
    if args.only:
        stereo = [c for c in stereo if re.search(args.only, c.name)]
        broadcast = [c for c in broadcast if re.search(args.only, c.name)]
    with ProcessPoolExecutor(args.jobs) as pool:
        futs = []
        if "track" in modes:
            futs += [pool.submit(job_track, c.name, str(out)) for c in stereo]
        if "broadcast" in modes:
            futs += [pool.submit(job_detect, c.name, "-", str(out), "broadcast") for c in broadcast]
        if "detect" in modes:
            futs += [pool.submit(job_detect, c.name, cam, str(out), None)
                     for c in stereo for cam in ("left", "right")]
        for f in futs:
            print(f.result(), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

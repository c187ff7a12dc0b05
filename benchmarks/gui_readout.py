"""What the desktop tool's feeds show on the real clips: the GUI's own tracking worker
(gui/worker.py, the source opened as *Source ▸ One video* / *Stereo video pair* opens it, with
its label files for the live score), run headless and as fast as possible, once live and once
with the look-ahead view (Playback ▸ Look-ahead view).

Why this file exists: the command line's figures (accuracy.py) come from the file loops; the
operator watching a recording sees the worker's readout instead, which until the thirtieth round
was the live one only. This prints the score the "Against the truth" readout would end on, per
clip and summed, for each view; `--lookahead` picks the views. Tuned-on clips unless `--held-out`.
The steps/s include opening the source (a TV clip's adaptation pass with the look-ahead view);
"+MB" is the most the run added to the process's resident memory.

    .venv/bin/python benchmarks/gui_readout.py                       # TV clips, 0 and 4 frames
    .venv/bin/python benchmarks/gui_readout.py --stereo --only 46-04  # a NYCU rally too
"""

from __future__ import annotations

import argparse
import re
import sys
import tempfile
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from badminton_gui.core.evaluation import Outcomes  # noqa: E402
from badminton_gui.io.presets import load_preset  # noqa: E402
from clips import broadcast_clips, nycu_cfgs, stereo_clips  # noqa: E402


def _rss_mb() -> float:
    """This process's resident memory now (Linux), MB; nan elsewhere."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return float("nan")


def run_worker(spec, params, lookahead: int) -> tuple[Outcomes | None, Outcomes | None, float, int, float]:
    """The worker's final scores per camera, its wall time, the results it produced and the most
    its run added to the process's resident memory (MB; sampled every 20 ms)."""
    from PySide6.QtCore import Qt

    from badminton_gui.gui.sources import open_spec
    from badminton_gui.gui.worker import TrackingWorker

    worker = TrackingWorker(lambda context: open_spec(spec, context), params, realtime=False,
                            lookahead_frames=lookahead)
    done = threading.Event()
    errors: list[str] = []
    # Direct: no event loop runs here to deliver a queued call from the worker's thread.
    direct = Qt.ConnectionType.DirectConnection
    worker.ended.connect(lambda *_: done.set(), direct)
    worker.error.connect(lambda text: (errors.append(text), done.set()), direct)
    start = time.perf_counter()
    base = peak = _rss_mb()
    thread = threading.Thread(target=worker.run, daemon=True)
    thread.start()
    while not done.wait(0.02):
        peak = max(peak, _rss_mb())
    worker.abort()
    thread.join(60)
    if errors:
        raise SystemExit(f"{spec.describe()}: {errors[0]}")
    stats = worker.latest_stats
    return stats.score_left, stats.score_right, time.perf_counter() - start, stats.frames, peak - base


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--lookahead", type=int, nargs="+", default=[0, 4], help="views to run")
    ap.add_argument("--only", default="", help="regex on clip names")
    ap.add_argument("--stereo", action="store_true", help="the NYCU rallies (default preset) instead of TV")
    ap.add_argument("--held-out", action="store_true", help="allow held-out clips (final measurement only)")
    args = ap.parse_args()

    from PySide6.QtCore import QCoreApplication
    app = QCoreApplication.instance() or QCoreApplication([])   # noqa: F841 - signals need one

    from badminton_gui.gui.settings import SourceSpec
    with tempfile.TemporaryDirectory() as tmp:
        if args.stereo:
            from badminton_gui.cli import main as cli
            rig = Path(tmp) / "nycu_rig.yaml"
            cli(["import-calib", "--nycu", *map(str, nycu_cfgs()), "-o", str(rig)])
            params = load_preset("default")
            jobs = [(c.name, c.held_out, SourceSpec("video", str(c.left), str(c.right), str(rig),
                                                    left_times=str(c.left_labels),
                                                    right_times=str(c.right_labels), realtime=False))
                    for c in stereo_clips() if c.name.startswith("rally")]
        else:
            params = load_preset("broadcast")
            jobs = [(c.name, c.held_out, SourceSpec("single", str(c.video), realtime=False,
                                                    left_labels=str(c.labels)))
                    for c in broadcast_clips()]
        jobs = [j for j in jobs if re.search(args.only, j[0]) and (args.held_out or not j[1])]
        totals = {k: Outcomes() for k in args.lookahead}
        for name, held_out, spec in jobs:
            line = f"{name:16s}{' (held out)' if held_out else '':11s}"
            for k in args.lookahead:
                left, right, seconds, frames, memory = run_worker(spec, params, k)
                both = Outcomes()
                for s in (left, right):
                    if s is not None:
                        both = both + s
                totals[k] = totals[k] + both
                line += (f"  view {k}: {100 * both.accuracy:6.2f} % ({frames / seconds:5.1f} steps/s, "
                         f"+{memory:.0f} MB)")
            print(line, flush=True)
        print("total           " + " " * 11 + "".join(
            f"  view {k}: {100 * t.accuracy:6.2f} % (TP {t.tp} TN {t.tn} FP1 {t.fp1} FP2 {t.fp2} FN {t.fn})"
            for k, t in totals.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""The real evaluation clips (GUIDE §5) and which ones tuning may look at.

Why this file exists: the accuracy benchmark and the classifier training must agree on which
clips are *tuned-on* (parameters and the classifier may be fitted to them) and which are
*held out* (only ever measured). Paths are relative to ``/work/shared/data`` (or $BADMINTON_DATA).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

DATA_DIR = Path(os.environ.get("BADMINTON_DATA",
                               Path(__file__).resolve().parents[1].parent / "shared" / "data"))

HELD_OUT = {"rally_11-48-10", "rally_11-49-21", "rally_11-47-41", "launcher-stereo",
            "bwf_00041", "1_06_06"}

# Clips whose labels do not follow the decoded frames: on launcher-stereo 81–84 % of the labels
# our detections meet are met 3–17 frames later (2–14 % on the NYCU rallies, where the shuttle
# at rest makes such matches); its videos have irregular timestamps and the labels were numbered
# on a time-resampled copy. Their rows stay in the tables; totals are also given without them.
# Evidence: benchmarks/label_alignment.py.
LABELS_MISALIGNED = {"launcher-stereo"}


@dataclass(frozen=True)
class StereoClip:
    name: str
    left: Path
    right: Path
    left_labels: Path
    right_labels: Path

    @property
    def held_out(self) -> bool:
        return self.name in HELD_OUT


@dataclass(frozen=True)
class MonoClip:
    name: str
    video: Path
    labels: Path

    @property
    def held_out(self) -> bool:
        return self.name in HELD_OUT


def stereo_clips() -> list[StereoClip]:
    out = []
    for rally in sorted((DATA_DIR / "nycu-stereo").glob("rally_*")):
        out.append(StereoClip(rally.name, rally / "CameraReader_1.mp4", rally / "CameraReader_2.mp4",
                              rally / "CameraReader_1.csv", rally / "CameraReader_2.csv"))
    launcher = DATA_DIR / "launcher-stereo"
    if launcher.is_dir():
        stem = launcher / "2024-09-19_10-26-01"
        out.append(StereoClip("launcher-stereo", Path(f"{stem}_1.mp4"), Path(f"{stem}_2.mp4"),
                              Path(f"{stem}_1_ball.csv"), Path(f"{stem}_2_ball.csv")))
    return [c for c in out if c.left.is_file() and c.right.is_file()]


def broadcast_clips() -> list[MonoClip]:
    return [MonoClip(v.stem, v, v.with_name(v.stem + "_ball.csv"))
            for v in sorted((DATA_DIR / "broadcast").glob("*.mp4"))
            if v.with_name(v.stem + "_ball.csv").is_file()]


def nycu_cfgs() -> tuple[Path, Path]:
    """The rally calibration (.cfg) that fits every NYCU clip and the launcher clip."""
    rally = sorted((DATA_DIR / "nycu-stereo").glob("rally_*"))[0]
    return rally / "CameraReader_1.cfg", rally / "CameraReader_2.cfg"

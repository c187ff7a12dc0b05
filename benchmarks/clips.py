"""The real evaluation clips and which ones tuning may look at.

Why this file exists: the accuracy benchmark and the classifier training must agree on which
clips are *tuned-on* (parameters and the classifier may be fitted to them) and which are
*held out* (only ever measured), and on which image each label row of a clip was drawn (a clip
labelled through seeks: ``seek_frame_map``). Paths are relative to ``/work/shared/data`` (or $BADMINTON_DATA).
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from pathlib import Path
from stat import S_ISLNK

import cv2
import numpy as np

from badminton_gui.core.evaluation import at_rest_frames
from badminton_gui.io.labels import read_point_labels, read_timestamps
from badminton_gui.io.safe_write import replacing
from badminton_gui.io.video import frame_times

DATA_DIR = Path(os.environ.get("BADMINTON_DATA",
                               Path(__file__).resolve().parents[1].parent / "shared" / "data"))

def cache_dir(name: str) -> Path:
    """A private folder for one benchmark's cache: ``$XDG_CACHE_HOME/badminton-gui/<name>``
    (default ``~/.cache``), mode 0700 and owned by this user, shared by every checkout of the same
    user. A cache in a fixed /tmp path could be planted by another local user; this one is
    refused if it is a symlink, another user's, or open to others."""
    root = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "badminton-gui"
    folder = root / name
    folder.mkdir(mode=0o700, parents=True, exist_ok=True)
    for path in (root, folder):
        info = os.lstat(path)
        if S_ISLNK(info.st_mode) or info.st_uid != os.getuid():
            raise RuntimeError(f"benchmark cache {path} is a symlink or another user's: remove it")
        if info.st_mode & 0o077:
            os.chmod(path, 0o700)
    return folder


# The clips whose frames were looked at while choosing parameters and training the shipped
# classifiers. Every other clip is held out: only ever measured. Listed this way round so that a
# clip added to the shared data later counts as held out (and is never trained on) by default.
TUNED_ON = {"rally_11-46-04", "rally_11-46-22", "rally_11-47-02", "rally_11-47-21", "rally_11-48-00",
            "1_02_01", "bwf_00001", "bwf_00025"}

# Clips whose labels were drawn on the frames a labelling tool got by *seeking* to each frame
# index (OpenCV's CAP_PROP_POS_FRAMES), not on the frames a sequential decode gives. On a video
# with irregular timestamps the two differ: on launcher-stereo (gaps of up to 90 ms, intervals of
# 2–7 ms) a seek to index i returns decoded frame i + 0, 5, 10, 12, 15, 16 or 17, in steps along
# the clip — the same steps as the frame shift at which our detections meet its labels. Such a
# clip is scored by comparing label row i with the prediction for the image that seek shows
# (``seek_frame_map``), and its two cameras are paired by the videos' own timestamps, since the
# label files' Timestamp column is only i / fps.
# The NYCU rallies have regular timestamps: seek and decode agree there.
LABELLED_BY_SEEK = {"launcher-stereo"}

# Frames of the tuned-on TV clips whose labels contradict each other: a shuttle held in the
# server's hand before the serve is labelled visible in bwf_00001 (frames 2–29) and not visible in
# bwf_00025 (frames 6–33; 0–5 and 34–35 of the same hold are visible). Whatever a chain does with a held shuttle it loses one clip, and which one
# flips with the classifier's random start: most of the leave-one-clip-out spread. A study may
# leave these frames out of its figure (``train_classifier.py --skip-disputed``) to compare two
# versions on the frames the labels agree on; the published figures never do.
DISPUTED_FRAMES: dict[str, frozenset[int]] = {
    "bwf_00001": frozenset(range(2, 30)),
    "bwf_00025": frozenset(range(6, 34)),
}


@dataclass(frozen=True)
class StereoClip:
    name: str
    left: Path
    right: Path
    left_labels: Path
    right_labels: Path

    @property
    def held_out(self) -> bool:
        return self.name not in TUNED_ON

    @property
    def labelled_by_seek(self) -> bool:
        return self.name in LABELLED_BY_SEEK


@dataclass(frozen=True)
class MonoClip:
    name: str
    video: Path
    labels: Path

    @property
    def held_out(self) -> bool:
        return self.name not in TUNED_ON


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


def rest_frames(labels_path: Path, width: int, video: Path) -> frozenset[int]:
    """The label rows of one file whose shuttle is at rest (core/evaluation.py ``at_rest_frames``:
    what the in-play score leaves out), timed by its Timestamp column when it has one, else by the
    video's frame rate."""
    labels = read_point_labels(labels_path).as_dict()
    try:
        frames, stamps = read_timestamps(labels_path)
        times = dict(zip(frames.tolist(), stamps.tolist()))
    except ValueError:
        times = None
    cap = cv2.VideoCapture(str(video))
    fps = cap.get(cv2.CAP_PROP_FPS) or 30.0
    cap.release()
    return at_rest_frames(labels, width, times, fps)


def seek_frame_map(video: Path) -> np.ndarray:
    """For each frame index i, the sequential decode index of the frame that a seek to i returns
    (OpenCV: set CAP_PROP_POS_FRAMES to i, then grab), matched by presentation time; -1 where the
    seek returns nothing. The seeks decode from a key frame each time (≈ 100 s for 557 frames of
    2048×1536), so the map is cached (``cache_dir``), keyed on the file and OpenCV's version."""
    stat = video.stat()
    key = hashlib.sha1(f"{video.resolve()}|{stat.st_size}|{stat.st_mtime_ns}|{cv2.__version__}"
                       .encode()).hexdigest()[:16]
    cache = cache_dir("seek-maps") / f"{key}.npy"
    if cache.is_file():
        return np.load(cache, allow_pickle=False)
    times = frame_times(video)
    cap = cv2.VideoCapture(str(video))
    out = np.full(len(times), -1, dtype=int)
    for i in range(len(times)):
        cap.set(cv2.CAP_PROP_POS_FRAMES, i)
        if cap.grab():
            match = np.flatnonzero(np.abs(times - cap.get(cv2.CAP_PROP_POS_MSEC) / 1000.0) < 1e-6)
            if len(match) == 1:
                out[i] = int(match[0])
    cap.release()
    with replacing(cache) as partial, open(partial, "wb") as fh:   # two jobs may build it at once
        np.save(fh, out)
    return out

"""Where the shared evaluation data lives, a marker to skip cleanly without it, and the NYCU
rally opened as the `track` command opens it (rig from its .cfg pair, cameras paired by the
label files' timestamps)."""

from pathlib import Path

import pytest

SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
NYCU_DIR = SHARED_DATA / "nycu-stereo"
BROADCAST_DIR = SHARED_DATA / "broadcast"
CHESSBOARD_DIR = SHARED_DATA / "chessboard-stereo"

requires_data = pytest.mark.skipif(not NYCU_DIR.is_dir(), reason="../shared/data is absent")


def open_nycu_rally(rally: Path):
    """(rig, VideoPair) of a NYCU rally folder: the rig imported from its two ``.cfg`` files and
    the cameras paired by the timestamps of its two label CSVs. The caller closes the pair."""
    from badminton_gui.io.labels import read_timestamps
    from badminton_gui.io.nycu import rig_from_nycu
    from badminton_gui.io.video import VideoPair

    rig = rig_from_nycu(rally / "CameraReader_1.cfg", rally / "CameraReader_2.cfg")
    src = VideoPair(rally / "CameraReader_1.mp4", rally / "CameraReader_2.mp4",
                    read_timestamps(rally / "CameraReader_1.csv")[1],
                    read_timestamps(rally / "CameraReader_2.csv")[1])
    return rig, src


def tracked_rally(rally: Path, preset: str):
    """(frame pair, TrackResult) for each pair of a NYCU rally, tracked live with ``preset``
    (no look-ahead, as the GUI gets them); the tracker and the videos are closed when the
    caller stops (use ``contextlib.closing`` to stop early)."""
    from badminton_gui.core.tracker import StereoTracker
    from badminton_gui.io.presets import load_preset

    rig, src = open_nycu_rally(rally)
    tracker = StereoTracker(rig, load_preset(preset))
    try:
        while (f := src.read()) is not None:
            yield f, tracker.process(f.left, f.right, f.t_left, f.index, f.index_right, keep_masks=False)
    finally:
        tracker.close()
        src.close()

"""Where the shared evaluation data lives, and a marker to skip cleanly without it."""

from pathlib import Path

import pytest

SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
NYCU_DIR = SHARED_DATA / "nycu-stereo"
BROADCAST_DIR = SHARED_DATA / "broadcast"
CHESSBOARD_DIR = SHARED_DATA / "chessboard-stereo"

requires_data = pytest.mark.skipif(not NYCU_DIR.is_dir(), reason="../shared/data is absent")

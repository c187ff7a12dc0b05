"""Nothing the user had is lost by a write (io/safe_write.py): outputs never overwrite inputs,
whole files appear at once, and a disk that fills up leaves a file that ends at a whole row."""

from __future__ import annotations

import csv
import errno
import os
import stat

import numpy as np
import pytest

from badminton_gui.io import safe_write
from badminton_gui.io.safe_write import RowFile, clashing_input, replacing, same_file


def _leftovers(folder) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


# ---- outputs against inputs ---------------------------------------------------------------------
def test_an_output_naming_an_input_is_found_by_path_symlink_and_hard_link(tmp_path):
    video = tmp_path / "left.mp4"
    video.write_bytes(b"video")
    (tmp_path / "link.mp4").symlink_to(video)
    os.link(video, tmp_path / "hard.mp4")
    (tmp_path / "sub").mkdir()
    for output in (video, tmp_path / "link.mp4", tmp_path / "hard.mp4", tmp_path / "sub" / ".." / "left.mp4"):
        assert clashing_input(output, [None, tmp_path / "other.csv", video]) == str(video)
    assert clashing_input(tmp_path / "track.csv", [video, None]) is None
    assert not same_file(tmp_path / "new.csv", video)


# ---- whole files at once --------------------------------------------------------------------------
def test_replacing_publishes_only_a_whole_file_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "rig.yaml"
    target.write_text("old")
    with pytest.raises(RuntimeError):
        with replacing(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError("the writer failed")
    assert target.read_text() == "old" and _leftovers(tmp_path) == []
    with replacing(target) as tmp:
        assert tmp.parent == tmp_path and tmp != target
        tmp.write_text("new")
    assert target.read_text() == "new" and _leftovers(tmp_path) == []


def test_a_new_file_gets_the_usual_mode_and_a_replaced_one_keeps_its_own(tmp_path):
    new = tmp_path / "new.csv"
    with replacing(new) as tmp:
        tmp.write_text("x")
    assert stat.S_IMODE(new.stat().st_mode) == 0o666 & ~safe_write._umask()
    kept = tmp_path / "kept.csv"
    kept.write_text("old")
    kept.chmod(0o640)
    with replacing(kept) as tmp:
        tmp.write_text("x")
    assert stat.S_IMODE(kept.stat().st_mode) == 0o640


def test_a_symlink_is_written_through_and_kept(tmp_path):
    real = tmp_path / "real.yaml"
    real.write_text("old")
    link = tmp_path / "link.yaml"
    link.symlink_to("real.yaml")
    with replacing(link) as tmp:
        tmp.write_text("new")
    assert link.is_symlink() and os.readlink(link) == "real.yaml"
    assert real.read_text() == "new" and _leftovers(tmp_path) == []
    rows = RowFile(link, ["a"])
    rows.write_row([1])
    rows.close()
    assert link.is_symlink() and real.read_text().splitlines() == ["a", "1"]


# ---- a disk that fills up ------------------------------------------------------------------------
class _DiskFillsUp:
    """The raw file of a disk with ``room`` bytes left: the write that overflows stores what fits
    (as a real disk does) and the next one fails with ENOSPC."""

    def __init__(self, real, room: int) -> None:
        self.real, self.room = real, room

    def write(self, data) -> int:
        if self.room <= 0:
            raise OSError(errno.ENOSPC, "No space left on device")
        part = bytes(data[:self.room])
        self.room -= len(part)
        return self.real.write(part)

    def __getattr__(self, name):
        return getattr(self.real, name)


@pytest.mark.parametrize("replace_at_close", [True, False])
def test_a_full_disk_leaves_whole_rows_only(tmp_path, monkeypatch, replace_at_close):
    """Whatever byte the disk fills up at, the file ends at a whole row, holds exactly the rows
    ``rows_saved`` says, and no temporary file remains."""
    monkeypatch.setattr(safe_write, "ROW_BUFFER_BYTES", 200)      # several writes per file
    rng = np.random.default_rng(42)
    for room in [0, 1, 5, 17] + [int(r) for r in rng.integers(18, 3000, 40)]:
        path = tmp_path / "track.csv"
        if path.exists():
            path.unlink()
        rows = RowFile(path, ["Frame", "X", "Y"], replace_at_close=replace_at_close)
        rows._fh = _DiskFillsUp(rows._fh, room)
        with pytest.raises(OSError) as failure:
            for i in range(400):
                rows.write_row([i, f"{rng.uniform(0, 2000):.2f}", f"{rng.uniform(0, 2000):.2f}"])
            rows.close()
        assert failure.value.errno == errno.ENOSPC
        assert rows.closed and _leftovers(tmp_path) == []
        if not path.exists():                 # not even the header fitted: nothing replaced
            assert replace_at_close and rows.rows_saved == 0 and room < len("Frame,X,Y\r\n")
            continue
        text = path.read_bytes().decode()
        assert text == "" or text.endswith("\r\n"), (room, text[-30:])
        lines = list(csv.reader(text.splitlines()))
        assert all(len(line) == 3 for line in lines)
        assert len(lines) == (1 + rows.rows_saved if lines else 0)
        assert [int(line[0]) for line in lines[1:]] == list(range(rows.rows_saved))


def test_a_full_disk_keeps_the_file_that_was_there_when_nothing_fitted(tmp_path):
    path = tmp_path / "track.csv"
    path.write_text("the previous run\n")
    rows = RowFile(path, ["Frame"])
    rows._fh = _DiskFillsUp(rows._fh, 3)
    with pytest.raises(OSError):
        rows.write_row([1])
        rows.close()
    assert path.read_text() == "the previous run\n" and _leftovers(tmp_path) == []


def test_a_failing_loop_keeps_the_rows_written_so_far(tmp_path):
    path = tmp_path / "track.csv"
    with pytest.raises(KeyError):
        with RowFile(path, ["Frame"]) as rows:
            rows.write_row([0])
            rows.write_row([1])
            raise KeyError("decoding failed")
    assert path.read_text().splitlines() == ["Frame", "0", "1"] and _leftovers(tmp_path) == []

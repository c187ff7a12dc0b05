"""Nothing the user had is lost by a write (io/safe_write.py): outputs never overwrite inputs,
whole files appear at once, and a disk that fills up leaves a file that ends at a whole row."""

from __future__ import annotations

import csv
import errno
import os
import stat
from pathlib import Path

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


# ---- the rig file ---------------------------------------------------------------------------------
def _rig():
    from badminton_gui.core.rig import StereoRig
    k = np.array([[300.0, 0, 160], [0, 300.0, 120], [0, 0, 1]])
    return StereoRig(k, np.zeros(5), k, np.zeros(5), np.eye(3), [-0.3, 0, 0], (320, 240))


def test_a_rig_saved_through_a_symlink_keeps_the_link_and_a_failed_save_changes_nothing(tmp_path, monkeypatch):
    from badminton_gui.core.rig import StereoRig
    real = tmp_path / "real.yaml"
    real.write_text("old")
    link = tmp_path / "rig.yaml"
    link.symlink_to("real.yaml")
    _rig().save(link)
    assert link.is_symlink() and StereoRig.load(real).image_size == (320, 240)
    assert _leftovers(tmp_path) == [] and not any(p.name.endswith(".tmp.yaml") for p in tmp_path.iterdir())
    before = real.read_bytes()

    def torn(self, tmp, path):       # a FileStorage that stopped half-way (a full disk)
        tmp.write_text("%YAML:1.0\n---\nimage_width: 320\n")
    monkeypatch.setattr(StereoRig, "_write_file_storage", torn)
    with pytest.raises(Exception):
        _rig().save(link)
    assert real.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == ["real.yaml", "rig.yaml"]


# ---- the commands refuse an output that is an input -----------------------------------------------
def _pair(folder):
    import cv2
    rng = np.random.default_rng(0)
    for name in ("l.avi", "r.avi"):
        writer = cv2.VideoWriter(str(folder / name), cv2.VideoWriter_fourcc(*"MJPG"), 30.0, (320, 240))
        for _ in range(5):
            writer.write(rng.integers(20, 60, size=(240, 320, 3), dtype=np.uint8))
        writer.release()
    _rig().save(folder / "rig.yaml")
    (folder / "times.csv").write_text("Frame,Timestamp\n" + "".join(f"{i},{i / 30:.6f}\n" for i in range(5)))


@pytest.mark.parametrize("output", ["l.avi", "r.avi", "rig.yaml", "times.csv", "link.avi", "hard.avi"])
def test_track_and_detect_refuse_to_write_over_an_input(tmp_path, capsys, output):
    from badminton_gui.cli import main
    tmp_path = tmp_path / "inputs"        # beside the test's log folder, which is not an input
    tmp_path.mkdir()
    _pair(tmp_path)
    (tmp_path / "link.avi").symlink_to("l.avi")
    os.link(tmp_path / "r.avi", tmp_path / "hard.avi")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    args = ["track", "--left", str(tmp_path / "l.avi"), "--right", str(tmp_path / "r.avi"),
            "--calib", str(tmp_path / "rig.yaml"), "--left-times", str(tmp_path / "times.csv"),
            "--right-times", str(tmp_path / "times.csv"), "-o", str(tmp_path / output), "--quiet"]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert f"the output {tmp_path / output} is also an input" in err and err.count("\n") == 1
    if output in ("link.avi", "hard.avi"):     # named: the file it really is
        assert str(tmp_path / ("l.avi" if output == "link.avi" else "r.avi")) in err
    if output.endswith(".avi"):
        assert main(["detect", str(tmp_path / output.replace("link", "l").replace("hard", "r")),
                     "-o", str(tmp_path / output), "--quiet"]) == 2
        assert "is also an input" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_track_writes_whole_and_leaves_no_temporary(tmp_path):
    from badminton_gui.cli import main
    _pair(tmp_path)
    out = tmp_path / "track.csv"
    out.write_text("the previous run\n")
    assert main(["track", "--left", str(tmp_path / "l.avi"), "--right", str(tmp_path / "r.avi"),
                 "--calib", str(tmp_path / "rig.yaml"), "-o", str(out), "--quiet"]) == 0
    assert len(out.read_text().splitlines()) == 1 + 5 and _leftovers(tmp_path) == []


def test_track_on_a_disk_that_fills_up_keeps_whole_rows_and_says_the_disk_is_full(tmp_path, monkeypatch):
    from badminton_gui.io.track_file import TrackFileError, track_to_csv
    from badminton_gui.io.video import VideoPair
    from badminton_gui.core.params import TrackerParams
    _pair(tmp_path)
    monkeypatch.setattr(safe_write, "ROW_BUFFER_BYTES", 1)         # every row is its own write
    real_init = RowFile.__init__

    def filling_up(self, *args, **kwargs):
        real_init(self, *args, **kwargs)
        self._fh = _DiskFillsUp(self._fh, 200)                     # the header and a few rows
    monkeypatch.setattr(RowFile, "__init__", filling_up)
    out = tmp_path / "track.csv"
    source = VideoPair(tmp_path / "l.avi", tmp_path / "r.avi")
    with pytest.raises(TrackFileError, match=f"^cannot write the track: the disk is full writing {out}; "
                                             r"its first \d+ rows are kept$"):
        track_to_csv(source, _rig(), TrackerParams(), out)
    source.close()
    text = out.read_text()
    assert text.endswith("\n") and _leftovers(tmp_path) == []
    lines = list(csv.reader(text.splitlines()))
    assert len(lines) >= 2 and all(len(line) == len(lines[0]) for line in lines)


def test_a_read_only_output_is_refused_not_replaced_by_the_rename(tmp_path, monkeypatch):
    """Renaming over a file replaces it even when its owner made it read-only; the writers refuse
    it as opening it for writing would (os.access is asked: root may write anything)."""
    target = tmp_path / "kept.csv"
    target.write_text("keep me")
    monkeypatch.setattr(safe_write.os, "access", lambda path, mode: Path(path) != target)
    with pytest.raises(PermissionError):
        with replacing(target) as tmp:
            tmp.write_text("new")
    with pytest.raises(PermissionError):
        RowFile(target, ["a"])
    assert target.read_text() == "keep me" and _leftovers(tmp_path) == []


def test_an_interrupted_demo_leaves_the_previous_files_and_no_temporary(tmp_path, monkeypatch):
    """The demo's videos and truth are written beside their names and renamed when whole."""
    from badminton_gui.cli import main
    from badminton_gui.io import demo_scene
    out = tmp_path / "demo"
    assert main(["demo", "-o", str(out), "--frames", "12", "--size", "160x120", "-q"]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    read = demo_scene.DemoScene.read
    calls = {"n": 0}

    def interrupted(self):
        calls["n"] += 1
        if calls["n"] > 6:
            raise KeyboardInterrupt
        return read(self)
    monkeypatch.setattr(demo_scene.DemoScene, "read", interrupted)
    assert main(["demo", "-o", str(out), "--frames", "12", "--size", "160x120", "--seed", "3", "-q"]) == 130
    after = {p.name: p.read_bytes() for p in out.iterdir()}
    assert after.keys() == before.keys()          # no temporary left beside them
    assert after["left.mp4"] == before["left.mp4"] and after["truth.csv"] == before["truth.csv"]

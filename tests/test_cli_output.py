"""What the command line prints and logs: versions, --json summaries, stdout for results only,
any console encoding, the output option's spellings, and the log file an operator hands over."""

import csv
import json
import logging
import os
import re
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from badminton_gui import __version__
from badminton_gui.cli import build_parser, main
from badminton_gui.core.rig import StereoRig
from badminton_gui.io import logging_setup
from badminton_gui.io.logging_setup import LOG_FILE_NAME, configure_logging, current_log_file

from .test_cli import N, W, dot_video, make_rig_for, moving_dot_frames, write_video  # noqa: F401

ROOT = Path(__file__).resolve().parents[1]


def run(args, capsys):
    """(exit status, stdout, stderr) of the CLI run in this process."""
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def log_text(state_dir: Path) -> str:
    return (state_dir / "logs" / LOG_FILE_NAME).read_text(encoding="utf-8")


def subprocess_env(**extra) -> dict:
    env = dict(os.environ, **extra)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return env


# ---- versions ---------------------------------------------------------------------------------

def test_both_programs_print_their_version(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out == f"badminton-track {__version__}\n"
    from badminton_gui.gui import app
    with pytest.raises(SystemExit) as stop:
        app.main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out == f"badminton-gui {__version__}\n"


# ---- --json: one object on stdout, the figures of the text summary ------------------------------

def test_detect_json_holds_the_rows_it_wrote(dot_video, tmp_path, capsys):
    video, _labels, _truth = dot_video
    out = tmp_path / "pred.csv"
    code, stdout, err = run(["detect", video, "-o", out, "--json"], capsys)
    assert code == 0, err
    summary = json.loads(stdout)           # nothing but the object on stdout
    rows = list(csv.DictReader(out.open()))
    assert summary["frames"] == len(rows) == N
    assert summary["found"] == sum(r["Visibility"] == "1" for r in rows) >= N - 5
    assert summary["found_percent"] == pytest.approx(100 * summary["found"] / N, abs=1e-3)
    assert summary["output"] == str(out) and summary["truncated"] is False
    assert summary["frames_per_second"] > 0


def test_track_json_holds_the_rows_it_wrote_and_the_score(tmp_path, capsys):
    frames_l, truth_l = moving_dot_frames()
    frames_r, truth_r = moving_dot_frames(offset=-10.0)
    write_video(tmp_path / "l.avi", frames_l)
    write_video(tmp_path / "r.avi", frames_r)
    make_rig_for().save(tmp_path / "rig.yaml")
    for name, truth in (("l.csv", truth_l), ("r.csv", truth_r)):
        with open(tmp_path / name, "w") as fh:
            fh.write("Frame,Visibility,X,Y,Timestamp\n")
            fh.writelines(f"{i},1,{x},{y},{i / 30.0}\n" for i, (x, y) in enumerate(truth))
    out = tmp_path / "t.csv"
    code, stdout, err = run(["track", "--left", tmp_path / "l.avi", "--right", tmp_path / "r.avi",
                             "--calib", tmp_path / "rig.yaml", "-o", out, "--left-times",
                             tmp_path / "l.csv", "--right-times", tmp_path / "r.csv", "--json"], capsys)
    assert code == 0, err
    summary = json.loads(stdout)
    rows = list(csv.DictReader(out.open()))
    assert summary["pairs"] == len(rows) == N
    assert summary["points_3d"] == sum(r["Vis3D"] == "1" for r in rows) >= N - 5
    assert summary["frame"] == "left-camera"            # this rig has no court pose
    left = summary["score"]["left"]
    assert left["tp"] + left["tn"] + left["fp1"] + left["fp2"] + left["fn"] == N
    assert left["accuracy"] == pytest.approx((left["tp"] + left["tn"]) / N)
    assert left["accuracy"] >= 0.9


def test_eval_json_counts_and_figures(tmp_path, capsys):
    _frames, truth = moving_dot_frames()
    labels, pred = tmp_path / "labels.csv", tmp_path / "pred.csv"
    with open(labels, "w") as fh:
        fh.write("Frame,Visibility,X,Y\n")
        fh.writelines(f"{i},1,{x},{y}\n" for i, (x, y) in enumerate(truth))
    with open(pred, "w") as fh:
        # 30 hits on the label, 5 of them 20 px off, 5 misses: TP 25, FP1 5, FN 10.
        fh.write("Frame,Visibility,X,Y\n")
        for i, (x, y) in enumerate(truth):
            if i < 30:
                fh.write(f"{i},1,{x + (20 if i < 5 else 0)},{y}\n")
            elif i < 35:
                fh.write(f"{i},0,0,0\n")
    code, stdout, err = run(["eval", pred, labels, "--width", 512, "--json"], capsys)
    assert code == 0, err
    s = json.loads(stdout)
    assert (s["tp"], s["tn"], s["fp1"], s["fp2"], s["fn"]) == (25, 0, 5, 0, 10)
    assert s["frames"] == N and s["width"] == 512 and s["width_assumed"] is False
    assert s["tolerance_px"] == pytest.approx(4.0)
    assert s["accuracy"] == pytest.approx(25 / 40)
    assert s["precision"] == pytest.approx(25 / 30) and s["recall"] == pytest.approx(25 / 35)
    assert s["f1"] == pytest.approx(2 * (25 / 30) * (25 / 35) / (25 / 30 + 25 / 35))


def test_calibrate_json_matches_the_rig_it_wrote(tmp_path, capsys):
    from badminton_gui.io.synthetic_chessboard import SyntheticChessboardSource
    src = SyntheticChessboardSource(n_poses=10, seed=11)
    left, right = tmp_path / "left", tmp_path / "right"
    left.mkdir(), right.mkdir()
    for k, pose in enumerate(src.poses):
        a, b = src.render_pair(pose)
        cv2.imwrite(str(left / f"img{k:02d}.png"), a)
        cv2.imwrite(str(right / f"img{k:02d}.png"), b)
    out = tmp_path / "rig.yaml"
    code, stdout, err = run(["calibrate", "--left-dir", left, "--right-dir", right, "--board", "9x6",
                             "--square", "0.03", "-o", out, "--json"], capsys)
    assert code == 0, err
    s = json.loads(stdout)
    rig = StereoRig.load(out)
    assert s["pairs"] == 10 and s["views_used"] + len(s["rejected"]) == 10
    assert len(s["views"]) == s["views_used"]
    assert s["baseline_m"] == pytest.approx(rig.baseline, rel=1e-6)
    assert s["baseline_m"] == pytest.approx(src.rig.baseline, rel=0.01)
    assert s["left"]["fx"] == pytest.approx(rig.M1[0, 0]) and s["right"]["cy"] == pytest.approx(rig.M2[1, 2])
    assert 0 < s["rms_stereo_px"] < 1.0 and s["image_size"] == list(rig.image_size)
    assert s["output"] == str(out.resolve())


def test_refine_calib_json_says_why_it_wrote_nothing(tmp_path, capsys):
    assert main(["demo", "--frames", "40", "-o", str(tmp_path), "--size", "320x240"]) == 0
    capsys.readouterr()
    out = tmp_path / "refined.yaml"
    code, stdout, err = run(["refine-calib", "--left", tmp_path / "left.mp4", "--right",
                             tmp_path / "right.mp4", "--calib", tmp_path / "rig.yaml", "-o", out,
                             "--json"], capsys)
    assert code == 2 and "not refined" in err and not out.exists()
    s = json.loads(stdout)
    assert s["frames"] == 40 and s["accepted"] is False and s["output"] is None
    assert s["reason"] and s["reason"] in err


def test_json_turns_nan_into_null(capsys):
    from badminton_gui.cli.common import print_json
    print_json({"precision": float("nan"), "n": np.int64(3), "x": np.float32(0.5)})
    assert json.loads(capsys.readouterr().out) == {"precision": None, "n": 3, "x": 0.5}


# ---- stdout is for results; warnings go to stderr ------------------------------------------------

def test_warnings_go_to_stderr_and_quiet_silences_them(tmp_path, capsys):
    labels = tmp_path / "labels.csv"
    labels.write_text("Frame,Visibility,X,Y\n0,1,300.0,20.0\n1,0,0,0\n")
    code, stdout, err = run(["eval", labels, labels], capsys)
    assert code == 0
    assert "width assumed 512 px" in err and "assumed" not in stdout
    assert "accuracy 1.0000" in stdout
    code, stdout, err = run(["eval", labels, labels, "--json"], capsys)
    assert json.loads(stdout)["width_assumed"] is True and "assumed" in err
    code, stdout, err = run(["eval", "-q", labels, labels], capsys)
    assert code == 0 and err == "" and "accuracy" in stdout
    # The warning reaches the log file even when the console is quiet.
    assert "width assumed 512 px" in log_text(Path(os.environ["BADMINTON_GUI_STATE_DIR"]))


def test_detect_survives_a_console_without_the_summary_characters(dot_video, tmp_path):
    """A Windows console or redirected output in cp1252: the CSV is written and the summary
    printed, exit status 0 (it used to crash on the summary's arrow after writing the CSV)."""
    video, _labels, _truth = dot_video
    out = tmp_path / "pred.csv"
    proc = subprocess.run([sys.executable, "-m", "badminton_gui.cli", "detect", str(video), "-o", str(out)],
                          env=subprocess_env(PYTHONIOENCODING="cp1252"), capture_output=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr.decode("cp1252", "replace")
    assert b"frames, shuttle found in" in proc.stdout and out.exists()


def test_console_safe_streams_escape_what_their_encoding_lacks(monkeypatch):
    import io
    raw = io.BytesIO()
    stream = io.TextIOWrapper(raw, encoding="cp1252")
    monkeypatch.setattr(sys, "stdout", stream)
    logging_setup.make_console_safe()
    print("3 frames → out.csv, 1280×720")
    stream.flush()
    assert raw.getvalue() == b"3 frames \\u2192 out.csv, 1280\xd7720\n"


# ---- -o and the old --out ---------------------------------------------------------------------

@pytest.mark.parametrize("option", ["-o", "--output", "--out"])
def test_demo_takes_o_output_and_the_old_out(tmp_path, capsys, option):
    folder = tmp_path / "demo"
    code, stdout, err = run(["demo", "--frames", "2", option, folder, "--size", "64x64"], capsys)
    assert code == 0, err
    assert (folder / "rig.yaml").exists() and (folder / "truth.csv").exists()
    assert str(folder) in stdout


def test_demo_help_hides_the_old_spelling():
    text = build_parser()._subparsers._group_actions[0].choices["demo"].format_help()
    assert "-o DIR, --output DIR" in text and "--out " not in text


def test_every_command_takes_the_logging_options(tmp_path):
    parser = build_parser()
    commands = parser._subparsers._group_actions[0].choices
    assert set(REQUIRED_ARGUMENTS) <= set(commands)
    for name in REQUIRED_ARGUMENTS:
        args = parser.parse_args([name, "-v", "-v", "--log-file", str(tmp_path / "x.log")]
                                 + REQUIRED_ARGUMENTS[name])
        assert args.verbose == 2 and args.log_file == str(tmp_path / "x.log") and not args.quiet
        args = parser.parse_args(["-q", name] + REQUIRED_ARGUMENTS[name])
        assert args.quiet and args.verbose == 0      # the program's option, not undone by the command's


# Placeholder arguments that make each command's line parse (nothing is run).
REQUIRED_ARGUMENTS = {
    "demo": ["--frames", "1", "-o", "d"], "detect": ["v.mp4", "-o", "o.csv"],
    "track": ["--left", "l", "--right", "r", "--calib", "c", "-o", "o.csv"],
    "eval": ["p.csv", "l.csv"], "import-calib": ["--nycu", "a", "b", "-o", "o.yaml"],
    "refine-calib": ["--left", "l", "--right", "r", "--calib", "c", "-o", "o.yaml"],
    "calibrate": ["--left-dir", "l", "--right-dir", "r", "--square", "1", "-o", "o.yaml"],
    "presets": [], "robot-listen": ["COM1"]}


# ---- units of every CSV column in --help ----------------------------------------------------------

def test_every_csv_column_is_documented_with_its_unit():
    from badminton_gui.cli import csv_columns
    from badminton_gui.io.demo_scene import LABEL_HEADER, TRUTH_HEADER
    from badminton_gui.io.labels import TRACK_COLUMNS
    assert list(csv_columns.TRACK_COLUMNS) == list(TRACK_COLUMNS)
    assert list(csv_columns.TRUTH_COLUMNS) == TRUTH_HEADER
    assert list(csv_columns.LABEL_COLUMNS) == LABEL_HEADER
    commands = build_parser()._subparsers._group_actions[0].choices
    for command, tables in (("track", [csv_columns.TRACK_COLUMNS]), ("detect", [csv_columns.LABEL_COLUMNS]),
                            ("demo", [csv_columns.TRUTH_COLUMNS, csv_columns.LABEL_COLUMNS])):
        text = commands[command].format_help()
        for table in tables:
            for name, meaning in table.items():
                assert any(line.split()[:1] == [name] and line.endswith(meaning)
                           for line in text.splitlines()), (command, name)
    track_help = commands["track"].format_help()
    assert re.search(r"Distance +m, from the left camera", track_help)
    assert re.search(r"Speed +m/s", track_help)


# ---- the log file ---------------------------------------------------------------------------------

def test_log_file_is_in_the_state_folder_and_verbose_adds_debug_lines(tmp_path, capsys,
                                                                       isolated_state_dir):
    labels = tmp_path / "labels.csv"
    labels.write_text("Frame,Visibility,X,Y\n0,1,30.0,20.0\n")
    assert run(["eval", labels, labels, "--width", "512"], capsys)[0] == 0
    assert current_log_file() == (isolated_state_dir / "logs" / LOG_FILE_NAME).resolve()
    text = log_text(isolated_state_dir)
    assert "eval started: badminton-track" in text and " DEBUG " not in text
    assert run(["eval", labels, labels, "--width", "512", "-v"], capsys)[0] == 0
    debug = [line for line in log_text(isolated_state_dir).splitlines() if " DEBUG " in line]
    assert any("arguments:" in line and "-v" in line for line in debug)


def test_log_file_option_and_faulthandler_into_it(tmp_path, capsys, isolated_state_dir):
    import faulthandler
    log = tmp_path / "elsewhere" / "run.log"
    assert run(["presets", "--log-file", log], capsys)[0] == 0
    assert current_log_file() == log.resolve() and "presets started" in log.read_text()
    assert not (isolated_state_dir / "logs").exists()
    assert faulthandler.is_enabled()


def test_an_unexpected_error_lands_in_the_log_with_its_traceback(tmp_path, capsys, monkeypatch,
                                                                 isolated_state_dir):
    from badminton_gui.cli import eval as eval_command

    def broken(args):
        raise RuntimeError("a bug for the log file")

    monkeypatch.setattr(eval_command, "run", broken)
    with pytest.raises(RuntimeError):
        main(["eval", "p.csv", "l.csv"])
    err = capsys.readouterr().err
    log = (isolated_state_dir / "logs" / LOG_FILE_NAME).resolve()
    assert f"internal error; the traceback is also in {log}" in err
    text = log.read_text()
    assert "CRITICAL" in text and "Traceback (most recent call last)" in text
    assert "in broken" in text and "RuntimeError: a bug for the log file" in text


def test_user_errors_are_one_line_on_stderr_and_logged(tmp_path, capsys, isolated_state_dir):
    code, _out, err = run(["eval", tmp_path / "none.csv", tmp_path / "none.csv"], capsys)
    assert code == 2 and err.count("\n") == 1
    assert "ERROR" in log_text(isolated_state_dir) and "none.csv" in log_text(isolated_state_dir)


def test_uncaught_exceptions_and_crashes_reach_the_log(tmp_path):
    """In a fresh process: an exception in a thread, one in the main thread, and a segmentation
    fault each leave their trace in the log file, and Python still reports them on stderr."""
    script = ("import sys, threading, faulthandler\n"
              "from badminton_gui.io.logging_setup import configure_logging\n"
              "configure_logging('test-program')\n"
              "def worker():\n    raise ValueError('raised in a thread')\n"
              "t = threading.Thread(target=worker, name='camera-thread'); t.start(); t.join()\n"
              "if sys.argv[1] == 'crash':\n    faulthandler._sigsegv()\n"
              "raise KeyError('raised in the main thread')\n")
    env = subprocess_env(BADMINTON_GUI_STATE_DIR=str(tmp_path / "state"))
    proc = subprocess.run([sys.executable, "-c", script, "raise"], env=env, capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 1 and "KeyError: 'raised in the main thread'" in proc.stderr
    assert "ValueError: raised in a thread" in proc.stderr
    text = log_text(tmp_path / "state")
    assert "uncaught exception in thread camera-thread" in text and "in worker" in text
    assert "ValueError: raised in a thread" in text and "KeyError: 'raised in the main thread'" in text
    assert text.count("Traceback (most recent call last)") == 2
    proc = subprocess.run([sys.executable, "-c", script, "crash"], env=env, capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode != 0
    text = log_text(tmp_path / "state")
    assert "Fatal Python error: Segmentation fault" in text and "<module>" in text


def test_an_unwritable_log_folder_leaves_the_console_with_one_warning(tmp_path, capsys, monkeypatch):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("BADMINTON_GUI_STATE_DIR", str(blocker / "state"))
    code, stdout, err = run(["presets"], capsys)
    assert code == 0 and "default" in stdout
    assert err.count("\n") == 1 and "cannot write the log file" in err and "console only" in err
    assert current_log_file() is None
    logging.getLogger("badminton_gui.test").warning("still said")
    assert "still said" in capsys.readouterr().err


def test_configuring_twice_replaces_the_handlers(tmp_path):
    root = logging.getLogger()
    before, hook = list(root.handlers), sys.excepthook
    configure_logging("one", log_file=tmp_path / "a.log")
    configure_logging("two", log_file=tmp_path / "b.log")
    ours = [h for h in root.handlers if h not in before]
    assert len(ours) == 2                       # one file, one console: not four
    logging.getLogger("badminton_gui.test").warning("to b only")
    assert "to b only" not in (tmp_path / "a.log").read_text()
    assert "two[" in (tmp_path / "b.log").read_text()
    logging_setup.reset_logging()
    assert list(root.handlers) == before and sys.excepthook is hook


def test_a_log_shared_with_another_process_loses_nothing_when_that_one_rotates(tmp_path,
                                                                                 monkeypatch):
    """The GUI and a `track` run write the same log. When the other process rotates it (here
    so often that the backups this process was writing into are deleted), this process's next
    record still lands in the log file on disk."""
    monkeypatch.setattr(logging_setup, "MAX_LOG_BYTES", 20_000)
    monkeypatch.setattr(logging_setup, "LOG_BACKUPS", 2)
    log = tmp_path / "shared.log"
    configure_logging("badminton-gui", log_file=log)
    said = logging.getLogger("badminton_gui.test")
    said.warning("the gui before")
    script = ("import logging\n"
              "from badminton_gui.io import logging_setup\n"
              "logging_setup.MAX_LOG_BYTES, logging_setup.LOG_BACKUPS = 20_000, 2\n"
              f"logging_setup.configure_logging('badminton-track', log_file={str(log)!r})\n"
              "for i in range(2000):\n"
              "    logging.getLogger('badminton_gui.track').warning('track line %d %s', i, 'x' * 60)\n")
    subprocess.run([sys.executable, "-c", script], env=subprocess_env(), check=True, timeout=120,
                   capture_output=True)
    said.warning("the gui after the other one rotated")
    said.warning("and once more")
    text = log.read_text()
    assert "the gui after the other one rotated" in text and "and once more" in text
    assert "track line 1999" in text
    assert not (tmp_path / "shared.log.3").exists()     # the backups stay at LOG_BACKUPS
    logging_setup.reset_logging()


# ---- the GUI's start-up ---------------------------------------------------------------------------

def test_gui_logs_its_start_and_a_bad_command_line_to_the_file(capsys, isolated_state_dir):
    from badminton_gui.gui import app
    assert app.main(["--source", "video", "-v"]) == 2      # returns before Qt is loaded
    assert "needs --left and --right" in capsys.readouterr().err
    text = log_text(isolated_state_dir)
    assert "badminton-gui 0.1.0 started" in text.replace(__version__, "0.1.0")
    assert "ERROR badminton_gui.gui.app: --source video needs --left and --right" in text
    assert " DEBUG " in text


def test_gui_routes_qt_messages_into_the_log(capsys, isolated_state_dir):
    from PySide6.QtCore import QtMsgType

    from badminton_gui.gui import app
    configure_logging("badminton-gui")
    app._qt_message_to_log(QtMsgType.QtWarningMsg, None, "QOpenGLWidget: failed to create a context")
    app._qt_message_to_log(QtMsgType.QtDebugMsg, None, "qt chatter")
    text = log_text(isolated_state_dir)
    assert "WARNING qt: QOpenGLWidget: failed to create a context" in text and "qt chatter" not in text
    assert "failed to create a context" in capsys.readouterr().err

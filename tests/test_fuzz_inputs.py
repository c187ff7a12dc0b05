"""Seeded fuzzing of every reader of user input and of the tracker's public entry point.

Why this file exists: a hostile but fair user found inputs that passed silently or crashed in
the middle of a run. The rule checked here is the product's: input is validated once, at the
boundary, and what cannot be used is refused with the reader's one documented error type
(RigError, CsvFormatError, an argparse usage error, TrackerInputError), never another
exception; and what is accepted holds the invariants the rest of the program relies on.

Mutations come from seeded ``random.Random`` / ``numpy`` generators (no third-party fuzzer), so
a failure is reproducible: the assertion message carries the case number and the input.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import random

import numpy as np
import pytest

from badminton_gui import StereoTracker, TrackerInputError
from badminton_gui.cli import build_parser
from badminton_gui.cli import demo as demo_cli
from badminton_gui.cli import eval as eval_cli
from badminton_gui.core.rig import DISTORTION_LENGTHS, RigError, StereoRig
from badminton_gui.io.demo_scene import make_rig
from badminton_gui.io.labels import CsvFormatError, MAX_FRAME, read_point_labels, read_timestamps
from badminton_gui.io.nycu import rig_from_nycu

# Tokens a mutation may put where a number was: each one a way users' files go wrong.
HOSTILE_NUMBERS = ["nan", "NaN", ".nan", "inf", "-inf", ".inf", "-.inf", "1e400", "-1e400", "0", "-0",
                   "-1", "1e308", "-1e308", "1e-320", "abc", "", " ", "1,5", "0x10", "1_000", "١٢",
                   "9" * 30, "-" + "9" * 30, "1e", "+", "--1", "1.2.3", "\"7\"", "[1]", "{}", "null",
                   "true", "12345678901234567890", "3.5", "-2.5", "1e9", "1e10", "%(x)s", "\x00"]


def _token(rng: random.Random) -> str:
    if rng.random() < 0.7:
        return rng.choice(HOSTILE_NUMBERS)
    return repr(rng.choice([rng.uniform(-1e6, 1e6), rng.randint(-10**12, 10**12), rng.random()]))


def _mutate_text(text: str, rng: random.Random, number_pattern: str = r"-?\d+\.?\d*(?:e[-+]?\d+)?") -> str:
    """One or a few random edits: a number replaced, a line dropped or doubled, bytes cut off,
    a character inserted or swapped."""
    import re
    for _ in range(rng.randint(1, 3)):
        kind = rng.random()
        lines = text.split("\n")
        if kind < 0.45:
            spans = [m.span() for m in re.finditer(number_pattern, text)]
            if spans:
                a, b = rng.choice(spans)
                text = text[:a] + _token(rng) + text[b:]
        elif kind < 0.6 and len(lines) > 1:
            del lines[rng.randrange(len(lines))]
            text = "\n".join(lines)
        elif kind < 0.7:
            k = rng.randrange(len(lines))
            lines.insert(k, lines[k])
            text = "\n".join(lines)
        elif kind < 0.8:
            text = text[:rng.randrange(len(text) + 1)]
        elif kind < 0.9 and text:
            k = rng.randrange(len(text))
            text = text[:k] + rng.choice(",:;[]{}\"'\t\r\n#%x-") + text[k + 1:]
        else:
            k = rng.randrange(len(text) + 1)
            text = text[:k] + rng.choice(["\ufeff", "é", "\x00", "\r\n", "  ", ",,", "0" * 20]) + text[k:]
    return text


def _check_rig_usable(rig: StereoRig) -> None:
    """What the tracker does with a rig: all of it must work on a rig that loaded."""
    assert np.all(np.isfinite(rig.M1)) and rig.M1[0, 0] > 0 and rig.M1[1, 1] > 0
    assert len(rig.D1) in DISTORTION_LENGTHS and len(rig.D2) in DISTORTION_LENGTHS
    assert np.linalg.norm(rig.T) > 0 and np.all(np.isfinite(rig.R))
    w, h = rig.image_size
    assert w >= 1 and h >= 1
    pts = np.array([[w / 2, h / 2], [w / 3, h / 4]])
    with np.errstate(all="ignore"):
        rig.triangulate(pts, pts)
        rig.epipolar_errors(pts, pts)
        rig.project(0, np.array([[0.0, 0.0, 5.0]]))


RIG_CASES = 300


def test_the_rig_reader_refuses_mutated_files_with_a_rig_error(tmp_path):
    base = tmp_path / "base.yaml"
    make_rig("binocular", (320, 180)).save(base)
    text = base.read_text()
    rng = random.Random(20261127)
    loaded = refused = 0
    for case in range(RIG_CASES):
        mutated = _mutate_text(text, rng)
        if rng.random() < 0.15:        # a key renamed or a matrix's declared shape changed
            mutated = mutated.replace(rng.choice(["M1:", "D2:", "R:", "T:", "rows: 3", "cols: 5",
                                                  "dt: d", "image_width:"]),
                                      rng.choice(["X1:", "rows: 2", "cols: 4", "dt: u", "dt: s",
                                                  "image_width: \"abc\"\nx:", "T: 1\nY:"]), 1)
        path = tmp_path / f"case{case}.yaml"
        path.write_bytes(mutated.encode("utf-8", "surrogatepass"))
        try:
            rig = StereoRig.load(path)
        except RigError as exc:
            assert str(exc) and "\n" not in str(exc), f"case {case}: {exc!r}"
            refused += 1
            continue
        except Exception as exc:      # noqa: BLE001 - the point of the test
            pytest.fail(f"case {case}: {type(exc).__name__}: {exc}\n--- input ---\n{mutated}")
        _check_rig_usable(rig)
        loaded += 1
    assert refused > RIG_CASES // 3 and loaded > 0, (loaded, refused)


def _nycu_cfg(extrinsic: np.ndarray, k: np.ndarray, dist, size=(320, 180)) -> str:
    return (f"[Camera]\nfps = 120\nRecordResolution = ({size[0]}, {size[1]})\n\n[Other]\n"
            f"ks = {json.dumps(k.tolist())}\ndist = {json.dumps([list(dist)])}\n"
            f"extrinsic_mat = {json.dumps(extrinsic.tolist())}\n")


def _nycu_pair() -> tuple[str, str]:
    rig = make_rig("ends", (320, 180))
    # X_cam1 = R1 X_w + t1 with R_court = R1ᵀ, T_court = −R1ᵀ t1; the right camera from R, T.
    r1 = rig.R_court.T
    t1 = -r1 @ rig.T_court
    r2 = rig.R @ r1
    t2 = rig.R @ t1 + rig.T
    dist = [-0.2, 0.05, 0.0, 0.001, -0.004]
    return (_nycu_cfg(np.hstack([r1, t1[:, None]]), rig.M1, dist),
            _nycu_cfg(np.hstack([r2, t2[:, None]]), rig.M2, dist))


CFG_CASES = 300


def test_the_nycu_importer_refuses_mutated_cfg_files_with_a_rig_error(tmp_path):
    left, right = _nycu_pair()
    good_left, good_right = tmp_path / "l.cfg", tmp_path / "r.cfg"
    good_left.write_text(left)
    good_right.write_text(right)
    _check_rig_usable(rig_from_nycu(good_left, good_right))
    rng = random.Random(42)
    imported = refused = 0
    for case in range(CFG_CASES):
        mutated = _mutate_text(left, rng)
        if rng.random() < 0.1:
            mutated = mutated.replace(rng.choice(["ks = ", "dist = ", "[Other]", "extrinsic_mat = "]),
                                      rng.choice(["ks = {1, 2}\nx = ", "dist = %(x)s\ny = ", "[Other",
                                                  "extrinsic_mat = [[1e999]]\nz = "]), 1)
        encoding = rng.choice(["utf-8", "utf-8-sig", "latin-1"])
        path = tmp_path / f"case{case}.cfg"
        path.write_bytes(mutated.encode(encoding, "replace"))
        try:
            rig = rig_from_nycu(path, good_right)
        except RigError as exc:
            assert str(exc) and "\n" not in str(exc), f"case {case}: {exc!r}"
            refused += 1
            continue
        except Exception as exc:      # noqa: BLE001
            pytest.fail(f"case {case}: {type(exc).__name__}: {exc}\n--- input ---\n{mutated}")
        _check_rig_usable(rig)
        imported += 1
    assert refused > CFG_CASES // 3 and imported > 0, (imported, refused)


CSV_CASES = 400


def _mutate_csv_bytes(text: str, rng: random.Random) -> bytes:
    mutated = _mutate_text(text, rng)
    data = mutated.encode("utf-8", "replace")
    if rng.random() < 0.1 and data:
        k = rng.randrange(len(data))
        data = data[:k] + bytes([rng.randrange(256)]) + data[k + 1:]
    return data


def test_the_timestamp_reader_refuses_mutated_files_with_a_csv_error(tmp_path):
    rng = random.Random(7)
    base = "Frame,Timestamp\n" + "".join(f"{i},{i / 120:.6f}\n" for i in range(12))
    read = refused = 0
    for case in range(CSV_CASES):
        path = tmp_path / f"t{case}.csv"
        path.write_bytes(_mutate_csv_bytes(base, rng))
        try:
            frames, times = read_timestamps(path)
        except CsvFormatError as exc:
            assert str(exc) and "\n" not in str(exc), f"case {case}: {exc!r}"
            refused += 1
            continue
        except Exception as exc:      # noqa: BLE001
            pytest.fail(f"case {case}: {type(exc).__name__}: {exc}\n--- input ---\n{path.read_bytes()!r}")
        assert np.array_equal(frames, np.arange(len(frames))), case
        assert np.all(np.isfinite(times)) and np.all(np.diff(times) >= 0), case
        assert len(times) == 1 or times[0] != times[-1], case
        read += 1
    assert refused > CSV_CASES // 3 and read > 0, (read, refused)


def test_the_label_reader_refuses_mutated_files_with_a_csv_error(tmp_path):
    rng = random.Random(11)
    base = "Frame,Visibility,X,Y\n" + "".join(
        f"{i},{i % 3 != 0:d},{10 + 3.5 * i:.2f},{50 - 1.25 * i:.2f}\n" for i in range(12))
    read = refused = 0
    for case in range(CSV_CASES):
        path = tmp_path / f"l{case}.csv"
        path.write_bytes(_mutate_csv_bytes(base, rng))
        try:
            labels = read_point_labels(path)
        except CsvFormatError as exc:
            assert str(exc) and "\n" not in str(exc), f"case {case}: {exc!r}"
            refused += 1
            continue
        except Exception as exc:      # noqa: BLE001
            pytest.fail(f"case {case}: {type(exc).__name__}: {exc}\n--- input ---\n{path.read_bytes()!r}")
        assert len(np.unique(labels.frames)) == len(labels.frames), case
        assert labels.frames.dtype == np.int64 and np.all((labels.frames >= 0) & (labels.frames <= MAX_FRAME))
        assert np.all(np.isfinite(labels.xy[labels.visible])), case
        read += 1
    assert refused > CSV_CASES // 3 and read > 0, (read, refused)


# The numeric options of the file commands, with the other arguments each needs to parse.
CLI_NUMERIC = {
    "demo": (["demo", "--out", "d"], ["--frames", "--seed", "--size", "--fps"], ["--frames", "3"]),
    "eval": (["eval", "p.csv", "l.csv"], ["--tolerance", "--width"], []),
    "track": (["track", "--left", "l", "--right", "r", "--calib", "c", "-o", "o"],
              ["--max-frames", "--baud", "--lookahead"], []),
    "detect": (["detect", "v.mp4", "-o", "o"], None, []),
}
CLI_CASES = 300


def _numeric_options(command: str) -> list[str]:
    """The options of ``command`` that take a number (any whose type is not str/Path/choices)."""
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return [opt for action in sub.choices[command]._actions
            if action.option_strings and action.type not in (None, str) and action.choices is None
            and getattr(action.type, "__name__", "") != "Path"
            for opt in action.option_strings[-1:]]


@pytest.mark.parametrize("command", sorted(CLI_NUMERIC))
def test_numeric_cli_arguments_parse_or_exit_2_with_a_message(command):
    base, options, needed = CLI_NUMERIC[command]
    options = options or _numeric_options(command)
    assert options, command
    parser = build_parser()
    rng = random.Random(command)
    accepted = refused = 0
    for case in range(CLI_CASES):
        option = rng.choice(options)
        value = _token(rng) if rng.random() < 0.8 else f"{rng.randint(0, 5000)}x{rng.randint(-10, 5000)}"
        argv = base + [x for x in needed if option != needed[0]] + [f"{option}={value}"]
        err = io.StringIO()
        try:
            with contextlib.redirect_stderr(err):
                args = parser.parse_args(argv)
        except SystemExit as exc:
            assert exc.code == 2, f"case {case}: {argv}"
            assert "error: argument" in err.getvalue() and "Traceback" not in err.getvalue(), argv
            refused += 1
            continue
        except Exception as exc:      # noqa: BLE001
            pytest.fail(f"case {case}: {argv}: {type(exc).__name__}: {exc}")
        _check_parsed_ranges(command, args)
        accepted += 1
    assert refused > 0 and accepted > 0, (accepted, refused)


def _check_parsed_ranges(command: str, args) -> None:
    """What demo and eval accept at parse time is inside their documented ranges."""
    if command == "demo":
        assert demo_cli.MIN_FPS <= args.fps <= demo_cli.MAX_FPS
        assert all(demo_cli.MIN_SIDE <= s <= demo_cli.MAX_SIDE for s in args.size)
        assert 0 <= args.seed <= demo_cli.MAX_SEED and 1 <= args.frames <= demo_cli.MAX_FRAMES
    if command == "eval":
        assert np.isfinite(args.tolerance) and args.tolerance > 0
        assert args.width is None or 1 <= args.width <= eval_cli.MAX_WIDTH


TRACKER_CASES = 400
SIZE = (96, 64)


def _hostile_image(rng: np.random.Generator, kind: str) -> object:
    w, h = SIZE
    if kind == "good":
        return rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
    if kind == "grey":
        return rng.integers(0, 256, (h, w), dtype=np.uint8)
    if kind == "grey1":
        return rng.integers(0, 256, (h, w, 1), dtype=np.uint8)
    if kind == "float32":
        return rng.random((h, w, 3), dtype=np.float32)
    if kind == "dtype":
        return rng.integers(0, 256, (h, w, 3)).astype(_pick(rng, [np.int16, np.uint16, np.float64, bool, np.int8]))
    if kind == "bgra":
        return rng.integers(0, 256, (h, w, 4), dtype=np.uint8)
    if kind == "size":
        return rng.integers(0, 256, (h + int(rng.integers(1, 9)), w - int(rng.integers(1, 9)), 3), dtype=np.uint8)
    if kind == "empty":
        return np.zeros((0, w, 3), dtype=np.uint8)
    if kind == "flat":
        return rng.integers(0, 256, w * h * 3, dtype=np.uint8)
    if kind == "4d":
        return rng.integers(0, 256, (1, h, w, 3), dtype=np.uint8)
    if kind == "strided":
        return rng.integers(0, 256, (h, 2 * w, 3), dtype=np.uint8)[:, ::2]
    return _pick(rng, [None, [[1, 2, 3]], "frame.png", 3.0])


def _pick(rng: np.random.Generator, options: list):
    return options[int(rng.integers(len(options)))]


IMAGE_KINDS = ["good"] * 8 + ["grey", "grey1", "strided", "float32", "dtype", "bgra", "size", "empty",
                              "flat", "4d", "other"]
ACCEPTED_IMAGES = {"good", "grey", "grey1", "strided"}


def test_the_tracker_refuses_hostile_arrays_and_times_with_its_one_error_type():
    rng = np.random.default_rng(3)
    tracker = StereoTracker(make_rig("binocular", SIZE), parallel=False)
    last_t = 0.0
    processed = refused = 0
    try:
        for case in range(TRACKER_CASES):
            kinds = (rng.choice(IMAGE_KINDS), rng.choice(IMAGE_KINDS))
            left, right = (_hostile_image(rng, k) for k in kinds)
            roll = rng.random()
            if roll < 0.7:
                t, time_ok = last_t + float(rng.choice([1 / 120, 0.5])), True
            else:
                t = _pick(rng, [float("nan"), float("inf"), -float("inf"), -1e300, 1e300, last_t - 1.0,
                                last_t, "0.5", None, True, complex(1, 1), np.float32(last_t + 1)])
                time_ok = isinstance(t, np.float32) and float(t) > last_t
            images_ok = kinds[0] in ACCEPTED_IMAGES and kinds[1] in ACCEPTED_IMAGES
            try:
                result = tracker.process(left, right, t)
            except TrackerInputError as exc:
                assert not (images_ok and time_ok), f"case {case}: {kinds}, t={t!r}: refused: {exc}"
                assert str(exc) and "\n" not in str(exc)
                refused += 1
                continue
            except Exception as exc:      # noqa: BLE001
                pytest.fail(f"case {case}: {kinds}, t={t!r}: {type(exc).__name__}: {exc}")
            assert images_ok and time_ok, f"case {case}: {kinds}, t={t!r} was accepted"
            assert result.timestamp == float(t)
            last_t = float(t)
            processed += 1
    finally:
        tracker.close()
    assert processed > TRACKER_CASES // 5 and refused > TRACKER_CASES // 5, (processed, refused)


def test_a_refused_pair_leaves_the_run_as_it_was_and_reset_starts_a_new_clock():
    tracker = StereoTracker(make_rig("binocular", SIZE), parallel=False)
    frame = np.zeros((SIZE[1], SIZE[0], 3), dtype=np.uint8)
    try:
        tracker.process(frame, frame, 1.0)
        with pytest.raises(TrackerInputError, match="earlier than"):
            tracker.process(frame, frame, 0.5)
        with pytest.raises(TrackerInputError, match="finite"):
            tracker.process(frame, frame, float("nan"))
        with pytest.raises(TrackerInputError, match="calibrated for 96×64"):
            tracker.process(frame[:32], frame[:32], 2.0)
        with pytest.raises(TrackerInputError, match="repeats that camera's previous one: its clock stalled"):
            tracker.process(frame, frame, 1.0)
        with pytest.raises(TrackerInputError, match="right timestamp 1.0 s repeats"):
            tracker.process(frame, frame, 1.5, t_right=1.0)
        assert tracker.process(frame, frame, 1.5, t_right=1.25).timestamp == 1.5   # the run goes on
        tracker.reset()
        assert tracker.process(frame, frame, 0.0).timestamp == 0.0     # a new run's clock
    finally:
        tracker.close()

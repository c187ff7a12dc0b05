"""Golden outputs: today's `track` and `detect` results, frozen, so any change to them is seen.

Why this file exists: a restructuring of the engine should change nothing it did not mean to
change. This tool runs the command line in-process (``badminton_gui.cli.main``, the same code
path as ``badminton-track``) on a fixed set of cases and either stores the CSVs it writes
(``--write``, into ``tests/golden/<case>.csv.gz``) or compares a fresh run with the stored ones
(``--check``), row by row, and prints per case ``identical`` or how many frames differ, the
first differing frames, the visibility flips and the largest position change.

    .venv/bin/python benchmarks/golden.py --check             # every case whose data is here
    .venv/bin/python benchmarks/golden.py --check --only demo # the demo-court cases only
    .venv/bin/python benchmarks/golden.py --write             # accept today's outputs

The cases: the synthetic demo court (seeds 0 and 1, rendered by `badminton-track demo`, then
`track` and a one-camera `detect`), two NYCU rallies of the shared data (`track`, default
preset and look-ahead, rig imported from the rally's .cfg pair, cameras paired by the label
files' timestamps; also the first 400 pairs of one, the slice the tests run) and two TV clips (`detect --preset broadcast`). Cases whose data is absent
are skipped. The stored CSVs are the CLI's own rows, at the CLI's precision: pixels to 0.01 px,
3D points, distances and landing points to 0.1 mm, speed to 1 mm/s, times to 1 µs.

Compared with a tolerance, not a digest, because OpenCV's floating point may differ in the last
bits between CPUs (vector units) and builds: a value differs when it moves by more than
``TOLERANCES`` (0.05 px in the image, 1 mm in 3D and for the predicted landing point, 1 cm/s
for speed, 1 ms for the landing time); a detection or 3D point that appears or disappears
always differs. Exit status: 0 all identical, 1 a difference, 2 a golden file is missing.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import gzip
import io
import os
import re
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parents[1]
GOLDEN_DIR = ROOT / "tests" / "golden"
DATA_DIR = Path(os.environ.get("BADMINTON_DATA", ROOT.parent / "shared" / "data"))

# Demo-court recordings: small and short, so the always-run cases stay fast.
DEMO_FRAMES = 300
DEMO_SIZE = "640x360"

# Frame pairs of the rally slice the test suite checks (the full rallies are checked here).
RALLY_SLICE = 400

# Per column: how far a value may move and still count as the same (units of the column).
TOLERANCES = {
    "XL": 0.05, "YL": 0.05, "XR": 0.05, "YR": 0.05, "X": 0.05, "Y": 0.05,   # pixels
    "Timestamp": 1e-6,                                                       # seconds
    "Distance": 0.001, "LandX": 0.001, "LandY": 0.001,                       # metres
    "Speed": 0.01,                                                           # m/s
    "LandT": 0.001,                                                          # seconds
}
# `track` writes X, Y, Z in metres; `detect` writes X, Y in pixels.
TRACK_TOLERANCES = {**TOLERANCES, "X": 0.001, "Y": 0.001, "Z": 0.001}
# Flags: a change is a detection or a 3D point appearing or vanishing.
VISIBILITY_COLUMNS = ("VisL", "VisR", "Vis3D", "Visibility")
# Columns whose largest move the report gives, per kind: (label, columns, unit per column unit).
POSITION_GROUPS = {
    "track": (("2D px", ("XL", "YL", "XR", "YR"), 1.0), ("3D mm", ("X", "Y", "Z"), 1000.0),
              ("landing mm", ("LandX", "LandY"), 1000.0)),
    "detect": (("2D px", ("X", "Y"), 1.0),),
}


@dataclass(frozen=True)
class Case:
    name: str
    kind: str                                   # "track" or "detect"
    needs: tuple[Path, ...]                     # files that must exist (shared data)
    run: Callable[[Path, Path], None]           # (work folder, output CSV) -> writes the CSV

    @property
    def golden_path(self) -> Path:
        return GOLDEN_DIR / f"{self.name}.csv.gz"

    @property
    def available(self) -> bool:
        return all(p.exists() for p in self.needs)


def cli(argv: list[str]) -> None:
    """One `badminton-track` command in this process; raises on a non-zero exit status."""
    import cv2

    from badminton_gui.cli import main
    threads = cv2.getNumThreads()     # `track` sets one OpenCV thread for the whole process
    try:
        status = main(argv)
    finally:
        cv2.setNumThreads(threads)
    if status:
        raise RuntimeError(f"badminton-track {' '.join(argv)} exited with status {status}")


def _demo_recording(work: Path, seed: int) -> Path:
    folder = work / f"demo-seed{seed}"
    if not (folder / "rig.yaml").exists():
        with contextlib.redirect_stdout(io.StringIO()):
            cli(["demo", "--frames", str(DEMO_FRAMES), "--size", DEMO_SIZE, "--seed", str(seed),
                 "--out", str(folder)])
    return folder


def _demo_track(seed: int, preset: str | None = None):
    def run(work: Path, out: Path) -> None:
        d = _demo_recording(work, seed)
        cli(["track", "--left", str(d / "left.mp4"), "--right", str(d / "right.mp4"),
             "--calib", str(d / "rig.yaml"), "-o", str(out), "--quiet"]
            + (["--preset", preset] if preset else []))
    return run


def _demo_detect(seed: int):
    def run(work: Path, out: Path) -> None:
        d = _demo_recording(work, seed)
        cli(["detect", str(d / "left.mp4"), "-o", str(out), "--quiet"])
    return run


def _rally_track(rally: Path, max_frames: int | None = None, preset: str | None = None):
    def run(work: Path, out: Path) -> None:
        rig = work / f"{rally.name}_rig.yaml"
        with contextlib.redirect_stdout(io.StringIO()):
            cli(["import-calib", "--nycu", str(rally / "CameraReader_1.cfg"),
                 str(rally / "CameraReader_2.cfg"), "-o", str(rig)])
        cli(["track", "--left", str(rally / "CameraReader_1.mp4"),
             "--right", str(rally / "CameraReader_2.mp4"), "--calib", str(rig),
             "--left-times", str(rally / "CameraReader_1.csv"),
             "--right-times", str(rally / "CameraReader_2.csv"), "-o", str(out), "--quiet"]
            + (["--max-frames", str(max_frames)] if max_frames else [])
            + (["--preset", preset] if preset else []))
    return run


def _broadcast_detect(video: Path):
    def run(work: Path, out: Path) -> None:
        cli(["detect", str(video), "--preset", "broadcast", "-o", str(out), "--quiet"])
    return run


def _rally_case(name: str, max_frames: int | None = None, preset: str | None = None) -> Case:
    rally = DATA_DIR / "nycu-stereo" / name
    needs = tuple(rally / f for f in ("CameraReader_1.cfg", "CameraReader_2.cfg", "CameraReader_1.mp4",
                                      "CameraReader_2.mp4", "CameraReader_1.csv", "CameraReader_2.csv"))
    first = f"-first{max_frames}" if max_frames else ""
    tag = f"-{preset}" if preset else ""
    return Case(f"{name}{first}{tag}-track", "track", needs, _rally_track(rally, max_frames, preset))


def _broadcast_case(name: str) -> Case:
    video = DATA_DIR / "broadcast" / f"{name}.mp4"
    return Case(f"{name}-detect-broadcast", "detect", (video,), _broadcast_detect(video))


CASES: tuple[Case, ...] = (
    *(Case(f"demo-seed{s}-track", "track", (), _demo_track(s)) for s in (0, 1)),
    *(Case(f"demo-seed{s}-detect-left", "detect", (), _demo_detect(s)) for s in (0, 1)),
    # The coarse preset: windowed tracking and the coarser model, which the default does not run.
    Case("demo-seed0-coarse-track", "track", (), _demo_track(0, "coarse")),
    _rally_case("rally_11-46-04"),
    # The serve and the first exchanges: the real stereo case short enough for the test suite.
    _rally_case("rally_11-46-04", max_frames=RALLY_SLICE),
    _rally_case("rally_11-49-21"),
    _rally_case("rally_11-49-21", preset="coarse"),
    _broadcast_case("1_02_01"),
    _broadcast_case("bwf_00001"),
)


def select(pattern: str | None) -> list[Case]:
    return [c for c in CASES if pattern is None or re.search(pattern, c.name)]


# ---------------------------------------------------------------------------------------------
# Reading, writing and comparing

def read_rows(text: str) -> tuple[list[str], list[dict[str, str]]]:
    reader = csv.DictReader(io.StringIO(text))
    return list(reader.fieldnames or []), list(reader)


def read_golden(case: Case) -> str:
    return gzip.decompress(case.golden_path.read_bytes()).decode()


def write_golden(case: Case, text: str) -> int:
    """Store ``text`` gzipped with no timestamp, so the same output gives the same bytes."""
    data = gzip.compress(text.encode(), compresslevel=9, mtime=0)
    case.golden_path.parent.mkdir(parents=True, exist_ok=True)
    case.golden_path.write_bytes(data)
    return len(data)


def produce(case: Case, work: Path) -> str:
    """Run ``case`` in ``work`` (a scratch folder shared by the cases) and return its CSV text."""
    out = work / f"{case.name}.csv"
    case.run(work, out)
    return out.read_text()


def _key(row: dict[str, str]) -> tuple[str, ...]:
    return (row["Frame"], row.get("FrameR", ""))


def _number(text: str) -> float | None:
    return float(text) if text not in ("", None) else None


@dataclass
class Comparison:
    """How a fresh output differs from the stored one."""
    rows: int
    differing: list[tuple[str, list[str]]]      # (frame key, descriptions), in file order
    flips: dict[str, int]                       # visibility column -> frames where it flipped
    max_delta: dict[str, float]                 # position group -> largest move (in the group's unit)
    missing: int = 0                            # stored rows the fresh output lacks
    extra: int = 0                              # fresh rows the stored output lacks
    header_changed: bool = False

    @property
    def identical(self) -> bool:
        return not (self.differing or self.missing or self.extra or self.header_changed)

    def report(self, name: str, first: int = 5, note: str = "") -> str:
        """``name: identical (N rows)``, or the count of differing frames, the visibility flips,
        the largest moves and the ``first`` differing frames; ``note`` ends the first line."""
        note = f" {note}" if note else ""
        if self.identical:
            return f"{name}: identical ({self.rows} rows){note}"
        lines = [f"{name}: {len(self.differing)} frames differ (of {self.rows})"
                 + (f", {self.missing} rows missing" if self.missing else "")
                 + (f", {self.extra} rows added" if self.extra else "")
                 + (", columns changed" if self.header_changed else "") + note]
        if self.flips:
            lines.append("  visibility flips: " + ", ".join(f"{c} {n}" for c, n in self.flips.items()))
        if self.max_delta:
            lines.append("  largest move where both have a value: "
                         + ", ".join(f"{g} {v:.2f}" for g, v in self.max_delta.items()))
        for key, what in self.differing[:first]:
            frame = key[0] if not key[1] else f"{key[0]}/{key[1]}"
            lines.append(f"  frame {frame}: " + "; ".join(what[:4]) + (" …" if len(what) > 4 else ""))
        return "\n".join(lines)


def compare(golden_text: str, fresh_text: str, kind: str) -> Comparison:
    """Row by row (rows matched by their frame numbers), column by column with ``TOLERANCES``."""
    tolerances = TRACK_TOLERANCES if kind == "track" else TOLERANCES
    g_cols, g_rows = read_rows(golden_text)
    f_cols, f_rows = read_rows(fresh_text)
    fresh = {_key(r): r for r in f_rows}
    golden_keys = {_key(r) for r in g_rows}
    result = Comparison(len(g_rows), [], {}, {}, header_changed=g_cols != f_cols)
    result.extra = sum(k not in golden_keys for k in fresh)
    for g in g_rows:
        key = _key(g)
        f = fresh.get(key)
        if f is None:
            result.missing += 1
            continue
        what = []
        # `detect` writes 0.00, 0.00 where it found nothing: a position only where both found one.
        placeholder = kind == "detect" and "0" in (g.get("Visibility"), f.get("Visibility"))
        for col in g_cols:
            a, b = g.get(col, ""), f.get(col, "")
            if a == b or (placeholder and col in ("X", "Y")):
                continue
            if col in VISIBILITY_COLUMNS:
                result.flips[col] = result.flips.get(col, 0) + 1
                what.append(f"{col} {a}→{b}")
                continue
            va, vb = _number(a), _number(b)
            if va is None or vb is None:
                what.append(f"{col} {a or '∅'}→{b or '∅'}")   # a value appeared or vanished
                continue
            delta = abs(va - vb)
            for group, cols, unit in POSITION_GROUPS[kind]:
                if col in cols:
                    result.max_delta[group] = max(result.max_delta.get(group, 0.0), delta * unit)
            if delta > tolerances.get(col, 0.0) + 1e-12:
                what.append(f"{col} {a}→{b}")
        if what:
            result.differing.append((key, what))
    return result


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--write", action="store_true", help="store today's outputs as the golden files")
    mode.add_argument("--check", action="store_true", help="compare fresh outputs with the golden files")
    ap.add_argument("--only", metavar="REGEX", help="only the cases whose name matches")
    ap.add_argument("--keep", metavar="DIR", type=Path,
                    help="write the fresh CSVs and demo recordings here and keep them")
    args = ap.parse_args(argv)
    cases = select(args.only)
    if not cases:
        print(f"no case matches {args.only!r}; cases: {', '.join(c.name for c in CASES)}")
        return 2
    status = 0
    with contextlib.ExitStack() as stack:
        if args.keep:
            work = args.keep
            work.mkdir(parents=True, exist_ok=True)
        else:
            work = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="golden_")))
        for case in cases:
            if not case.available:
                print(f"{case.name}: skipped (no {next(p for p in case.needs if not p.exists())})")
                continue
            if args.check and not case.golden_path.exists():
                print(f"{case.name}: no golden file {case.golden_path.relative_to(ROOT)} (run --write)")
                status = max(status, 2)
                continue
            start = time.perf_counter()
            fresh = produce(case, work)
            took = f"[{time.perf_counter() - start:.0f} s]"
            if args.write:
                size = write_golden(case, fresh)
                print(f"{case.name}: wrote {case.golden_path.relative_to(ROOT)} "
                      f"({len(read_rows(fresh)[1])} rows, {size / 1024:.1f} KB) {took}", flush=True)
                continue
            comparison = compare(read_golden(case), fresh, case.kind)
            print(comparison.report(case.name, note=took), flush=True)
            if not comparison.identical:
                status = max(status, 1)
    return status


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    raise SystemExit(main())

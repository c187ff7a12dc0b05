"""Today's `track` and `detect` outputs must not change unnoticed (benchmarks/golden.py).

The demo-court cases always run; the real-clip cases run when ../shared/data is present. A
failure prints the tool's report: how many frames differ, the visibility flips, the largest
move and the first differing frames. When a change is meant, accept it with
``.venv/bin/python benchmarks/golden.py --write`` and commit the golden files with the change.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

from .conftest_data import requires_data

ROOT = Path(__file__).resolve().parents[1]


def _load_golden():
    spec = importlib.util.spec_from_file_location("golden_tool", ROOT / "benchmarks" / "golden.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module     # dataclasses look their module up while being built
    spec.loader.exec_module(module)
    return module


golden = _load_golden()
CASES = {c.name: c for c in golden.CASES}
DEMO_CASES = [name for name in CASES if name.startswith("demo-")]
# The real cases this test runs: a slice of one stereo rally and one short TV clip; the full
# rallies and the second TV clip take minutes and are checked by `benchmarks/golden.py --check`.
REAL_CASES = ["rally_11-46-04-first400-track", "1_02_01-detect-broadcast"]


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    """One scratch folder for the module: a demo recording is rendered once for its two cases."""
    return tmp_path_factory.mktemp("golden")


def _check(case_name: str, work: Path) -> None:
    case = CASES[case_name]
    assert case.golden_path.exists(), f"{case.golden_path} is missing: run benchmarks/golden.py --write"
    comparison = golden.compare(golden.read_golden(case), golden.produce(case, work), case.kind)
    assert comparison.identical, comparison.report(case.name, first=10)


@pytest.mark.parametrize("case_name", DEMO_CASES)
def test_demo_court_output_matches_golden(case_name, work):
    _check(case_name, work)


@requires_data
@pytest.mark.shared_data
@pytest.mark.parametrize("case_name", REAL_CASES)
def test_real_clip_output_matches_golden(case_name, work):
    if not CASES[case_name].available:
        pytest.skip(f"{case_name}: its clip is absent from ../shared/data")
    _check(case_name, work)


# --- the comparison itself: it must see what it is there to see -------------------------------

TRACK_HEADER = "Frame,FrameR,Timestamp,VisL,XL,YL,VisR,XR,YR,Vis3D,X,Y,Z,Distance,Speed,LandX,LandY,LandT"
TRACK_ROWS = [
    "0,0,0.000000,0,,,0,,,0,,,,,,,,",
    "1,1,0.008333,1,100.00,200.00,1,110.00,205.00,1,0.1000,2.0000,1.5000,6.0000,10.000,0.5000,5.0000,0.8000",
    "2,2,0.016667,1,101.00,201.00,1,111.00,206.00,1,0.1100,2.1000,1.5100,6.1000,10.100,0.5100,5.0100,0.7900",
]


def _track_text(rows):
    return "\n".join([TRACK_HEADER, *rows]) + "\n"


def _edited(row: int, column: str, value: str) -> str:
    cells = [r.split(",") for r in TRACK_ROWS]
    cells[row][TRACK_HEADER.split(",").index(column)] = value
    return _track_text(",".join(c) for c in cells)


def test_comparison_calls_the_same_text_identical():
    result = golden.compare(_track_text(TRACK_ROWS), _track_text(TRACK_ROWS), "track")
    assert result.identical and result.rows == 3
    assert "identical (3 rows)" in result.report("case")


def test_comparison_accepts_moves_within_the_tolerance():
    result = golden.compare(_track_text(TRACK_ROWS), _edited(1, "XL", "100.04"), "track")
    assert result.identical
    result = golden.compare(_track_text(TRACK_ROWS), _edited(2, "Z", "1.5109"), "track")
    assert result.identical


def test_comparison_reports_a_move_beyond_the_tolerance():
    result = golden.compare(_track_text(TRACK_ROWS), _edited(2, "Z", "1.5130"), "track")
    assert not result.identical
    assert [key for key, _ in result.differing] == [("2", "2")]
    assert result.max_delta["3D mm"] == pytest.approx(3.0)
    assert "1 frames differ" in result.report("case")
    result = golden.compare(_track_text(TRACK_ROWS), _edited(1, "YR", "205.06"), "track")
    assert not result.identical and result.max_delta["2D px"] == pytest.approx(0.06)


def test_comparison_counts_visibility_flips_and_vanished_values():
    fresh = _edited(1, "VisR", "0").replace("0,110.00,205.00", "0,,", 1)
    result = golden.compare(_track_text(TRACK_ROWS), fresh, "track")
    assert result.flips == {"VisR": 1}
    assert len(result.differing) == 1
    assert any("XR 110.00→∅" in what for what in result.differing[0][1])
    result = golden.compare(_track_text(TRACK_ROWS), _edited(2, "LandT", ""), "track")
    assert not result.identical


def test_comparison_reports_missing_and_added_rows():
    result = golden.compare(_track_text(TRACK_ROWS), _track_text(TRACK_ROWS[:2]), "track")
    assert result.missing == 1 and not result.identical
    longer = TRACK_ROWS + ["3,3,0.025000,0,,,0,,,0,,,,,,,,"]
    result = golden.compare(_track_text(TRACK_ROWS), _track_text(longer), "track")
    assert result.extra == 1 and not result.identical


def test_detect_comparison_reads_x_y_as_pixels():
    stored = "Frame,Visibility,X,Y\n0,1,10.00,20.00\n1,0,0.00,0.00\n"
    assert golden.compare(stored, stored.replace("10.00", "10.04"), "detect").identical
    result = golden.compare(stored, stored.replace("10.00", "10.30"), "detect")
    assert not result.identical and result.max_delta["2D px"] == pytest.approx(0.3)
    result = golden.compare(stored, stored.replace("1,0,0.00,0.00", "1,1,30.00,40.00"), "detect")
    assert result.flips == {"Visibility": 1} and not result.identical
    assert "2D px" not in result.max_delta      # the 0.00, 0.00 of "not found" is no position


def test_golden_files_stay_small():
    """They are the CLI's own rows, gzipped: a full 1,600-pair rally is about 65 KB."""
    for case in golden.CASES:
        if case.golden_path.exists():
            assert case.golden_path.stat().st_size < 100 * 1024, case.golden_path

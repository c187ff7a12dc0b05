"""What benchmarks/perturb.py changes: every numeric preset value by the factor, inside its range.

Why this file exists: a perturbation study that silently skipped values, stepped outside a
parameter's declared range (the detector would refuse the preset) or left an integer a float
would report a study it did not run.
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
sys.path.insert(0, str(BENCHMARKS))

import perturb  # noqa: E402
from badminton_gui.io.presets import load_preset  # noqa: E402


def test_every_numeric_value_moves_both_ways_inside_its_range():
    params = load_preset("broadcast")
    changes = perturb.perturbed_values(params, ["association"], 0.25, None)
    group = params.association
    numeric = [f for f in dataclasses.fields(group)
               if not isinstance(getattr(group, f.name), bool)
               and isinstance(getattr(group, f.name), (int, float)) and getattr(group, f.name) != 0]
    names = {name for name, _ in changes}
    assert {f"association.{f.name}" for f in numeric} >= names
    for name, value in changes:
        field = next(f for f in numeric if f"association.{f.name}" == name)
        lo, hi = field.metadata["range"]
        assert lo <= value <= hi
        assert type(value) is type(getattr(group, field.name))
        assert value != getattr(group, field.name)
        # the changed preset loads: the value is one the parameter accepts
        params.with_value(name, value)
    # a value at the top of its range moves down only (lone_quality 0.75 → 0.5625 and 0.9375;
    # followed_swap_margin 1.0 → 0.75 only)
    assert [v for n, v in changes if n == "association.followed_swap_margin"] == [0.75]
    assert sorted(v for n, v in changes if n == "association.lone_quality") == [0.5625, 0.9375]
    # booleans and zeros are left alone
    assert "association.history_needs_motion" not in names
    assert "association.blind_gate" not in names


def test_only_the_named_values():
    changes = perturb.perturbed_values(load_preset("broadcast"), ["association", "motion"], 0.5,
                                       ["association.min_travel"])
    assert changes == [("association.min_travel", 5.0), ("association.min_travel", 15.0)]

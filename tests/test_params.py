"""Parameter dataclasses: ranges enforced, round trip through preset files, every field declared."""

import dataclasses
import json

import pytest

from badminton_gui.core.params import ParamError, ParamGroup, TrackerParams
from badminton_gui.io.presets import list_presets, load_preset


def test_every_field_has_range_or_options_and_label():
    for name, group in TrackerParams().groups():
        assert isinstance(group, ParamGroup), name
        assert type(group).TITLE, name
        for f in dataclasses.fields(group):
            meta = f.metadata
            assert meta.get("label"), f"{name}.{f.name} has no label"
            if isinstance(f.default, bool):
                continue
            assert "range" in meta or "options" in meta, f"{name}.{f.name} has no range"
            if "range" in meta:
                lo, hi = meta["range"]
                assert lo <= f.default <= hi, f"{name}.{f.name} default outside its range"


def test_out_of_range_is_rejected_with_a_clear_message():
    with pytest.raises(ParamError, match="binarize.threshold|threshold"):
        TrackerParams().with_value("binarize.threshold", 999)
    with pytest.raises(ParamError, match="unknown parameter"):
        TrackerParams().with_value("binarize.nope", 1)
    with pytest.raises(ParamError, match="not one of"):
        TrackerParams().with_value("background.method", "magic")


def test_with_value_coerces_types_and_is_immutable():
    p = TrackerParams()
    q = p.with_value("binarize.threshold", "140.4")
    assert q.binarize.threshold == 140 and isinstance(q.binarize.threshold, int)
    assert p.binarize.threshold != 140 or p is not q
    with pytest.raises(dataclasses.FrozenInstanceError):
        q.binarize.threshold = 3  # type: ignore[misc]


def test_preset_round_trip(tmp_path):
    p = TrackerParams().with_value("colour.min_whiteness", 77).with_value("background.detect_shadows", True)
    path = tmp_path / "mine.json"
    p.save(path, "test preset")
    data = json.loads(path.read_text())
    assert data["_description"] == "test preset"
    assert TrackerParams.load(path) == p


def test_partial_and_malformed_presets(tmp_path):
    path = tmp_path / "partial.json"
    path.write_text('{"binarize": {"threshold": 120}}')
    assert TrackerParams.load(path).binarize.threshold == 120
    path.write_text("{not json")
    with pytest.raises(ParamError, match="not valid JSON"):
        TrackerParams.load(path)
    path.write_text('{"nogroup": {"x": 1}}')
    with pytest.raises(ParamError, match="unknown parameter group"):
        TrackerParams.load(path)


def test_shipped_presets_load():
    names = list_presets()
    assert "default" in names
    for name in names:
        assert isinstance(load_preset(name), TrackerParams)
    with pytest.raises(ParamError, match="known presets"):
        load_preset("no-such-preset")

"""Tracker parameters: frozen dataclasses whose fields carry their own range, unit and help.

Why this file exists: each stage declares its parameter groups beside its code
(``core/detect/params.py``, ``core/stereo/params.py``, ``core/flight/params.py``, with the
helpers of ``core/param_fields.py``); :class:`TrackerParams` composes them into the one snapshot
that the tuning dialog, presets, the CLI and the tests read, so adding a parameter needs no GUI
code (stytra's ``Param(default, (lo, hi))`` idea). Each group dataclass is one box in the tuning
dialog.

All pixel quantities are in *full-resolution* pixels of the camera image, whatever resolution
the pipeline works at internally, so a preset means the same thing at any processing scale.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, Iterator

from .detect.params import (AssociationParams, BackgroundParams, BinarizeParams, ClassifierParams,
                            ColourParams, ContourLengthParams, MotionParams, ShuttleScaleParams,
                            TiltedRectParams, WindowParams)
from .flight.params import LookaheadParams, TrajectoryParams
from .param_fields import ParamError, ParamGroup, choice, flag, param
from .stereo.params import CourtAdaptParams, StereoParams

__all__ = ["TrackerParams", "ParamError", "ParamGroup", "param", "choice", "flag", "field_info",
           "BackgroundParams", "BinarizeParams", "ContourLengthParams", "TiltedRectParams",
           "ColourParams", "MotionParams", "AssociationParams", "ClassifierParams", "WindowParams",
           "StereoParams", "TrajectoryParams", "LookaheadParams", "CourtAdaptParams",
           "ShuttleScaleParams"]


@dataclass(frozen=True, slots=True)
class TrackerParams:
    """Every parameter of the pipeline, one group per box of the tuning dialog."""

    background: BackgroundParams = field(default_factory=BackgroundParams)
    binarize: BinarizeParams = field(default_factory=BinarizeParams)
    shuttle_scale: ShuttleScaleParams = field(default_factory=ShuttleScaleParams)
    contour_length: ContourLengthParams = field(default_factory=ContourLengthParams)
    tilted_rect: TiltedRectParams = field(default_factory=TiltedRectParams)
    colour: ColourParams = field(default_factory=ColourParams)
    motion: MotionParams = field(default_factory=MotionParams)
    association: AssociationParams = field(default_factory=AssociationParams)
    classifier: ClassifierParams = field(default_factory=ClassifierParams)
    stereo: StereoParams = field(default_factory=StereoParams)
    trajectory: TrajectoryParams = field(default_factory=TrajectoryParams)
    lookahead: LookaheadParams = field(default_factory=LookaheadParams)
    window: WindowParams = field(default_factory=WindowParams)
    adapt: CourtAdaptParams = field(default_factory=CourtAdaptParams)

    # ---- generic access, used by presets, the tuning dialog and the CLI -------------------
    def groups(self) -> Iterator[tuple[str, ParamGroup]]:
        """(attribute name, group) in dialog order."""
        for f in fields(self):
            yield f.name, getattr(self, f.name)

    def get(self, path: str) -> Any:
        """Value at ``"group.name"``."""
        group, name = self._split(path)
        return getattr(getattr(self, group), name)

    def with_value(self, path: str, value: Any) -> "TrackerParams":
        """A copy with one value replaced (validated)."""
        group, name = self._split(path)
        g = getattr(self, group)
        value = _coerce(type(g), name, value)
        return dataclasses.replace(self, **{group: dataclasses.replace(g, **{name: value})})

    def to_dict(self) -> dict[str, dict[str, Any]]:
        return {name: dataclasses.asdict(g) for name, g in self.groups()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "TrackerParams":
        """Build from a (possibly partial) nested dict; unknown keys are an error."""
        out = cls()
        for group, values in data.items():
            if group.startswith("_"):
                continue  # comments / metadata in preset files
            if not isinstance(values, dict) or group not in {f.name for f in fields(cls)}:
                raise ParamError(f"unknown parameter group {group!r}")
            for name, value in values.items():
                out = out.with_value(f"{group}.{name}", value)
        return out

    def save(self, path: str | Path, description: str = "") -> None:
        data: dict[str, Any] = {}
        if description:
            data["_description"] = description
        data.update(self.to_dict())
        Path(path).write_text(json.dumps(data, indent=2, ensure_ascii=False) + "\n", encoding="utf-8")

    @classmethod
    def load(cls, path: str | Path) -> "TrackerParams":
        try:
            data = json.loads(Path(path).read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise ParamError(f"preset file not found: {path}") from None
        except json.JSONDecodeError as exc:
            raise ParamError(f"preset file {path} is not valid JSON: {exc}") from None
        return cls.from_dict(data)

    def _split(self, path: str) -> tuple[str, str]:
        group, _, name = path.partition(".")
        g = getattr(self, group, None)
        if not isinstance(g, ParamGroup) or name not in {f.name for f in fields(g)}:
            raise ParamError(f"unknown parameter {path!r}")
        return group, name


def _coerce(group_type: type, name: str, value: Any) -> Any:
    """Convert a value (from JSON, a slider, the command line) to the field's declared type."""
    f = {f.name: f for f in fields(group_type)}[name]
    default = f.default
    if isinstance(default, bool):
        if isinstance(value, str):
            return value.strip().lower() in {"1", "true", "yes", "on"}
        return bool(value)
    if isinstance(default, int):
        return int(round(float(value)))
    if isinstance(default, float):
        return float(value)
    return str(value)


def field_info(group: ParamGroup) -> list[tuple[str, dataclasses.Field]]:
    """(name, field) of a group in declaration order; the tuning dialog renders these."""
    return [(f.name, f) for f in fields(group)]

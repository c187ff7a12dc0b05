"""The declaration of a tunable parameter: a dataclass field with its range, unit and help.

Why this file exists: every stage declares its parameter groups beside its own code
(``core/detect/params.py``, ``core/stereo/params.py``, ``core/flight/params.py``) with these
helpers; :class:`~badminton_gui.core.params.TrackerParams` composes the groups, and the tuning
dialog renders any group from its fields' metadata, so a new parameter needs no GUI code.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any, ClassVar

def param(default: Any, lo: float, hi: float, *, step: float | None = None, unit: str = "",
          label: str = "", help: str = "") -> Any:
    """A numeric dataclass field with its valid range, unit and a one-line explanation."""
    return field(default=default, metadata={
        "range": (lo, hi), "step": step, "unit": unit, "label": label, "help": help})


def choice(default: str, options: tuple[str, ...], *, label: str = "", help: str = "") -> Any:
    """A dataclass field restricted to a fixed set of strings."""
    return field(default=default, metadata={"options": options, "label": label, "help": help})


def flag(default: bool, *, label: str = "", help: str = "") -> Any:
    """A boolean dataclass field."""
    return field(default=default, metadata={"label": label, "help": help})


class ParamError(ValueError):
    """A parameter value outside its declared range, or an unknown parameter name."""


@dataclass(frozen=True, slots=True)
class ParamGroup:
    """Base of every parameter group; validates ranges on construction."""

    TITLE: ClassVar[str] = ""
    # False for a group only the file commands read (the live tuning dialog leaves it out: a
    # slider that changes nothing on screen would mislead the operator).
    LIVE: ClassVar[bool] = True

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            meta = f.metadata
            if "range" in meta:
                lo, hi = meta["range"]
                if not (lo <= value <= hi):
                    raise ParamError(f"{type(self).__name__}.{f.name} = {value!r} is outside "
                                     f"its range [{lo}, {hi}]")
            elif "options" in meta and value not in meta["options"]:
                raise ParamError(f"{type(self).__name__}.{f.name} = {value!r} is not one of "
                                 f"{', '.join(meta['options'])}")

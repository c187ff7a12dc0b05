"""Tracking results saved to a file and read back without pickle, for the look-ahead study.

Why this file exists: ``lookahead_record.py`` records the online results of the clips once and
``lookahead_study.py`` replays the look-ahead on them many times. Pickle would do it in one line,
but unpickling a file runs whatever code the file names, so a cache that someone else could write
(a fixed /tmp path) is a way into the account. This is gzip-compressed JSON that can only build
the frozen result types of ``badminton_gui.core.types`` (and tuples, numbers, strings), with the
values exact: floats as JSON numbers keep every bit, NaN and infinities included.
"""

from __future__ import annotations

import dataclasses
import gzip
import json
import math
from pathlib import Path

import numpy as np

from badminton_gui.core import types as result_types
from badminton_gui.io.safe_write import replacing

# The only classes a file may name.
TYPES = {cls.__name__: cls for cls in vars(result_types).values()
         if isinstance(cls, type) and dataclasses.is_dataclass(cls)
         and cls.__module__ == result_types.__name__}


def _encode(value):
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        name = type(value).__name__
        if TYPES.get(name) is not type(value):
            raise TypeError(f"cannot save a {name}")
        fields = {f.name: _encode(getattr(value, f.name)) for f in dataclasses.fields(value)}
        return {"@": name, **fields}
    if isinstance(value, tuple):
        return {"@tuple": [_encode(v) for v in value]}
    if isinstance(value, list):
        return [_encode(v) for v in value]
    if isinstance(value, np.ndarray):
        return {"@array": value.tolist(), "dtype": value.dtype.str}
    if isinstance(value, np.generic):
        return value.item()
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise TypeError(f"cannot save a {type(value).__name__}")


def _decode(value):
    if isinstance(value, list):
        return [_decode(v) for v in value]
    if not isinstance(value, dict):
        return value
    if "@tuple" in value:
        return tuple(_decode(v) for v in value["@tuple"])
    if "@array" in value:
        return np.array(value["@array"], dtype=np.dtype(value["dtype"]))
    cls = TYPES.get(value.get("@"))
    if cls is None:
        raise ValueError(f"unknown type {value.get('@')!r} in a result cache")
    return cls(**{k: _decode(v) for k, v in value.items() if k != "@"})


def save_results(path: Path, results) -> None:
    """Write ``results`` (lists / tuples of the core's result types) to ``path``, whole or not at all."""
    text = json.dumps(_encode(results), allow_nan=True, separators=(",", ":"))
    with replacing(path) as partial:
        with gzip.open(partial, "wt", encoding="utf-8") as fh:
            fh.write(text)


def load_results(path: Path):
    """What :func:`save_results` wrote (an empty list for a missing file)."""
    try:
        with gzip.open(path, "rt", encoding="utf-8") as fh:
            return _decode(json.loads(fh.read(), parse_constant=_constant))
    except FileNotFoundError:
        return []


def _constant(name: str) -> float:
    return {"NaN": math.nan, "Infinity": math.inf, "-Infinity": -math.inf}[name]

"""`badminton-track presets`: list the shipped parameter presets."""

from __future__ import annotations

import argparse

from ..io.presets import DEFAULT_PRESET, list_presets, presets_dir


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("presets", help="list parameter presets",
                       description="List the parameter presets shipped in resources/presets.")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    presets = list_presets()
    width = max((len(n) for n in presets), default=0)
    for name, description in presets.items():
        mark = " (default)" if name == DEFAULT_PRESET else ""
        print(f"{name:<{width}}  {description}{mark}")
    print(f"\n{len(presets)} presets in {presets_dir()}; use --preset NAME, or a .json path.")
    return 0

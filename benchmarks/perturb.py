"""Perturbation study: each preset value moved by ±25 %, one at a time, and which clips collapse.

Why this file exists: the presets were tuned on a handful of clips, and footage we do not have
(other halls, other matches) moves the operating point as a changed value does. A figure that
falls by a point when a value moves by a quarter is tuning; a clip that falls by ten is a rule
that breaks — the twenty-third round found three that way in the out-of-picture hold
(benchmarks/README.md). This prints, per changed value, the total accuracy and every clip that
lost more than ``--drop`` against the preset itself, so a rule's failure shows as one line.

    .venv/bin/python benchmarks/perturb.py                              # broadcast, tuned-on clips (~10 s a value)
    .venv/bin/python benchmarks/perturb.py --groups association --factor 0.5
    .venv/bin/python benchmarks/perturb.py --kind rally --only 'rally_11-(46-22|47-02)' \\
        --values background.learning_rate contour_length.min_length     # ~100 s a value

Broadcast runs the one-camera chain in-process (``broadcast_census.census``, look-ahead 4);
rally runs ``accuracy.py --track-only`` on a preset file written for each value. Held-out clips
are not offered: a perturbation study is development work.
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from badminton_gui.io.presets import load_preset, preset_path  # noqa: E402

DEFAULT_GROUPS = ("motion", "association", "contour_length", "tilted_rect", "colour", "background")


def perturbed_values(params, groups, factor: float, only: list[str] | None):
    """[(dotted name, new value)] for every numeric value of ``groups`` (or the ``only`` names),
    ×(1 − factor) and ×(1 + factor), kept inside each parameter's declared range."""
    out = []
    for group_name in groups:
        group = getattr(params, group_name)
        for f in dataclasses.fields(group):
            name = f"{group_name}.{f.name}"
            if only and name not in only:
                continue
            value = getattr(group, f.name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or value == 0:
                continue
            lo, hi = f.metadata.get("range", (-float("inf"), float("inf")))
            for mul in (1 - factor, 1 + factor):
                new = min(max(value * mul, lo), hi)
                new = int(round(new)) if isinstance(value, int) else round(new, 6)
                if new != value:
                    out.append((name, new))
    return out


def broadcast_scores(preset: str, overrides: tuple) -> dict[str, float]:
    """{clip: accuracy} of the tuned-on TV clips, ``overrides`` ((name, value), ...) applied."""
    from broadcast_census import census
    from clips import broadcast_clips
    scores = {}
    for clip in broadcast_clips():
        if clip.held_out:
            continue
        counts = census(clip, preset, 4, None, tuple((n, str(v)) for n, v in overrides))
        n = sum(counts[k] for k in ("TP", "TN", "FP1", "FP2", "FN"))
        scores[clip.name] = (counts["TP"] + counts["TN"]) / n
        scores.setdefault("_frames", 0)
        scores["_frames"] += n
        scores.setdefault("_right", 0)
        scores["_right"] += counts["TP"] + counts["TN"]
    return scores


def rally_scores(preset: str, overrides: tuple, only: str) -> dict[str, float]:
    """{clip camera: accuracy} of ``accuracy.py --track-only --only ONLY`` with ``overrides``."""
    data = json.loads(preset_path(preset).read_text(encoding="utf-8"))
    for name, value in overrides:
        group, field = name.split(".")
        data.setdefault(group, {})[field] = value
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as fh:
        json.dump(data, fh)
    out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "accuracy.py"), "--jobs", "2",
                          "--track-only", "--preset", fh.name, "--only", only],
                         capture_output=True, text=True, cwd=ROOT).stdout
    Path(fh.name).unlink()
    scores = {}
    for clip, cam, tp, tn, fp1, fp2, fn in re.findall(
            r"^(\S+)\s+(left|right)\s+track\s+\S+\s+(\d+)\s+(\d+)\s+(\d+)\s+(\d+)\s+(\d+)", out, re.M):
        n = sum(map(int, (tp, tn, fp1, fp2, fn)))
        scores[f"{clip} {cam}"] = (int(tp) + int(tn)) / n
        scores["_frames"] = scores.get("_frames", 0) + n
        scores["_right"] = scores.get("_right", 0) + int(tp) + int(tn)
    if not scores:
        raise SystemExit(f"accuracy.py gave no table:\n{out[-2000:]}")
    return scores


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kind", choices=("broadcast", "rally"), default="broadcast")
    ap.add_argument("--preset", default=None, help="preset name or .json (default: broadcast / default)")
    ap.add_argument("--groups", nargs="+", default=list(DEFAULT_GROUPS))
    ap.add_argument("--values", nargs="+", default=None, metavar="GROUP.NAME",
                    help="only these values (within --groups)")
    ap.add_argument("--factor", type=float, default=0.25, help="relative change (default 0.25)")
    ap.add_argument("--drop", type=float, default=0.05, help="flag a clip that loses more than this")
    ap.add_argument("--only", default="rally_11-(46-22|47-02)", help="--kind rally: clips (regex)")
    args = ap.parse_args()
    preset = args.preset or ("broadcast" if args.kind == "broadcast" else "default")
    if args.kind == "rally" and re.search(r"47-41|48-10|49-21|launcher", args.only):
        print("held-out clips are for the final measurement only", file=sys.stderr)
        return 1
    params = load_preset(preset)
    score = (broadcast_scores if args.kind == "broadcast"
             else lambda p, o: rally_scores(p, o, args.only))
    base = score(preset, ())
    total = base["_right"] / base["_frames"]
    print(f"{preset} as it is: {100 * total:.2f} %  "
          + "  ".join(f"{k} {100 * v:.1f}" for k, v in base.items() if not k.startswith("_")))
    collapses = collections.Counter()
    for name, value in perturbed_values(params, args.groups, args.factor, args.values):
        s = score(preset, ((name, value),))
        worse = {k: v - base[k] for k, v in s.items()
                 if not k.startswith("_") and v - base.get(k, v) < -args.drop}
        collapses.update(worse.keys())
        flag = "  ".join(f"{k} {100 * base[k]:.1f} → {100 * s[k]:.1f}" for k in worse)
        print(f"{name} = {value}: {100 * s['_right'] / s['_frames']:.2f} %  {flag}", flush=True)
    if collapses:
        print("clips that collapsed under some change: "
              + ", ".join(f"{k} ({n}×)" for k, n in collapses.most_common()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Size figures of the tracking core: the longest functions, the longest modules, the size of
``StereoTracker`` and of its ``process``.

Why this file exists: the core is meant to read as short named stages (no function over 80
lines, no module over 600, ``StereoTracker`` within 300 lines and its ``process`` within 60);
this prints where it stands, so a change can say what it did to those figures.

Usage::

    python scripts/code_metrics.py [--top N] [PACKAGE_DIR]
"""

from __future__ import annotations

import argparse
import ast
from pathlib import Path


def function_lengths(path: Path) -> list[tuple[int, str]]:
    """(lines, qualified name) of every function and method defined in ``path``."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found: list[tuple[int, str]] = []

    def visit(node: ast.AST, prefix: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                name = f"{prefix}{child.name}"
                found.append((child.end_lineno - child.lineno + 1, name))
                visit(child, name + ".")
            elif isinstance(child, ast.ClassDef):
                visit(child, f"{prefix}{child.name}.")

    visit(tree, "")
    return found


def class_length(path: Path, name: str) -> int | None:
    """Lines of the class ``name`` defined at the top of ``path``, or None."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and node.name == name:
            return node.end_lineno - node.lineno + 1
    return None


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("root", nargs="?", default=str(Path(__file__).resolve().parents[1] / "badminton_gui" / "core"),
                    help="package folder to measure (default: badminton_gui/core)")
    ap.add_argument("--top", type=int, default=10, help="how many functions and modules to list")
    args = ap.parse_args(argv)
    root = Path(args.root)
    modules = sorted(root.rglob("*.py"))
    functions = []
    sizes = []
    for path in modules:
        rel = path.relative_to(root)
        sizes.append((len(path.read_text(encoding="utf-8").splitlines()), str(rel)))
        functions += [(n, f"{rel}:{name}") for n, name in function_lengths(path)]
    tracker = root / "tracker.py"
    if tracker.exists():
        print(f"StereoTracker: {class_length(tracker, 'StereoTracker')} lines")
        process = [n for n, name in functions if name == "tracker.py:StereoTracker.process"]
        print(f"StereoTracker.process: {process[0] if process else None} lines")
    print(f"functions over 80 lines: {sum(1 for n, _ in functions if n > 80)} of {len(functions)}")
    print(f"modules over 600 lines: {sum(1 for n, _ in sizes if n > 600)} of {len(sizes)}")
    print(f"\nlongest functions:")
    for n, name in sorted(functions, reverse=True)[:args.top]:
        print(f"{n:6d}  {name}")
    print(f"\nlongest modules:")
    for n, name in sorted(sizes, reverse=True)[:args.top]:
        print(f"{n:6d}  {name}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

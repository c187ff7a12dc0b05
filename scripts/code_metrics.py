"""Lengths of the functions and modules of a source folder, longest first.

Why this file exists: the core keeps to two size limits (no function over 80 lines, no module
over 600), and a refactoring is judged by the before → after of these lists.

Usage: python scripts/code_metrics.py [FOLDER] [--only PREFIX,PREFIX...] [--top N]
FOLDER defaults to badminton_gui/core; --only keeps the modules whose path (relative to FOLDER)
starts with one of the prefixes.
"""

from __future__ import annotations

import argparse
import ast
from pathlib import Path


def function_lengths(root: Path) -> list[tuple[int, str]]:
    """(lines, "module.py:Class.method") of every function and method under ``root``."""
    out: list[tuple[int, str]] = []

    def walk(node: ast.AST, rel: str, prefix: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                out.append((child.end_lineno - child.lineno + 1, f"{rel}:{prefix}{child.name}"))
                walk(child, rel, f"{prefix}{child.name}.")
            elif isinstance(child, ast.ClassDef):
                walk(child, rel, f"{prefix}{child.name}.")

    for path in sorted(root.rglob("*.py")):
        walk(ast.parse(path.read_text()), str(path.relative_to(root)), "")
    return out


def module_lengths(root: Path) -> list[tuple[int, str]]:
    """(lines, "module.py") of every module under ``root``."""
    return [(len(p.read_text().splitlines()), str(p.relative_to(root))) for p in sorted(root.rglob("*.py"))]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", nargs="?", default="badminton_gui/core")
    ap.add_argument("--only", default="", help="comma-separated module path prefixes to keep")
    ap.add_argument("--top", type=int, default=10, help="how many of each list (default 10)")
    args = ap.parse_args()
    root = Path(args.folder)
    prefixes = [p for p in args.only.split(",") if p]

    def kept(name: str) -> bool:
        return not prefixes or any(name.startswith(p) for p in prefixes)

    print("longest functions:")
    for n, name in sorted((x for x in function_lengths(root) if kept(x[1])), reverse=True)[:args.top]:
        print(f"  {n:5d}  {name}")
    print("longest modules:")
    for n, name in sorted((x for x in module_lengths(root) if kept(x[1])), reverse=True)[:args.top]:
        print(f"  {n:5d}  {name}")


if __name__ == "__main__":
    main()

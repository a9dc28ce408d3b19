"""Size and complexity of the pinflex package: the figures docs/architecture.md speaks of.

Module sizes: total lines and logic lines (lines holding code: no blank, comment or
docstring line) of every module, the largest first. Complexity: the findings of ruff's
McCabe and Pylint size rules at their default thresholds (``--select C901,PLR09``) per 1,000
lines, with and without PLR0917 (too many positional arguments), when ruff is installed.

Run: ``python benchmarks/code_metrics.py [TREE] [--top 15]`` (TREE: a source tree of pinflex,
default this one; point it at a worktree of an older commit to compare).
"""

from __future__ import annotations

import argparse
import ast
import io
import re
import shutil
import subprocess
import tokenize
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
_SKIP = {tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT,
         tokenize.ENDMARKER}


def logic_lines(source: str) -> int:
    """Lines with code, docstrings (of modules, classes, functions, attributes) excluded."""
    doc: set[int] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) \
                and isinstance(node.value.value, str):
            doc.update(range(node.lineno, node.end_lineno + 1))
    code: set[int] = set()
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type not in _SKIP:
            code.update(range(tok.start[0], tok.end[0] + 1))
    return len(code - doc)


def sizes(tree: Path) -> list[tuple[int, int, str]]:
    """(total, logic, path) of every module under ``tree/pinflex``."""
    rows = []
    for path in sorted((tree / "pinflex").rglob("*.py")):
        text = path.read_text()
        rows.append((len(text.splitlines()), logic_lines(text), str(path.relative_to(tree))))
    return rows


def complexity(tree: Path, ignore: str = "") -> int | None:
    """Number of ruff C901/PLR09 findings in ``tree/pinflex`` (None without ruff)."""
    ruff = shutil.which("ruff")
    if ruff is None:
        return None
    cmd = [ruff, "check", "--isolated", "--select", "C901,PLR09", "--statistics", "pinflex"]
    if ignore:
        cmd += ["--ignore", ignore]
    out = subprocess.run(cmd, cwd=tree, capture_output=True, text=True).stdout
    found = re.search(r"Found (\d+) error", out)
    return int(found.group(1)) if found else 0


def main(argv=None):
    """Print the tables."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], epilog=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("tree", nargs="?", type=Path, default=ROOT, help="source tree")
    parser.add_argument("--top", type=int, default=15, help="largest modules shown")
    args = parser.parse_args(argv)
    rows = sizes(args.tree)
    total = sum(r[0] for r in rows)
    print(f"{'lines':>6} {'logic':>6}  module (largest {args.top} by lines)")
    for n, logic, path in sorted(rows, reverse=True)[:args.top]:
        print(f"{n:6d} {logic:6d}  {path}")
    print(f"{total:6d} {sum(r[1] for r in rows):6d}  total ({len(rows)} modules)")
    found = complexity(args.tree)
    if found is None:
        print("complexity: ruff not installed")
        return
    plain = complexity(args.tree, "PLR0917")
    print(f"complexity (ruff C901,PLR09, default thresholds): {found} findings = "
          f"{1000 * found / total:.2f} per 1,000 lines; without PLR0917 {plain} = "
          f"{1000 * plain / total:.2f}")


if __name__ == "__main__":
    main()

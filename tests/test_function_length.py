"""Functions you can read at once: none over 100 lines in src/ (compiled-kernel modules, whose
bodies are unrolled loops for numba, excepted) and at most 20 over 60.  Files are parsed, not
imported; a function's length counts its docstring and its nested functions."""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
#: Modules of compiled kernels (numba bodies): exempt from the line budgets.
KERNEL_MODULE_WORD = "kernel"
LONGEST = 100
LONG, MOST_LONG = 60, 20


def function_lengths(root: Path) -> list[tuple[int, str]]:
    """``(lines, "path:function")`` of every function under ``root`` outside kernel modules."""
    out = []
    for p in sorted(root.rglob("*.py")):
        if KERNEL_MODULE_WORD in p.name:
            continue
        for node in ast.walk(ast.parse(p.read_text(), filename=str(p))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                out.append((node.end_lineno - node.lineno + 1, f"{p.relative_to(root)}:{node.name}"))
    return out


def test_no_function_over_100_lines():
    over = sorted((n, f) for n, f in function_lengths(SRC) if n > LONGEST)
    assert over == [], f"functions over {LONGEST} lines (split them by job): {over}"


def test_at_most_20_functions_over_60_lines():
    over = sorted(((n, f) for n, f in function_lengths(SRC) if n > LONG), reverse=True)
    assert len(over) <= MOST_LONG, f"{len(over)} functions over {LONG} lines (at most {MOST_LONG}): {over}"


def test_the_count_sees_a_long_function(tmp_path):
    body = "\n".join(f"    x{i} = {i}" for i in range(101))
    (tmp_path / "m.py").write_text(f"def f():\n{body}\n")
    (tmp_path / "my_kernels.py").write_text(f"def g():\n{body}\n")
    assert function_lengths(tmp_path) == [(102, "m.py:f")]

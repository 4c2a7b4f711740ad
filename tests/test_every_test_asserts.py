"""Every test asserts something: a test function with no ``assert``, no ``pytest.raises``/
``warns``/``fail``/``skip`` and no call of a helper that has one cannot fail on a wrong
result, only on an exception.  Files are parsed, not imported.  A helper counts when it is
a function of the same file (followed through its own calls) or a check passed in as a
parameter (the conformance suites: ``check(entry)``, ``run_check(check, ...)``)."""

from __future__ import annotations

import ast
from pathlib import Path

TESTS = Path(__file__).resolve().parent
#: Calls that assert by themselves (pytest's and numpy/pandas' testing helpers).
ASSERTING_CALLS = {"raises", "warns", "deprecated_call", "fail", "skip", "xfail", "importorskip", "approx"}


def _asserts(fn: ast.FunctionDef, helpers: dict[str, ast.FunctionDef], seen: frozenset[str]) -> bool:
    params = {a.arg for a in fn.args.args + fn.args.kwonlyargs}
    for node in ast.walk(fn):
        if isinstance(node, (ast.Assert, ast.Raise)):
            return True
        if not isinstance(node, ast.Call):
            continue
        f = node.func
        name = f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else ""
        if name in ASSERTING_CALLS or name.startswith("assert"):
            return True
        if isinstance(f, ast.Name) and name in params:  # a check passed in
            return True
        if any(isinstance(a, ast.Name) and a.id == "check" and a.id in params for a in node.args):
            return True
        if name in helpers and name not in seen and _asserts(helpers[name], helpers, seen | {name}):
            return True
    return False


def unasserting_tests(folder: Path) -> list[str]:
    """``"file:line name"`` of every test function under ``folder`` that asserts nothing."""
    out = []
    for path in sorted(folder.glob("test_*.py")):
        tree = ast.parse(path.read_text(), filename=str(path))
        helpers = {n.name: n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)}
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef) and node.name.startswith("test") \
                    and not _asserts(node, helpers, frozenset({node.name})):
                out.append(f"{path.name}:{node.lineno} {node.name}")
    return out


def test_every_test_asserts_something():
    assert unasserting_tests(TESTS) == []


def test_the_check_sees_a_test_that_asserts_nothing(tmp_path):
    (tmp_path / "test_x.py").write_text(
        "import pytest\n\n\ndef _close(a, b):\n    assert abs(a - b) < 1\n\n\n"
        "def test_runs_only():\n    sorted([2, 1])\n\n\n"
        "def test_asserts():\n    assert sorted([2, 1]) == [1, 2]\n\n\n"
        "def test_through_a_helper():\n    _close(1, 1.5)\n\n\n"
        "def test_raises():\n    with pytest.raises(ValueError):\n        int('x')\n\n\n"
        "@pytest.mark.parametrize('check', [print])\ndef test_a_check_passed_in(check):\n    check(1)\n")
    assert unasserting_tests(tmp_path) == ["test_x.py:8 test_runs_only"]

"""No module defines a function or class under a name it imports at its top.

Found after a merge: ``accelcal_repro/discrepancy/figures.py`` imported
``wander_named`` from the wander-process table and kept a local ``def wander_named``
whose body called the imported one -- which by then was itself, so drawing the sessions
figure recursed until Python gave up.  A shadowed import is never what was meant."""

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"


def shadowed(tree: ast.Module) -> list[str]:
    imported = {a.asname or a.name.split(".")[0] for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom))
                for a in n.names}
    return [n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))
            and n.name in imported]


def test_the_check_finds_a_shadowed_import():
    code = "from x import f\n\ndef f(r):\n    return f(r)\n"
    assert shadowed(ast.parse(code)) == ["f"]


def test_no_module_defines_a_name_it_imports():
    found = {str(p.relative_to(SRC)): names for p in sorted(SRC.rglob("*.py"))
             if (names := shadowed(ast.parse(p.read_text(encoding="utf-8"))))}
    assert not found, f"a module defines a name it also imports (the definition hides the import): {found}"

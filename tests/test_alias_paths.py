"""One import path per name: a subpackage's ``__init__`` exports (``__all__``) its own
modules' names, never a name of another package (``accelcal.discrepancy.EFFECTS`` was
``accelcal.effects.EFFECTS`` under a second path).  The top-level ``accelcal`` is the
exception by design: it is the library's front (its PEP 562 table).  Files are parsed."""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"


def foreign_exports(root: Path) -> list[str]:
    """``"package: name from module"`` for every ``__all__`` name a subpackage's ``__init__``
    imports from outside itself (``from ..x import name``, ``from accelcal.x import name``)."""
    out = []
    for init in sorted(root.rglob("__init__.py")):
        if init.parent.parent == root:  # a top-level package: its front
            continue
        tree = ast.parse(init.read_text(), filename=str(init))
        exported = {c.value for n in tree.body if isinstance(n, ast.Assign)
                    and any(getattr(t, "id", "") == "__all__" for t in n.targets)
                    for c in ast.walk(n.value) if isinstance(c, ast.Constant) and isinstance(c.value, str)}
        for n in tree.body:
            if isinstance(n, ast.ImportFrom) and (n.level >= 2 or n.level == 0):
                module = "." * n.level + (n.module or "")
                out += [f"{init.parent.relative_to(root).as_posix()}: {a.asname or a.name} from {module}"
                        for a in n.names if (a.asname or a.name) in exported]
    return out


def test_no_subpackage_exports_another_packages_name():
    assert foreign_exports(SRC) == []


def test_the_check_sees_a_re_export(tmp_path):
    (tmp_path / "lib" / "sub").mkdir(parents=True)
    (tmp_path / "lib" / "__init__.py").write_text("from .effects import EFFECTS\n__all__ = ['EFFECTS']\n")
    (tmp_path / "lib" / "sub" / "__init__.py").write_text(
        "import numpy as np\nfrom ..effects import EFFECTS, effect\nfrom .fit import fit\n\n__all__ = ['EFFECTS', 'fit']\n")
    assert foreign_exports(tmp_path) == ["lib/sub: EFFECTS from ..effects"]

"""Imports at the top of the core's modules; laziness only at the edges.

A function-level import hides a dependency from the reader, the IDE and the type checker,
so ``src/accelcal`` keeps one only where it buys something a test can name:

* an **optional extra or a costly package** (:data:`DEFERRED_PACKAGES`, each with its
  reason: an extra a user may not have installed, or an import cost the command line must
  not pay on its common path, checked by ``test_distributions`` and
  ``test_package_boundary``);
* one of the library's own modules that a command's common path need not load
  (:data:`DEFERRED_MODULES`, each with its reason and the test that measures it);
* an **edge module** (:data:`EDGE_MODULES`): the command line's modules, which keep
  ``accelcal --help`` free of numpy, and the modules its help imports.

Anything else fails.  :data:`CEILING` caps the total, so that a new deferred import of an
allowed kind is a decision, not a drift.  One function resolves ``module:attr`` strings
(:func:`accelcal.registry.resolve`); the package's PEP 562 ``__getattr__`` (``import
accelcal`` loads no numpy) is the only other place that imports a module to take a name
from it.  Nothing is imported: the files are parsed.
"""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"

#: Top-level packages a function may import, and why.
DEFERRED_PACKAGES = {
    "casadi": "optional extra: the IPOPT estimators (accelcal.nlls)",
    "numba": "optional extra: the compiled kernels (accelcal.kernels)",
    "fcntl": "POSIX only: the kernel cache's lock",
    "pyulog": "optional extra: the PX4 reader",
    "rosbags": "optional extra: the ROS readers",
    "ruamel": "optional extra (with rosbags): a ROS 2 bag's metadata",
    "lz4": "optional extra: compressed MCAP chunks",
    "compression": "zstd in the standard library from Python 3.14 on",
    "backports": "zstd before Python 3.14 (optional)",
    "io": "with the zstd decompressors above (ros_recover)",
    "pymavlink": "optional extra: the ArduPilot reader",
    "rdata": "optional extra: the R data reader",
    "ppigrf": "optional extra: the IGRF field model",
    "h5py": "optional extra: MATLAB v7.3 (HDF5) files",
    "pandas": "0.8 s at import: read by the readers that parse with its C parser, when they parse",
    "matplotlib": "plotting: figures are drawn only when asked for",
    "scipy": "calibrating an accelerometer loads no scipy (tests/test_distributions.py), nor does importing "
             "the estimators (tests/test_package_boundary.py); scipy.signal costs 1.2 s",
}
#: The library's own plotting modules (matplotlib at their top): deferred like matplotlib.
PLOTTING = ("plotting", "figures", "calibration_figures")

#: Modules whose function-level imports are the edge itself, and why.
EDGE_MODULES = {
    "accelcal/cli/": "the command line: a command's handler imports the numerical modules when it runs, so "
                     "that `accelcal --help` loads no numpy (tests/test_package_boundary.py)",
    "accelcal/formats/dispatch.py": "the formats package's entry, imported by the CLI's help for the format "
                                    "list: numpy and the readers load when a file is read",
    "accelcal/export/registry.py": "imported by the CLI's help for the consumer list: export.base loads numpy",
    "accelcal/distributions.py": "scipy.special at its first use (see DEFERRED_PACKAGES['scipy'])",
}

#: The library's own modules a function may import, where the import cost a command's common
#: path does not need (file, imported module): the reason, with the test that measures it.
DEFERRED_MODULES = {
    ("accelcal/export/kalibr.py", "..gyro.model"): "only a calibrated export writes a gyro model; `accelcal "
        "noise` writes Kalibr's noise file without one, and the package accelcal.gyro costs it 0.12 s of its "
        "~2.3 s of CPU (tests/test_noise.py checks the command imports no accelcal.gyro module)",
}

#: Function-level imports in src/accelcal, all kinds: may only go down.
CEILING = 95
#: The same count in src/accelcal_repro (plotting, optional extras, the peers' packages,
#: compiled kernels and the gyro stage's session readers): may only go down.
REPRO_CEILING = 32


def function_level_imports(root: Path) -> list[tuple[str, int, str]]:
    """``(file relative to root, line, imported module)`` of every import inside a function
    (relative modules keep their dots)."""
    found = []
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root).as_posix()

        def visit(node, in_function):
            for child in ast.iter_child_nodes(node):
                if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    visit(child, True)
                elif isinstance(child, (ast.Import, ast.ImportFrom)) and in_function:
                    names = ([a.name for a in child.names] if isinstance(child, ast.Import)
                             else ["." * child.level + (child.module or "")])
                    found.extend((rel, child.lineno, name) for name in names)
                else:
                    visit(child, in_function)

        visit(ast.parse(path.read_text(), filename=str(path)), False)
    return found


def _allowed(rel: str, module: str) -> bool:
    if any(rel == edge or (edge.endswith("/") and rel.startswith(edge)) for edge in EDGE_MODULES):
        return True
    if module.split(".")[0] in DEFERRED_PACKAGES:
        return True
    last = module.rpartition(".")[2]
    return module.startswith(".") and last in PLOTTING or (rel, module) in DEFERRED_MODULES


def test_function_level_imports_only_at_the_edges():
    found = function_level_imports(SRC)
    core = [(rel, line, mod) for rel, line, mod in found if rel.startswith("accelcal/")]
    bad = [f"{rel}:{line} imports {mod}" for rel, line, mod in core if not _allowed(rel, mod)]
    assert not bad, ("imports inside functions outside the edges (move them to the module's top, or name the "
                     "edge in tests/test_import_placement.py with its reason):\n" + "\n".join(bad))
    assert len(core) <= CEILING, f"{len(core)} function-level imports in src/accelcal (ceiling {CEILING})"
    repro = [f for f in found if f[0].startswith("accelcal_repro/")]
    assert len(repro) <= REPRO_CEILING, f"{len(repro)} function-level imports in src/accelcal_repro ({REPRO_CEILING})"


def test_the_checker_finds_what_it_must(tmp_path):
    """A function-level import outside an edge is found; a top-level one and an edge's are not."""
    pkg = tmp_path / "accelcal"
    (pkg / "cli").mkdir(parents=True)
    (pkg / "core.py").write_text("import math\n\ndef f():\n    from .model import m\n    import pandas\n    return m\n")
    (pkg / "cli" / "run.py").write_text("def main():\n    from ..core import f\n    return f()\n")
    found = function_level_imports(tmp_path)
    assert found == [("accelcal/cli/run.py", 2, "..core"), ("accelcal/core.py", 4, ".model"),
                     ("accelcal/core.py", 5, "pandas")]
    assert [_allowed(rel, mod) for rel, _, mod in found] == [True, False, True]


#: The functions that import a module to take a name from it (``getattr`` on what
#: ``importlib.import_module`` returns), and why.
RESOLVERS = {
    "accelcal/registry.py:resolve": "the one resolver of 'module:attr' strings (the registries' tables)",
    "accelcal/__init__.py:__getattr__": "PEP 562: `import accelcal` loads no numpy (tests/test_package_boundary.py)",
    "accelcal/mag/__init__.py:__getattr__": "PEP 562: the CLI's help reads accelcal.mag.registry without numpy",
}


def _imports_a_module(node) -> bool:
    f = node.func if isinstance(node, ast.Call) else None
    return f is not None and (getattr(f, "attr", None) or getattr(f, "id", None)) == "import_module"


def name_resolvers(root: Path) -> list[str]:
    """``"file:function"`` of every function under ``root`` that takes an attribute
    (``getattr``) of a module it imports by name (``import_module``, directly or through a
    variable)."""
    out = []
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            modules = {t.id for a in ast.walk(node) if isinstance(a, ast.Assign) and _imports_a_module(a.value)
                       for t in a.targets if isinstance(t, ast.Name)}
            if any(isinstance(c, ast.Call) and getattr(c.func, "id", None) == "getattr" and c.args
                   and (_imports_a_module(c.args[0]) or getattr(c.args[0], "id", None) in modules)
                   for c in ast.walk(node)):
                out.append(f"{path.relative_to(root).as_posix()}:{node.name}")
    return out


def test_one_resolver_for_module_attr_strings():
    assert sorted(name_resolvers(SRC)) == sorted(RESOLVERS), "resolve 'module:attr' with accelcal.registry.resolve"


def test_the_resolver_check_sees_a_copy(tmp_path):
    (tmp_path / "m.py").write_text("import importlib\n\n\ndef _resolve(s):\n    mod, _, name = s.partition(':')\n"
                                   "    return getattr(importlib.import_module(mod), name)\n\n\n"
                                   "def load(s):\n    m = importlib.import_module(s)\n    return getattr(m, 'f')\n\n\n"
                                   "def cache(s, d):\n    m = importlib.import_module(s)\n    return getattr(d, 'c'), m\n")
    assert name_resolvers(tmp_path) == ["m.py:_resolve", "m.py:load"]

"""The modules of ``src/`` import one another without cycles, and each stays readable in size.

An import cycle (``a`` imports ``b`` and ``b`` imports ``a``, directly or through other
modules) makes the import order matter and usually hides two modules that are one
concept, or a helper that belongs lower down; a function-level import that dodges the
cycle at run time hides it from the reader too, so it counts here.  Every module of
``src/`` is parsed with :mod:`ast` (nothing is imported): every ``import`` and
``from ... import`` anywhere in the file, inside functions and ``if TYPE_CHECKING:``
blocks included; relative imports resolved; ``from pkg import name`` counted as an
import of the submodule ``pkg.name`` when there is one, else of ``pkg``; and importing
``pkg.sub.mod`` also runs ``pkg.sub``'s ``__init__``, so it counts as an import of it
(except for the packages that contain the importing module: they are being imported
already).

Size budget: :data:`MAX_LINES` lines per module (``wc -l``).  Compiled-kernel modules
(``_*_kernels.py``, ``_fast.py``: numba loops that read best whole) are exempt by name.
"""

from __future__ import annotations

import ast
import fnmatch
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
#: Lines a module of src/ may have.
MAX_LINES = 600
#: Module file names exempt from the budget: the compiled kernels.
EXEMPT = ("_*_kernels.py", "_fast.py")
#: Modules over the budget that are being split in other branches right now.  This set
#: must be emptied: the test fails for a module listed here that is no longer over the
#: budget (or no longer exists), so that the list cannot outlive the splits.
PENDING_SPLIT: set[str] = set()


# --------------------------------------------------------------------------- the checkers


def module_name(root: Path, path: Path) -> str:
    """Dotted name of the module in file ``path`` under the source root ``root``."""
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _imported(node: ast.AST, package: str, modules: set[str]) -> set[str]:
    """The modules (dotted names, not yet filtered to ``modules``) an import statement names;
    ``package`` is the package relative imports start from."""
    if isinstance(node, ast.Import):
        return {alias.name for alias in node.names}
    if not isinstance(node, ast.ImportFrom):
        return set()
    if node.level:
        parts = package.split(".")
        base = parts[: len(parts) - (node.level - 1)]
        target = ".".join(base + ([node.module] if node.module else []))
    else:
        target = node.module
    submodules = {f"{target}.{alias.name}" for alias in node.names} & modules
    names_that_are_not = len(node.names) > len(submodules)
    return submodules | ({target} if names_that_are_not else set())


def import_graph(root: Path) -> dict[str, set[str]]:
    """``{module: modules of root it imports}`` for every ``*.py`` under ``root`` (module docstring)."""
    root = Path(root)
    files = {module_name(root, p): p for p in sorted(root.rglob("*.py"))}
    modules = set(files)
    graph = {}
    for mod, path in files.items():
        package = mod if path.name == "__init__.py" else mod.rpartition(".")[0]
        parts = mod.split(".")
        importing = {".".join(parts[:i]) for i in range(1, len(parts) + 1)}   # itself and its packages
        tree = ast.parse(path.read_text(), filename=str(path))
        targets = set().union(*(_imported(node, package, modules) for node in ast.walk(tree)))
        edges = set()
        for target in targets:   # the target and every package on its way that is not being imported already
            t = target.split(".")
            edges |= {".".join(t[:i]) for i in range(1, len(t) + 1)} & modules - importing
        graph[mod] = edges
    return graph


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out)


def module_sizes(root: Path) -> dict[str, int]:
    """Lines of every module under ``root`` not exempt by name, by path relative to ``root``."""
    root = Path(root)
    return {p.relative_to(root).as_posix(): len(p.read_text().splitlines()) for p in sorted(root.rglob("*.py"))
            if not any(fnmatch.fnmatch(p.name, pattern) for pattern in EXEMPT)}


# --------------------------------------------------------------------------- src/


def test_src_has_no_import_cycle():
    cycles = import_cycles(import_graph(SRC))
    assert not cycles, "import cycles in src/: " + "; ".join(" <-> ".join(c) for c in cycles)


def test_modules_stay_within_the_size_budget():
    over = {m: n for m, n in module_sizes(SRC).items() if n > MAX_LINES and m not in PENDING_SPLIT}
    assert not over, f"modules over {MAX_LINES} lines: " + ", ".join(f"{m} ({n})" for m, n in sorted(over.items()))


def test_modules_pending_a_split_are_still_over_the_budget():
    sizes = module_sizes(SRC)
    done = sorted(m for m in PENDING_SPLIT if sizes.get(m, 0) <= MAX_LINES)
    assert not done, f"remove from PENDING_SPLIT (split, or within {MAX_LINES} lines now): {', '.join(done)}"


# --------------------------------------------------------------------------- the checkers can fail


def _package(root: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return root


def test_the_checker_finds_a_cycle_hidden_in_a_function(tmp_path):
    # a -> b through a lazy relative import of a submodule, b -> c relative, c -> a absolute
    root = _package(tmp_path, {
        "pkg/__init__.py": "",
        "pkg/a.py": "def f():\n    from . import b\n    return b\n",
        "pkg/b.py": "from .c import helper\n",
        "pkg/c.py": "import pkg.a\n\ndef helper():\n    pass\n",
        "pkg/d.py": "from pkg import a\n",
    })
    graph = import_graph(root)
    assert graph["pkg.a"] == {"pkg.b"} and graph["pkg.b"] == {"pkg.c"} and graph["pkg.c"] == {"pkg.a"}
    assert import_cycles(graph) == [["pkg.a", "pkg.b", "pkg.c"]]
    (root / "pkg/c.py").write_text("def helper():\n    pass\n")
    assert import_cycles(import_graph(root)) == []


def test_the_checker_resolves_relative_imports_and_packages(tmp_path):
    root = _package(tmp_path, {
        "top/__init__.py": "from .sub import thing\n",
        "top/sub/__init__.py": "thing = 1\n",
        "top/sub/deep.py": "from .. import other\nfrom ..sub import thing\nfrom . import leaf as L\n",
        "top/sub/leaf.py": "",
        "top/other.py": "import top.sub.leaf\n",
        "elsewhere.py": "from top.sub import thing, leaf\n",
    })
    graph = import_graph(root)
    # `from ..sub import thing`: a name of the package top.sub, which deep.py is inside: no edge
    assert graph["top.sub.deep"] == {"top.other", "top.sub.leaf"}
    # importing top.sub.leaf runs top.sub's __init__ (top is other.py's own package)
    assert graph["top.other"] == {"top.sub", "top.sub.leaf"}
    assert graph["elsewhere"] == {"top", "top.sub", "top.sub.leaf"}
    assert graph["top"] == {"top.sub"}
    # top.sub.deep -> top.other -> top.sub (the __init__), which does not import deep: no cycle
    assert import_cycles(graph) == []
    (root / "top/sub/__init__.py").write_text("from .deep import L\n")
    assert import_cycles(import_graph(root)) == [["top.other", "top.sub", "top.sub.deep"]]


def test_the_size_budget_sees_a_long_module_and_exempts_kernels(tmp_path):
    root = _package(tmp_path, {
        "pkg/__init__.py": "",
        "pkg/long.py": "x = 1\n" * (MAX_LINES + 1),
        "pkg/short.py": "x = 1\n" * MAX_LINES,
        "pkg/_lls_kernels.py": "x = 1\n" * (2 * MAX_LINES),
        "pkg/_fast.py": "x = 1\n" * (2 * MAX_LINES),
    })
    sizes = module_sizes(root)
    assert sizes == {"pkg/__init__.py": 0, "pkg/long.py": MAX_LINES + 1, "pkg/short.py": MAX_LINES}

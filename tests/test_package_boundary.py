"""The core library knows nothing of the reproductions that use it.

``accelcal`` is what a person calibrating an IMU imports; ``accelcal_repro`` (the paper
reproductions, the measured-data stage, the discrepancy benchmark, the report) imports
it, never the reverse.  The core needs only the numerical stack; matplotlib (the
``plots`` extra) only where figures are drawn.  A layer uses only the public names of the
layers below it (workflow scripts -> ``accelcal_repro`` -> ``accelcal``): a name with a
leading underscore is free to change inside its own package.
"""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SRC = REPO / "src"
CORE = SRC / "accelcal"
#: The layers, each with the packages it may import from below it.  Tests are not a layer:
#: they may look inside what they test.
LAYERS = {"accelcal": CORE, "accelcal_repro": SRC / "accelcal_repro", "workflow": REPO / "workflow" / "scripts"}
PACKAGES = ("accelcal", "accelcal_repro")
#: Third-party packages the core may import anywhere, and where matplotlib is allowed.
# threadpoolctl: the BLAS's thread count around the loop's small stacked LAPACK calls (accelcal.threads;
# pure Python, no dependencies of its own, what scikit-learn and scipy's own tests use for the same job)
CORE_DEPENDENCIES = {"numpy", "scipy", "pandas", "casadi", "threadpoolctl"}
PLOTTING_MODULES = {"plotting.py", "discrepancy/figures.py", "noise/figures.py"}
#: Optional extras (ros, px4, ardupilot, rdata, mat73, geomag), each imported lazily by its reader (the IGRF by
#: the magnetometer's field module) only.
EXTRA_MODULES = {"formats/ros.py": {"rosbags", "ruamel"},
                 "formats/ros_write.py": {"rosbags"},
                 # rosbags' own dependencies: its YAML, and its MCAP chunk decompressors
                 "formats/ros_recover.py": {"rosbags", "lz4", "backports", "compression"},
                 "formats/px4.py": {"pyulog"}, "formats/ardupilot.py": {"pymavlink"}, "formats/rda.py": {"rdata"},
                 "formats/mat.py": {"h5py"}, "mag/field.py": {"ppigrf"}}
#: numba (the optional ``fast`` extra) is imported by the kernel loader only, on first use.
KERNEL_LOADER = "kernels.py"


def _imports(path: Path):
    """Top-level names of every module ``path`` imports (also inside functions)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name.split(".")[0], node.lineno
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            yield node.module.split(".")[0], node.lineno


def _core_files():
    return sorted(CORE.rglob("*.py"))


def test_core_never_imports_the_reproductions():
    wrong = [f"{p.relative_to(SRC)}:{line}" for p in _core_files() for name, line in _imports(p)
             if name == "accelcal_repro"]
    assert not wrong, f"accelcal imports accelcal_repro at {', '.join(wrong)}"


def test_core_depends_only_on_the_numerical_stack():
    stdlib = set(sys.stdlib_module_names)
    bad = []
    for p in _core_files():
        rel = p.relative_to(CORE).as_posix()
        allowed = (CORE_DEPENDENCIES | {"accelcal"} | ({"matplotlib"} if rel in PLOTTING_MODULES else set())
                   | ({"numba"} if rel == KERNEL_LOADER else set()) | EXTRA_MODULES.get(rel, set()))
        bad += [f"{rel}:{line} imports {name}" for name, line in _imports(p) if name not in stdlib | allowed]
    assert not bad, "; ".join(bad)


def test_the_boundary_check_sees_a_wrong_import(tmp_path):
    # the scanner must catch a lazy import inside a function, not only top-level ones
    f = tmp_path / "m.py"
    f.write_text("def f():\n    from accelcal_repro.claims import Claim\n    import snakemake\n")
    assert {n for n, _ in _imports(f)} == {"accelcal_repro", "snakemake"}


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def _private_uses(path: Path, layer: str):
    """``(line, what)`` of every private name ``path`` (in ``layer``) takes from another
    package: a private module or name in an import, or a private attribute of a name
    imported from another package (``import accelcal.static as S; S._x``)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    bound = {}  # local name -> the other package's module it came from
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            if node.module.split(".")[0] not in PACKAGES or node.module.split(".")[0] == layer:
                continue
            if any(_private(part) for part in node.module.split(".")):
                yield node.lineno, f"from {node.module} import ..."
            for alias in node.names:
                if _private(alias.name):
                    yield node.lineno, f"from {node.module} import {alias.name}"
                bound[alias.asname or alias.name] = node.module
        elif isinstance(node, ast.Import):
            for alias in node.names:
                top = alias.name.split(".")[0]
                if top not in PACKAGES or top == layer:
                    continue
                if any(_private(part) for part in alias.name.split(".")):
                    yield node.lineno, f"import {alias.name}"
                bound[alias.asname or top] = alias.name
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in bound
                and _private(node.attr)):
            yield node.lineno, f"{node.value.id}.{node.attr} ({bound[node.value.id]})"


def test_no_private_name_crosses_a_package():
    wrong = [f"{p.relative_to(REPO)}:{line}: {what}" for layer, folder in LAYERS.items()
             for p in sorted(folder.rglob("*.py")) for line, what in _private_uses(p, layer)]
    assert not wrong, "private names used from another package (give them a public name): " + "; ".join(wrong)


def test_the_private_name_check_sees_each_kind_of_use(tmp_path):
    f = tmp_path / "script.py"
    f.write_text("from accelcal.results import _finite_json, CalibrationResult\n"
                 "import accelcal.batista._filter_kernels\n"
                 "from accelcal_repro.batista2011._shared_gain_kernels import shared_gain_block\n"
                 "from accelcal import static as S, kernels\n"
                 "import accelcal_repro.timing as T\n"
                 "from _helpers import configure_logging\n"  # the scripts' own helpers: same layer
                 "from accelcal import __version__\n"
                 "def f():\n"
                 "    return S._geyer, kernels._resolve('auto'), T.available_backends, kernels.backend\n")
    found = [what for _, what in _private_uses(f, "workflow")]
    assert found == ["from accelcal.results import _finite_json", "import accelcal.batista._filter_kernels",
                     "from accelcal_repro.batista2011._shared_gain_kernels import ...", "S._geyer (accelcal)",
                     "kernels._resolve (accelcal)"], found
    # inside its own package a private name is fine
    found = [what for _, what in _private_uses(f, "accelcal_repro")]
    assert found == ["from accelcal.results import _finite_json", "import accelcal.batista._filter_kernels",
                     "S._geyer (accelcal)", "kernels._resolve (accelcal)"], found


@pytest.mark.parametrize("module", ["accelcal", "accelcal.cli"])
def test_importing_the_core_loads_no_workflow_package(module):
    code = (f"import sys, {module}\n"
            "bad = sorted(m for m in ('accelcal_repro', 'snakemake', 'matplotlib', 'jinja2', 'yaml') if m in sys.modules)\n"
            "print(','.join(bad))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "", f"import {module} loaded {out}"


def test_importing_accelcal_loads_nothing_heavy():
    """``import accelcal`` (what ``accelcal --help`` needs first) loads no numerical
    package: names are loaded on first use (PEP 562)."""
    code = ("import sys, accelcal\n"
            "print(','.join(sorted(m for m in ('numpy', 'scipy', 'casadi', 'pandas', 'numba') if m in sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "", f"import accelcal loaded {out}"


def test_estimators_load_casadi_scipy_and_numba_only_when_used():
    code = ("import sys\n"
            "from accelcal import full_lls, bias_lls, full_als, full_nlls, bias_nlls, ESTIMATORS\n"
            "print(','.join(sorted(m for m in ('scipy', 'casadi', 'pandas', 'numba') if m in sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "", f"importing the estimators loaded {out}"


_BLOCK_NUMBA = """
import sys
class _NoNumba:
    def find_spec(self, name, path=None, target=None):
        if name == "numba" or name.startswith("numba."):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
sys.meta_path.insert(0, _NoNumba())
"""


def test_core_works_without_numba():
    """Without the ``fast`` extra the numpy implementations run (same API, same errors)."""
    code = _BLOCK_NUMBA + (
        "import numpy as np\n"
        "from accelcal import full_lls, bias_lls, full_als, full_lls_batch, kernels, DegeneratePosesError\n"
        "from accelcal.simulation import random_directions, simulate_poses\n"
        "rng = np.random.default_rng(0)\n"
        "z = simulate_poses(random_directions(rng, 24), 9.8, np.eye(3), np.full(3, 0.01), 1e-4, rng)\n"
        "r = full_lls(z, 9.8); bias_lls(z, 9.8); full_als(z, 9.8, 1e-4); full_lls_batch(z[None], 9.8)\n"
        "try:\n"
        "    full_lls(np.column_stack([z[:, :2], np.zeros(24)]), 9.8)\n"
        "except DegeneratePosesError:\n"
        "    pass\n"
        "print(kernels.backend(), 'numba' in sys.modules, np.abs(r.bias - 0.01).max() < 1e-3)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["numpy", "False", "True"]

"""tools/setup.sh compiles only part of site-packages (tools/bytecode.py's rule): every
third-party module the project imports must be inside the part compiled, or each process of
the workflow and the tests would compile it again where PYTHONDONTWRITEBYTECODE is set."""

import ast
import json
import os
import re
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tools"))
from bytecode import SKIP  # noqa: E402

#: Where the project's processes import from: the library, the workflow's scripts, the tests.
SOURCES = ("src/**/*.py", "workflow/**/*.py", "workflow/**/*.smk", "Snakefile", "tests/**/*.py")

#: Imported by the processes without an import statement in the sources: Snakemake's own
#: entry point and its script jobs' preamble, pytest's workers, and the ArduPilot reader's
#: pymavlink path (its dialect module is chosen at run time).
ENTRY_POINTS = ("snakemake.cli", "snakemake.script", "xdist.remote", "pymavlink.DFReader")

# Runs in a fresh interpreter with PYTHONDONTWRITEBYTECODE=1: imports every name installed in
# site-packages (not the project's, not the standard library's) and reports the site-packages
# files loaded and any compiled from source on the way.
PROBE = """
import importlib, importlib.util, json, sys, sysconfig
site = tuple({sysconfig.get_path("purelib"), sysconfig.get_path("platlib")})
compiled = []
sys.addaudithook(lambda e, a: e == "compile" and isinstance(a[1], str) and a[1].startswith(site)
                 and compiled.append(a[1]))

def installed(top):
    spec = importlib.util.find_spec(top)
    where = spec and (spec.origin or next(iter(spec.submodule_search_locations or ()), None))
    return bool(where) and where.startswith(site)

tried, failed = [], []
for name in json.loads(sys.argv[1]):
    if not installed(name.split(".")[0]):
        continue
    try:
        importlib.import_module(name)
        tried.append(name)
    except ModuleNotFoundError as exc:
        if exc.name != name:  # else ``from a import b`` where b is not a module
            failed.append(f"{name}: {exc!r}")
    except Exception as exc:
        failed.append(f"{name}: {exc!r}")
files = {getattr(m, "__file__", None) or "" for m in list(sys.modules.values())}
print(json.dumps({"tried": tried, "compiled": compiled, "failed": failed,
                  "loaded": sorted(f for f in files if f.startswith(site))}))
"""


def _imported_names(path):
    """Absolute module names a file imports (``from a import b`` gives ``a`` and ``a.b``);
    of a Snakefile, the modules its top-level import lines name (the rest is not Python)."""
    text = path.read_text()
    if path.suffix != ".py":
        return {a or b for a, b in re.findall(r"^(?:from ([\w.]+) import|import ([\w.]+))", text, re.M)}
    names = set()
    for node in ast.walk(ast.parse(text, str(path))):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
            names.update(f"{node.module}.{a.name}" for a in node.names if a.name != "*")
    return names


def test_every_module_the_project_imports_is_compiled_by_setup():
    names = set(ENTRY_POINTS)
    for pattern in SOURCES:
        for path in REPO.glob(pattern):
            names |= _imported_names(path)
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1", MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, "-c", PROBE, json.dumps(sorted(names))], env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    seen = json.loads(proc.stdout.splitlines()[-1])
    assert {"numpy", "scipy.optimize", "pandas", "casadi", "pymavlink.DFReader"} <= set(seen["tried"])
    assert seen["failed"] == []
    # The rule, whatever this environment holds: no file the processes load is skipped.
    assert [f for f in seen["loaded"] if SKIP.search(f)] == []
    # This environment: no module was compiled from source (tools/setup.sh ran its compile).
    # Files compiled that are not modules are configuration some packages exec at import
    # (cv2's config.py): no bytecode can serve those.
    assert sorted(set(seen["compiled"]) & set(seen["loaded"])) == []

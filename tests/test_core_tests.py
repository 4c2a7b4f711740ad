"""The core's own tests do not import the reproductions.

``accelcal`` never imports ``accelcal_repro`` (tests/test_package_boundary.py); its tests must
not either, so that the library's tests say what the library does, and a change to a
reproduction cannot break or carry them.  A test file may import ``accelcal_repro`` only if
its name says it tests a reproduction (:data:`REPRODUCTION_TESTS`: the papers, the measured
stage, the claims, the Monte Carlo, the workflow's stages and report; new ones:
``test_repro_*.py``), with no exception: the tests that ran on a reproduction's simulated
sessions live in ``test_repro_<the core file's name>.py`` beside the core file that keeps the
rest.  Files are parsed, not imported.
"""

from __future__ import annotations

import ast
import fnmatch
from pathlib import Path

TESTS = Path(__file__).resolve().parent

#: Names of the test files of the reproductions (fnmatch patterns).
REPRODUCTION_TESTS = (
    "test_repro_*.py", "test_reproduction_*.py",
    "test_batista_*.py", "test_burkhard2024_*.py", "test_tereshkov_*.py",   # the papers
    "test_measured_*.py", "test_montecarlo.py", "test_benchmark.py",          # measured stage, Monte Carlo
    "test_claims*.py", "test_report*.py", "test_*_stage.py",                  # claims, report, stages
    "test_workflow*.py", "test_cli_workflow_agreement.py", "test_config_schemas.py", "test_resilience.py",
    "test_discrepancy_benchmark.py", "test_discrepancy_oracle.py", "test_discrepancy_sessions.py",
    "test_discrepancy_claims.py", "test_discrepancy_adis.py", "test_gyro_sessions.py",
    "test_reader_variants.py",                                                # accelcal_repro.reader_variants
)


def imports_the_reproductions(path: Path) -> bool:
    """Whether ``path`` imports ``accelcal_repro`` anywhere (top level or inside a function)."""
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import) and any(a.name.split(".")[0] == "accelcal_repro" for a in node.names):
            return True
        if isinstance(node, ast.ImportFrom) and not node.level and (node.module or "").split(".")[0] == "accelcal_repro":
            return True
    return False


def is_reproduction_test(name: str) -> bool:
    return any(fnmatch.fnmatch(name, pattern) for pattern in REPRODUCTION_TESTS)


def test_core_tests_import_no_reproduction():
    offenders = sorted(p.name for p in TESTS.glob("*.py")
                       if imports_the_reproductions(p) and not is_reproduction_test(p.name))
    assert not offenders, ("core test files import accelcal_repro: move those tests to a test_repro_*.py file "
                           f"(or a reproduction's test file): {offenders}")


def test_the_checker_finds_an_import_in_a_function(tmp_path):
    (tmp_path / "a.py").write_text("import accelcal\n\ndef test_x():\n    from accelcal_repro.claims import x\n")
    (tmp_path / "b.py").write_text("'''accelcal_repro in a docstring'''\nfrom accelcal import repro\n")
    assert imports_the_reproductions(tmp_path / "a.py") and not imports_the_reproductions(tmp_path / "b.py")
    assert is_reproduction_test("test_repro_gyro.py") and not is_reproduction_test("test_gyro_only.py")
